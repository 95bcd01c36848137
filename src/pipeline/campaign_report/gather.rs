//! The report's data: the energy table of the job's [`Source`] (simulated
//! then computed, computed from the campaign's sweeps, or read as given) checked against
//! the campaign ([`obtain`]).
//!
//! Takes the job, its source and the work folder; gives [`Data`] (the analysed campaign,
//! its energy table, where it came from, the energy stage's warnings).

use super::{Job, Source, Timings};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy::{self, EnergyMatrix};
use crate::error::Result;
use crate::simulate::{simulate, SimReport};
use std::path::{Path, PathBuf};

/// The analysed campaign and its energy table.
pub(super) struct Data {
    /// The analysed campaign (the simulated one for [`Source::Simulate`]).
    pub(super) campaign: Campaign,
    /// What the simulator wrote, when it ran.
    pub(super) sim: Option<SimReport>,
    /// Truth folder for the truth column.
    pub(super) truth: Option<PathBuf>,
    /// The energy table's path.
    pub(super) energy_path: PathBuf,
    /// Where the energy table came from, for the summary.
    pub(super) energy_shown: String,
    /// The energy stage's warnings when it ran here (none for a given table).
    pub(super) energy_warnings: Vec<String>,
    /// The energy table.
    pub(super) em: EnergyMatrix,
}

/// The energy table of the source: simulated then computed, computed from the campaign's
/// sweeps, or read as given.
pub(super) fn obtain(
    job: &Job,
    source: &Source,
    work: &Path,
    timings: &mut Timings,
) -> Result<Data> {
    let progress = job.progress;
    let energy_path = work.join("energy.parquet");
    // the energy stage's warnings go on to the page and the command line
    let compute = |c: &Campaign, timings: &mut Timings| -> Result<Vec<String>> {
        timings.time("energy", || {
            let cb = progress("energy", c.manifest.positions());
            energy::run(c, &energy_path, &*cb).map(|r| r.warnings)
        })
    };
    let (campaign, sim, truth, energy_path, energy_shown, energy_warnings) = match source {
        Source::Simulate(c) => {
            let dir = work.join("simulated");
            let sim = timings.time("simulate", || {
                let cb = progress("simulate", c.manifest.positions());
                simulate(c, &dir, SweepFormat::Touchstone, &*cb)
            })?;
            let sc = Campaign::load(&sim.manifest)?;
            let warnings = compute(&sc, timings)?;
            let truth = Some(dir.join("truth"));
            (
                sc,
                Some(sim),
                truth,
                energy_path,
                "work/energy.parquet".into(),
                warnings,
            )
        }
        Source::Campaign { campaign, energy } => {
            let c = (*campaign).clone();
            match energy {
                Some(e) => {
                    let shown = format!("{} (given)", e.display());
                    (
                        c,
                        None,
                        job.truth.clone(),
                        e.to_path_buf(),
                        shown,
                        Vec::new(),
                    )
                }
                None => {
                    let warnings = compute(&c, timings)?;
                    let shown = "work/energy.parquet (computed from the sweeps)".into();
                    (c, None, job.truth.clone(), energy_path, shown, warnings)
                }
            }
        }
    };
    let em = EnergyMatrix::read(&energy_path)?;
    crate::energy::matrix::check_campaign(&campaign, &em, &energy_path)?;
    Ok(Data {
        campaign,
        sim,
        truth,
        energy_path,
        energy_shown,
        energy_warnings,
        em,
    })
}
