//! The `pradar` command line's clap definitions (binary-private: declared by `main.rs`,
//! not by the library).
//!
//! One `…Args` struct per subcommand; their flag names, defaults and help texts are the
//! command contract of DESIGN §3 and the README's "Commands". The enumerated flags
//! (`--format`, `--method`, `--criterion`, `--ekf`) parse straight into the library's enums
//! (`clap::ValueEnum` is derived there, with the flag spellings in `#[value(name)]`).
//! Numeric flags with a range are checked while parsing ([`ranges`]), so an out-of-range
//! value fails before any file is read, with a message naming the flag.

pub mod params;
pub mod ranges;

use clap::{Args, Parser, Subcommand};
use pradar::campaign::manifest::SweepFormat;
use pradar::cluster::Criterion;
use pradar::mapping::{EkfVariant, Method as MapMethod};
use pradar::mpc::Method as ExtractMethod;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "pradar",
    version,
    about = "mm-wave personal radar campaigns: simulate, energy matrices, channel statistics, maps"
)]
pub struct Cli {
    /// No progress bars (for scripts).
    #[arg(long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub cmd: Cmd,
}

#[derive(Subcommand)]
pub enum Cmd {
    /// Build and validate a manifest from a poses CSV and a folder of sweep files.
    Import(ImportArgs),
    /// Simulate a campaign: sweeps (Touchstone or Parquet), manifest with [sweeps], truth/.
    Simulate(SimulateArgs),
    /// Energy matrices from a campaign's sweeps.
    Energy(EnergyArgs),
    /// Statistical channel model: an energy table (and its truth) from a model file.
    Synth(SynthArgs),
    /// Occupancy-grid map from one run (--campaign + --energy) or several (--run, fused).
    Map(MapArgs),
    /// Extract MPCs (2-D CLEAN, or the local-maximum baseline) from an energy table.
    Extract(ExtractArgs),
    /// Cluster MPCs per position with K-means (writes <out> and <stem>_summary.parquet).
    Cluster(ClusterArgs),
    /// Fit the channel model (Table 1) from clustered MPCs.
    Fit(FitArgs),
    /// Calibrate the channel model without clustering (ABC-SMC, synth as the simulator).
    Calibrate(CalibrateArgs),
    /// Posterior-predictive check: does `synth` from a model give channels like the table's?
    Check(CheckArgs),
    /// The report of any campaign (measured or simulated): energy, MPCs, Table 1, check, maps.
    Report(ReportArgs),
    /// The main job: simulate the built-in corridor, compute energy matrices, write the report.
    Reproduce(ReproduceArgs),
    /// The paper's mapping experiments: fig5, fig6, prior-sensitivity, pose-noise (or all).
    Experiment(ExperimentArgs),
    /// Write the scene zoo: seeded physics scenes, each with a noise-only twin and a second
    /// realisation (campaign.toml + layout.geojson per folder; scripts/zoo runs the chain).
    Zoo(ZooArgs),
}

// `pradar zoo`
#[derive(Args)]
pub struct ZooArgs {
    /// Output folder: DIR/<name>/, DIR/<name>-twin/, DIR/<name>-r2/, DIR/scenes.tsv.
    #[arg(long)]
    pub out: PathBuf,
    /// Generator seed (same seed, same bytes).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of scenes (>= 1).
    #[arg(long, default_value_t = 20)]
    pub count: usize,
}

// `pradar import`
#[derive(Args)]
pub struct ImportArgs {
    /// Poses CSV: position (any label: 7, P01), x, y, heading (m, degrees); lab headers
    /// such as `Pos,X [m],Y [m],Heading [deg]` are read.
    #[arg(long)]
    pub poses: PathBuf,
    /// Sweep files: a glob, e.g. 'raw/*.s2p' (with --name-pattern).
    #[arg(
        long,
        requires = "name_pattern",
        conflicts_with = "index",
        required_unless_present = "index"
    )]
    pub sweeps: Option<String>,
    /// File-name pattern with {position} (a label of the poses), {direction} (index) or
    /// {angle} (signed degrees, e.g. {angle:+03}), and {pulse} ({direction:02}: fixed width).
    #[arg(long)]
    pub name_pattern: Option<String>,
    /// Index CSV: position, direction (index) or angle_deg, [pulse,] path (instead of
    /// --sweeps).
    #[arg(long)]
    pub index: Option<PathBuf>,
    /// Directions START:STOP:STEP, degrees (else the base's [directions]).
    #[arg(long, value_parser = ranges::directions, allow_hyphen_values = true)]
    pub directions: Option<pradar::campaign::manifest::Directions>,
    /// Layout GeoJSON (else the base's `layout`).
    #[arg(long)]
    pub layout: Option<PathBuf>,
    /// Base manifest fragment: name, seed, [array], [noise], [processing], [calibration],
    /// [sweeps] parameter.
    #[arg(long)]
    pub base: Option<PathBuf>,
    /// Campaign name (else the base's, else the output folder's name).
    #[arg(long)]
    pub name: Option<String>,
    /// [array] elements (16, 100, 400; else the base's).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Output manifest (campaign.toml).
    #[arg(long)]
    pub out: PathBuf,
    /// Also convert the sweeps to the Parquet sweep table (sweeps.parquet beside --out).
    #[arg(long)]
    pub to_parquet: bool,
    /// Go on without what is missing: a position without any sweep file is left out, a
    /// (position, direction) without a file is recorded as missing in the manifest
    /// (energy, extraction and maps skip it); one warning per item.
    #[arg(long)]
    pub allow_missing: bool,
}

// `pradar simulate`
#[derive(Args)]
pub struct SimulateArgs {
    /// Input manifest with [scene] (and optionally [clutter]).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Override [array] elements (16, 100, 400).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Sweep file format.
    #[arg(long, value_enum, default_value = "touchstone")]
    pub format: SweepFormat,
}

// `pradar energy`
#[derive(Args)]
pub struct EnergyArgs {
    /// Manifest with [sweeps].
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output energy Parquet.
    #[arg(long)]
    pub out: PathBuf,
}

// `pradar synth`
#[derive(Args)]
pub struct SynthArgs {
    /// Model file (fitted_model.toml or hand-written, DESIGN §3 "Model").
    #[arg(long)]
    pub model: PathBuf,
    /// Campaign manifest (layout, poses, directions, band, array, noise; no sweeps).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output energy Parquet.
    #[arg(long)]
    pub out: PathBuf,
    /// Override [array] elements (16, 100, 400).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Seed (default: the campaign's).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Ground-truth folder (default: <out stem>_truth beside the output).
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// A value for a model quantity, e.g. one the fit marked not estimable
    /// (`--set diffuse.decay=10`; names as in the model file; repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = ranges::name_value)]
    pub set: Vec<(String, f64)>,
}

// `pradar calibrate`
#[derive(Args)]
pub struct CalibrateArgs {
    /// Energy Parquet (from `energy` or `synth`).
    #[arg(long)]
    pub energy: PathBuf,
    /// Campaign manifest (layout, poses, directions, band, array, noise, processing).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output model file (the final population goes beside it, <stem>_posterior.csv).
    #[arg(long)]
    pub out: PathBuf,
    /// Prior file in the model schema: each free quantity's `interval` is its log-uniform
    /// prior range (default: the documented wide indoor ranges).
    #[arg(long)]
    pub prior: Option<PathBuf>,
    /// Without `--prior`: the default prior with the layout's parts free too (`[diffuse]`
    /// σ′ and Lambert n, `[walls]` |Γ|, corner and edge σ at their default ranges; 13
    /// free quantities, each simulation several times dearer).
    #[arg(long, conflicts_with = "prior")]
    pub walls: bool,
    /// Simulation budget (at least the population).
    #[arg(long, default_value_t = 3000, value_parser = ranges::simulations)]
    pub simulations: usize,
    /// Report folder: index.html with the marginal posteriors and their correlations, and
    /// the predictive checks (`pradar check`'s table and CDFs) of the calibrated model
    /// (plug-in, and posterior predictive as `check --posterior`) and of the `--chain`
    /// model.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// The cluster chain's model file (`fit --out`), shown beside the posterior in the
    /// report and flagged where outside the credible interval.
    #[arg(long, requires = "report")]
    pub chain: Option<PathBuf>,
    /// Population size per generation.
    #[arg(long, default_value_t = 400, value_parser = ranges::population)]
    pub population: usize,
    /// Seed (default: the campaign's).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// The ABC distance: `summaries-quantiles` (semi-automatic summaries of the 42 pooled
    /// statistics and the check statistics' quantiles, issue 30), `summaries` (the 42
    /// pooled statistics only, issue 19) or `mmd` (the MMD between the per-profile and
    /// per-position statistics' distributions, issue 30).
    #[arg(long, value_enum, default_value = "summaries-quantiles")]
    pub distance: pradar::calibrate::Distance,
    /// The summaries' projection's ridge penalty: `cv` (per parameter by 5-fold
    /// cross-validation over 1e-3·n … 1e3·n at every refit), `fixed` (1e-3·n, issue 19)
    /// or `cv-drop` (as `cv`, parameters whose held-out R² is ≤ 0 left out of the
    /// distance).
    #[arg(long, value_enum, default_value = "cv")]
    pub ridge: pradar::calibrate::Ridge,
}

// `pradar check`
#[derive(Args)]
pub struct CheckArgs {
    /// Model file (fitted, calibrated or hand-made).
    #[arg(long)]
    pub model: PathBuf,
    /// Campaign manifest (poses, directions, band, array, noise, processing, layout).
    #[arg(long)]
    pub campaign: PathBuf,
    /// The campaign's measured energy table (Parquet).
    #[arg(long)]
    pub energy: PathBuf,
    /// synth draws of the model.
    #[arg(long, default_value_t = 20, value_parser = ranges::draws)]
    pub draws: usize,
    /// Seed of the draws (default: the campaign's).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Output folder: check.csv, check.md, check_cdfs.png, index.html.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Exit 1 when the Bonferroni-corrected p-value is below P or a KS ratio is over 1.5.
    #[arg(long, value_name = "P", value_parser = ranges::probability)]
    pub fail_below: Option<f64>,
    /// `calibrate`'s posterior CSV (<stem>_posterior.csv): each draw's free quantities
    /// from a particle drawn by weight (the posterior predictive), the rest from --model.
    #[arg(long)]
    pub posterior: Option<PathBuf>,
}

// `pradar map`
#[derive(Args)]
pub struct MapArgs {
    /// Inverse sensor model.
    #[arg(long, value_enum, default_value = "og")]
    pub method: MapMethod,
    /// Campaign manifest of a single run (with --energy).
    #[arg(long, requires = "energy", conflicts_with = "run")]
    pub campaign: Option<PathBuf>,
    /// Energy Parquet of a single run (with --campaign).
    #[arg(long, requires = "campaign")]
    pub energy: Option<PathBuf>,
    /// A run `campaign.toml=energy.parquet` (repeatable: runs are fused).
    #[arg(long)]
    pub run: Vec<String>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Override [array] elements (16, 100, 400).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Cell side, m.
    #[arg(long, default_value_t = 0.1, value_parser = ranges::cell_m, allow_negative_numbers = true)]
    pub cell_m: f64,
    /// Detector false-alarm probability per bin.
    #[arg(long, default_value_t = 1e-3, value_parser = ranges::pfa, allow_negative_numbers = true)]
    pub pfa: f64,
    /// Prior occupancy probability.
    #[arg(long, default_value_t = 0.5, value_parser = ranges::open_unit, allow_negative_numbers = true)]
    pub prior: f64,
    /// Passes of the side-lobe-aware OG (`--method og`): pass 2 on uses the previous pass's
    /// map for the responsibilities and the mapped surfaces, 1..=10.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=10))]
    pub passes: u64,
    /// EKF implementation (`--method ekf`): dense (exact) or scalable (tiled).
    #[arg(
        long,
        value_enum,
        default_value = "scalable",
        hide_possible_values = true
    )]
    pub ekf: EkfVariant,
    /// EKF prior mean of the RRCS μ0, m.
    #[arg(long, default_value_t = 0.01, value_parser = ranges::positive, allow_negative_numbers = true)]
    pub mu0: f64,
    /// EKF prior standard deviation σ0, m.
    #[arg(long, default_value_t = 0.1, value_parser = ranges::positive, allow_negative_numbers = true)]
    pub sigma0: f64,
    /// EKF binary rule: occupied when x̂ − κ·σ̂ > μ0.
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().kappa, value_parser = ranges::non_negative, allow_negative_numbers = true)]
    pub kappa: f64,
    /// EKF free-space evidence (low-energy bins in front of an echo observed as RRCS ≈ 0).
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().free_space, action = clap::ArgAction::Set)]
    pub ekf_free_space: bool,
    /// EKF negative means: reflected (true) or clamped to the lowest mean (false).
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().reflect, action = clap::ArgAction::Set)]
    pub ekf_reflect: bool,
    /// OG (`--method og`): no free evidence at the range of a main-lobe echo before the
    /// beam's occluder.
    #[arg(long, default_value_t = pradar::mapping::OgParams::default().hold_echoes, action = clap::ArgAction::Set)]
    pub og_hold_echoes: bool,
    /// OG (`--method og`): where a beam's free evidence ends: at its occluder, its first
    /// echo not explained by a side lobe, or its first detection.
    #[arg(long, value_enum, default_value = "occluder")]
    pub og_free_end: pradar::mapping::og::FreeEnd,
    /// OG (`--method og`): weight in [0, 1] of the free evidence of a beam without an
    /// occluder (no detection not explained by a side lobe).
    #[arg(long, default_value_t = pradar::mapping::OgParams::default().free_without_occluder)]
    pub og_free_without_occluder: f64,
    /// OG (`--method og`): how a direction without an occluder bounds the visibility
    /// polygon: not at all (`off`, alias `false`), at its first detection (`leak`, alias
    /// `true`; interpolated from its neighbours without one), or at the nearer of that and
    /// the range interpolated from its neighbours' occluders (`nearer`).
    #[arg(long, value_enum, default_value = "nearer")]
    pub og_bound_silent: pradar::mapping::grid::SilentBound,
    /// OG (`--method og`): lowest log-odds free evidence can bring a cell to (the clamp,
    /// −10, by default: no floor).
    #[arg(long, default_value_t = pradar::mapping::OgParams::default().free_floor, allow_hyphen_values = true)]
    pub og_free_floor: f64,
    /// OG (`--method og`): occupancy credit of a range ring only to cells whose centre lies
    /// at most this far (m, >= 0) behind the visibility polygon (0.05 m: half a cell of
    /// the default 0.1 m grid); `guard`: every visible cell, to the occlusion guard.
    #[arg(long, default_value = "0.05", value_parser = ranges::credit_depth, allow_negative_numbers = true)]
    pub og_credit_depth: f64,
    /// Ghost rule of `og` and `ekf` once the map is built: mirror (each pose's evidence
    /// judged again against the final map's surfaces), aspect (occupancy needs support from
    /// poses spanning a minimum aspect) or none.
    #[arg(long, value_enum, default_value = "none", hide_possible_values = true)]
    pub ghost: pradar::mapping::grid::GhostRule,
    /// Minimum aspect of `--ghost aspect`, in two-way −3 dB main-lobe widths, [0, 36].
    #[arg(long, default_value_t = pradar::mapping::grid::GhostParams::default().aspect_lobes, value_parser = ranges::aspect_lobes, allow_negative_numbers = true)]
    pub ghost_aspect_lobes: f64,
    /// Scalable EKF: split each bin's information over the tiles it touches (false: the
    /// plain tiled update, overconfident).
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().split, action = clap::ArgAction::Set)]
    pub ekf_split: bool,
    /// EKF arc explanation γ in [0, 1]: a cell is occupied only if, on the range ring of some
    /// detected echo (main and side lobes), its share c̃·x̂² of the echo is at least γ times
    /// the ring's largest (0: off).
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().arc_explain, value_parser = ranges::probability)]
    pub ekf_arc_explain: f64,
    /// EKF arc explanation: distinct poses whose echoes a cell must explain to be occupied
    /// (1: one echo suffices; needs `--ekf-arc-explain` > 0).
    #[arg(long, default_value_t = pradar::mapping::EkfParams::default().explain_poses, value_parser = ranges::explain_poses)]
    pub ekf_explain_poses: u32,
    /// EKF: how a direction without an occluder bounds the visibility polygon of the
    /// filter's sight (as `--og-bound-silent`): `off`, `leak` or `nearer`.
    #[arg(long, value_enum, default_value = "off")]
    pub ekf_bound_silent: pradar::mapping::grid::SilentBound,
    /// Pose noise given to the mapper: position standard deviation per axis, m.
    #[arg(long, default_value_t = 0.0, value_parser = ranges::non_negative, allow_negative_numbers = true)]
    pub pose_noise_m: f64,
    /// Pose noise given to the mapper: heading standard deviation, degrees.
    #[arg(long, default_value_t = 0.0, value_parser = ranges::non_negative, allow_negative_numbers = true)]
    pub pose_noise_deg: f64,
    /// Seed of the pose-noise draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub pose_seed: u64,
}

// `pradar extract`
#[derive(Args)]
pub struct ExtractArgs {
    /// Energy Parquet.
    #[arg(long)]
    pub energy: PathBuf,
    /// The campaign the energy came from.
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output MPC Parquet.
    #[arg(long)]
    pub out: PathBuf,
    /// Method.
    #[arg(long, value_enum, default_value = "clean")]
    pub method: ExtractMethod,
    /// Keep components above the floor plus this margin, dB.
    #[arg(long, default_value_t = 13.0, value_parser = ranges::non_negative, allow_negative_numbers = true)]
    pub margin_db: f64,
    /// Stop at components this far below the position's strongest, dB.
    #[arg(
        long,
        default_value_t = pradar::mpc::ExtractParams::default().dynamic_range_db,
        value_parser = ranges::dynamic_range_db,
        allow_negative_numbers = true
    )]
    pub dynamic_range_db: f64,
    /// Do not label diffuse wall returns (every MPC discrete).
    #[arg(long)]
    pub no_diffuse: bool,
    /// An MPC on a wall's curve this far above the diffuse level is discrete, dB.
    #[arg(
        long,
        default_value_t = pradar::mpc::DiffuseParams::default().discrete_db,
        value_parser = ranges::non_negative,
        allow_negative_numbers = true
    )]
    pub diffuse_db: f64,
}

// `pradar cluster`
#[derive(Args)]
pub struct ClusterArgs {
    /// MPC Parquet from `extract`.
    #[arg(long)]
    pub mpcs: PathBuf,
    /// Output clustered MPC Parquet.
    #[arg(long)]
    pub out: PathBuf,
    /// Largest K tried per position.
    #[arg(long, default_value_t = pradar::cluster::ClusterParams::default().k_max, value_parser = ranges::k_max, allow_negative_numbers = true)]
    pub k_max: usize,
    /// Seed of the k-means++ draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// Criterion choosing K.
    #[arg(long, value_enum, default_value = "cv")]
    pub criterion: Criterion,
}

// `pradar fit`
#[derive(Args)]
pub struct FitArgs {
    /// Clustered MPC Parquet from `cluster`.
    #[arg(long)]
    pub clusters: PathBuf,
    /// The campaign (analysis view: [scene]/[clutter] are never read).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Output model file.
    #[arg(long)]
    pub out: PathBuf,
    /// Table 1 Markdown (a CSV is written beside it).
    #[arg(long)]
    pub table: PathBuf,
    /// Bootstrap resamples.
    #[arg(long, default_value_t = 1000, value_parser = ranges::bootstrap, allow_negative_numbers = true)]
    pub bootstrap: usize,
    /// Seed.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// A simulator's truth/ folder: add the same estimators on its true clusters.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// The campaign's energy table: read the model's levels from it (the walls' specular
    /// |Γ|, the diffuse σ′, the clusters' σ; see `model::levels`).
    #[arg(long)]
    pub energy: Option<PathBuf>,
}

// `pradar report`
#[derive(Args)]
pub struct ReportArgs {
    /// The campaign's manifest (measured: `pradar import`; or simulated).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Energy table of its sweeps (default: computed from them into OUT/work).
    #[arg(long)]
    pub energy: Option<PathBuf>,
    /// Report folder.
    #[arg(long, default_value = "reports/campaign")]
    pub out: PathBuf,
    /// Model for the check and the experiments (default: the one fitted from the campaign).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// A simulator's truth folder for Table 1's truth column (default: truth/ beside the
    /// manifest when it has one).
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Skip the mapping experiments.
    #[arg(long)]
    pub skip_experiments: bool,
    /// Model-data seeds of the experiments (comma-separated).
    #[arg(
        long,
        allow_negative_numbers = true,
        value_delimiter = ',',
        default_value = "1,2,3"
    )]
    pub seeds: Vec<u64>,
}

// `pradar reproduce`
#[derive(Args)]
pub struct ReproduceArgs {
    /// Report folder.
    #[arg(long, default_value = "reports/corridor")]
    pub out: PathBuf,
    /// Use this manifest instead of the built-in corridor.
    #[arg(long)]
    pub campaign: Option<PathBuf>,
    /// Override [array] elements.
    #[arg(long)]
    pub elements: Option<usize>,
    /// Skip the mapping experiments.
    #[arg(long)]
    pub skip_experiments: bool,
    /// Model-data seeds of the experiments (comma-separated).
    #[arg(
        long,
        allow_negative_numbers = true,
        value_delimiter = ',',
        default_value = "1,2,3"
    )]
    pub seeds: Vec<u64>,
}

// `pradar experiment`
#[derive(Args)]
pub struct ExperimentArgs {
    /// fig5 | fig6 | prior-sensitivity | pose-noise | all.
    pub name: String,
    /// Output folder (DIR/NAME/ per experiment, DIR/maps/, DIR/index.html).
    #[arg(long)]
    pub out: PathBuf,
    /// Campaign manifest (default: the built-in corridor, simulated).
    #[arg(long)]
    pub campaign: Option<PathBuf>,
    /// Energy table of the campaign's sweeps (default: computed, simulating if needed).
    #[arg(long)]
    pub energy: Option<PathBuf>,
    /// Model file for model data (default: fitted from the campaign's energy table).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Model-data seeds (comma-separated).
    #[arg(
        long,
        allow_negative_numbers = true,
        value_delimiter = ',',
        default_value = "1,2,3"
    )]
    pub seeds: Vec<u64>,
}
