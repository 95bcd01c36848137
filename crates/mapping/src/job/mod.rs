//! The map job: one or several runs (campaign + energy table) → one map, its files and its
//! metrics against the reference map. The `pradar map` command ([`crate::job`]),
//! the experiments, the explorer and the report's maps all run this job ([`run_map`]).
//!
//! Takes [`MapOptions`] (method, runs, output folder, element override, grid, OG and EKF
//! parameters, pose noise);
//! gives in the output folder, for method `<m>` (`og` or `og-boresight`):
//! * `<m>.png/.pgm/.yaml` — the soft map (grey = 1 − p), YAML `occupied_thresh` = η = 0.5,
//!   `free_thresh` = 0.45 (cells left at the prior read as unknown in map_server);
//! * `<m>_binary.png/.pgm/.yaml` — the binary map (p > η = 0.5);
//! * `reference.png/.pgm/.yaml` — the reference map rasterised from the layout on the same
//!   grid (occupied 0, free 254, outside 205);
//! * `metrics.json` — figures on the observable region, the building and the whole map, each
//!   beside the all-free map's, and the per-class figures ([`crate::score`]); with several runs also every single run's figures and the fused map's
//!   figures for the first n runs, n = 1..R (metrics vs number of runs).
//!
//! Choices:
//! * the grid is the reference raster's ([`LayoutRaster::rasterize`](crate::reference::LayoutRaster::rasterize): cell 0.1 m, margin 0.5 m);
//!   fused runs must share the layout's grid;
//! * regions ([`crate::score`]): observable = cells in line of sight of a pose through
//!   the layout's walls, inside the −3 dB main lobe of one of its directions, within the
//!   usable bins (coupling gate to the last bin); building = inside the perimeter or on a
//!   wall; whole map = every cell, `Outside` reference cells counted as free. None comes
//!   from the reference, and all are mapper-independent, so every method is scored on the
//!   same cells; fused runs use the first run's layout (load checks they share its grid);
//! * usable bins start after the coupling gate (`gate_ns` from the energy metadata when the
//!   coupling removal was `gate`) plus 2 bins (the Hann kernel's half-width), and never
//!   before bin 2;
//! * the energy table must match the campaign: positions = poses, directions and their
//!   angles, headings, bin width = 1/B, and (when the metadata records it) the element count
//!   (`--elements` overrides the manifest's).
//!
//! Layout: [`load`] (runs → [`LoadedRun`]s on one grid, the first usable bin, the window
//! kernel, the runs' scoring regions), [`ekf`] (the `--method ekf` job); the scoring
//! against the reference is [`crate::score`]. This file holds the
//! options, the occupancy-grid job and the report written to `metrics.json`. The report
//! page is rendered by `report::maps` from [`report_maps`].
//!
//! ```no_run
//! use pradar_formats::params::ParamGuard;
//! use pradar_mapping::job::{run_map, MapOptions, MapRun};
//! use pradar_mapping::Method;
//! let opts = MapOptions {
//!     method: Method::Og,
//!     runs: vec![MapRun::parse("campaign.toml=energy.parquet")?],
//!     out: "maps".into(),
//!     elements: None,
//!     grid: Default::default(),
//!     og: Default::default(),
//!     ekf: Default::default(),
//!     pose_noise: Default::default(),
//!     poses_from: Default::default(),
//!     odometry: Default::default(),
//! };
//! let report = run_map(&opts.check()?, &|_, _| {})?;
//! println!("psi {:.3}", report.metrics.observable.psi);
//! # Ok::<(), pradar_formats::error::Error>(())
//! ```

pub mod ekf;
pub mod load;

pub use ekf::run_map_ekf;
pub use load::{load_run, load_runs, min_bin, runs_regions, window_kernel, LoadedRun};

pub use crate::pose_noise::{PoseNoise, PoseNoiseValid};
use crate::score::{score, MetricsPair};
pub use crate::slam::{OdometryNoise, PosesFrom};
pub use load::{slam_summaries, SlamSummary};

use crate::ekf::{EkfParams, EkfReport, EkfValid};
use crate::error::{Error, Result};
use crate::grid::{GridParams, GridValid};
use crate::og::{fuse, og_map_stats, LogOddsMap, Method, OgParams, OgStats, OgValid};
use crate::output::{self, soft_grey, GREY_FREE, GREY_OCCUPIED, GREY_UNKNOWN};
use crate::params::{ParamGuard, Valid};
use crate::reference::{CellClass, ReferenceMap};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// One run: a campaign manifest and its energy table.
#[derive(Debug, Clone, PartialEq)]
pub struct MapRun {
    /// `campaign.toml`.
    pub campaign: PathBuf,
    /// Energy Parquet.
    pub energy: PathBuf,
}

impl MapRun {
    /// Parse `campaign.toml=energy.parquet`.
    pub fn parse(s: &str) -> Result<MapRun> {
        let (c, e) = s.split_once('=').ok_or_else(|| {
            Error::param(
                "--run",
                format!("`{s}`: expected campaign.toml=energy.parquet"),
            )
        })?;
        if c.is_empty() || e.is_empty() {
            return Err(Error::param(
                "--run",
                format!("`{s}`: expected campaign.toml=energy.parquet"),
            ));
        }
        Ok(MapRun {
            campaign: PathBuf::from(c),
            energy: PathBuf::from(e),
        })
    }
}

/// Options of `pradar map`.
#[derive(Debug, Clone)]
pub struct MapOptions {
    /// Inverse sensor model.
    pub method: Method,
    /// Runs (one, or several to fuse).
    pub runs: Vec<MapRun>,
    /// Output folder.
    pub out: PathBuf,
    /// `--elements` override of every run's `[array] elements`.
    pub elements: Option<usize>,
    /// Grid / observation model parameters.
    pub grid: GridParams,
    /// Occupancy-grid parameters.
    pub og: OgParams,
    /// EKF parameters (method `ekf`).
    pub ekf: EkfParams,
    /// Pose noise given to the mapper (none by default).
    pub pose_noise: PoseNoise,
    /// Where the mapper's poses come from: the manifest's (with `pose_noise`), the
    /// dead reckoning of an odometry drawn from them, or that odometry and the sweeps
    /// ([`crate::slam`]).
    pub poses_from: PosesFrom,
    /// The odometry's noise per step (`poses_from` odometry or sweeps).
    pub odometry: OdometryNoise,
}

/// Map options that passed [`ParamGuard::check`] (every run given, every parameter set in
/// range).
pub type MapValid = Valid<MapOptions>;

impl ParamGuard for MapOptions {
    type Checked = MapValid;

    /// At least one run; the grid, occupancy-grid, EKF and pose-noise parameters each in
    /// range (their own checks, in that order).
    fn check(&self) -> Result<MapValid> {
        self.grid.check()?;
        self.og.check()?;
        self.ekf.check()?;
        if self.runs.is_empty() {
            return Err(Error::param(
                "--run",
                "give --campaign and --energy, or at least one --run campaign.toml=energy.parquet",
            ));
        }
        self.pose_noise.check()?;
        if self.poses_from != PosesFrom::Manifest {
            self.odometry.check()?;
            if !self.pose_noise.is_none() {
                return Err(Error::param(
                    "--poses-from",
                    "odometry and sweeps draw the poses' errors from --odometry-*, not --pose-noise-*",
                ));
            }
        }
        Ok(Valid::new(self.clone()))
    }
}

// The parameter sets inside checked options were checked with them: these hand them out
// as their checked types without checking again (called on the checked [`MapValid`], which
// derefs to the options).
impl MapOptions {
    /// The grid parameters (checked).
    pub fn grid(&self) -> GridValid {
        Valid::new(self.grid)
    }
    /// The occupancy-grid parameters (checked).
    pub fn og(&self) -> OgValid {
        Valid::new(self.og)
    }
    /// The EKF parameters (checked).
    pub fn ekf(&self) -> EkfValid {
        Valid::new(self.ekf)
    }
}

/// The maps of the report: one run mapped with every method (`og`, `og-boresight`, `ekf`;
/// default parameters) into `dir/<method>/`; gives each method's name and figures, in
/// that order.
pub fn report_maps(
    campaign: &Path,
    energy: &Path,
    dir: &Path,
) -> Result<Vec<(&'static str, MetricsPair)>> {
    let mut maps = Vec::new();
    for method in [Method::Og, Method::OgBoresight, Method::Ekf] {
        let name = method.name();
        let opts = MapOptions {
            method,
            runs: vec![MapRun {
                campaign: campaign.to_path_buf(),
                energy: energy.to_path_buf(),
            }],
            out: dir.join(name),
            elements: None,
            grid: GridParams::default(),
            og: OgParams::default(),
            ekf: EkfParams::default(),
            pose_noise: PoseNoise::default(),
            poses_from: Default::default(),
            odometry: Default::default(),
        };
        let r = run_map(&opts.check()?, &|_, _| {})?;
        maps.push((name, r.metrics));
    }
    Ok(maps)
}

/// One row of the fusion table.
#[derive(Debug, Clone, Serialize)]
pub struct FusionRow {
    /// Runs fused (the first n).
    pub runs: usize,
    /// Figures of the fused map.
    pub metrics: MetricsPair,
}

/// What `pradar map` wrote and measured.
#[derive(Debug, Clone, Serialize)]
pub struct MapReport {
    /// Method name.
    pub method: String,
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Cell side, m.
    pub cell_m: f64,
    /// Binary threshold η on p.
    pub eta: f64,
    /// Observable cells.
    pub observable_cells: usize,
    /// Figures of the (fused) map.
    pub metrics: MetricsPair,
    /// Per run: campaign, energy, detector threshold, work statistics, figures alone.
    pub runs: Vec<RunSummary>,
    /// Figures of the fused map of the first n runs (n = 1..R; one row for a single run).
    pub fusion: Vec<FusionRow>,
    /// EKF parameters and work statistics (method `ekf` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ekf: Option<EkfReport>,
    /// Pose noise given to the mapper.
    pub pose_noise: PoseNoise,
    /// The poses from an odometry (`--poses-from odometry|sweeps`), per run.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub slam: Vec<SlamSummary>,
    /// The (fused) binary map, row-major from the lowest y (not in metrics.json).
    #[serde(skip)]
    pub binary: Vec<bool>,
}

/// Per-run summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Manifest path.
    pub campaign: String,
    /// Energy path.
    pub energy: String,
    /// Detector energy threshold.
    pub threshold: f64,
    /// Work statistics.
    pub stats: OgStats,
    /// This run alone.
    pub metrics: MetricsPair,
}

/// Run `pradar map` with checked options; `progress(done, total)` counts poses over all
/// runs.
pub fn run_map(opts: &MapValid, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<MapReport> {
    match opts.method {
        Method::Ekf => ekf::run_map_ekf(opts, progress),
        Method::Og | Method::OgBoresight => run_map_og(opts, progress),
    }
}

/// The occupancy-grid job (`og`, `og-boresight`): each run mapped from the prior, the runs
/// fused, every run and every prefix of the runs scored; writes `<m>.*`, `<m>_binary.*`,
/// `reference.*` and `metrics.json`.
fn run_map_og(opts: &MapValid, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<MapReport> {
    let (loaded, reference) = load_runs(opts)?;
    let (maps, stats) = og_maps(&loaded, &opts.og(), opts.method, progress)?;
    let region = runs_regions(&loaded, &reference)?;
    let fused = fuse(&maps)?;
    let metrics = score(&fused, &reference, &region);
    let mut runs = Vec::new();
    for ((l, m), s) in loaded.iter().zip(&maps).zip(&stats) {
        runs.push(RunSummary {
            campaign: l.campaign.path.display().to_string(),
            energy: l.energy_path.display().to_string(),
            threshold: l.detector.threshold,
            stats: *s,
            metrics: score(m, &reference, &region),
        });
    }
    let mut fusion = Vec::new();
    for n in 1..=maps.len() {
        let f = fuse(&maps[..n])?;
        fusion.push(FusionRow {
            runs: n,
            metrics: score(&f, &reference, &region),
        });
    }
    let spec = reference.spec;
    let name = opts.method.name();
    write_og_files(&opts.out, name, &fused, &reference)?;
    let report = MapReport {
        method: name.to_string(),
        rows: spec.rows,
        cols: spec.cols,
        cell_m: spec.cell_m,
        eta: 0.5,
        observable_cells: region.observable.iter().filter(|&&v| v).count(),
        metrics,
        runs,
        fusion,
        ekf: None,
        pose_noise: opts.pose_noise,
        slam: slam_summaries(&opts.out, &loaded)?,
        binary: fused.binary(),
    };
    write_metrics_json(&opts.out, &report)?;
    Ok(report)
}

/// Each run mapped on its own from the prior, with its work statistics.
fn og_maps(
    loaded: &[LoadedRun],
    og: &OgValid,
    method: Method,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Vec<LogOddsMap>, Vec<OgStats>)> {
    let total: usize = loaded.iter().map(|l| l.model.poses.len()).sum();
    let mut done = 0;
    let mut maps = Vec::new();
    let mut stats = Vec::new();
    for l in loaded {
        let base = done;
        let (m, s) = og_map_stats(&l.model, &l.energy, og, method, &l.detector, &|d, _| {
            progress(base + d, total)
        })?;
        done += l.model.poses.len();
        maps.push(m);
        stats.push(s);
    }
    Ok((maps, stats))
}

/// Write the soft map `<name>.*`, the binary map `<name>_binary.*` and `reference.*`.
fn write_og_files(
    out: &Path,
    name: &str,
    fused: &LogOddsMap,
    reference: &ReferenceMap,
) -> Result<()> {
    let spec = reference.spec;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let soft: Vec<u8> = fused.probs().iter().map(|&p| soft_grey(p)).collect();
    output::write_map_files(out, name, &spec, &soft, 0.5, 0.45)?;
    let bin: Vec<u8> = fused
        .binary()
        .iter()
        .map(|&o| if o { GREY_OCCUPIED } else { GREY_FREE })
        .collect();
    output::write_map_files(out, &format!("{name}_binary"), &spec, &bin, 0.5, 0.45)?;
    write_reference(out, reference)
}

/// Write `metrics.json` (pretty-printed [`MapReport`]).
pub fn write_metrics_json(out: &Path, report: &MapReport) -> Result<()> {
    let json =
        serde_json::to_string_pretty(report).map_err(|e| Error::param("metrics", e.to_string()))?;
    crate::io::write_bytes(&out.join("metrics.json"), json.as_bytes())
}

/// Grey values of the reference map (occupied 0, free 254, outside 205).
pub fn reference_grey(reference: &ReferenceMap) -> Vec<u8> {
    reference
        .cells
        .iter()
        .map(|c| match c {
            CellClass::Occupied => GREY_OCCUPIED,
            CellClass::Free => GREY_FREE,
            CellClass::Outside => GREY_UNKNOWN,
        })
        .collect()
}

/// Write `reference.png/.pgm/.yaml` (map_server default thresholds 0.65 / 0.196).
pub fn write_reference(out: &Path, reference: &ReferenceMap) -> Result<()> {
    output::write_map_files(
        out,
        "reference",
        &reference.spec,
        &reference_grey(reference),
        0.65,
        0.196,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_options_are_checked_once_with_every_part() {
        let ok = MapOptions {
            method: Method::Og,
            runs: vec![MapRun::parse("c.toml=e.parquet").unwrap()],
            out: PathBuf::from("out"),
            elements: None,
            grid: Default::default(),
            og: Default::default(),
            ekf: Default::default(),
            pose_noise: Default::default(),
            poses_from: Default::default(),
            odometry: Default::default(),
        };
        let v = ok.check().unwrap();
        assert_eq!(v.grid().cell_m, 0.1);
        let field = |o: MapOptions| o.check().unwrap_err().to_string();
        let mut o = ok.clone();
        o.grid.cell_m = 0.0;
        assert!(field(o).contains("`cell_m`"));
        let mut o = ok.clone();
        o.og.pfa = 2.0;
        assert!(field(o).contains("`pfa`"));
        let mut o = ok.clone();
        o.ekf.sigma0 = 0.0;
        assert!(field(o).contains("`sigma0`"));
        let mut o = ok.clone();
        o.runs.clear();
        assert!(field(o).contains("`--run`"));
        let mut o = ok;
        o.pose_noise.position_m = -1.0;
        assert!(field(o).contains("`pose_noise.position_m`"));
    }
}
