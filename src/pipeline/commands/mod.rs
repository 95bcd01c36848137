//! One library entry per `pradar` subcommand, so the binary only parses arguments.
//!
//! Each subcommand's arguments arrive as one plain struct ([`Simulate`], [`Energy`],
//! [`Synth`], [`Map`], [`Extract`], [`Cluster`], [`Fit`], [`Calibrate`], [`Check`],
//! [`Experiments`]; `import` takes [`ImportParams`] as it is) holding paths and the stage's
//! own parameter struct; the function of the same name in lower case loads the inputs, runs
//! the stage, writes its outputs (DESIGN §3) and returns a summary whose `Display` is the
//! line(s) the command prints on success. `reproduce` and `report` need no entry here:
//! [`crate::pipeline::reproduce`] and [`crate::pipeline::report()`] are already one call.
//!
//! What lives here rather than in the binary is the glue the stages do not own: applying
//! `--elements` after loading a manifest, gathering `--run` specifications, recovering the
//! pose headings of an MPC table ([`pose_headings`]), reading the scanned sector from the
//! MPC table's metadata, the K = K_max warning, writing the model file beside Table 1,
//! resolving `all` into the list of experiments, the problem report of an import that
//! found problems ([`ImportOutcome::problem_report`]) and the `--fail-below` verdict of a check
//! ([`CheckSummary::failure`]).
//!
//! Every command first refuses to write over one of its own inputs
//! ([`crate::io::refuse_overwrite`]: `energy --out` naming the manifest, a sweep file or
//! a `[calibration]` file,
//! `extract`/`cluster`/`fit` naming their input table, `fit --out x --table x`, `simulate`
//! or `synth` writing into the folder of the manifest or the model file they read). `fit`
//! writes Table 1 first and the model file last, so a failed table leaves no model.
//!
//! The commands are grouped by stage, each group in its own file and every item
//! re-exported here: `import` (a folder of its own: its CSV reader, name pattern, file
//! collection, check and write), `campaign` (simulate, energy, synth), `analysis` (extract,
//! cluster, fit), `model` (calibrate, check), [`map`](mod@map) (the map job: options, runs,
//! fusion, metrics.json), `experiments` and `zoo` (the scene zoo's
//! manifests).
//!
//!
//! ```no_run
//! use pradar::campaign::manifest::SweepFormat;
//! use pradar::pipeline::commands::{self, Cluster, Energy, Extract, Fit, Simulate};
//! use std::path::PathBuf;
//! let none = |_: usize, _: usize| {};
//! let sim = commands::simulate(
//!     &Simulate {
//!         campaign: "data/corridor/campaign.toml".into(),
//!         out: "sim".into(),
//!         elements: None,
//!         format: SweepFormat::Touchstone,
//!     },
//!     &none,
//! )?;
//! println!("{sim}");
//! let campaign: PathBuf = "sim/campaign.toml".into();
//! commands::energy(&Energy { campaign: campaign.clone(), out: "energy.parquet".into() }, &none)?;
//! commands::extract(&Extract {
//!     energy: "energy.parquet".into(),
//!     campaign: campaign.clone(),
//!     out: "mpcs.parquet".into(),
//!     params: pradar::mpc::ExtractParams::default(),
//! })?;
//! let clustered = commands::cluster(&Cluster {
//!     mpcs: "mpcs.parquet".into(),
//!     out: "clusters.parquet".into(),
//!     params: pradar::cluster::ClusterParams::default(),
//! })?;
//! if let Some(w) = clustered.warning() {
//!     eprintln!("warning: {w}");
//! }
//! let fit = commands::fit(&Fit {
//!     clusters: "clusters.parquet".into(),
//!     campaign,
//!     out: "fitted_model.toml".into(),
//!     table: "table1.md".into(),
//!     truth: Some("sim/truth".into()),
//!     energy: Some("energy.parquet".into()),
//!     params: pradar::fit::channel::FitParams::default(),
//!     closed_loop: 0,
//! })?;
//! println!("{fit}");
//! let synth = commands::synth(
//!     &commands::Synth {
//!         model: "fitted_model.toml".into(),
//!         campaign: "sim/campaign.toml".into(),
//!         out: "model.parquet".into(),
//!         elements: None,
//!         values: Default::default(),
//!         params: pradar::model::SynthParams::default(),
//!     },
//!     &none,
//! )?;
//! println!("{synth}");
//! let map = commands::Map {
//!     options: pradar::mapping::job::MapOptions {
//!         method: pradar::mapping::Method::Og,
//!         runs: vec![],
//!         out: "map".into(),
//!         elements: None,
//!         grid: Default::default(),
//!         og: Default::default(),
//!         ekf: Default::default(),
//!         pose_noise: Default::default(),
//!         poses_from: Default::default(),
//!         odometry: Default::default(),
//!     },
//!     run_specs: vec!["sim/campaign.toml=energy.parquet".into()],
//! };
//! println!("{}", commands::map(&map, &none)?);
//! let experiments = commands::Experiments {
//!     name: "all".into(),
//!     inputs: Default::default(),
//!     params: Default::default(),
//!     out: "experiments".into(),
//! };
//! let bars = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
//! println!("{}", commands::experiments(&experiments, &bars)?);
//! # Ok::<(), pradar::Error>(())
//! ```

mod analysis;
mod campaign;
mod experiments;
mod explore;
mod import;
mod map;
mod model;
mod zoo;

pub use analysis::{
    cluster, extract, fit, pose_headings, Cluster, ClusterSummary, Extract, ExtractSummary, Fit,
    FitSummary,
};
pub use campaign::{
    energy, simulate, synth, Energy, EnergySummary, Simulate, SimulateSummary, Synth, SynthSummary,
};
pub use experiments::{experiments, select_experiments, Experiments, ExperimentsSummary};
pub use explore::{explore, Explore, ExploreSummary};
pub use import::{
    import, ImportOutcome, ImportParams, SweepFiles, MAX_INDEX_ROWS, MAX_POSES, SHOWN_PROBLEMS,
};
pub use map::{map, Map, MapSummary};
pub use model::{
    calibrate, check, holdout, posterior_csv, Calibrate, CalibrateSummary, Check, CheckSummary,
    Holdout, HoldoutSummary,
};
pub use zoo::{zoo, Zoo, ZooSummary};

use crate::campaign::manifest::Campaign;
use crate::error::Result;
use std::path::{Path, PathBuf};

pub use crate::progress::StepProgress;

/// The files a campaign's analysis reads: the manifest and its layout.
fn campaign_inputs(c: &Campaign) -> [(PathBuf, &'static str); 2] {
    [
        (c.path.clone(), "--campaign"),
        (c.layout_path(), "layout (of --campaign)"),
    ]
}

/// [`crate::io::refuse_overwrite`] over owned paths.
fn refuse(outputs: &[(PathBuf, &str)], inputs: &[(PathBuf, &str)]) -> Result<()> {
    let outs: Vec<(&Path, &str)> = outputs.iter().map(|(p, w)| (p.as_path(), *w)).collect();
    let ins: Vec<(&Path, &str)> = inputs.iter().map(|(p, w)| (p.as_path(), *w)).collect();
    crate::io::refuse_overwrite(&outs, &ins)
}

/// Load a manifest and apply an `--elements` override.
fn load_campaign(path: &Path, elements: Option<usize>) -> Result<Campaign> {
    let mut c = Campaign::load(path)?;
    if let Some(n) = elements {
        c.set_elements(n)?;
    }
    Ok(c)
}
