//! Occupancy grids (DESIGN §2 "Mapping"): log-odds maps from energy matrices, with the
//! side-lobe-aware inverse sensor model (`og`) and the classic boresight-only baseline
//! (`og-boresight`).
//!
//! Takes an [`ObservationModel`], the run's [`EnergyMatrix`] and [`OgParams`]; gives a
//! [`LogOddsMap`] (log-odds per cell, the cells that got evidence) and [`OgStats`].
//!
//! Equations and choices:
//! * log-odds l = ln(p/(1−p)), prior l0 = ln(p0/(1−p0)) (p0 = 0.5 by default), increments
//!   l_occ = ln(p_occ/(1−p_occ)), l_free = ln(p_free/(1−p_free)); a run's log-odds are
//!   clamped to ±`clamp` after every increment;
//! * detector per (pose, direction, bin): energy E_k > η_E, η_E the (1 − P_fa) quantile of
//!   the noise-only bin energy, modelled as Gamma(shape TW·N_p, mean N0·TW) (mean N0·TW,
//!   variance N0²·TW/N_p, the energy detector's statistics with the stored mean over N_p
//!   pulses); bins before `min_bin` (coupling gate plus the window kernel's half-width) are
//!   not used; a detection must also be a local maximum of the profile not explained by the
//!   window kernel's range side lobes of a stronger bin ([`Detector`]), so one echo gives
//!   one detected bin;
//! * `og` (side-lobe aware): a detection in bin k of direction d is first tested against the
//!   other directions of the same scan: it is *explained by a side lobe* when
//!   E_d(k) < β_s·w_d(θ_d')·max_{|k'−k|≤1} E_d'(k') for some direction d' outside the main
//!   lobe of d (w_d(θ_d') the two-way weight of d towards the boresight of d', β_s =
//!   `side_db`, 0 dB); the *main-lobe occluder* of the scan is its strongest detection not
//!   so explained (the first of equals); the cells with w ≥ `free_db` (−10 dB) of every bin
//!   before it get Δl_i = l_free·s_{k,i}·w_i (a cell
//!   wholly in front of it on boresight gets l_free once; weaker illumination, weaker free
//!   evidence); every detection credits the illuminated cells of its
//!   range ring (main and side lobes down to −40 dB, [`crate::mapping::grid::Beam`]) with
//!   Δl_i = l_occ·r_i, r_i = w_i·s_{k,i}·p_i / Σ_j w_j·s_{k,j}·p_j (two-way weight × the
//!   cell's share of the bin × current belief: one cause per detection shared by
//!   responsibility, not a blur by the pattern); for a side-lobe detection before the first
//!   occluder the main-lobe cells (w ≥ −3 dB) are left out of the ring (they were just
//!   found free).
//!   Bins after the occluder without a detection give no evidence (they may be shadowed).
//!   Why the strongest and not the first detection: at 60 GHz walls and objects are opaque,
//!   so the surface the main lobe meets first returns its echo at the full two-way main-lobe
//!   gain, and an earlier but weaker detection is more likely leakage the side-lobe test
//!   cannot reject (a very strong echo at another bearing: the metal cabinet's corner or the
//!   specular foot of a wall, 30-45 dB stronger in its own direction and seen through far
//!   side lobes, quantisation lobes and nulls filled in over the 6 GHz band, where the
//!   centre-frequency pattern underestimates the leakage; or multipath). With the first
//!   detection as the occluder such leaks, which appear at the same short range in almost
//!   every direction, ended the free evidence a few decimetres from the radar, so the
//!   corridor's interior was never cleared and kept the occupancy credit of later echoes:
//!   at N = 100 the map had 3x too many occupied cells (observable precision 0.26, F1 0.40
//!   vs 0.47 at N = 16). The choice has no constant and never reads the reference; its cost
//!   is that a weak true first surface at the edge of a wide main lobe is cleared (N = 16:
//!   observable F1 0.47 → 0.41, still above the boresight baseline);
//! * `og-boresight` (baseline, the classic laser-like model): only the cells crossed by the
//!   boresight ray; a cell gets l_occ if any bin the ray spends in it is detected, l_free if
//!   the ray leaves it before the first detected bin;
//! * order and determinism: poses are processed in order; the beliefs p_i used by the
//!   responsibilities are those at the start of the pose's scan (a scan is one observation),
//!   the directions' increments are computed in parallel from that snapshot and added in
//!   direction order, so maps are bit-identical for any number of threads;
//! * binary map: occupied when p > η = 0.5 (more likely occupied than free), a rule that
//!   never looks at the reference; cells without evidence stay at the prior and count as
//!   free in binary maps;
//! * fusion ([`fuse`]): each run is mapped on its own from the prior, and the fused log-odds
//!   are l0 + Σ_runs (l_run − l0), the sum of the runs' evidence (not clamped).

use crate::energy::{EnergyMatrix, EnergyMeta};
use crate::error::{Error, Result};
use crate::mapping::grid::{Beam, ObservationModel, PoseGeometry};
use crate::params::{ParamGuard, Valid};
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Gamma};
use std::time::Instant;

/// Inverse sensor model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Side-lobe-aware occupancy grid (responsibilities over the range ring).
    Og,
    /// Boresight-only baseline.
    OgBoresight,
    /// EKF over the RRCS per cell ([`crate::mapping::ekf`]; not an inverse sensor model:
    /// [`og_map`] refuses it, [`crate::mapping::run_map`] dispatches it).
    Ekf,
}

impl Method {
    /// Command-line / file name.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Og => "og",
            Method::OgBoresight => "og-boresight",
            Method::Ekf => "ekf",
        }
    }
    /// Parse a name (`og`, `og-boresight`, `ekf`).
    pub fn parse(s: &str) -> Result<Method> {
        match s {
            "og" => Ok(Method::Og),
            "og-boresight" => Ok(Method::OgBoresight),
            "ekf" => Ok(Method::Ekf),
            other => Err(Error::param(
                "method",
                format!("unknown method `{other}` (og|og-boresight|ekf)"),
            )),
        }
    }
}

/// Occupancy-grid parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OgParams {
    /// Prior occupancy probability p0 (0.5).
    pub prior: f64,
    /// Detector false-alarm probability per bin (1e-3).
    pub pfa: f64,
    /// Inverse-sensor occupancy probability of a detection (0.9 → l_occ = 2.20).
    pub p_occ: f64,
    /// Inverse-sensor probability of a cell in front of the first detection (0.35 →
    /// l_free = −0.62).
    pub p_free: f64,
    /// Log-odds clamp (±10).
    pub clamp: f64,
    /// Range-side-lobe masking margin β of the detector, dB (10).
    pub mask_db: f64,
    /// Margin of the side-lobe explanation test, dB (0): a detection is explained by a side
    /// lobe when E_d < 10^(side_db/10)·w_d(θ_d')·E_d'.
    pub side_db: f64,
    /// Lowest two-way weight of a cell that gets free evidence, dB (−10); the evidence is
    /// l_free·s·w (weighted by the two-way pattern).
    pub free_db: f64,
    /// Passes of the side-lobe-aware model over the run (1; a pass > 1 restarts from the prior
    /// and takes its responsibilities from the previous pass's final map).
    pub passes: usize,
}

impl Default for OgParams {
    fn default() -> Self {
        OgParams {
            prior: 0.5,
            pfa: 1e-3,
            p_occ: 0.9,
            p_free: 0.35,
            clamp: 10.0,
            mask_db: 10.0,
            passes: 1,
            side_db: 0.0,
            free_db: -10.0,
        }
    }
}

fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// Logistic function p = 1/(1 + e^{−l}).
pub fn sigmoid(l: f64) -> f64 {
    1.0 / (1.0 + (-l).exp())
}

/// Occupancy-grid parameters that passed [`ParamGuard::check`].
pub type OgValid = Valid<OgParams>;

impl ParamGuard for OgParams {
    type Checked = OgValid;

    /// Prior in (0, 1) with log-odds inside the clamp, P_fa in (0, 0.5], p_occ in
    /// (0.5, 1), p_free in (0, 0.5), clamp > 0, masking margin ≥ 0 dB, free level ≤ 0 dB,
    /// side-lobe margin finite, passes in 1..=10.
    fn check(&self) -> Result<OgValid> {
        let open01 = |v: f64| v.is_finite() && v > 0.0 && v < 1.0;
        if !open01(self.prior) {
            return Err(Error::param("prior", "must be in (0, 1)"));
        }
        if !(open01(self.pfa) && self.pfa <= 0.5) {
            return Err(Error::param("pfa", "must be in (0, 0.5]"));
        }
        if !(open01(self.p_occ) && self.p_occ > 0.5) {
            return Err(Error::param("p_occ", "must be in (0.5, 1)"));
        }
        if !(open01(self.p_free) && self.p_free < 0.5) {
            return Err(Error::param("p_free", "must be in (0, 0.5)"));
        }
        if !(self.clamp.is_finite() && self.clamp > 0.0) {
            return Err(Error::param("clamp", "must be > 0"));
        }
        if !(self.mask_db.is_finite() && self.mask_db >= 0.0) {
            return Err(Error::param("mask_db", "must be >= 0 dB"));
        }
        if !(self.free_db.is_finite() && self.free_db <= 0.0) {
            return Err(Error::param("free_db", "must be <= 0 dB"));
        }
        if !self.side_db.is_finite() {
            return Err(Error::param("side_db", "must be finite"));
        }
        if self.passes == 0 || self.passes > 10 {
            return Err(Error::param("passes", "must be in 1..=10"));
        }
        if logit(self.prior).abs() >= self.clamp {
            return Err(Error::param("prior", "prior log-odds beyond the clamp"));
        }
        Ok(Valid::new(*self))
    }
}

impl OgParams {
    /// Prior log-odds l0.
    pub fn l0(&self) -> f64 {
        logit(self.prior)
    }
    /// Occupied increment l_occ.
    pub fn l_occ(&self) -> f64 {
        logit(self.p_occ)
    }
    /// Free increment l_free (negative).
    pub fn l_free(&self) -> f64 {
        logit(self.p_free)
    }
}

/// Energy threshold of the per-bin detector at false-alarm rate `pfa`: the (1 − pfa)
/// quantile of Gamma(shape TW·N_p, rate N_p/N0). `file` names the energy table in errors.
pub fn detection_threshold(meta: &EnergyMeta, pfa: f64, file: &std::path::Path) -> Result<f64> {
    if !(meta.n0.is_finite() && meta.n0 > 0.0) {
        return Err(Error::input(
            file,
            "metadata `n0` must be a positive number",
        ));
    }
    if !(meta.tw.is_finite() && meta.tw > 0.0) || meta.pulses == 0 {
        return Err(Error::input(
            file,
            "metadata `tw`/`pulses` must be positive",
        ));
    }
    let shape = meta.tw * meta.pulses as f64;
    let rate = meta.pulses as f64 / meta.n0;
    let g = Gamma::new(shape, rate)
        .map_err(|e| Error::input(file, format!("noise statistics: {e}")))?;
    let t = g.inverse_cdf(1.0 - pfa);
    if !t.is_finite() || t <= 0.0 {
        return Err(Error::input(
            file,
            "could not compute the detection threshold",
        ));
    }
    Ok(t)
}

/// The per-bin energy detector shared by both inverse sensor models.
///
/// Bin k is a detection when (1) E_k > η_E (noise threshold at the false-alarm rate),
/// (2) E_k is a local maximum of the profile (E_k ≥ E_{k−1}, E_k > E_{k+1}, k − 1 usable):
/// one detection
/// per echo, at its peak, instead of the window kernel's 4-5 bins, and (3) E_k is not
/// explained by the window kernel's range side lobes of a stronger bin j:
/// E_k ≥ β·E_j·K(|k − j|) for every j within ±M bins, K the bin-averaged kernel of a point
/// echo normalised to its peak (from the run's band and processing), β = `mask_db` (10 dB:
/// the kernel seen through frequency-dependent patterns is wider than the ideal one).
#[derive(Debug, Clone)]
pub struct Detector {
    /// Noise threshold η_E.
    pub threshold: f64,
    /// Kernel K(m), m = 0..=M (K(0) = 1).
    pub kernel: Vec<f64>,
    /// Margin β (linear).
    pub margin: f64,
    /// First usable bin.
    pub min_bin: usize,
}

impl Detector {
    /// Detector from the threshold, the window kernel (`kernel[m]` = energy at m bins from the
    /// peak, any scale) and the masking margin in dB. Kernel values below −80 dB of the peak
    /// are dropped.
    pub fn new(threshold: f64, kernel: &[f64], mask_db: f64, min_bin: usize) -> Detector {
        let k0 = kernel
            .first()
            .copied()
            .unwrap_or(1.0)
            .max(f64::MIN_POSITIVE);
        let mut k: Vec<f64> = kernel.iter().map(|v| v / k0).collect();
        while k.len() > 1 && k[k.len() - 1] < 1e-8 {
            k.pop();
        }
        k.truncate(32);
        Detector {
            threshold,
            kernel: k,
            margin: 10f64.powf(mask_db / 10.0),
            min_bin,
        }
    }

    /// Detections of one profile (true = detected), bins before `min_bin` never.
    pub fn detect(&self, prof: &[f64], out: &mut Vec<bool>) {
        let n = prof.len();
        out.clear();
        out.resize(n, false);
        let m = self.kernel.len();
        // k − 1 must be usable too: a profile still falling at the first usable bin is the
        // tail of a gated echo, not a new one
        for k in self.min_bin + 1..n {
            let e = prof[k];
            if e <= self.threshold || prof[k - 1] > e {
                continue;
            }
            if k + 1 < n && prof[k + 1] >= e {
                continue;
            }
            let lo = k.saturating_sub(m - 1);
            let hi = (k + m).min(n);
            let masked = (lo..hi)
                .any(|j| prof[j] > e && e < self.margin * prof[j] * self.kernel[j.abs_diff(k)]);
            if !masked {
                out[k] = true;
            }
        }
    }
}

/// A log-odds occupancy map.
#[derive(Debug, Clone, PartialEq)]
pub struct LogOddsMap {
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Prior log-odds l0.
    pub l0: f64,
    /// Log-odds per cell (row-major, row 0 = lowest y).
    pub logodds: Vec<f64>,
    /// Cells that received any evidence.
    pub observed: Vec<bool>,
}

impl LogOddsMap {
    /// A map at the prior.
    pub fn prior(rows: usize, cols: usize, l0: f64) -> LogOddsMap {
        LogOddsMap {
            rows,
            cols,
            l0,
            logodds: vec![l0; rows * cols],
            observed: vec![false; rows * cols],
        }
    }
    /// Occupancy probabilities.
    pub fn probs(&self) -> Vec<f64> {
        self.logodds.iter().map(|&l| sigmoid(l)).collect()
    }
    /// Binary map: occupied when p > 0.5 (l > 0).
    pub fn binary(&self) -> Vec<bool> {
        self.logodds.iter().map(|&l| l > 0.0).collect()
    }
}

/// Work done by a mapper.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct OgStats {
    /// (pose, direction) scans processed.
    pub scans: u64,
    /// Detected bins.
    pub detections: u64,
    /// Cell updates (log-odds increments applied).
    pub cell_updates: u64,
    /// (cell, bin) entries evaluated by the inverse sensor model (beam entries for `og`,
    /// ray cells for `og-boresight`).
    pub entries: u64,
    /// Wall time, s.
    pub seconds: f64,
}

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

/// Fuse runs mapped on the same grid: l = l0 + Σ_runs (l_run − l0) (runs in order).
pub fn fuse(runs: &[LogOddsMap]) -> Result<LogOddsMap> {
    let first = runs
        .first()
        .ok_or_else(|| Error::param("runs", "nothing to fuse"))?;
    let mut out = LogOddsMap::prior(first.rows, first.cols, first.l0);
    for r in runs {
        if r.rows != first.rows || r.cols != first.cols || r.l0 != first.l0 {
            return Err(Error::param(
                "runs",
                "runs must share the grid and the prior to be fused",
            ));
        }
    }
    for (i, l) in out.logodds.iter_mut().enumerate() {
        let mut acc = first.l0;
        for r in runs {
            acc += r.logodds[i] - r.l0;
        }
        *l = acc;
        out.observed[i] = runs.iter().any(|r| r.observed[i]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_round_trip() {
        for m in [Method::Og, Method::OgBoresight, Method::Ekf] {
            assert_eq!(Method::parse(m.name()).unwrap(), m);
        }
        assert!(Method::parse("ekf2").is_err());
    }

    #[test]
    fn params_check() {
        assert!(OgParams::default().check().is_ok());
        let bad = OgParams {
            prior: 1.0,
            ..Default::default()
        };
        assert!(bad.check().unwrap_err().to_string().contains("prior"));
    }
}
