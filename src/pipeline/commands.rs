//! One library entry per `pradar` subcommand, so the binary only parses arguments.
//!
//! Each subcommand's arguments arrive as one plain struct ([`Simulate`], [`Energy`],
//! [`Synth`], [`Map`], [`Extract`], [`Cluster`], [`Fit`], [`Experiments`]) holding paths and
//! the stage's own parameter struct; the function of the same name in lower case loads the
//! inputs, runs the stage, writes its outputs (DESIGN §3) and returns a summary whose
//! `Display` is the line(s) the command prints on success. `reproduce` needs no entry here:
//! [`crate::pipeline::reproduce`] is already one call.
//!
//! What lives here rather than in the binary is the glue the stages do not own: applying
//! `--elements` after loading a manifest, gathering `--run` specifications, recovering the
//! pose headings of an MPC table ([`pose_headings`]), reading the scanned sector from the
//! MPC table's metadata, the K = K_max warning, writing the model file beside Table 1 and
//! resolving `all` into the list of experiments.
//!
//! Every command first refuses to write over one of its own inputs
//! ([`crate::io::refuse_overwrite`]: `energy --out` naming the manifest, a sweep file or
//! a `[calibration]` file,
//! `extract`/`cluster`/`fit` naming their input table, `fit --out x --table x`, `simulate`
//! or `synth` writing into the folder of the manifest or the model file they read). `fit`
//! writes Table 1 first and the model file last, so a failed table leaves no model.
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
//!     options: pradar::mapping::MapOptions {
//!         method: pradar::mapping::Method::Og,
//!         runs: vec![],
//!         out: "map".into(),
//!         elements: None,
//!         grid: Default::default(),
//!         og: Default::default(),
//!         ekf: Default::default(),
//!         pose_noise: Default::default(),
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

use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::campaign::modelfile::ModelConfig;
use crate::campaign::simulate::SimReport;
use crate::cluster::ClusterParams;
use crate::energy::{EnergyReport, EnergySource, EnergyTable};
use crate::error::Result;
use crate::fit::channel::{ChannelFit, FitParams};
use crate::mapping::{MapOptions, MapReport, MapRun};
use crate::model::{SynthParams, SynthReport};
use crate::mpc::{ExtractParams, Mpc};
use crate::params::ParamGuard;
use crate::pipeline::experiment::{
    run_experiments, Experiment, ExperimentParams, ExperimentResult, InputOptions,
};
use crate::pipeline::Progress;
use std::fmt;
use std::path::{Path, PathBuf};

/// Progress of a single-stage command: called with (done, total) after each step.
pub type StepProgress<'a> = &'a (dyn Fn(usize, usize) + Sync);

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

/// Run `pradar simulate` ([`crate::campaign::simulate::simulate`]).
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
    let r = crate::campaign::simulate::simulate(&c, &cmd.out, cmd.format, progress)?;
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

impl fmt::Display for MapSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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

/// Run `pradar map` ([`crate::mapping::run_map`]); `progress` counts poses over all runs.
pub fn map(cmd: &Map, progress: StepProgress) -> Result<MapSummary> {
    let mut opts = cmd.options.clone();
    for r in &cmd.run_specs {
        opts.runs.push(MapRun::parse(r)?);
    }
    let report = crate::mapping::run_map(&opts.check()?, progress)?;
    Ok(MapSummary {
        report,
        out: opts.out,
    })
}

/// `pradar extract`: MPCs of an energy table.
#[derive(Debug, Clone)]
pub struct Extract {
    /// Energy Parquet.
    pub energy: PathBuf,
    /// The campaign the energy came from.
    pub campaign: PathBuf,
    /// Output MPC Parquet.
    pub out: PathBuf,
    /// Method, margin and dynamic range.
    pub params: ExtractParams,
}

/// What `extract` wrote.
#[derive(Debug, Clone)]
pub struct ExtractSummary {
    /// MPCs written.
    pub mpcs: usize,
    /// Of which diffuse.
    pub diffuse: usize,
    /// Positions of the energy table.
    pub positions: usize,
    /// The MPC Parquet written.
    pub out: PathBuf,
}

impl fmt::Display for ExtractSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} MPCs ({} diffuse) from {} positions -> {}",
            self.mpcs,
            self.diffuse,
            self.positions,
            self.out.display()
        )
    }
}

/// Run `pradar extract` ([`crate::mpc::extract`]), writing the table with its metadata.
pub fn extract(cmd: &Extract) -> Result<ExtractSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.energy.clone(), "--energy"));
    refuse(&[(cmd.out.clone(), "--out")], &inputs)?;
    // read a few positions at a time: memory does not grow with the number of poses
    let table = EnergyTable::open(&cmd.energy)?;
    let em = table.header();
    // checked here, where the energy file's name is known, so a mismatch names it
    crate::energy::check_campaign(&c, em, &cmd.energy)?;
    em.meta.check_noise(&cmd.energy)?;
    let (mpcs, diffuse) = crate::mpc::extract_labelled(&table, &c, &cmd.params.check()?)?;
    let mut meta = crate::mpc::table_metadata(em, &c, &cmd.params);
    meta.push((
        "diffuse_level_m2_per_m".into(),
        format!("{:.17e}", diffuse.level_m2_per_m),
    ));
    crate::mpc::write_mpcs(&cmd.out, &mpcs, meta)?;
    Ok(ExtractSummary {
        mpcs: mpcs.len(),
        diffuse: diffuse.diffuse,
        positions: em.positions,
        out: cmd.out.clone(),
    })
}

/// `pradar cluster`: K-means clusters of an MPC table, per position.
#[derive(Debug, Clone)]
pub struct Cluster {
    /// MPC Parquet from `extract`.
    pub mpcs: PathBuf,
    /// Output clustered MPC Parquet (the summary goes to `<stem>_summary.parquet`).
    pub out: PathBuf,
    /// K_max, seed and criterion; the sector is read from the MPC table (180° when absent).
    pub params: ClusterParams,
}

/// What `cluster` wrote.
#[derive(Debug, Clone)]
pub struct ClusterSummary {
    /// Clusters over the campaign.
    pub clusters: usize,
    /// Positions.
    pub positions: usize,
    /// The clustered MPC Parquet.
    pub out: PathBuf,
    /// The cluster summary Parquet.
    pub summary: PathBuf,
    /// The K_max used.
    pub k_max: usize,
    /// Positions whose K is the cap while the criterion still preferred more.
    pub capped: Vec<usize>,
}

impl ClusterSummary {
    /// The K = K_max warning, when some position hit the cap.
    pub fn warning(&self) -> Option<String> {
        (!self.capped.is_empty()).then(|| {
            format!(
                "K = K_max = {} at {} of {} positions (the criterion still preferred more clusters there; the counts are set by --k-max)",
                self.k_max,
                self.capped.len(),
                self.positions
            )
        })
    }
}

impl fmt::Display for ClusterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} clusters over {} positions -> {} and {}",
            self.clusters,
            self.positions,
            self.out.display(),
            self.summary.display()
        )
    }
}

/// The pose heading of every position of an MPC table, degrees: global − relative angle
/// of the position's first MPC (0 for a position without MPCs; not wrapped). An MPC table
/// carries no poses, and every MPC of a position shares its pose's heading.
pub fn pose_headings(mpcs: &[Mpc]) -> Vec<f64> {
    let np = mpcs.iter().map(|x| x.position + 1).max().unwrap_or(0);
    let mut headings: Vec<Option<f64>> = vec![None; np];
    for x in mpcs {
        headings[x.position].get_or_insert(x.angle_global_deg - x.angle_rel_deg);
    }
    headings.into_iter().map(|h| h.unwrap_or(0.0)).collect()
}

/// Run `pradar cluster` ([`crate::cluster::cluster`]) and write both tables.
pub fn cluster(cmd: &Cluster) -> Result<ClusterSummary> {
    refuse(
        &[
            (cmd.out.clone(), "--out"),
            (
                crate::cluster::summary_path(&cmd.out),
                "--out (its summary)",
            ),
        ],
        &[(cmd.mpcs.clone(), "--mpcs")],
    )?;
    let m = crate::mpc::read_mpcs(&cmd.mpcs)?;
    let sector = crate::mpc::read_sector_deg(&cmd.mpcs)?.unwrap_or(180.0);
    let params = cmd.params.sector_deg(sector);
    let c = crate::cluster::cluster(&m, &pose_headings(&m), &params.check()?)?;
    let summary = crate::cluster::write(&cmd.out, &c)?;
    Ok(ClusterSummary {
        clusters: c.summary.len(),
        positions: c.positions.len(),
        out: cmd.out.clone(),
        summary,
        k_max: params.k_max,
        capped: c.positions_at_k_max(params.k_max),
    })
}

/// `pradar fit`: the channel model (Table 1) of clustered MPCs.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Clustered MPC Parquet from `cluster`.
    pub clusters: PathBuf,
    /// The campaign (analysis view: `[scene]`/`[clutter]` are never read).
    pub campaign: PathBuf,
    /// Output model file.
    pub out: PathBuf,
    /// Table 1 Markdown (a CSV is written beside it).
    pub table: PathBuf,
    /// A simulator's `truth/` folder: the same estimators on its true clusters.
    pub truth: Option<PathBuf>,
    /// The campaign's energy table: the model's levels (`[walls]`, σ′, σ) are then read
    /// from it ([`crate::model::levels`]); without it they are the cluster chain's.
    pub energy: Option<PathBuf>,
    /// Bootstrap resamples and seed.
    pub params: FitParams,
}

/// The fits `fit` wrote.
#[derive(Debug, Clone)]
pub struct FitSummary {
    /// The fit of the clustered MPCs.
    pub fit: ChannelFit,
    /// The same estimators on the simulator's truth, when given.
    pub truth: Option<ChannelFit>,
}

impl FitSummary {
    /// One line per quantity of the fit that is not estimable (the command line prints each
    /// after `warning: `): "`<quantity>` not estimable: `<reason>`".
    pub fn warnings(&self) -> Vec<String> {
        (self.fit.model.not_estimable().into_iter())
            .map(|(q, r)| format!("{q} not estimable: {r}"))
            .collect()
    }
}

impl fmt::Display for FitSummary {
    /// One line per Table 1 row: parameter, value, interval, truth.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rows = crate::fit::table1::rows(&self.fit, self.truth.as_ref());
        for (i, r) in rows.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(
                f,
                "{:<38} {:<60} {:<20} truth {}",
                r.parameter,
                r.value_shown,
                r.interval_shown(),
                r.truth_shown()
            )?;
        }
        Ok(())
    }
}

/// Run `pradar fit` ([`crate::fit::channel::fit_channel`], and
/// [`crate::fit::channel::fit_truth`] with a truth folder); writes the model file and
/// Table 1. A partial fit is written with its not-estimable quantities marked
/// ([`FitSummary::warnings`] lists them); a fit where no quantity can be estimated is an
/// error and writes nothing.
pub fn fit(cmd: &Fit) -> Result<FitSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.clusters.clone(), "--clusters"));
    if let Some(dir) = &cmd.truth {
        inputs.push((dir.join("rays.parquet"), "--truth"));
    }
    if let Some(e) = &cmd.energy {
        inputs.push((e.clone(), "--energy"));
    }
    refuse(
        &[
            (cmd.table.clone(), "--table"),
            (cmd.table.with_extension("csv"), "--table (its CSV)"),
            (cmd.out.clone(), "--out"),
        ],
        &inputs,
    )?;
    let params = cmd.params.check()?;
    let mut fit = crate::fit::channel::fit_channel(&cmd.clusters, &c, &params)?;
    if let Some(e) = &cmd.energy {
        let em = crate::energy::EnergyMatrix::read(e)?;
        crate::energy::matrix::check_campaign(&c, &em, e)?;
        fit.model = crate::model::levels::fit_levels(&c, &em, &fit.model)?.0;
    }
    let truth = match &cmd.truth {
        Some(dir) => Some(crate::fit::channel::fit_truth(dir, &c, &params)?),
        None => None,
    };
    // the table first, the model last: a model file on disk means the run completed
    crate::fit::channel::write_table1(&cmd.table, &c.manifest.name, &fit, truth.as_ref())?;
    fit.model.save(&cmd.out)?;
    Ok(FitSummary { fit, truth })
}

/// `pradar calibrate`: the channel model fitted without clustering (ABC-SMC with `synth`
/// as the simulator, [`crate::calibrate`]).
#[derive(Debug, Clone)]
pub struct Calibrate {
    /// Energy Parquet (measured or synthesised).
    pub energy: PathBuf,
    /// The campaign (analysis view: `[scene]`/`[clutter]` are never read).
    pub campaign: PathBuf,
    /// Output model file; the final population is written beside it as
    /// `<stem>_posterior.csv`.
    pub out: PathBuf,
    /// Prior file (model schema; default: [`crate::calibrate::DEFAULT_PRIOR`]).
    pub prior: Option<PathBuf>,
    /// Budget, population, seed.
    pub params: crate::calibrate::CalibrateParams,
    /// Report folder (`index.html` with the marginal posteriors and correlations).
    pub report: Option<PathBuf>,
    /// The cluster chain's model file (`fit` output), shown beside the posterior in the
    /// report.
    pub chain: Option<PathBuf>,
}

/// What `calibrate` wrote.
#[derive(Debug, Clone)]
pub struct CalibrateSummary {
    /// The calibration.
    pub calibration: crate::calibrate::Calibration,
    /// The model file written.
    pub out: PathBuf,
    /// The posterior CSV written.
    pub posterior: PathBuf,
}

impl fmt::Display for CalibrateSummary {
    /// One line per free quantity (median and 95 % credible interval), then the run.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.calibration;
        for name in &c.free {
            let q = c.model.quantity(name).expect("a free quantity exists");
            let [lo, hi] = q.interval.unwrap_or([f64::NAN; 2]);
            writeln!(
                f,
                "{name:<26} {:>10.4} {:<5} 95 % [{lo:.4}, {hi:.4}]",
                q.value, q.unit
            )?;
        }
        let p = &c.posterior;
        write!(
            f,
            "calibrated with {} simulations in {} generations ({:.1} s, {:.1} simulations/s, final ε {:.3}, acceptance {:.3}) -> {} (posterior in {})",
            p.simulations,
            p.generations,
            c.wall_s,
            p.simulations as f64 / c.wall_s.max(1e-9),
            p.epsilon,
            p.acceptance,
            self.out.display(),
            self.posterior.display()
        )
    }
}

/// The posterior CSV beside a calibrated model file: `<stem>_posterior.csv`.
pub fn posterior_csv(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "calibrated".into());
    out.with_file_name(format!("{stem}_posterior.csv"))
}

/// Run `pradar calibrate` ([`crate::calibrate::calibrate()`]).
pub fn calibrate(cmd: &Calibrate, progress: StepProgress) -> Result<CalibrateSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let posterior = posterior_csv(&cmd.out);
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.energy.clone(), "--energy"));
    if let Some(p) = &cmd.prior {
        inputs.push((p.clone(), "--prior"));
    }
    if let Some(p) = &cmd.chain {
        inputs.push((p.clone(), "--chain"));
    }
    let mut outputs = vec![
        (cmd.out.clone(), "--out"),
        (posterior.clone(), "--out (its posterior CSV)"),
    ];
    if let Some(r) = &cmd.report {
        outputs.push((r.join("index.html"), "--report"));
        outputs.push((r.join("posterior.png"), "--report"));
    }
    refuse(&outputs, &inputs)?;
    let chain = match &cmd.chain {
        Some(p) => Some(ModelConfig::load(p)?),
        None => None,
    };
    let params = cmd.params.check()?;
    let prior = match &cmd.prior {
        Some(p) => crate::calibrate::Prior::load(p)?,
        None => crate::calibrate::Prior::default_prior(),
    };
    let em = crate::energy::EnergyMatrix::read(&cmd.energy)?;
    let calibration = crate::calibrate::calibrate(&c, &em, &cmd.energy, &prior, &params, progress)?;
    calibration.write_posterior_csv(&posterior)?;
    if let Some(r) = &cmd.report {
        std::fs::create_dir_all(r).map_err(|e| crate::error::Error::io(r, e))?;
        let sec =
            crate::report::calibrate::section(r, "posterior.png", &calibration, chain.as_ref())?;
        crate::report::write_index(&r.join("index.html"), "pradar calibrate", &[sec])?;
    }
    calibration.model.save(&cmd.out)?;
    Ok(CalibrateSummary {
        calibration,
        out: cmd.out.clone(),
        posterior,
    })
}

/// `pradar check`: the posterior-predictive check of a model against an energy table.
#[derive(Debug, Clone)]
pub struct Check {
    /// Model file (fitted, calibrated or hand-made).
    pub model: PathBuf,
    /// Campaign manifest (poses, directions, band, array, noise, processing, layout).
    pub campaign: PathBuf,
    /// The measured energy table of the campaign.
    pub energy: PathBuf,
    /// Output folder (`check.csv`, `check.md`, `check_cdfs.png`, `index.html`), if any.
    pub out: Option<PathBuf>,
    /// Draws, seed, cull.
    pub params: crate::check::CheckParams,
}

/// What `check` found.
#[derive(Debug, Clone)]
pub struct CheckSummary {
    /// The result.
    pub result: crate::check::CheckResult,
    /// The output folder, if any.
    pub out: Option<PathBuf>,
}

impl fmt::Display for CheckSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.result.table().to_markdown())?;
        write!(
            f,
            "{} ({} draws, {:.1} s)",
            self.result.verdict(),
            self.result.draws.len(),
            self.result.wall_s
        )?;
        if let Some(o) = &self.out {
            write!(f, " -> {}", o.display())?;
        }
        Ok(())
    }
}

/// Run `pradar check` ([`crate::check::check()`]); writes the table and plots when `out`
/// is set.
pub fn check(cmd: &Check, progress: StepProgress) -> Result<CheckSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    if let Some(o) = &cmd.out {
        let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
        inputs.push((cmd.model.clone(), "--model"));
        inputs.push((cmd.energy.clone(), "--energy"));
        let outputs: Vec<(PathBuf, &str)> =
            ["check.csv", "check.md", "check_cdfs.png", "index.html"]
                .iter()
                .map(|n| (o.join(n), "--out"))
                .collect();
        refuse(&outputs, &inputs)?;
    }
    let model = ModelConfig::load(&cmd.model)?
        .require_estimable(&Default::default())
        .map_err(|e| crate::error::Error::input(&cmd.model, e.to_string()))?;
    let params = cmd.params.check()?;
    let em = crate::energy::EnergyMatrix::read(&cmd.energy)?;
    let result = crate::check::check(&c, &em, &cmd.energy, &model, &params, progress)?;
    if let Some(o) = &cmd.out {
        let what = format!(
            "model {} against {}",
            cmd.model.display(),
            cmd.energy.display()
        );
        crate::report::check::write(o, &what, &result)?;
    }
    Ok(CheckSummary {
        result,
        out: cmd.out.clone(),
    })
}

/// `pradar experiment`: the paper's mapping experiments.
#[derive(Debug, Clone)]
pub struct Experiments {
    /// `fig5`, `fig6`, `prior-sensitivity`, `pose-noise` or `all`.
    pub name: String,
    /// Campaign, energy table and model (each resolved when absent).
    pub inputs: InputOptions,
    /// Seeds and the experiments' settings.
    pub params: ExperimentParams,
    /// Output folder (`out/NAME/` per experiment, `out/index.html`).
    pub out: PathBuf,
}

/// What `experiment` wrote.
#[derive(Debug, Clone)]
pub struct ExperimentsSummary {
    /// Every experiment run, in order.
    pub results: Vec<ExperimentResult>,
    /// The index page.
    pub index: PathBuf,
}

impl fmt::Display for ExperimentsSummary {
    /// Each experiment's findings, then the index page.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for r in &self.results {
            writeln!(f, "{}:", r.name)?;
            for (k, v) in &r.findings {
                writeln!(f, "  {k}: {v}")?;
            }
        }
        write!(f, "report: {}", self.index.display())
    }
}

/// The experiments a command-line name selects (`all`: every one, in report order).
pub fn select_experiments(name: &str) -> Result<Vec<Experiment>> {
    if name == "all" {
        Ok(Experiment::ALL.to_vec())
    } else {
        Ok(vec![Experiment::parse(name)?])
    }
}

/// Run `pradar experiment` ([`run_experiments`]).
pub fn experiments(cmd: &Experiments, progress: Progress) -> Result<ExperimentsSummary> {
    let which = select_experiments(&cmd.name)?;
    let params = cmd.params.check()?;
    let results = run_experiments(&which, &cmd.inputs, &params, &cmd.out, progress)?;
    Ok(ExperimentsSummary {
        results,
        index: cmd.out.join("index.html"),
    })
}
