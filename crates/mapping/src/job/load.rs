//! Loading the runs of a map job: campaign, layout and energy table checked against each
//! other, the run's detector and observation model on one grid.
//!
//! Takes [`MapRun`]s (campaign + energy paths) and checked grid and occupancy-grid
//! parameters; gives [`LoadedRun`]s and the reference map rasterised from the first run's
//! layout on the same grid. The first usable bin ([`min_bin`]) is the coupling gate plus
//! 2 bins (the Hann kernel's half-width), never before bin 2; [`window_kernel`] is the
//! bin-averaged energy of a unit point echo computed by the run's own `energy` processing.

use super::{MapRun, MapValid};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, Pose};
use crate::detectable::{detectable_returns, truth_rays};
use crate::energy::{EnergyMatrix, EnergySource, EnergyTable};
use crate::error::{Error, Result};
use crate::grid::{GridValid, ObservationModel, Occlusion};
use crate::memo::Memo;
use crate::objects::{find_truth, load_objects};
use crate::og::scan::position_batches;
use crate::og::{detection_threshold, Detector, OgValid};
use crate::params::ParamGuard;
use crate::reference::{GridSpec, LayoutRaster, ReferenceMap};
use crate::score::{building_region, observable_region, Regions};
use crate::slam::matching::steering_step_rad;
use crate::slam::odometry::{pose2, position_rmse};
use crate::slam::{estimate, Estimate, Odometry, OdometryNoise, PosesFrom, Scan, SolveParams};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// A loaded, checked run ready to map.
#[derive(Debug)]
pub struct LoadedRun {
    /// The campaign.
    pub campaign: Campaign,
    /// Its layout.
    pub layout: Layout,
    /// The energy table (read a few poses at a time by the mappers).
    pub energy: EnergyTable,
    /// Its path.
    pub energy_path: PathBuf,
    /// The observation model.
    pub model: ObservationModel,
    /// The run's detector.
    pub detector: Detector,
    /// The poses the data were recorded at (the manifest's; `model.poses` holds the poses
    /// the mapper believes, which differ under [`super::PoseNoise`] and `--poses-from
    /// odometry|sweeps`).
    pub true_poses: Vec<Pose>,
    /// The poses from an odometry (`--poses-from odometry|sweeps`), its noise and source.
    pub slam: Option<(Estimate, OdometryNoise, PosesFrom)>,
}

impl LoadedRun {
    /// The run's occlusion model (first usable bin of the model and the detector, the
    /// side-lobe margin of `og`), shared by both mappers.
    pub fn occlusion(&self, og: &OgValid) -> Occlusion {
        Occlusion::new(
            &self.model,
            self.model.min_bin.max(self.detector.min_bin),
            og.side_db,
        )
    }
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
    let key = format!("{:?} {:?}", m.band, m.processing);
    WINDOW_MEMO.get_or(key, || window_kernel_of(c))
}

/// Window kernels already made in this process ([`crate::memo`]).
static WINDOW_MEMO: Memo<Vec<f64>> = Memo::new();

/// [`window_kernel`] without the memo.
fn window_kernel_of(c: &Campaign) -> Result<Vec<f64>> {
    let m = &c.manifest;
    let proc = crate::energy::EnergyProcessor::new(m.band, m.processing)
        .map_err(|e| Error::input(&c.path, e.to_string()))?;
    let tb = proc.bin_width_ns() * 1e-9;
    let nb = proc.nbins();
    let centre = (nb / 2).min(200);
    // only the 65 bins around the centre are read (each bin's energy is its own sum)
    let e = |b: usize| (b < nb).then(|| proc.point_echo_energy_at(1.0, centre as f64 * tb, b));
    Ok((0..=32)
        .map(|j| {
            let a = e(centre + j).unwrap_or(0.0);
            let b = centre.checked_sub(j).and_then(e).unwrap_or(a);
            a.max(b)
        })
        .collect())
}

/// Detectable references already made in this process ([`crate::memo`]): the experiments
/// map the same simulated sweeps many times.
static DETECTABLE_MEMO: Memo<crate::detectable::DetectableReturns> = Memo::new();

/// Load and check one run on the grid `spec` (None: the run's own reference grid).
pub fn load_run(
    run: &MapRun,
    elements: Option<usize>,
    grid: &GridValid,
    og: &OgValid,
    spec: Option<GridSpec>,
) -> Result<LoadedRun> {
    let mut c = Campaign::load(&run.campaign)?;
    if let Some(n) = elements {
        c.set_elements(n)?;
    }
    let layout = Layout::load(&c.layout_path())?;
    let energy = EnergyTable::open(&run.energy)?;
    let head = energy.header();
    crate::energy::check_campaign(&c, head, &run.energy)?;
    let threshold = detection_threshold(&head.meta, og.pfa, &run.energy)?;
    let detector = Detector::new(threshold, &window_kernel(&c)?, og.mask_db, min_bin(head));
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
        grid,
        &c.manifest,
        head.bins,
        head.meta.bin_width_ns,
        min_bin(head),
    )?;
    Ok(LoadedRun {
        true_poses: c.manifest.poses.clone(),
        campaign: c,
        layout,
        energy,
        energy_path: run.energy.clone(),
        model,
        detector,
        slam: None,
    })
}

/// Load and check every run of `opts` on one grid, with the reference map rasterised from
/// the first run's layout on the same grid.
pub fn load_runs(opts: &MapValid) -> Result<(Vec<LoadedRun>, ReferenceMap)> {
    let (grid, og) = (opts.grid(), opts.og());
    let mut loaded: Vec<LoadedRun> = Vec::new();
    for (i, r) in opts.runs.iter().enumerate() {
        let spec = loaded.first().map(|l| l.model.spec);
        let mut l = load_run(r, opts.elements, &grid, &og, spec)?;
        l.model.poses = opts.pose_noise.apply(&l.true_poses, i);
        if opts.poses_from != PosesFrom::Manifest {
            let noise = OdometryNoise {
                seed: (opts.odometry.seed) ^ (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                ..opts.odometry
            };
            let est = estimate_poses(&l, &noise, grid.cell_m, opts.poses_from)?;
            l.model.poses = (est.poses.iter())
                .map(|p| Pose {
                    x_m: p.x,
                    y_m: p.y,
                    heading_deg: p.theta.to_degrees(),
                })
                .collect();
            l.slam = Some((est, noise, opts.poses_from));
        }
        loaded.push(l);
    }
    let reference = loaded[0].layout.rasterize(grid.cell_m, grid.margin_m);
    if reference.spec != loaded[0].model.spec {
        return Err(Error::param("cell_m", "reference grid mismatch"));
    }
    Ok((loaded, reference))
}

/// The regions of loaded runs, from the poses their data were recorded at and the first
/// run's layout, with the first run's truth objects when it has a truth
/// ([`find_truth`]; an unreadable truth is an error) and, for `simulate`'s truth, its
/// detectable returns at the first run's detector threshold ([`detectable_returns`]).
pub fn runs_regions(loaded: &[LoadedRun], reference: &ReferenceMap) -> Result<Regions> {
    let models: Vec<ObservationModel> = loaded
        .iter()
        .map(|l| {
            let mut m = l.model.clone();
            m.poses = l.true_poses.clone();
            m
        })
        .collect();
    let refs: Vec<&ObservationModel> = models.iter().collect();
    let layout = &loaded[0].layout;
    let truth = find_truth(&loaded[0].campaign.path, &loaded[0].energy_path);
    let objects = match &truth {
        Some(dir) => Some(load_objects(dir, layout, reference.spec)?),
        None => None,
    };
    let detectable = match truth.as_deref().and_then(truth_rays) {
        Some(rays) => {
            let (threshold, k0) = (
                loaded[0].detector.threshold,
                window_kernel(&loaded[0].campaign)?[0],
            );
            let period_ns = 1e9 / loaded[0].campaign.manifest.band.step_hz();
            // the file's identity (path, length, modification time) and every input
            let stamp = std::fs::metadata(&rays)
                .ok()
                .map(|m| (m.len(), m.modified().ok()));
            let key = format!(
                "{rays:?} {stamp:?} {} {threshold:?} {k0:?} {period_ns:?} {layout:?}",
                models[0].memo_key()
            );
            Some(DETECTABLE_MEMO.get_or(key, || {
                detectable_returns(&rays, &models[0], threshold, k0, period_ns, reference)
            })?)
        }
        None => None,
    };
    Ok(Regions {
        observable: observable_region(&refs, layout),
        building: building_region(layout, reference),
        edge_band: layout.edge_band(reference),
        objects,
        detectable,
    })
}

/// The poses of run `l` from an odometry drawn from the manifest's poses with `noise`:
/// its dead reckoning (`from` odometry), or estimated from the sweeps as well
/// ([`crate::slam::run`]: each pose's detections by the run's detector, matched on a field
/// of `cell_m`).
fn estimate_poses(
    l: &LoadedRun,
    noise: &OdometryNoise,
    cell_m: f64,
    from: PosesFrom,
) -> Result<Estimate> {
    let truth: Vec<_> = l.true_poses.iter().map(pose2).collect();
    let odo = Odometry::simulate(&truth, &noise.check()?);
    if from == PosesFrom::Odometry {
        // the dead reckoning alone, its covariances the odometry graph's
        let mut g = odo.graph()?;
        let sol = g.optimise(&SolveParams::default().check()?)?;
        return Ok(Estimate {
            poses: g.poses,
            covariances: sol.covariances,
            dead_reckoning: odo.dead_reckoning(),
            matched: vec![false; truth.len()],
        });
    }
    // the scans a few positions at a time (the table streamed, as the mappers read it)
    let header = l.energy.header();
    let mut scans: Vec<Scan> = Vec::with_capacity(header.positions);
    for batch in position_batches(header.positions) {
        let part = l.energy.load(batch.start, batch.end)?;
        scans
            .extend(batch.map(|p| Scan::from_detections(&part, &l.detector.detect_pose(&part, p))));
    }
    estimate(
        &odo,
        &scans,
        cell_m,
        steering_step_rad(&header.angles_rel_deg),
        &SolveParams::default().check()?,
    )
}

/// One run's poses from an odometry (`--poses-from odometry|sweeps`), in `metrics.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlamSummary {
    /// `odometry` (dead reckoning) or `sweeps` (estimated).
    pub poses_from: String,
    /// σ of x and y per odometry step, m.
    pub odometry_step_m: f64,
    /// σ of the heading per step, degrees.
    pub odometry_step_deg: f64,
    /// Seed of this run's odometry draws (`--pose-seed` mixed with the run's index).
    pub odometry_seed: u64,
    /// Position RMSE against the manifest's poses of the dead reckoning, m.
    pub rmse_dead_reckoning_m: f64,
    /// … of the estimated poses, m.
    pub rmse_estimated_m: f64,
    /// Poses whose scan was matched to the map (the first never is).
    pub matched: usize,
    /// Poses.
    pub poses: usize,
}

/// The runs' [`SlamSummary`] (none with `--poses-from manifest`); writes `poses.csv` in
/// `out` when there is one: per run and pose the estimated pose with its standard
/// deviations and x–y covariance, the dead reckoning and the manifest's pose.
pub fn slam_summaries(out: &Path, loaded: &[LoadedRun]) -> Result<Vec<SlamSummary>> {
    let mut rows = String::from(
        "run,pose,x_m,y_m,heading_deg,sd_x_m,sd_y_m,sd_heading_deg,cov_xy_m2,dead_x_m,dead_y_m,dead_heading_deg,true_x_m,true_y_m,true_heading_deg,matched\n",
    );
    let mut out_rows = Vec::new();
    for (i, l) in loaded.iter().enumerate() {
        let Some((est, noise, from)) = &l.slam else {
            continue;
        };
        let truth: Vec<_> = l.true_poses.iter().map(pose2).collect();
        for (k, ((p, c), (d, t))) in (est.poses.iter().zip(&est.covariances))
            .zip(est.dead_reckoning.iter().zip(&l.true_poses))
            .enumerate()
        {
            rows.push_str(&format!(
                "{i},{k},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                p.x,
                p.y,
                p.theta.to_degrees(),
                c[(0, 0)].max(0.0).sqrt(),
                c[(1, 1)].max(0.0).sqrt(),
                c[(2, 2)].max(0.0).sqrt().to_degrees(),
                c[(0, 1)],
                d.x,
                d.y,
                d.theta.to_degrees(),
                t.x_m,
                t.y_m,
                t.heading_deg,
                est.matched[k]
            ));
        }
        out_rows.push(SlamSummary {
            poses_from: from.name().to_string(),
            odometry_step_m: noise.step_m,
            odometry_step_deg: noise.step_deg,
            odometry_seed: noise.seed,
            rmse_dead_reckoning_m: position_rmse(&est.dead_reckoning, &truth),
            rmse_estimated_m: position_rmse(&est.poses, &truth),
            matched: est.matched.iter().filter(|m| **m).count(),
            poses: est.poses.len(),
        });
    }
    if !out_rows.is_empty() {
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
        crate::io::write_bytes(&out.join("poses.csv"), rows.as_bytes())?;
    }
    Ok(out_rows)
}
