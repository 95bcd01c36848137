//! The `pradar map` job: one or several runs (campaign + energy table) → one occupancy map,
//! its files and its metrics against the reference map.
//!
//! Takes [`MapOptions`] (method, runs, output folder, `--elements`, grid and OG parameters);
//! gives in the output folder, for method `<m>` (`og` or `og-boresight`):
//! * `<m>.png/.pgm/.yaml` — the soft map (grey = 1 − p), YAML `occupied_thresh` = η = 0.5,
//!   `free_thresh` = 0.45 (cells left at the prior read as unknown in map_server);
//! * `<m>_binary.png/.pgm/.yaml` — the binary map (p > η = 0.5);
//! * `reference.png/.pgm/.yaml` — the reference map rasterised from the layout on the same
//!   grid (occupied 0, free 254, outside 205);
//! * `metrics.json` — figures on the observable region and on the whole map, each beside the
//!   all-free map's; with several runs also every single run's figures and the fused map's
//!   figures for the first n runs, n = 1..R (metrics vs number of runs).
//!
//! Choices:
//! * the grid is the reference raster's ([`Layout::rasterize`]: cell 0.1 m, margin 0.5 m);
//!   fused runs must share the layout's grid;
//! * observable region = cells inside the −3 dB main lobe of at least one (pose, direction)
//!   of any run, within the usable bins (coupling gate to the last bin), and not `Outside` in
//!   the reference (mapper-independent, so all methods are scored on the same cells);
//! * whole map = every cell of the grid, `Outside` reference cells counted as free;
//! * usable bins start after the coupling gate (`gate_ns` from the energy metadata when the
//!   coupling removal was `gate`) plus 2 bins (the Hann kernel's half-width), and never
//!   before bin 2;
//! * the energy table must match the campaign: positions = poses, directions and their
//!   angles, headings, bin width = 1/B, and (when the metadata records it) the element count
//!   (`--elements` overrides the manifest's).

use crate::campaign::layout::{CellClass, GridSpec, Layout, ReferenceMap};
use crate::campaign::manifest::{Campaign, Pose};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::mapping::grid::{GridParams, ObservationModel};
use crate::mapping::metrics::{evaluate, MapMetrics};
use crate::mapping::og::{
    detection_threshold, fuse, og_map_stats, Detector, LogOddsMap, Method, OgParams, OgStats,
};
use crate::mapping::output::{self, soft_grey, GREY_FREE, GREY_OCCUPIED, GREY_UNKNOWN};
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
    pub ekf: crate::mapping::ekf::EkfParams,
    /// Pose noise given to the mapper (none by default).
    pub pose_noise: PoseNoise,
}

/// Pose noise of the mapper: the energy was recorded at the manifest's poses, the mapper is
/// given x̃ = x + N(0, σ_p²), ỹ = y + N(0, σ_p²), h̃ = h + N(0, σ_h²), drawn independently
/// per pose (no drift) from a ChaCha stream keyed by (`seed`, run index). The observable
/// region and the reference stay those of the true poses, so maps with and without noise are
/// scored on the same cells.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PoseNoise {
    /// Position standard deviation per axis, m.
    pub position_m: f64,
    /// Heading standard deviation, degrees.
    pub heading_deg: f64,
    /// Seed of the draws.
    pub seed: u64,
}

impl PoseNoise {
    /// Validate (finite, ≥ 0).
    pub fn check(&self) -> Result<()> {
        if !(self.position_m.is_finite() && self.position_m >= 0.0) {
            return Err(Error::param("pose_noise.position_m", "must be >= 0"));
        }
        if !(self.heading_deg.is_finite() && self.heading_deg >= 0.0) {
            return Err(Error::param("pose_noise.heading_deg", "must be >= 0"));
        }
        Ok(())
    }
    /// Whether it changes any pose.
    pub fn is_none(&self) -> bool {
        self.position_m == 0.0 && self.heading_deg == 0.0
    }
    /// The poses the mapper believes for run `run` (the true poses when there is no noise).
    pub fn apply(&self, poses: &[Pose], run: usize) -> Vec<Pose> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        if self.is_none() {
            return poses.to_vec();
        }
        let key = self.seed ^ (run as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(key);
        poses
            .iter()
            .map(|p| {
                let dx: f64 = StandardNormal.sample(&mut rng);
                let dy: f64 = StandardNormal.sample(&mut rng);
                let dh: f64 = StandardNormal.sample(&mut rng);
                Pose {
                    x_m: p.x_m + self.position_m * dx,
                    y_m: p.y_m + self.position_m * dy,
                    heading_deg: p.heading_deg + self.heading_deg * dh,
                }
            })
            .collect()
    }
}

/// A loaded, checked run ready to map.
#[derive(Debug)]
pub struct LoadedRun {
    /// The campaign.
    pub campaign: Campaign,
    /// Its layout.
    pub layout: Layout,
    /// The energy matrix.
    pub energy: EnergyMatrix,
    /// Its path.
    pub energy_path: PathBuf,
    /// The observation model.
    pub model: ObservationModel,
    /// The run's detector.
    pub detector: Detector,
    /// The poses the data were recorded at (the manifest's; `model.poses` holds the poses
    /// the mapper believes, which differ under [`PoseNoise`]).
    pub true_poses: Vec<Pose>,
}

/// First usable bin of an energy table (see the module docs).
pub fn min_bin(em: &EnergyMatrix) -> usize {
    let gate = em.meta.gate_ns();
    let g = (gate.max(0.0) / em.meta.bin_width_ns).ceil() as usize;
    (g + 2).max(2)
}

/// Bin-averaged window kernel of a point echo, K(m) for m = 0..=32 bins from its peak (the
/// run's band and processing; any scale).
pub fn window_kernel(c: &Campaign) -> Result<Vec<f64>> {
    let m = &c.manifest;
    let proc = crate::energy::EnergyProcessor::new(m.band, m.processing)
        .map_err(|e| Error::input(&c.path, e.to_string()))?;
    let tb = proc.bin_width_ns() * 1e-9;
    let nb = proc.nbins();
    let centre = (nb / 2).min(200);
    let e = proc.point_echo_energy(1.0, centre as f64 * tb);
    Ok((0..=32)
        .map(|j| {
            let a = e.get(centre + j).copied().unwrap_or(0.0);
            let b = centre
                .checked_sub(j)
                .and_then(|i| e.get(i))
                .copied()
                .unwrap_or(a);
            a.max(b)
        })
        .collect())
}

/// Load and check one run on the grid `spec` (None: the run's own reference grid).
pub fn load_run(
    run: &MapRun,
    elements: Option<usize>,
    grid: &GridParams,
    og: &OgParams,
    spec: Option<GridSpec>,
) -> Result<LoadedRun> {
    let mut c = Campaign::load(&run.campaign)?;
    if let Some(n) = elements {
        c.set_elements(n)?;
    }
    let layout = Layout::load(&c.layout_path())?;
    let energy = EnergyMatrix::read(&run.energy)?;
    crate::energy::check_campaign(&c, &energy, &run.energy)?;
    let threshold = detection_threshold(&energy.meta, og.pfa, &run.energy)?;
    let detector = Detector::new(threshold, &window_kernel(&c)?, og.mask_db, min_bin(&energy));
    let own = GridSpec::covering(layout.bbox(), grid.cell_m, grid.margin_m);
    let spec = match spec {
        Some(s) => {
            if s != own {
                return Err(Error::input(
                    &run.campaign,
                    "layout differs from the first run's (fused runs must share one area)",
                ));
            }
            s
        }
        None => own,
    };
    let model = ObservationModel::new(
        spec,
        *grid,
        &c.manifest,
        energy.bins,
        energy.meta.bin_width_ns,
        min_bin(&energy),
    )?;
    Ok(LoadedRun {
        true_poses: c.manifest.poses.clone(),
        campaign: c,
        layout,
        energy,
        energy_path: run.energy.clone(),
        model,
        detector,
    })
}

/// Metrics of a map and of the all-free map, on the observable region and the whole map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MetricsPair {
    /// The map on the observable region.
    pub observable: MapMetrics,
    /// The all-free map on the observable region.
    pub observable_all_free: MapMetrics,
    /// The map on the whole grid.
    pub whole: MapMetrics,
    /// The all-free map on the whole grid.
    pub whole_all_free: MapMetrics,
}

/// Score a log-odds map (binary at p > 0.5) against the reference.
pub fn score(map: &LogOddsMap, reference: &ReferenceMap, observable: &[bool]) -> MetricsPair {
    score_binary(&map.binary(), reference, observable)
}

/// Score a binary map (true = occupied) against the reference.
pub fn score_binary(bin: &[bool], reference: &ReferenceMap, observable: &[bool]) -> MetricsPair {
    let (rows, cols) = (reference.spec.rows, reference.spec.cols);
    let refo: Vec<bool> = reference
        .cells
        .iter()
        .map(|c| *c == CellClass::Occupied)
        .collect();
    let free = vec![false; bin.len()];
    let all = vec![true; bin.len()];
    MetricsPair {
        observable: evaluate(bin, &refo, observable, rows, cols),
        observable_all_free: evaluate(&free, &refo, observable, rows, cols),
        whole: evaluate(bin, &refo, &all, rows, cols),
        whole_all_free: evaluate(&free, &refo, &all, rows, cols),
    }
}

/// Observable region of a set of runs on a reference (see the module docs).
pub fn observable_region(runs: &[&ObservationModel], reference: &ReferenceMap) -> Vec<bool> {
    let mut region: Vec<bool> = reference
        .cells
        .iter()
        .map(|c| *c != CellClass::Outside)
        .collect();
    let mut cov = vec![false; region.len()];
    for m in runs {
        for (c, v) in cov.iter_mut().zip(m.main_lobe_coverage()) {
            *c |= v;
        }
    }
    for (r, c) in region.iter_mut().zip(cov) {
        *r &= c;
    }
    region
}

/// Observable region of loaded runs, from the poses their data were recorded at.
pub fn runs_region(loaded: &[LoadedRun], reference: &ReferenceMap) -> Vec<bool> {
    let models: Vec<ObservationModel> = loaded
        .iter()
        .map(|l| {
            let mut m = l.model.clone();
            m.poses = l.true_poses.clone();
            m
        })
        .collect();
    let refs: Vec<&ObservationModel> = models.iter().collect();
    observable_region(&refs, reference)
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
    pub ekf: Option<crate::mapping::ekf::EkfReport>,
    /// Pose noise given to the mapper.
    pub pose_noise: PoseNoise,
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

/// Load and check every run of `opts` on one grid, with the reference map rasterised from
/// the first run's layout on the same grid.
pub fn load_runs(opts: &MapOptions) -> Result<(Vec<LoadedRun>, ReferenceMap)> {
    if opts.runs.is_empty() {
        return Err(Error::param(
            "--run",
            "give --campaign and --energy, or at least one --run campaign.toml=energy.parquet",
        ));
    }
    opts.pose_noise.check()?;
    let mut loaded: Vec<LoadedRun> = Vec::new();
    for (i, r) in opts.runs.iter().enumerate() {
        let spec = loaded.first().map(|l| l.model.spec);
        let mut l = load_run(r, opts.elements, &opts.grid, &opts.og, spec)?;
        l.model.poses = opts.pose_noise.apply(&l.true_poses, i);
        loaded.push(l);
    }
    let reference = loaded[0]
        .layout
        .rasterize(opts.grid.cell_m, opts.grid.margin_m);
    if reference.spec != loaded[0].model.spec {
        return Err(Error::param("cell_m", "reference grid mismatch"));
    }
    Ok((loaded, reference))
}

/// Run `pradar map`; `progress(done, total)` counts poses over all runs.
pub fn run_map(opts: &MapOptions, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<MapReport> {
    opts.grid.check()?;
    opts.og.check()?;
    if opts.method == Method::Ekf {
        return crate::mapping::ekf::run_map_ekf(opts, progress);
    }
    let (loaded, reference) = load_runs(opts)?;
    let total: usize = loaded.iter().map(|l| l.model.poses.len()).sum();
    let mut done = 0;
    let mut maps = Vec::new();
    let mut stats = Vec::new();
    for l in &loaded {
        let base = done;
        let (m, s) = og_map_stats(
            &l.model,
            &l.energy,
            &opts.og,
            opts.method,
            &l.detector,
            &|d, _| progress(base + d, total),
        )?;
        done += l.model.poses.len();
        maps.push(m);
        stats.push(s);
    }
    let region = runs_region(&loaded, &reference);
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
    // files
    let spec = reference.spec;
    let out = &opts.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let name = opts.method.name();
    let soft: Vec<u8> = fused.probs().iter().map(|&p| soft_grey(p)).collect();
    output::write_map_files(out, name, &spec, &soft, 0.5, 0.45)?;
    let bin: Vec<u8> = fused
        .binary()
        .iter()
        .map(|&o| if o { GREY_OCCUPIED } else { GREY_FREE })
        .collect();
    output::write_map_files(out, &format!("{name}_binary"), &spec, &bin, 0.5, 0.45)?;
    write_reference(out, &reference)?;
    let report = MapReport {
        method: name.to_string(),
        rows: spec.rows,
        cols: spec.cols,
        cell_m: spec.cell_m,
        eta: 0.5,
        observable_cells: region.iter().filter(|&&v| v).count(),
        metrics,
        runs,
        fusion,
        ekf: None,
        pose_noise: opts.pose_noise,
        binary: fused.binary(),
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::param("metrics", e.to_string()))?;
    crate::io::write_bytes(&out.join("metrics.json"), json.as_bytes())?;
    Ok(report)
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

/// The `reproduce` report section: the occupancy maps (`og`, `og-boresight`) and the EKF
/// RRCS map (`ekf`, scalable filter) of one run,
/// written under `report_dir/<sub>/<method>/`, shown beside the reference map with their
/// figures and the all-free map's.
pub fn report_section(
    campaign: &Path,
    energy: &Path,
    report_dir: &Path,
    sub: &str,
) -> Result<crate::report::Section> {
    use crate::report::html_escape;
    let mut rows = String::new();
    let mut imgs = String::new();
    let mut all_free: Option<MetricsPair> = None;
    for (i, method) in [Method::Og, Method::OgBoresight, Method::Ekf]
        .into_iter()
        .enumerate()
    {
        let name = method.name();
        let opts = MapOptions {
            method,
            runs: vec![MapRun {
                campaign: campaign.to_path_buf(),
                energy: energy.to_path_buf(),
            }],
            out: report_dir.join(sub).join(name),
            elements: None,
            grid: GridParams::default(),
            og: OgParams::default(),
            ekf: Default::default(),
            pose_noise: PoseNoise::default(),
        };
        let r = run_map(&opts, &|_, _| {})?;
        if i == 0 {
            imgs.push_str(&format!(
                "<figure><img src=\"{sub}/{name}/reference.png\" alt=\"reference\"><figcaption>reference</figcaption></figure>\n"
            ));
        }
        for stem in [name.to_string(), format!("{name}_binary")] {
            imgs.push_str(&format!(
                "<figure><img src=\"{sub}/{name}/{stem}.png\" alt=\"{stem}\"><figcaption>{}</figcaption></figure>\n",
                html_escape(&stem)
            ));
        }
        rows.push_str(&metric_row(
            name,
            &r.metrics,
            &format!("{sub}/{name}/metrics.json"),
        ));
        all_free = Some(r.metrics);
    }
    if let Some(m) = all_free {
        let free = MetricsPair {
            observable: m.observable_all_free,
            observable_all_free: m.observable_all_free,
            whole: m.whole_all_free,
            whole_all_free: m.whole_all_free,
        };
        rows.push_str(&metric_row("all-free map", &free, ""));
    }
    let html = format!(
        "<p>Occupancy grids (0.1 m cells; binary map: p &gt; 0.5) and the EKF map over RRCS (scalable filter; binary map: mean − 2·std &gt; μ0). Observable region: cells inside the −3 dB main lobe of some (pose, direction) within the usable bins, not outside the perimeter; whole map: every cell, outside cells counted as free. ψ in cells (lower is better).</p>\n<div>{imgs}</div>\n<table>\n<tr><th>map</th><th>ψ obs.</th><th>F1 obs.</th><th>F1 (1 cell) obs.</th><th>wrong cells obs.</th><th>ψ whole</th><th>F1 whole</th><th>F1 (1 cell) whole</th><th>wrong cells whole</th><th>metrics</th></tr>\n{rows}</table>\n"
    );
    Ok(crate::report::Section {
        title: "Maps: occupancy grid (side-lobe aware vs boresight) and EKF".into(),
        html,
    })
}

fn metric_row(name: &str, m: &MetricsPair, link: &str) -> String {
    let (o, w) = (&m.observable, &m.whole);
    let link = if link.is_empty() {
        String::new()
    } else {
        format!("<a href=\"{link}\">metrics.json</a>")
    };
    format!(
        "<tr><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.4}</td><td>{link}</td></tr>\n",
        crate::report::html_escape(name),
        o.psi,
        o.f1,
        o.f1_1,
        o.wrong_cell_rate,
        w.psi,
        w.f1,
        w.f1_1,
        w.wrong_cell_rate
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Vec<Pose> {
        (0..n)
            .map(|i| Pose {
                x_m: i as f64 * 0.4,
                y_m: -0.3,
                heading_deg: 10.0,
            })
            .collect()
    }

    #[test]
    fn no_pose_noise_keeps_the_poses() {
        let p = line(5);
        assert_eq!(PoseNoise::default().apply(&p, 0), p);
    }

    #[test]
    fn pose_noise_has_the_stated_spread_and_is_seeded() {
        let p = line(20_000);
        let n = PoseNoise {
            position_m: 0.05,
            heading_deg: 2.0,
            seed: 7,
        };
        let a = n.apply(&p, 0);
        assert_eq!(a, n.apply(&p, 0), "same seed, same draws");
        assert_ne!(a, n.apply(&p, 1), "another run, other draws");
        // mean within 4 standard errors of 0, sample std returned
        let sd = |f: &dyn Fn(&Pose, &Pose) -> f64, sigma: f64| {
            let v: Vec<f64> = a.iter().zip(&p).map(|(x, y)| f(x, y)).collect();
            let m = v.iter().sum::<f64>() / v.len() as f64;
            assert!(m.abs() < 4.0 * sigma / (v.len() as f64).sqrt(), "mean {m}");
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let sx = sd(&|x, y| x.x_m - y.x_m, 0.05);
        let sy = sd(&|x, y| x.y_m - y.y_m, 0.05);
        let sh = sd(&|x, y| x.heading_deg - y.heading_deg, 2.0);
        // 20,000 draws: the sample std is within 2 % of σ (≈ 4 standard errors)
        assert!((sx / 0.05 - 1.0).abs() < 0.02, "x {sx}");
        assert!((sy / 0.05 - 1.0).abs() < 0.02, "y {sy}");
        assert!((sh / 2.0 - 1.0).abs() < 0.02, "heading {sh}");
        assert!(PoseNoise {
            position_m: -1.0,
            ..n
        }
        .check()
        .is_err());
        assert!(PoseNoise {
            heading_deg: f64::NAN,
            ..n
        }
        .check()
        .is_err());
    }
}
