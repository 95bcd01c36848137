//! `pradar reproduce` ([`reproduce`]): simulate the built-in corridor (or a campaign with a
//! `[scene]`) and write its report through `pradar report`'s code path
//! ([`super::campaign_report`]): the simulated campaign's energy table, CLEAN → K-means → fit,
//! Table 1 beside the simulator's truth, the geometry-only Table 1, the check, the maps,
//! the experiments and the page.
//!
//! Options are checked once ([`ReproduceOptions`] → [`ReproduceValid`]). A campaign without
//! `[scene]` is refused before anything is written (it is a measured campaign: `pradar
//! report` takes it). A failed run leaves nothing behind, as `report`'s.

use super::campaign_report::{run_inner, Job, OutGuard, ReportOutput, Source};
use super::experiment::ExperimentValid;
use super::{write_builtin_corridor, Progress};
use crate::campaign::manifest::Campaign;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use crate::simulate::has_scene;
use std::path::{Path, PathBuf};

/// `reproduce`'s report folder when none is given.
pub const DEFAULT_REPRODUCE_OUT: &str = "reports/corridor";

/// Options of `reproduce` (checked by [`ParamGuard::check`] into a [`ReproduceValid`]).
#[derive(Debug, Clone)]
pub struct ReproduceOptions {
    /// Report folder (`reports/corridor`).
    pub out: PathBuf,
    /// Manifest to use instead of the built-in corridor.
    pub campaign: Option<PathBuf>,
    /// `--elements` override.
    pub elements: Option<usize>,
    /// Run the mapping experiments ([`experiment`]) into `out/experiments` (default true).
    pub experiments: bool,
    /// Their parameters, checked.
    pub experiment_params: ExperimentValid,
}

/// [`ReproduceOptions`] that passed their check.
pub type ReproduceValid = Valid<ReproduceOptions>;

impl ParamGuard for ReproduceOptions {
    type Checked = ReproduceValid;

    /// `--elements` a perfect square (16, 100, 400); the experiment parameters are checked
    /// by their type.
    fn check(&self) -> Result<ReproduceValid> {
        if let Some(n) = self.elements {
            let s = (n as f64).sqrt().round() as usize;
            if n == 0 || s * s != n {
                return Err(Error::param(
                    "--elements",
                    format!("{n} is not a perfect square (use 16, 100 or 400)"),
                ));
            }
        }
        Ok(Valid::new(self.clone()))
    }
}

/// Run the main job; returns the index path.
///
/// ```no_run
/// use pradar::params::ParamGuard;
/// use pradar::pipeline::experiment::ExperimentParams;
/// use pradar::pipeline::{reproduce, ReproduceOptions};
/// let opts = ReproduceOptions {
///     out: "reports/corridor".into(),
///     campaign: None,
///     elements: None,
///     experiments: false,
///     experiment_params: ExperimentParams::default().check()?,
/// }
/// .check()?;
/// let progress = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
/// let done = reproduce(&opts, &progress)?;
/// println!("report: {}", done.index.display());
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn reproduce(opts: &ReproduceValid, progress: Progress) -> Result<ReportOutput> {
    if let Some(p) = &opts.campaign {
        let c = Campaign::load(p)?;
        if !has_scene(&c)? {
            return Err(Error::input(
                p,
                "reproduce simulates the campaign and it has no [scene] section; for a measured campaign run `pradar report --campaign` on it",
            ));
        }
        super::campaign_report::refuse_inside(&opts.out, &[(p.clone(), "--campaign")])?;
    }
    let guard = OutGuard::begin(&opts.out)?;
    let c = load_campaign(opts, &opts.out.join("work"))?;
    let job = Job {
        out: &opts.out,
        model: None,
        truth: None,
        experiments: opts.experiments.then_some(&opts.experiment_params),
        explore: None,
        progress,
    };
    let done = run_inner(&job, Source::Simulate(&c))?;
    guard.done();
    Ok(done)
}

/// The campaign (the built-in corridor unless `--campaign`, written into `work/input`) with
/// the `--elements` override.
fn load_campaign(opts: &ReproduceOptions, work: &Path) -> Result<Campaign> {
    let src = match &opts.campaign {
        Some(p) => p.clone(),
        None => write_builtin_corridor(&work.join("input"))?,
    };
    let mut c = Campaign::load(&src)?;
    if let Some(n) = opts.elements {
        c.set_elements(n)?;
    }
    Ok(c)
}
