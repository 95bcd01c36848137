//! The report's mapping experiments ([`run_experiments`]) on the campaign's sweeps and the
//! model, into `out/experiments`.
//!
//! Takes the job, the gathered data, the fit and the sweeps made beside it; gives the
//! experiments' sections (or one saying why they did not run), removing what they made
//! when they do not run.

use super::gather::Data;
use super::Job;
use crate::error::Result;
use crate::fit::channel::ChannelFit;
use crate::pipeline::experiment::{self, ExperimentValid};
use crate::report::reproduce as page;
use crate::report::{self, Section};
use std::path::{Path, PathBuf};

/// The mapping experiments on the campaign's sweeps and the model (`--model`, else the
/// fitted one), into `out/experiments`: their sections, or one saying why they did not run
/// (the fit failed or left a quantity not estimable: the model data need every quantity;
/// or an experiment failed).
pub(super) fn run_experiments(
    job: &Job,
    params: &ExperimentValid,
    s: &Data,
    fit: &Result<ChannelFit>,
    presim: Vec<(usize, Result<(PathBuf, PathBuf)>)>,
) -> Vec<Section> {
    let dir = job.out.join("experiments");
    let not_run = match (job.model, fit) {
        (Some(_), _) => None,
        (None, Err(e)) => Some(page::experiments_not_run(e)),
        // a schema-1 style partial model (no stated values) cannot be drawn from
        (None, Ok(f)) if f.model.require_estimable(&Default::default()).is_err() => {
            Some(page::experiments_not_run_partial(&f.model.not_estimable()))
        }
        (None, Ok(_)) => None,
    };
    if let Some(section) = not_run {
        remove_experiments(&dir, &presim);
        return vec![section];
    }
    let inputs = experiment::ExperimentInputs {
        campaign: s.campaign.path.clone(),
        energy: s.energy_path.clone(),
        model: match job.model {
            Some(m) => m.to_path_buf(),
            None => job.out.join("fitted_model.toml"),
        },
    };
    let run = || -> Result<Vec<Section>> {
        let mut lab = experiment::Lab::new(inputs, params.clone(), &dir, job.progress)?;
        // sweeps made beside the fit (one that failed is left to the lab, which reports it)
        for (n, r) in presim {
            if let Ok(r) = r {
                lab.preset_sweeps(n, r);
            }
        }
        lab.prepare(&experiment::Experiment::ALL)?;
        let mut sections = Vec::new();
        for e in experiment::Experiment::ALL {
            let r = lab.run(e)?;
            report::experiments::write_figures(&r, &dir)?;
            sections.push(report::experiments::section(&r, "experiments/"));
        }
        Ok(sections)
    };
    run().unwrap_or_else(|e| {
        let _ = std::fs::remove_dir_all(&dir);
        vec![Section {
            title: "Experiments".into(),
            html: page::failed("the experiments", &e),
        }]
    })
}

/// The sweeps made beside the fit for experiments that do not run are not the report's:
/// removed with their folders.
fn remove_experiments(dir: &Path, presim: &[(usize, Result<(PathBuf, PathBuf)>)]) {
    for (n, _) in presim {
        let sweeps = experiment::lab::sweeps_dir(dir, *n);
        if sweeps.exists() {
            let _ = std::fs::remove_dir_all(&sweeps);
        }
    }
    let _ = std::fs::remove_dir(dir.join("work"));
    let _ = std::fs::remove_dir(dir);
}
