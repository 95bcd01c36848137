//! The `pradar map` command: the CLI's map options plus its `--run` values, run as the map
//! job ([`crate::mapping::job`], which holds the options, the job and `metrics.json`).

use crate::error::Result;
use crate::mapping::job::{run_map, MapOptions, MapReport, MapRun};
use crate::params::ParamGuard;
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

impl std::fmt::Display for MapSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
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

/// Run `pradar map` ([`run_map`]); `progress` counts poses over all runs.
pub fn map(cmd: &Map, progress: super::StepProgress) -> Result<MapSummary> {
    let mut opts = cmd.options.clone();
    for r in &cmd.run_specs {
        opts.runs.push(MapRun::parse(r)?);
    }
    let report = run_map(&opts.check()?, progress)?;
    Ok(MapSummary {
        report,
        out: opts.out,
    })
}
