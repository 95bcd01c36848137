//! The inverse sensor models over one run: side-lobe aware (`og`) and boresight only
//! (`og-boresight`), see [`crate::og`] for the equations; [`og_map`] and
//! [`og_map_stats`] map a run scan by scan.

use super::angular::{AngularModel, Components, MIN_AFFINITY};
use super::{sigmoid, Detector, LogOddsMap, Method, OgStats, OgValid};
use crate::energy::{EnergyMatrix, EnergySource};
use crate::error::{Error, Result};
use crate::grid::{
    Beam, ObservationModel, Occlusion, PoseGeometry, ScanEchoes, SilentBound, Visibility,
};
use rayon::prelude::*;
use std::time::Instant;

/// One scan's increments (cell, Δl), detections, detections withheld and evaluated entries.
type ScanResult = (Vec<(u32, f32)>, u64, u64, u64);

/// Side-lobe-aware increments of one scan (beam restricted to what it sees, detections,
/// occluder bin `first` (`bins` when none), last observed bin `last`, visibility) into
/// `out`: free evidence in the bins before `first`, occupancy credit from the detections
/// from `first` to `last`; returns (detections, detections withheld: before `first` or
/// after `last`).
#[allow(clippy::too_many_arguments)]
fn scan_og(
    beam: &Beam,
    det: &[bool],
    first: usize,
    last: usize,
    vis: &Visibility,
    belief: &[f32],
    k: &IncrementConstants,
    credit: Option<&CreditFn<'_>>,
    out: &mut Vec<(u32, f32)>,
) -> (u64, u64) {
    let bins = det.len().min(beam.ptr.len() - 1);
    let lf = k.l_free as f32;
    for b in k.min_bin..first.min(bins) {
        for j in beam.bin_range(b) {
            let w = beam.weight[j];
            if w >= k.free_w && vis.clearable(beam.cell[j]) {
                out.push((beam.cell[j], lf * beam.share[j] * w.min(1.0)));
            }
        }
    }
    let (mut dets, mut withheld) = (0, 0);
    for (b, _) in det
        .iter()
        .enumerate()
        .take(bins)
        .skip(k.min_bin)
        .filter(|x| *x.1)
    {
        dets += 1;
        if b < first || b > last {
            // before the occluder: weaker than it (or explained by a side lobe), leakage of
            // a strong echo at another bearing (credited by that direction's own scan) or a
            // weak surface the main lobe just cleared; beyond it plus the guard: behind the
            // first opaque surface of this beam. Either way not evidence of occupancy here
            withheld += 1;
            continue;
        }
        let rg = beam.bin_range(b);
        // the ring's cells that may hold the echo (at most `credit_depth` behind the
        // polygon; every visible one with `guard`, +∞)
        let holds = |c: u32| vis.depth[c as usize] <= k.credit_depth;
        // the echo's bearings (none: leakage of an echo another direction explains)
        let aff = match credit {
            Some(f) => match f(b, &beam.cell[rg.clone()]) {
                Some(a) => Some(a),
                None => {
                    withheld += 1;
                    continue;
                }
            },
            None => None,
        };
        let start = rg.start;
        let a = |j: usize| aff.as_ref().map_or(1.0, |a| a[j - start]);
        // (ring: a = 1 exactly, the products in the order they always had)
        let mut denom = 0.0f32;
        let mut near_echo = false;
        for j in rg.clone() {
            if holds(beam.cell[j]) {
                denom += beam.weight[j] * beam.share[j] * belief[beam.cell[j] as usize] * a(j);
                near_echo |= a(j) as f64 >= MIN_AFFINITY;
            }
        }
        // an echo on no cell the ring may credit (behind the polygon) is not moved to one
        // far from its bearing
        if aff.is_some() && !near_echo {
            withheld += 1;
            continue;
        }
        if denom <= 0.0 {
            continue;
        }
        let scale = k.l_occ as f32 / denom;
        for j in rg.filter(|&j| holds(beam.cell[j]) && a(j) > 0.0) {
            let c = beam.cell[j];
            out.push((
                c,
                scale * beam.weight[j] * beam.share[j] * belief[c as usize] * a(j),
            ));
        }
    }
    (dets, withheld)
}

/// Per detected bin and the cells of its ring's entries: the entries' affinities with the
/// echoes fitted from this direction, or None when it fitted none.
type CreditFn<'a> = dyn Fn(usize, &[u32]) -> Option<Vec<f32>> + Sync + 'a;

/// The inverse sensor model's constants.
struct IncrementConstants {
    l_occ: f64,
    l_free: f64,
    free_w: f32,
    min_bin: usize,
    bound_silent: SilentBound,
    /// Deepest behind the polygon a cell gets occupancy credit, m (+∞: every visible cell).
    credit_depth: f32,
    /// Cell side, m.
    cell_m: f64,
    /// Range of one bin, m.
    bin_m: f64,
}

/// Boresight-only increments of one scan into `out`.
fn scan_boresight(
    ray: &[crate::grid::RayCell],
    det: &[bool],
    min_bin: usize,
    l_occ: f64,
    l_free: f64,
    out: &mut Vec<(u32, f32)>,
) -> u64 {
    let bins = det.len();
    let first = (min_bin..bins).find(|&k| det[k]).unwrap_or(bins);
    let dets = (first..bins).filter(|&k| det[k]).count() as u64;
    for rc in ray {
        let (lo, hi) = (rc.bin_lo as usize, (rc.bin_hi as usize).min(bins - 1));
        if (hi as isize) < first as isize {
            out.push((rc.cell, l_free as f32));
        } else if lo <= hi && (lo..=hi).any(|k| det[k]) {
            out.push((rc.cell, l_occ as f32));
        }
    }
    dets
}

/// Map one run with the run's [`Detector`]; `progress(done, total)` is called after each
/// pose.
pub fn og_map(
    model: &ObservationModel,
    em: &dyn EnergySource,
    params: &OgValid,
    method: Method,
    detector: &Detector,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<LogOddsMap> {
    og_map_stats(model, em, params, method, detector, progress).map(|r| r.0)
}

/// [`og_map`] with the work statistics. The energies are loaded a batch of poses at a time
/// (a table read from its file never needs to be held whole).
pub fn og_map_stats(
    model: &ObservationModel,
    src: &dyn EnergySource,
    params: &OgValid,
    method: Method,
    detector: &Detector,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(LogOddsMap, OgStats)> {
    if method == Method::Ekf {
        return Err(Error::param(
            "method",
            "ekf is not an occupancy-grid model (use mapping::ekf)",
        ));
    }
    let np = model.poses.len();
    let nd = model.directions();
    let em = src.header();
    if em.positions != np || em.directions() != nd {
        return Err(Error::param(
            "energy",
            format!(
                "{} positions x {} directions, observation model has {np} x {nd}",
                em.positions,
                em.directions()
            ),
        ));
    }
    let t0 = Instant::now();
    let spec = model.spec;
    let ctx = ScanContext::new(model, params, method, detector);
    let mut stats = OgStats::default();
    let mut map = LogOddsMap::prior(spec.rows, spec.cols, params.l0());
    let mut belief: Vec<f32> = Vec::new();
    // pose geometries are independent of the map: build them a batch at a time in parallel
    for std::ops::Range { start: p0, end: p1 } in position_batches(np) {
        let part = src.load(p0, p1)?;
        let geoms: Vec<_> = if method == Method::Og {
            (p0..p1)
                .into_par_iter()
                .map(|p| Some(model.pose_geometry(p)))
                .collect()
        } else {
            (p0..p1).map(|_| None).collect()
        };
        for (p, geom) in (p0..p1).zip(geoms) {
            if method == Method::Og {
                map.logodds
                    .par_iter()
                    .map(|&l| sigmoid(l) as f32)
                    .collect_into_vec(&mut belief);
            }
            let scans = ctx.scan_pose(&part, p, geom.as_ref(), &belief);
            apply_scans(&mut map, &mut stats, scans, ctx.clamp);
            progress(p + 1, np);
        }
    }
    stats.seconds = t0.elapsed().as_secs_f64();
    Ok((map, stats))
}

/// The runs of positions `0..np` a streamed energy table is read in: two per thread at a
/// time (at least 2), so a batch's per-pose work fills the pool while only the batch's
/// energies are held.
pub(crate) fn position_batches(np: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let batch = (2 * rayon::current_num_threads()).max(2);
    (0..np)
        .step_by(batch)
        .map(move |p0| p0..(p0 + batch).min(np))
}

/// What the scans of a run share: the model, the detector, the occlusion model and the
/// inverse sensor model's constants.
struct ScanContext<'a> {
    model: &'a ObservationModel,
    detector: &'a Detector,
    method: Method,
    clamp: f64,
    /// Belief above which a cell is a mapped surface: max(0.5, p0).
    surface_p: f32,
    inc: IncrementConstants,
    occlusion: Occlusion,
    /// The echo-bearing model when detections credit their echoes' bearings.
    angular: Option<AngularModel>,
}

impl<'a> ScanContext<'a> {
    fn new(
        model: &'a ObservationModel,
        params: &OgValid,
        method: Method,
        detector: &'a Detector,
    ) -> ScanContext<'a> {
        let min_bin = model.min_bin.max(detector.min_bin);
        let occlusion = Occlusion::new(model, min_bin, params.side_db);
        ScanContext {
            model,
            detector,
            method,
            clamp: params.clamp,
            surface_p: (super::sigmoid(params.l0()).max(0.5)) as f32,
            inc: IncrementConstants {
                l_occ: params.l_occ(),
                l_free: params.l_free(),
                free_w: 10f64.powf(params.free_db / 10.0) as f32,
                min_bin,
                bound_silent: params.bound_silent,
                credit_depth: params.credit_depth_m.map_or(f32::INFINITY, |x| x as f32),
                cell_m: model.spec.cell_m,
                bin_m: crate::units::C0 * model.bin_width_s / 2.0,
            },
            occlusion,
            angular: (params.credit == super::OgCredit::Echo).then(|| AngularModel::new(model)),
        }
    }

    /// The increments of every direction of pose `p` (in parallel, in direction order)
    /// from its energies `em` and the beliefs `bel` (`geom`: the pose's geometry, for `og`).
    fn scan_pose(
        &self,
        em: &EnergyMatrix,
        p: usize,
        geom: Option<&PoseGeometry>,
        bel: &[f32],
    ) -> Vec<ScanResult> {
        let nd = self.model.directions();
        let dets = self.detector.detect_pose(em, p);
        match (geom, self.method) {
            (Some(g), Method::Og) => {
                let comps = self
                    .angular
                    .as_ref()
                    .map(|a| a.components(self.model, em, p, &dets, self.detector.threshold));
                // mapped surfaces: more likely occupied than free and above the prior (a
                // prior above 0.5 does not make unobserved cells surfaces)
                let t = self.surface_p;
                let occupied: Vec<bool> = bel.par_iter().map(|&b| b > t).collect();
                let echoes = self
                    .occlusion
                    .echoes(self.model, em, p, dets, Some(&occupied));
                // (the occlusion's min_bin is the scan's, `inc.min_bin`: both are the
                // model's and the detector's larger)
                let vis = self.occlusion.visibility_bounded(
                    self.model,
                    g,
                    &echoes,
                    self.inc.bound_silent,
                );
                (0..nd)
                    .into_par_iter()
                    .map(|d| {
                        if !em.has(p, d) {
                            return (Vec::new(), 0, 0, 0); // no sweep: no evidence
                        }
                        self.scan_direction_og(
                            d,
                            g,
                            &echoes,
                            &vis,
                            bel,
                            comps.as_ref().map(|c| (c, p)),
                        )
                    })
                    .collect()
            }
            _ => (0..nd)
                .into_par_iter()
                .map(|d| {
                    if !em.has(p, d) {
                        return (Vec::new(), 0, 0, 0); // no sweep: no evidence
                    }
                    let ray = self.model.boresight_ray(p, d);
                    let mut out = Vec::new();
                    let dets = scan_boresight(
                        &ray,
                        &dets[d],
                        self.inc.min_bin,
                        self.inc.l_occ,
                        self.inc.l_free,
                        &mut out,
                    );
                    (out, dets, 0, ray.len() as u64)
                })
                .collect(),
        }
    }

    /// The side-lobe-aware increments of direction `d` of a pose's scan (`echo`: the pose's
    /// echo components and its index, with `--og-credit echo`).
    fn scan_direction_og(
        &self,
        d: usize,
        g: &PoseGeometry,
        echoes: &ScanEchoes,
        vis: &Visibility,
        bel: &[f32],
        echo: Option<(&Components, usize)>,
    ) -> ScanResult {
        let bins = echoes.det[d].len();
        let explain = |k: usize, cells: &[u32]| -> Option<Vec<f32>> {
            let (comps, p) = echo?;
            let ex = comps.of_direction(d, k);
            if ex.is_empty() {
                return None;
            }
            let half = self.inc.cell_m / (2.0 * (k as f64 * self.inc.bin_m).max(self.inc.cell_m));
            Some(
                cells
                    .iter()
                    .map(|&c| {
                        let th = self.model.cell_bearing_rad(p, c);
                        Components::affinity(&ex, th, half) as f32
                    })
                    .collect(),
            )
        };
        let credit: Option<&CreditFn<'_>> = echo.is_some().then_some(&explain as &CreditFn<'_>);
        let first = echoes.occluder[d].unwrap_or(bins);
        let last = echoes.last_observed(d, self.occlusion.guard_bins(), bins);
        let beam = self.model.beam_seen(g, d, Some((vis, last)));
        let mut out = Vec::with_capacity(beam.len() / 2);
        let (dets, withheld) = scan_og(
            &beam,
            &echoes.det[d],
            first,
            last,
            vis,
            bel,
            &self.inc,
            credit,
            &mut out,
        );
        (out, dets, withheld, beam.len() as u64)
    }
}

/// Add a pose's scans to the map in direction order (log-odds clamped to ±`clamp` after
/// every increment) and count them.
fn apply_scans(map: &mut LogOddsMap, stats: &mut OgStats, scans: Vec<ScanResult>, clamp: f64) {
    for (inc, dets, withheld, entries) in scans {
        stats.scans += 1;
        stats.entries += entries;
        stats.detections += dets;
        stats.withheld += withheld;
        stats.cell_updates += inc.len() as u64;
        for (c, dl) in inc {
            let c = c as usize;
            map.logodds[c] = (map.logodds[c] + dl as f64).clamp(-clamp, clamp);
            map.observed[c] = true;
        }
    }
}
