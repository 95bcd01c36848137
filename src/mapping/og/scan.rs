//! The inverse sensor models over one run: side-lobe aware (`og`) and boresight only
//! (`og-boresight`), see [`crate::mapping::og`] for the equations; [`og_map`] and
//! [`og_map_stats`] map a run scan by scan.

use super::{sigmoid, Detector, LogOddsMap, Method, OgStats, OgValid};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::mapping::grid::{Beam, ObservationModel, PoseGeometry};
use rayon::prelude::*;
use std::time::Instant;

/// One scan's increments (cell, Δl), detections and evaluated entries.
type ScanResult = (Vec<(u32, f32)>, u64, u64);

/// Side-lobe-aware increments of one scan (beam, detections, profile `prof`) into `out`.
#[allow(clippy::too_many_arguments)]
fn scan_og(
    beam: &Beam,
    det: &[bool],
    prof: &[f64],
    side: &[bool],
    min_bin: usize,
    belief: &[f32],
    l_occ: f64,
    l_free: f64,
    main_w: f32,
    free_w: f32,
    out: &mut Vec<(u32, f32)>,
) -> u64 {
    let bins = det.len().min(beam.ptr.len() - 1);
    // the main-lobe occluder: the strongest detection not explained by a side lobe (the
    // first of equals); weaker earlier detections are left to the side lobes
    let mut first = bins;
    for k in min_bin..bins {
        if det[k] && !side[k] && (first == bins || prof[k] > prof[first]) {
            first = k;
        }
    }
    let lf = l_free as f32;
    for k in min_bin..first {
        let rg = beam.bin_range(k);
        for j in rg {
            let w = beam.weight[j];
            if w >= free_w {
                out.push((beam.cell[j], lf * beam.share[j] * w.min(1.0)));
            }
        }
    }
    let mut dets = 0;
    for (k, _) in det
        .iter()
        .enumerate()
        .take(bins)
        .skip(min_bin)
        .filter(|x| *x.1)
    {
        dets += 1;
        // a side-lobe detection before the first main-lobe one: its main-lobe cells were
        // just found free, so only the side-lobe cells share it
        let side_only = k < first;
        let rg = beam.bin_range(k);
        let mut denom = 0.0f32;
        for j in rg.clone() {
            if side_only && beam.weight[j] >= main_w {
                continue;
            }
            denom += beam.weight[j] * beam.share[j] * belief[beam.cell[j] as usize];
        }
        if denom <= 0.0 {
            continue;
        }
        let scale = l_occ as f32 / denom;
        for j in rg {
            if side_only && beam.weight[j] >= main_w {
                continue;
            }
            let c = beam.cell[j];
            out.push((
                c,
                scale * beam.weight[j] * beam.share[j] * belief[c as usize],
            ));
        }
    }
    dets
}

/// Per bin of direction `d` at pose `p`: true when the detection is explained by a side
/// lobe of `d` towards another direction d' of the same scan: E_d(k) < β·w_d(θ_d')·E_d'(k'),
/// k' within ±1 bin, for a d' outside the main lobe of d (w_d(θ_d') < main-lobe weight).
fn side_lobe_flags(
    em: &EnergyMatrix,
    p: usize,
    d: usize,
    det: &[bool],
    cross: &[Vec<f64>],
    margin: f64,
    main_w: f64,
) -> Vec<bool> {
    let prof = em.profile(p, d);
    let n = prof.len();
    let mut side = vec![false; n];
    for k in 0..n {
        if !det[k] {
            continue;
        }
        let e = prof[k];
        side[k] = (0..cross.len()).any(|d2| {
            if d2 == d {
                return false;
            }
            let w = cross[d][d2];
            if w <= 0.0 || w >= main_w {
                return false;
            }
            let o = em.profile(p, d2);
            let lo = k.saturating_sub(1);
            let hi = (k + 2).min(n);
            let m = o[lo..hi].iter().cloned().fold(0.0, f64::max);
            e < margin * w * m
        });
    }
    side
}

/// Boresight-only increments of one scan into `out`.
fn scan_boresight(
    ray: &[crate::mapping::grid::RayCell],
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
    em: &EnergyMatrix,
    params: &OgValid,
    method: Method,
    detector: &Detector,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<LogOddsMap> {
    og_map_stats(model, em, params, method, detector, progress).map(|r| r.0)
}

/// [`og_map`] with the work statistics.
pub fn og_map_stats(
    model: &ObservationModel,
    em: &EnergyMatrix,
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
    let ctx = ScanContext::new(model, em, params, method, detector);
    let mut stats = OgStats::default();
    let passes = if method == Method::Og {
        params.passes
    } else {
        1
    };
    let mut map = LogOddsMap::prior(spec.rows, spec.cols, params.l0());
    // belief of the previous pass (pass ≥ 2 uses it, fixed, for the responsibilities)
    let mut fixed_belief: Option<Vec<f32>> = None;
    for pass in 0..passes {
        if pass > 0 {
            fixed_belief = Some(map.logodds.par_iter().map(|&l| sigmoid(l) as f32).collect());
            map = LogOddsMap::prior(spec.rows, spec.cols, params.l0());
        }
        let mut belief: Vec<f32> = Vec::new();
        // pose geometries are independent of the map: build them a batch at a time in parallel
        let batch = (2 * rayon::current_num_threads()).max(2);
        let mut p0 = 0;
        while p0 < np {
            let p1 = (p0 + batch).min(np);
            let geoms: Vec<_> = if method == Method::Og {
                (p0..p1)
                    .into_par_iter()
                    .map(|p| Some(model.pose_geometry(p)))
                    .collect()
            } else {
                (p0..p1).map(|_| None).collect()
            };
            for (p, geom) in (p0..p1).zip(geoms) {
                if method == Method::Og && fixed_belief.is_none() {
                    map.logodds
                        .par_iter()
                        .map(|&l| sigmoid(l) as f32)
                        .collect_into_vec(&mut belief);
                }
                let bel: &[f32] = fixed_belief.as_deref().unwrap_or(&belief);
                let scans = ctx.scan_pose(p, geom.as_ref(), bel);
                apply_scans(&mut map, &mut stats, scans, ctx.clamp);
                progress(pass * np + p + 1, passes * np);
            }
            p0 = p1;
        }
    }
    stats.seconds = t0.elapsed().as_secs_f64();
    Ok((map, stats))
}

/// What the scans of a run share: the model, the energy, the detector and the inverse
/// sensor model's constants.
struct ScanContext<'a> {
    model: &'a ObservationModel,
    em: &'a EnergyMatrix,
    detector: &'a Detector,
    method: Method,
    l_occ: f64,
    l_free: f64,
    clamp: f64,
    main_w: f32,
    free_w: f32,
    min_bin: usize,
    side_margin: f64,
    /// cross[d][d'] = two-way weight of direction d towards the boresight of direction d'.
    cross: Vec<Vec<f64>>,
}

impl<'a> ScanContext<'a> {
    fn new(
        model: &'a ObservationModel,
        em: &'a EnergyMatrix,
        params: &OgValid,
        method: Method,
        detector: &'a Detector,
    ) -> ScanContext<'a> {
        let nd = model.directions();
        ScanContext {
            model,
            em,
            detector,
            method,
            l_occ: params.l_occ(),
            l_free: params.l_free(),
            clamp: params.clamp,
            main_w: model.params.main_weight() as f32,
            free_w: 10f64.powf(params.free_db / 10.0) as f32,
            min_bin: model.min_bin.max(detector.min_bin),
            side_margin: 10f64.powf(params.side_db / 10.0),
            cross: (0..nd)
                .map(|d| {
                    (0..nd)
                        .map(|d2| model.weight(d, model.direction_rad(d2)))
                        .collect()
                })
                .collect(),
        }
    }

    /// The increments of every direction of pose `p` (in parallel, in direction order)
    /// from the beliefs `bel` (`geom`: the pose's geometry, for `og`).
    fn scan_pose(&self, p: usize, geom: Option<&PoseGeometry>, bel: &[f32]) -> Vec<ScanResult> {
        let nd = self.model.directions();
        let dets: Vec<Vec<bool>> = (0..nd)
            .into_par_iter()
            .map(|d| {
                let mut det = Vec::new();
                self.detector.detect(self.em.profile(p, d), &mut det);
                det
            })
            .collect();
        (0..nd)
            .into_par_iter()
            .map(|d| self.scan_direction(p, d, &dets[d], geom, bel))
            .collect()
    }

    /// The increments of (pose `p`, direction `d`) with detections `det`.
    fn scan_direction(
        &self,
        p: usize,
        d: usize,
        det: &[bool],
        geom: Option<&PoseGeometry>,
        bel: &[f32],
    ) -> ScanResult {
        let (em, model) = (self.em, self.model);
        let mut out = Vec::new();
        let entries;
        let dets = match (geom, self.method) {
            (Some(g), Method::Og) => {
                let beam = model.beam(g, d);
                entries = beam.len() as u64;
                let side = side_lobe_flags(
                    em,
                    p,
                    d,
                    det,
                    &self.cross,
                    self.side_margin,
                    self.main_w as f64,
                );
                out.reserve(beam.len() / 2);
                scan_og(
                    &beam,
                    det,
                    em.profile(p, d),
                    &side,
                    self.min_bin,
                    bel,
                    self.l_occ,
                    self.l_free,
                    self.main_w,
                    self.free_w,
                    &mut out,
                )
            }
            _ => {
                let ray = model.boresight_ray(p, d);
                entries = ray.len() as u64;
                scan_boresight(&ray, det, self.min_bin, self.l_occ, self.l_free, &mut out)
            }
        };
        (out, dets, entries)
    }
}

/// Add a pose's scans to the map in direction order (log-odds clamped to ±`clamp` after
/// every increment) and count them.
fn apply_scans(map: &mut LogOddsMap, stats: &mut OgStats, scans: Vec<ScanResult>, clamp: f64) {
    for (inc, dets, entries) in scans {
        stats.scans += 1;
        stats.entries += entries;
        stats.detections += dets;
        stats.cell_updates += inc.len() as u64;
        for (c, dl) in inc {
            let c = c as usize;
            map.logodds[c] = (map.logodds[c] + dl as f64).clamp(-clamp, clamp);
            map.observed[c] = true;
        }
    }
}
