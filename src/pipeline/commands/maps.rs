//! The mapping commands: `map` (one or several runs of campaign + energy table into an
//! occupancy-grid map and its metrics) and `experiment` (the paper's mapping experiments,
//! by name or `all`, into one folder each and an index page). Each takes its command
//! struct and gives a summary whose `Display` is printed.

use super::StepProgress;
use crate::error::Result;
use crate::mapping::{MapOptions, MapReport, MapRun};
use crate::params::ParamGuard;
use crate::pipeline::experiment::{
    run_experiments, Experiment, ExperimentParams, ExperimentResult, InputOptions,
};
use crate::pipeline::Progress;
use std::fmt;
use std::path::PathBuf;

/// `pradar map`: the map options plus the `--run` specifications still to parse.
#[derive(Debug, Clone)]
pub struct Map {
    /// Everything but the `--run` runs (`options.runs` holds the `--campaign` +
    /// `--energy` run, if given).
    pub options: MapOptions,
    /// `--run campaign.toml=energy.parquet` values, appended after `options.runs`.
    pub run_specs: Vec<String>,
}

/// What `map` wrote.
#[derive(Debug, Clone)]
pub struct MapSummary {
    /// The stage's report.
    pub report: MapReport,
    /// The output folder.
    pub out: PathBuf,
}

impl fmt::Display for MapSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        let m = &r.metrics.observable;
        write!(
            f,
            "{} map {}x{} -> {} (observable: psi {:.3}, F1 {:.3}; all-free psi {:.3})",
            r.method,
            r.rows,
            r.cols,
            self.out.display(),
            m.psi,
            m.f1,
            r.metrics.observable_all_free.psi
        )
    }
}

/// Run `pradar map` ([`crate::mapping::run_map`]); `progress` counts poses over all runs.
pub fn map(cmd: &Map, progress: StepProgress) -> Result<MapSummary> {
    let mut opts = cmd.options.clone();
    for r in &cmd.run_specs {
        opts.runs.push(MapRun::parse(r)?);
    }
    let report = crate::mapping::run_map(&opts.check()?, progress)?;
    Ok(MapSummary {
        report,
        out: opts.out,
    })
}

/// `pradar experiment`: the paper's mapping experiments.
#[derive(Debug, Clone)]
pub struct Experiments {
    /// `fig5`, `fig6`, `prior-sensitivity`, `pose-noise` or `all`.
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
