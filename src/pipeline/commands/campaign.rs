//! The campaign commands: `simulate` (a manifest with `[scene]` into sweeps, a manifest and
//! its truth), `energy` (a campaign's sweeps into an energy table) and `synth` (a model file
//! and a campaign into an energy table and its truth). Each takes its command struct and gives a summary whose `Display` is printed.

use super::{campaign_inputs, load_campaign, refuse, StepProgress};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy::EnergyReport;
use crate::error::Result;
use crate::model::file::ModelConfig;
use crate::model::{SynthParams, SynthReport};
use crate::params::ParamGuard;
use crate::simulate::SimReport;
use std::fmt;
use std::path::PathBuf;

/// `pradar simulate`: a manifest with `[scene]` simulated into a folder.
#[derive(Debug, Clone)]
pub struct Simulate {
    /// Input manifest with `[scene]` (and optionally `[clutter]`).
    pub campaign: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// `[array] elements` override.
    pub elements: Option<usize>,
    /// Sweep file format.
    pub format: SweepFormat,
}

/// What `simulate` wrote.
#[derive(Debug, Clone)]
pub struct SimulateSummary(pub SimReport);

impl fmt::Display for SimulateSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.0;
        write!(
            f,
            "simulated {} sweeps ({} scatterers, {} clutter clusters) -> {}",
            r.sweeps,
            r.scatterers,
            r.clusters,
            r.manifest.display()
        )
    }
}

/// Run `pradar simulate` ([`crate::simulate::simulate`]).
pub fn simulate(cmd: &Simulate, progress: StepProgress) -> Result<SimulateSummary> {
    let c = load_campaign(&cmd.campaign, cmd.elements)?;
    let truth = cmd.out.join("truth");
    let outputs: Vec<(PathBuf, &str)> = [
        cmd.out.join("campaign.toml"),
        cmd.out.join("layout.geojson"),
        cmd.out.join("sweeps.parquet"),
        truth.join("rays.parquet"),
        truth.join("scatterers.csv"),
        truth.join("clusters.csv"),
    ]
    .into_iter()
    .map(|p| (p, "--out"))
    .collect();
    refuse(&outputs, &campaign_inputs(&c))?;
    let r = crate::simulate::simulate(&c, &cmd.out, cmd.format, progress)?;
    Ok(SimulateSummary(r))
}

/// `pradar energy`: the energy table of a campaign's sweeps.
#[derive(Debug, Clone)]
pub struct Energy {
    /// Manifest with `[sweeps]`.
    pub campaign: PathBuf,
    /// Output energy Parquet.
    pub out: PathBuf,
}

/// What `energy` wrote.
#[derive(Debug, Clone)]
pub struct EnergySummary {
    /// The stage's report.
    pub report: EnergyReport,
    /// The energy Parquet written.
    pub out: PathBuf,
}

impl fmt::Display for EnergySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        write!(
            f,
            "{} sweeps -> {} rows in {} (N0 {:.3e}, noise bin mean {:.3e})",
            r.sweeps,
            r.rows,
            self.out.display(),
            r.n0,
            r.noise_bin_mean
        )
    }
}

/// Run `pradar energy` ([`crate::energy::run`]).
pub fn energy(cmd: &Energy, progress: StepProgress) -> Result<EnergySummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let reader = crate::campaign::sweeps::SweepReader::open(&c)?;
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.extend(
        reader
            .files()
            .into_iter()
            .map(|p| (p.to_path_buf(), "sweep file (of --campaign)")),
    );
    drop(reader);
    inputs.extend(crate::energy::calibration::Calibration::files(&c));
    refuse(&[(cmd.out.clone(), "--out")], &inputs)?;
    let report = crate::energy::run(&c, &cmd.out, progress)?;
    Ok(EnergySummary {
        report,
        out: cmd.out.clone(),
    })
}

/// `pradar synth`: an energy table (and its truth) drawn from a model file.
#[derive(Debug, Clone)]
pub struct Synth {
    /// Model file (DESIGN §3 "Model").
    pub model: PathBuf,
    /// Campaign manifest (layout, poses, directions, band, array, noise).
    pub campaign: PathBuf,
    /// Output energy Parquet.
    pub out: PathBuf,
    /// `[array] elements` override.
    pub elements: Option<usize>,
    /// Values for model quantities (`--set NAME=VALUE`), e.g. ones marked not estimable.
    pub values: std::collections::BTreeMap<String, f64>,
    /// Seed and truth folder.
    pub params: SynthParams,
}

/// What `synth` wrote.
#[derive(Debug, Clone)]
pub struct SynthSummary {
    /// The stage's report.
    pub report: SynthReport,
    /// The energy Parquet written.
    pub out: PathBuf,
}

impl fmt::Display for SynthSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        write!(
            f,
            "synthesised {} profiles ({} clusters, {:.1} rays seen per position{}) -> {} (truth in {})",
            r.profiles,
            r.clusters,
            r.rays_per_position,
            if r.diffuse_points > 0 {
                format!(
                    "; {} diffuse wall points, {:.0} seen per position",
                    r.diffuse_points, r.diffuse_per_position
                )
            } else {
                String::new()
            },
            self.out.display(),
            r.truth_dir.display()
        )
    }
}

/// Run `pradar synth` ([`crate::model::synth()`]).
pub fn synth(cmd: &Synth, progress: StepProgress) -> Result<SynthSummary> {
    let c = load_campaign(&cmd.campaign, cmd.elements)?;
    let truth = cmd
        .params
        .truth_dir
        .clone()
        .unwrap_or_else(|| crate::model::synth::default_truth_dir(&cmd.out));
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.model.clone(), "--model"));
    refuse(
        &[
            (cmd.out.clone(), "--out"),
            (truth.join("rays.parquet"), "--truth"),
            (truth.join("model.toml"), "--truth"),
        ],
        &inputs,
    )?;
    let m = ModelConfig::load(&cmd.model)?
        .require_estimable(&cmd.values)
        .map_err(|e| crate::error::Error::input(&cmd.model, e.to_string()))?;
    let report = crate::model::synth(&c, &m, &cmd.out, &cmd.params.check()?, progress)?;
    Ok(SynthSummary {
        report,
        out: cmd.out.clone(),
    })
}
