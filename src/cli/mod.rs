//! The `pradar` command line's clap definitions (binary-private: declared by `main.rs`,
//! not by the library).
//!
//! One `…Args` struct per subcommand; their flag names, defaults and help texts are the
//! command contract of DESIGN §3 and the README's "Commands". The enumerated flags
//! (`--format`, `--method`, `--criterion`, `--ekf`, …) parse straight into the library's
//! enums, which know nothing of clap: [`choice`] lists their values by the enums' own
//! names (`ALL`, `name`, the `Display` a default is shown with).
//! Numeric flags with a range are checked while parsing ([`ranges`]), so an out-of-range
//! value fails before any file is read, with a message naming the flag.

pub mod choice;
pub mod params;
pub mod ranges;

use choice::choice;
use clap::{Args, Parser, Subcommand};
use pradar::calibrate::{CalibrateParams, Distance, Ridge};
use pradar::campaign::manifest::SweepFormat;
use pradar::check::{CheckParams, EstimatorKind};
use pradar::cluster::{ClusterParams, Criterion};
use pradar::explore::ExploreParams;
use pradar::fit::channel::FitParams;
use pradar::mapping::grid::SilentBound;
use pradar::mapping::job::{OdometryNoise, PoseNoise, PosesFrom};
use pradar::mapping::og::OgCredit;
use pradar::mapping::{
    EkfParams, EkfUpdate, EkfVariant, GridParams, Method as MapMethod, OgParams,
};
use pradar::mpc::{DiffuseParams, ExtractParams, Method as ExtractMethod};
use pradar::pipeline::experiment::{ExperimentParams, Fig6Data};
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
    /// The mapping experiments: fig5, fig6, prior-sensitivity, pose-noise (or all), slam.
    Experiment(ExperimentArgs),
    /// Design space: map quality, energy per scan and scan time over N, pulses, step,
    /// bandwidth and transmit power.
    Explore(ExploreArgs),
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
    #[arg(long, default_value_t = SweepFormat::default(), value_parser = choice(&SweepFormat::ALL, SweepFormat::name))]
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
    /// prior range (default: every quantity of the model free at the documented wide
    /// indoor ranges, the layout's `[diffuse]` and `[walls]` included; 13 quantities).
    #[arg(long)]
    pub prior: Option<PathBuf>,
    /// Without `--prior`: free the clusters' eight quantities only, no `[diffuse]` or
    /// `[walls]` (for a table drawn from a model without them; each simulation cheaper).
    #[arg(long, conflicts_with = "prior")]
    pub no_walls: bool,
    /// Simulation budget (at least the population).
    #[arg(long, default_value_t = CalibrateParams::default().simulations, value_parser = ranges::simulations)]
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
    #[arg(long, default_value_t = CalibrateParams::default().population, value_parser = ranges::population)]
    pub population: usize,
    /// Seed (default: the campaign's).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// The ABC distance (docs/cli.md).
    #[arg(long, default_value_t = CalibrateParams::default().distance, value_parser = choice(&Distance::ALL, Distance::name))]
    pub distance: Distance,
    /// The summaries' projection's ridge penalty (docs/cli.md).
    #[arg(long, default_value_t = CalibrateParams::default().ridge, value_parser = choice(&Ridge::ALL, Ridge::name))]
    pub ridge: Ridge,
}

// `pradar check`
#[derive(Args)]
pub struct CheckArgs {
    /// Model file (fitted, calibrated or hand-made).
    #[arg(long, required_unless_present = "holdout", conflicts_with = "holdout")]
    pub model: Option<PathBuf>,
    /// Instead of --model: fit a model on each half of the walk, check it on the other half.
    #[arg(long)]
    pub holdout: bool,
    /// Campaign manifest (poses, directions, band, array, noise, processing, layout).
    #[arg(long)]
    pub campaign: PathBuf,
    /// The campaign's measured energy table (Parquet).
    #[arg(long)]
    pub energy: PathBuf,
    /// synth draws of the model.
    #[arg(long, default_value_t = CheckParams::default().draws, value_parser = ranges::draws)]
    pub draws: usize,
    /// Seed of the draws (default: the campaign's).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Output folder: check.csv, check.md, check_cdfs.png, index.html.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Exit 1 when the check's max-T p-value is at or below P (the rule: 0.05) or the
    /// measured noise floor is more than 1 dB from the draws'.
    #[arg(long, value_name = "P", value_parser = ranges::probability)]
    pub fail_below: Option<f64>,
    /// `calibrate`'s posterior CSV (<stem>_posterior.csv): each draw's free quantities
    /// from a particle drawn by weight (the posterior predictive), the rest from --model.
    #[arg(long, conflicts_with = "holdout")]
    pub posterior: Option<PathBuf>,
    /// With --holdout: each half's model by chain (default), smm or calibrate (docs/cli.md).
    #[arg(long, conflicts_with = "model", value_parser = choice(&EstimatorKind::ALL, EstimatorKind::name))]
    pub estimator: Option<EstimatorKind>,
}

// `pradar map`
#[derive(Args)]
pub struct MapArgs {
    /// Mapper: og, og-boresight or ekf.
    #[arg(long, default_value_t = MapMethod::default(), value_parser = choice(&MapMethod::ALL, MapMethod::name), hide_possible_values = true, help_heading = "Input")]
    pub method: MapMethod,
    /// Campaign manifest of a single run (with --energy).
    #[arg(
        long,
        requires = "energy",
        conflicts_with = "run",
        help_heading = "Input"
    )]
    pub campaign: Option<PathBuf>,
    /// Energy Parquet of a single run (with --campaign).
    #[arg(long, requires = "campaign", help_heading = "Input")]
    pub energy: Option<PathBuf>,
    /// A run `campaign.toml=energy.parquet` (repeatable: runs are fused).
    #[arg(long, help_heading = "Input")]
    pub run: Vec<String>,
    /// Output folder.
    #[arg(long, help_heading = "Input")]
    pub out: PathBuf,
    /// Override [array] elements (16, 100, 400).
    #[arg(long, help_heading = "Input")]
    pub elements: Option<usize>,
    /// Cell side, m.
    #[arg(long, default_value_t = GridParams::default().cell_m, value_parser = ranges::cell_m, allow_negative_numbers = true, help_heading = "Input")]
    pub cell_m: f64,
    /// Detector false-alarm probability per bin.
    #[arg(long, default_value_t = OgParams::default().pfa, value_parser = ranges::pfa, allow_negative_numbers = true, help_heading = "Occupancy grid (og, og-boresight)")]
    pub pfa: f64,
    /// Prior occupancy probability.
    #[arg(long, default_value_t = OgParams::default().prior, value_parser = ranges::open_unit, allow_negative_numbers = true, help_heading = "Occupancy grid (og, og-boresight)")]
    pub prior: f64,
    /// Where a direction without an occluder bounds the visibility polygon: off, leak or nearer.
    // `false` and `true`, the values of the flag when it was a switch, stay `off` and `leak`
    #[arg(long, default_value_t = OgParams::default().bound_silent, value_parser = choice(&SilentBound::ALL, SilentBound::name).alias("off", "false").alias("leak", "true"), hide_possible_values = true, help_heading = "Occupancy grid (og, og-boresight)")]
    pub og_bound_silent: SilentBound,
    /// Deepest behind the visibility polygon a cell gets occupancy credit, m, or `guard`.
    #[arg(long, default_value_t = credit_depth_default(), value_parser = ranges::credit_depth, allow_negative_numbers = true, help_heading = "Occupancy grid (og, og-boresight)")]
    pub og_credit_depth: f64,
    /// Occupancy credit of a detection: ring (its range ring) or echo (only its echo's
    /// bearing: fewer false cells, fewer walls found).
    #[arg(long, default_value_t = OgParams::default().credit, value_parser = choice(&OgCredit::ALL, OgCredit::name), hide_possible_values = true, help_heading = "Occupancy grid (og, og-boresight)")]
    pub og_credit: OgCredit,
    /// EKF implementation: dense (exact) or scalable (tiled).
    #[arg(long, default_value_t = EkfParams::default().variant, value_parser = choice(&EkfVariant::ALL, EkfVariant::name), hide_possible_values = true, help_heading = "EKF (ekf)")]
    pub ekf: EkfVariant,
    /// EKF linearisation of the energy rows: first-order or second-order (a consistent
    /// confidence, NEES ≈ 2 against ≈ 97, for about half the walls found).
    #[arg(long, default_value_t = EkfParams::default().update, value_parser = choice(&EkfUpdate::ALL, EkfUpdate::name), hide_possible_values = true, help_heading = "EKF (ekf)")]
    pub ekf_update: EkfUpdate,
    /// Prior mean of the RRCS μ0, m.
    #[arg(long, default_value_t = EkfParams::default().mu0, value_parser = ranges::positive, allow_negative_numbers = true, help_heading = "EKF (ekf)")]
    pub mu0: f64,
    /// Prior standard deviation σ0, m.
    #[arg(long, default_value_t = EkfParams::default().sigma0, value_parser = ranges::positive, allow_negative_numbers = true, help_heading = "EKF (ekf)")]
    pub sigma0: f64,
    /// Binary rule: occupied when x̂ − κ·σ̂ > μ0.
    #[arg(long, default_value_t = EkfParams::default().kappa, value_parser = ranges::non_negative, allow_negative_numbers = true, help_heading = "EKF (ekf)")]
    pub kappa: f64,
    /// Arc explanation γ in [0, 1] (0: off).
    #[arg(long, default_value_t = EkfParams::default().arc_explain, value_parser = ranges::probability, help_heading = "EKF (ekf)")]
    pub ekf_arc_explain: f64,
    /// Position standard deviation per axis given to the mapper, m.
    #[arg(long, default_value_t = PoseNoise::default().position_m, value_parser = ranges::non_negative, allow_negative_numbers = true, help_heading = "Pose noise")]
    pub pose_noise_m: f64,
    /// Heading standard deviation given to the mapper, degrees.
    #[arg(long, default_value_t = PoseNoise::default().heading_deg, value_parser = ranges::non_negative, allow_negative_numbers = true, help_heading = "Pose noise")]
    pub pose_noise_deg: f64,
    /// Seed of the pose-noise and odometry draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = PoseNoise::DEFAULT_SEED, help_heading = "Pose noise")]
    pub pose_seed: u64,
    /// The mapper's poses: manifest, odometry (the dead reckoning of steps drawn from the
    /// manifest's with --odometry-*) or sweeps (those steps and the scans; poses.csv).
    #[arg(long, default_value_t = PosesFrom::default(), value_parser = choice(&PosesFrom::ALL, PosesFrom::name), hide_possible_values = true, help_heading = "Pose noise")]
    pub poses_from: PosesFrom,
    /// Odometry σ of x and y per step, m (seed --pose-seed).
    #[arg(long, default_value_t = OdometryNoise::default().step_m, value_parser = ranges::positive, allow_negative_numbers = true, help_heading = "Pose noise")]
    pub odometry_m: f64,
    /// Odometry σ of the heading per step, degrees.
    #[arg(long, default_value_t = OdometryNoise::default().step_deg, value_parser = ranges::positive, allow_negative_numbers = true, help_heading = "Pose noise")]
    pub odometry_deg: f64,
}

/// `--og-credit-depth`'s default: the library's depth (`guard`, infinity, when it has none).
fn credit_depth_default() -> f64 {
    OgParams::default().credit_depth_m.unwrap_or(f64::INFINITY)
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
    #[arg(long, default_value_t = ExtractParams::default().method, value_parser = choice(&ExtractMethod::ALL, ExtractMethod::name))]
    pub method: ExtractMethod,
    /// Keep components above the floor plus this margin, dB.
    #[arg(long, default_value_t = ExtractParams::default().margin_db, value_parser = ranges::non_negative, allow_negative_numbers = true)]
    pub margin_db: f64,
    /// Stop at components this far below the position's strongest, dB.
    #[arg(
        long,
        default_value_t = ExtractParams::default().dynamic_range_db,
        value_parser = ranges::dynamic_range_db,
        allow_negative_numbers = true
    )]
    pub dynamic_range_db: f64,
    /// Do not label diffuse wall returns (every MPC discrete, but the folded wall echoes).
    #[arg(long)]
    pub no_diffuse: bool,
    /// An MPC on a wall's curve this far above the diffuse level is discrete, dB.
    #[arg(
        long,
        default_value_t = DiffuseParams::default().discrete_db,
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
    #[arg(long, default_value_t = ClusterParams::default().k_max, value_parser = ranges::k_max, allow_negative_numbers = true)]
    pub k_max: usize,
    /// Seed of the k-means++ draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = ClusterParams::default().seed)]
    pub seed: u64,
    /// Criterion choosing K.
    #[arg(long, default_value_t = ClusterParams::default().criterion, value_parser = choice(&Criterion::ALL, Criterion::name))]
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
    #[arg(long, default_value_t = FitParams::default().bootstrap, value_parser = ranges::bootstrap, allow_negative_numbers = true)]
    pub bootstrap: usize,
    /// Seed.
    #[arg(long, allow_negative_numbers = true, default_value_t = FitParams::default().seed)]
    pub seed: u64,
    /// A simulator's truth/ folder: add the same estimators on its true clusters.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// The campaign's energy table: read the model's levels from it (the walls' specular
    /// |Γ|, the diffuse σ′, the clusters' σ; see `model::levels`). Default: the table the
    /// clusters file names (written by `extract`, passed on by `cluster`); without either
    /// `fit` refuses.
    #[arg(long)]
    pub energy: Option<PathBuf>,
    /// Table 1's "identifiable from this campaign" column: the default chain on R tables
    /// drawn from the written model over these poses, seeded by the manifest's seed
    /// (about a chain's time each; `report` runs 6). 0: not run.
    #[arg(long, value_name = "R", default_value_t = 0, value_parser = ranges::closed_loop_draws)]
    pub closed_loop: usize,
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
    #[arg(long, default_value = pradar::pipeline::DEFAULT_REPORT_OUT)]
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
    /// A `pradar explore` folder to show as a section (its files copied into OUT/explore/).
    #[arg(long)]
    pub explore: Option<PathBuf>,
    #[command(flatten)]
    pub seeds: SeedsArg,
}

// `pradar reproduce`
#[derive(Args)]
pub struct ReproduceArgs {
    /// Report folder.
    #[arg(long, default_value = pradar::pipeline::DEFAULT_REPRODUCE_OUT)]
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
    #[command(flatten)]
    pub seeds: SeedsArg,
}

// `pradar experiment`
#[derive(Args)]
pub struct ExperimentArgs {
    /// fig5 | fig6 | prior-sensitivity | pose-noise | all (those four) | slam.
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
    /// fig6's data per seed: model (synth of the model file) or physics (the campaign's
    /// [scene] simulated at each N and seed).
    #[arg(
        long,
        default_value_t = ExperimentParams::default().fig6_data,
        value_parser = choice(&Fig6Data::ALL, Fig6Data::name),
        hide_possible_values = true
    )]
    pub data: Fig6Data,
    #[command(flatten)]
    pub seeds: SeedsArg,
}

// `pradar explore`
#[derive(Args)]
pub struct ExploreArgs {
    /// Output folder: explore.csv|.md, summary.csv|.md, pareto_*.png, heatmap_*.png,
    /// index.html.
    #[arg(long)]
    pub out: PathBuf,
    /// Campaign manifest (default: the built-in corridor).
    #[arg(long)]
    pub campaign: Option<PathBuf>,
    /// Elements per array (perfect squares).
    #[arg(long, value_delimiter = ',', default_values_t = ExploreParams::default().elements)]
    pub elements: Vec<usize>,
    /// Pulses per direction.
    #[arg(long, value_delimiter = ',', default_values_t = ExploreParams::default().pulses)]
    pub pulses: Vec<usize>,
    /// Angular steps, degrees (each must divide the campaign's sector).
    #[arg(long, value_delimiter = ',', default_values_t = ExploreParams::default().step_deg)]
    pub step_deg: Vec<f64>,
    /// Bandwidths, GHz (default: the campaign's; centre and frequency step kept).
    #[arg(long, value_delimiter = ',')]
    pub bandwidth_ghz: Vec<f64>,
    /// Transmit powers, dBm (default: the campaign's [noise] tx_power_dbm).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub tx_power_dbm: Vec<f64>,
    /// Mappers: og, ekf (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "og",
        value_parser = choice(&MapMethod::ALL, MapMethod::name),
        hide_possible_values = true
    )]
    pub mapper: Vec<MapMethod>,
    /// Seeds (each draws a new scene and noise).
    #[arg(long, value_delimiter = ',', default_values_t = ExploreParams::default().seeds)]
    pub seeds: Vec<u64>,
    /// Data: sweeps (physics, the campaign's [scene]) or model (synth of --model).
    #[arg(
        long,
        value_enum,
        default_value = "sweeps",
        hide_possible_values = true
    )]
    pub data: ExploreData,
    /// Model file (--data model; given alone it means model data).
    #[arg(long, required_if_eq("data", "model"))]
    pub model: Option<PathBuf>,
    /// Energy-model constants (TOML; defaults in docs/explore.md).
    #[arg(long)]
    pub energy_model: Option<PathBuf>,
    /// Refuse a grid estimated (from a timed probe job) above this many minutes.
    #[arg(long, default_value_t = ExploreParams::default().max_minutes)]
    pub max_minutes: f64,
    /// Keep every job's data and maps in DIR/work/.
    #[arg(long)]
    pub keep_work: bool,
}

/// `explore --data`.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ExploreData {
    /// Physics simulator.
    Sweeps,
    /// synth of --model.
    Model,
}

/// `--seeds`, shared by `report`, `reproduce` and `experiment`.
#[derive(Args)]
pub struct SeedsArg {
    /// Seeds of the experiments' model data, of fig6's physics sweeps and of slam's odometry (comma-separated).
    #[arg(
        long = "seeds",
        allow_negative_numbers = true,
        value_delimiter = ',',
        default_values_t = ExperimentParams::default().seeds
    )]
    pub seeds: Vec<u64>,
}
