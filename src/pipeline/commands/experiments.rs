//! The `experiment` command: the paper's mapping experiments, by name or `all`, into one
//! folder each and an index page. Takes its command struct and gives a summary whose
//! `Display` is printed.

use crate::error::Result;
use crate::params::ParamGuard;
use crate::pipeline::experiment::{
    run_experiments, Experiment, ExperimentParams, ExperimentResult, InputOptions,
};
use crate::pipeline::Progress;
use std::fmt;
use std::path::PathBuf;

/// `pradar experiment`: the paper's mapping experiments.
#[derive(Debug, Clone)]
pub struct Experiments {
    /// `fig5`, `fig6`, `prior-sensitivity`, `pose-noise`, `all` (those four) or `slam`.
    pub name: String,
    /// Campaign, energy table and model (each resolved when absent).
    pub inputs: InputOptions,
    /// Seeds and the experiments' settings.
    pub params: ExperimentParams,
    /// Output folder (`out/NAME/` per experiment, `out/index.html`).
    pub out: PathBuf,
}

/// What `experiment` wrote.
#[derive(Debug, Clone)]
pub struct ExperimentsSummary {
    /// Every experiment run, in order.
    pub results: Vec<ExperimentResult>,
    /// The index page.
    pub index: PathBuf,
}

impl fmt::Display for ExperimentsSummary {
    /// Each experiment's findings, then the index page.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for r in &self.results {
            writeln!(f, "{}:", r.name)?;
            for (k, v) in &r.findings {
                writeln!(f, "  {k}: {v}")?;
            }
        }
        write!(f, "report: {}", self.index.display())
    }
}

/// The experiments a command-line name selects (`all`: every one, in report order).
pub fn select_experiments(name: &str) -> Result<Vec<Experiment>> {
    if name == "all" {
        Ok(Experiment::ALL.to_vec())
    } else {
        Ok(vec![Experiment::parse(name)?])
    }
}

/// Run `pradar experiment` ([`run_experiments`]).
pub fn experiments(cmd: &Experiments, progress: Progress) -> Result<ExperimentsSummary> {
    let which = select_experiments(&cmd.name)?;
    let params = cmd.params.check()?;
    let run = run_experiments(&which, &cmd.inputs, &params, &cmd.out, progress)?;
    crate::report::experiments::write_all(&cmd.out, &run.inputs, &run.results)?;
    Ok(ExperimentsSummary {
        results: run.results,
        index: cmd.out.join("index.html"),
    })
}
