//! The paper's mapping experiments (DESIGN §2 "Experiments" 2–5): `pradar experiment NAME
//! --out DIR`.
//!
//! Takes a campaign (the built-in corridor unless `--campaign`), the energy table of its
//! sweeps (simulated by `simulate` → `energy` unless given) and a model file (`--model`; by
//! default the chain CLEAN → K-means → fit is run on that energy table and its
//! `fitted_model.toml` used — never the simulator's `[clutter]` truth). Gives, per experiment
//! `NAME` in `DIR/NAME/`: `NAME.md` and `NAME.csv` (the table), `NAME.json` (every case with
//! all its figures), `NAME.png` (the maps in one panel) and, where a figure is a curve,
//! `NAME_plot.png`; every map it made in `DIR/maps/<case>/` (the `pradar map` files: PNG,
//! PGM and YAML, metrics.json); model data in `DIR/work/synth/`; and `DIR/index.html` linking
//! the experiments run.
//!
//! Layout: [`params`] (the parameters and their check), [`inputs`] (resolving the inputs),
//! [`lab`] (cases, scoring, the shared maps, the case table), one file per experiment
//! ([`fig5`], [`fig6`], [`prior_sensitivity`], [`pose_noise`], [`slam`]). The experiments produce
//! results ([`ExperimentResult`]: figures, findings and what the page shows, as data) and
//! never call the report: the panels, plots and HTML are drawn from the results by
//! [`crate::report::experiments`] (`pradar experiment` and the campaign report call it).
//!
//! Choices (where DESIGN and the issue are silent):
//! * **model data** = `synth` with the model file on the campaign's layout and trajectory,
//!   the campaign's array type (the corridor's is the 1-bit transmitarray) at N elements;
//!   seeds 1, 2, 3 (`--seeds`): a seed draws a new channel (clusters, rays, shadowing) and new
//!   detector noise;
//! * **mappers**: the side-lobe-aware occupancy grid `og` (prior 0.5, P_fa 1e-3, binary
//!   p > 0.5) and the scalable EKF (μ0 0.01 m, σ0 0.1 m, binary x̂ − κσ̂ > μ0, κ = 3.09, free-space evidence), 0.1 m cells —
//!   `pradar map`'s defaults, not tuned on the reference;
//! * **figures** per map: ψ, F1 and the wrong-cell count on three regions, each the same
//!   for every N, mapper, prior and pose noise of a campaign except (b): (a) the *whole map*
//!   (every cell of the grid, cells outside the perimeter counted as free), (b) the
//!   *observable region* of that run (cells in line of sight of a pose inside some −3 dB
//!   main lobe; it widens with the beam, so N = 16 is scored on slightly more cells than
//!   N = 100) and (c) the *interior*: the building (inside the perimeter or on a wall), where
//!   wrong cells are what an indoor map gets wrong. Each beside the all-free map's;
//! * **fig6 statement**: the paper's "N = 16 has more wrong cells than N = 100" is checked per
//!   mapper and seed on the interior and on the whole map, and on the campaign's sweeps
//!   simulated at both N when the campaign has a `[scene]`;
//! * **fig5**: EKF maps at the campaign's array (400-element 1-bit for the corridor) from the
//!   campaign's sweeps (simulated or measured) and from model data (every seed), side by side with the reference;
//! * **fig6**: OG and EKF on model data at N = 16 and N = 100, every seed (and on the
//!   sweeps simulated at both N);
//! * **prior-sensitivity**: at N = 16 on model data, the OG prior p0 and the EKF μ0 each
//!   scaled by 1 ± 0.4 (p0 0.3 / 0.5 / 0.7, μ0 0.006 / 0.01 / 0.014 m) with everything else
//!   fixed (the binary rules stay p > 0.5 and x̂ − κσ̂ > μ0, so μ0 moves the EKF's threshold as
//!   it moves its prior); relative change Δψ/ψ = (ψ̄(changed) − ψ̄(base))/ψ̄(base) of the mean ψ
//!   over seeds;
//! * **pose-noise**: at N = 100 on model data, the mapper is given poses with Gaussian noise
//!   ([`PoseNoise`](crate::mapping::job::PoseNoise): σ per axis 0, 2, 5, 10 cm with no heading
//!   noise, and heading σ 0, 1, 2, 5° with no position noise; one draw per pose, keyed by the
//!   data seed) while the data were taken at the true poses; mean ψ over seeds.
//!
//! Maps shared between experiments (the base cases) are computed once per process.

use super::Progress;
use crate::error::{Error, Result};
use serde::Serialize;
use std::path::Path;

pub mod fig5;
pub mod fig6;
pub mod inputs;
pub mod lab;
pub mod params;
pub mod pose_noise;
pub mod prior_sensitivity;
pub mod slam;

pub use inputs::{prepare_inputs, ExperimentInputs, InputOptions};
pub use lab::{
    case_table, Case, CaseFigures, DataSource, ExperimentResult, Figure, Lab, Panel, PanelTile,
};
pub use params::{ExperimentParams, ExperimentValid, Fig6Data};

/// The experiments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Experiment {
    /// EKF maps from the campaign's sweeps and from model data.
    Fig5,
    /// OG vs EKF for N = 16 and N = 100 on model data.
    Fig6,
    /// OG prior and EKF μ0 changed by ±40 %.
    PriorSensitivity,
    /// ψ as pose noise grows.
    PoseNoise,
    /// Pose RMSE and maps with the true, dead-reckoned and estimated poses (issue 56; not
    /// in `all`).
    Slam,
}

impl Experiment {
    /// The experiments of `all` and of the report, in report order (`slam` is asked by
    /// name).
    pub const ALL: [Experiment; 4] = [
        Experiment::Fig5,
        Experiment::Fig6,
        Experiment::PriorSensitivity,
        Experiment::PoseNoise,
    ];
    /// Command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Experiment::Fig5 => "fig5",
            Experiment::Fig6 => "fig6",
            Experiment::PriorSensitivity => "prior-sensitivity",
            Experiment::PoseNoise => "pose-noise",
            Experiment::Slam => "slam",
        }
    }
    /// Parse a command-line name (`all` is handled by the caller; `slam` is asked by name).
    pub fn parse(s: &str) -> Result<Experiment> {
        (Experiment::ALL.into_iter())
            .chain([Experiment::Slam])
            .find(|e| e.name() == s)
            .ok_or_else(|| {
                Error::param(
                    "experiment",
                    format!(
                        "unknown experiment `{s}` (fig5|fig6|prior-sensitivity|pose-noise|slam|all)"
                    ),
                )
            })
    }
}

/// What [`run_experiments`] gives: the inputs it used (name, value) and each result.
#[derive(Debug, Clone)]
pub struct ExperimentsRun {
    /// The inputs as listed on the page: campaign, energy, model, seeds.
    pub inputs: Vec<(String, String)>,
    /// One result per experiment run, in the order asked.
    pub results: Vec<ExperimentResult>,
}

/// `pradar experiment`'s computation: resolve the inputs into `out/work`, run `which`
/// (maps and data files). The images and `out/index.html` are the report's
/// ([`crate::report::experiments::write_all`]).
///
/// ```no_run
/// use pradar::params::ParamGuard;
/// use pradar::pipeline::experiment::{run_experiments, Experiment, ExperimentParams, InputOptions};
/// let params = ExperimentParams::default().seeds(vec![1]).check()?;
/// let progress = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
/// let out = std::path::Path::new("experiments");
/// let run = run_experiments(&[Experiment::Fig5], &InputOptions::default(), &params, out, &progress)?;
/// println!("{:?}", run.results[0].findings);
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn run_experiments(
    which: &[Experiment],
    inputs: &InputOptions,
    params: &ExperimentValid,
    out: &Path,
    progress: Progress,
) -> Result<ExperimentsRun> {
    let resolved = prepare_inputs(inputs, &out.join("work"), progress)?;
    let mut lab = Lab::new(resolved, params.clone(), out, progress)?;
    lab.prepare(which)?;
    let mut results = Vec::new();
    for &e in which {
        results.push(lab.run(e)?);
    }
    let i = lab.inputs();
    let listed = vec![
        ("campaign".to_string(), i.campaign.display().to_string()),
        ("energy (sweeps)".into(), i.energy.display().to_string()),
        ("model".into(), i.model.display().to_string()),
        ("seeds".into(), lab::join_u(&params.seeds)),
    ];
    Ok(ExperimentsRun {
        inputs: listed,
        results,
    })
}
