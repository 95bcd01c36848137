//! The experiments' inputs: a campaign, the energy table of its sweeps and a model file,
//! each given or made ([`prepare_inputs`]).
//!
//! Missing inputs are made in a work folder: the built-in corridor is written when no
//! campaign is given; a campaign without `[sweeps]` is simulated (Parquet sweeps); its
//! energy table is computed; and the model is fitted by the chain CLEAN → K-means → fit on
//! that energy table (never the simulator's `[clutter]` truth).

use super::super::{analyse, write_builtin_corridor, Progress};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy::{self, EnergyMatrix};
use crate::error::{Error, Result};
use crate::model::file::ModelConfig;
use crate::simulate::simulate;
use std::path::{Path, PathBuf};

/// Where the experiments' inputs come from (all optional).
#[derive(Debug, Clone, Default)]
pub struct InputOptions {
    /// Campaign manifest (default: the built-in corridor).
    pub campaign: Option<PathBuf>,
    /// Energy table of its sweeps (default: computed from its `[sweeps]`, or simulated).
    pub energy: Option<PathBuf>,
    /// Model file (default: fitted from that energy table).
    pub model: Option<PathBuf>,
}

/// The experiments' inputs, resolved.
#[derive(Debug, Clone)]
pub struct ExperimentInputs {
    /// Campaign manifest of the energy table (layout, trajectory, array).
    pub campaign: PathBuf,
    /// Energy table of its (simulated or measured) sweeps.
    pub energy: PathBuf,
    /// Model file used for model data.
    pub model: PathBuf,
}

/// Resolve the inputs into `work`: write the built-in corridor, simulate it (Parquet sweeps)
/// when the campaign has no `[sweeps]`, compute its energy table, fit a model.
pub fn prepare_inputs(
    opts: &InputOptions,
    work: &Path,
    progress: Progress,
) -> Result<ExperimentInputs> {
    std::fs::create_dir_all(work).map_err(|e| Error::io(work, e))?;
    let src = match &opts.campaign {
        Some(p) => p.clone(),
        None => write_builtin_corridor(&work.join("input"))?,
    };
    let (campaign, energy) = sweeps_energy(&src, opts.energy.as_ref(), work, progress)?;
    let model = match &opts.model {
        Some(m) => {
            ModelConfig::load(m)?;
            m.clone()
        }
        None => fit_model(&campaign, &energy, work)?,
    };
    Ok(ExperimentInputs {
        campaign,
        energy,
        model,
    })
}

/// The (manifest, energy table) of campaign `src`: the given table, the one computed from
/// its `[sweeps]`, or the one of its simulation into `work/simulated`.
fn sweeps_energy(
    src: &Path,
    energy: Option<&PathBuf>,
    work: &Path,
    progress: Progress,
) -> Result<(PathBuf, PathBuf)> {
    let c = Campaign::load(src)?;
    let np = c.manifest.positions();
    Ok(match (energy, &c.manifest.sweeps) {
        (Some(e), _) => (src.to_path_buf(), e.clone()),
        (None, Some(_)) => {
            let e = work.join("energy.parquet");
            energy::run(&c, &e, &*progress("energy", np))?;
            (src.to_path_buf(), e)
        }
        (None, None) => {
            let sim = simulate(
                &c,
                &work.join("simulated"),
                SweepFormat::Parquet,
                &*progress("simulate", np),
            )?;
            let sc = Campaign::load(&sim.manifest)?;
            let e = work.join("energy.parquet");
            energy::run(&sc, &e, &*progress("energy", np))?;
            (sim.manifest, e)
        }
    })
}

/// Fit a model on the energy table (CLEAN → K-means → fit in `work/analysis`) and save it as
/// `work/fitted_model.toml`.
fn fit_model(campaign: &Path, energy: &Path, work: &Path) -> Result<PathBuf> {
    let sc = Campaign::load(campaign)?;
    let em = EnergyMatrix::read(energy)?;
    let dir = work.join("analysis");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let fit = analyse(&sc, &em, energy, &dir, false)?.fit?;
    let m = work.join("fitted_model.toml");
    fit.model.save(&m)?;
    Ok(m)
}
