//! The raw summary statistics of an energy matrix E[p][d][b] (positions × directions ×
//! bins), computed the same way on the measured and on every simulated matrix. The
//! calibration projects them onto the parameters (semi-automatic ABC, [`super::abc`]), so
//! they need not be individually tuned: they only have to carry the information.
//!
//! With μ = N0·TW the mean noise-bin energy and σ_n = μ/√(TW·N_p) its standard deviation
//! (DESIGN §2), the signal part of a bin is S = E − μ where E > μ + 3σ_n (else 0), a bin is
//! *detected* where E > μ + 10σ_n, and a *peak* is a detected bin above its 8 neighbours in
//! (delay, direction). τ_b = b·T_b; T_0(p) the earliest detected delay of position p after
//! the coupling gate. The summaries ([`NAMES`], in order):
//!
//! * level: ln of the mean S, ln(1 + detected bins), the share of (position, direction)
//!   profiles with a detection, the median over positions of ln(max E/μ);
//! * temporal moments per profile with signal (Bharti, Adeogun & Pedersen 2020):
//!   m0 = Σ_b S, m1 = Σ τ_b S/m0, m2 = (Σ (τ_b − m1)² S/m0)^½ — the mean and sd of ln m0,
//!   the mean and sd of m1 − T_0, the mean m2;
//! * the delay profile after T_0: ln of the share of ΣS in the windows 0–1, 1–3, 3–6, 6–10,
//!   10–15, 15–25, 25–40, > 40 ns (Γ, γ, λ);
//! * peaks: ln(1 + peaks per position), peaks per profile with a detection, the
//!   least-squares slope and intercept of ln(peak power) against τ − T_0, the slope of the
//!   per-5-ns maximum (the clusters' envelope, Γ), the median ln(peak power/μ) (σ);
//! * peak pairs of a position within 6 ns of each other (λ, AoA): ln(pairs per peak),
//!   the share with |Δθ| ≤ 5°, 15°, 30°, the median |Δθ| of pairs within 2 ns, the median
//!   |Δτ| of pairs within 5°; the next peak in delay in the same direction: median ln gap
//!   and the share of gaps under 2 ns;
//! * depth behind the layout's wall: for each peak, R_w − cτ/2 with R_w the range to the
//!   first wall along the direction (the layout, an input): ln of the share of peak power
//!   with depth ≤ −0.2, −0.2–0.15, 0.15–0.4, 0.4–0.8, 0.8–1.5, > 1.5 m; the median depth
//!   of all peaks and of each profile's first peak (d_p);
//! * angles: the mean over positions of the normalised entropy of the angular profile
//!   Σ_b S, and the share of detected bins whose neighbour direction at the same bin is
//!   detected (d_c, AoA).
//!
//! A summary that cannot be formed (no peak, no pair) takes a fixed fallback value, so
//! every vector is finite.
//!
//! [`quantile_summaries`] (the default distance appends them to the 42): the
//! quantiles 10, 25, 50, 75, 90 % (the value at rank round(q·(n − 1)) of the sorted
//! sample) of each component of the predictive check's per-profile set (signal energy,
//! mean delay, RMS delay spread, signal bins, first arrival, peaks, angular power profile;
//! silent profiles as the censored point of [`super::mmd`]) and per-position set (angular
//! spread, share of directions with signal): 7·5 + 2·5 = 45 values, 0 for an empty set.

use crate::campaign::layout::Layout;
use crate::stats::median;
use crate::units::C0;
use geo::Coord;

/// The summaries' names, in order.
pub const NAMES: [&str; 42] = [
    "ln mean S",
    "ln(1 + detected)",
    "profiles with a detection",
    "median ln max E/mu",
    "mean ln m0",
    "sd ln m0",
    "mean m1 - T0",
    "sd m1",
    "mean m2",
    "share 0-1 ns",
    "share 1-3 ns",
    "share 3-6 ns",
    "share 6-10 ns",
    "share 10-15 ns",
    "share 15-25 ns",
    "share 25-40 ns",
    "share > 40 ns",
    "ln(1 + peaks/position)",
    "peaks per profile",
    "peak slope",
    "peak intercept",
    "envelope slope",
    "median ln peak/mu",
    "ln pairs per peak",
    "pairs within 5 deg",
    "pairs within 15 deg",
    "pairs within 30 deg",
    "median |dtheta| (< 2 ns)",
    "median |dtau| (< 5 deg)",
    "median ln gap",
    "gaps < 2 ns",
    "depth <= -0.2 m",
    "depth -0.2-0.15 m",
    "depth 0.15-0.4 m",
    "depth 0.4-0.8 m",
    "depth 0.8-1.5 m",
    "depth > 1.5 m",
    "median depth",
    "median first depth",
    "angular entropy",
    "neighbour detections",
    "ln T0",
];

/// What the summaries need besides the energies: the matrix's shape and axes, the noise
/// statistics and the walls' ranges.
#[derive(Debug, Clone)]
pub struct SummaryContext {
    /// Positions, directions, bins.
    pub np: usize,
    /// Directions.
    pub nd: usize,
    /// Bins.
    pub nb: usize,
    /// Bin width, ns.
    pub bin_ns: f64,
    /// Mean noise-bin energy μ.
    pub mu: f64,
    /// Its standard deviation σ_n.
    pub sdn: f64,
    /// First bin after the coupling gate.
    pub first_bin: usize,
    /// Relative direction angles, degrees.
    pub angles_deg: Vec<f64>,
    /// Range to the first wall per (position, direction), m (NaN: none).
    pub wall_m: Vec<f64>,
}

impl SummaryContext {
    /// The context of a campaign's matrices: poses (x, y, heading deg), relative angles
    /// (deg), bins, bin width (ns), noise mean μ, TW·N_p, gate (ns), layout.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        poses: &[(f64, f64, f64)],
        angles_deg: &[f64],
        nb: usize,
        bin_ns: f64,
        mu: f64,
        tw_pulses: f64,
        gate_ns: f64,
        layout: &Layout,
    ) -> SummaryContext {
        let mut wall_m = Vec::with_capacity(poses.len() * angles_deg.len());
        for &(x, y, h) in poses {
            for a in angles_deg {
                wall_m.push(
                    layout
                        .first_hit(Coord { x, y }, (h + a).to_radians())
                        .map_or(f64::NAN, |w| w.0),
                );
            }
        }
        SummaryContext {
            np: poses.len(),
            nd: angles_deg.len(),
            nb,
            bin_ns,
            mu,
            sdn: mu / tw_pulses.max(1e-12).sqrt(),
            first_bin: ((gate_ns / bin_ns).ceil() as usize).min(nb),
            angles_deg: angles_deg.to_vec(),
            wall_m,
        }
    }
}

fn mean_sd(v: &[f64], fallback: f64) -> (f64, f64) {
    if v.is_empty() {
        return (fallback, 0.0);
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (
        m,
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

/// Least-squares slope and intercept of y on x (fallbacks when fewer than 3 points).
fn line(xy: &[(f64, f64)], fallback: (f64, f64)) -> (f64, f64) {
    if xy.len() < 3 {
        return fallback;
    }
    let n = xy.len() as f64;
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return fallback;
    }
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let b = sxy / sxx;
    (b, my - b * mx)
}

struct Peak {
    d: usize,
    tau: f64,
    ln_p: f64,
}

/// The summaries ([`NAMES`]) of energies `e` (position-major, then direction, then bin).
pub fn summaries(ctx: &SummaryContext, e: &[f64]) -> Vec<f64> {
    let c = Cells::new(ctx, e);
    let mut s = Sums::default();
    let step = if ctx.nd > 1 {
        (ctx.angles_deg[1] - ctx.angles_deg[0]).abs()
    } else {
        1.0
    };
    for p in 0..ctx.np {
        s.add_position(&c, p, step);
    }
    s.finish(ctx)
}

/// The upper edges (ns after T_0) of the delay profile's windows.
const WINDOWS_NS: [f64; 8] = [1.0, 3.0, 6.0, 10.0, 15.0, 25.0, 40.0, f64::INFINITY];

/// The upper edges (m) of the depth classes behind the wall.
const DEPTH_EDGES_M: [f64; 6] = [-0.2, 0.15, 0.4, 0.8, 1.5, f64::INFINITY];

/// The energies as the summaries read them (module docs): a cell's energy E, whether it
/// is detected and its signal S.
struct Cells<'a> {
    /// The matrix's shape, noise and walls.
    ctx: &'a SummaryContext,
    /// The energies (position-major, then direction, then bin).
    e: &'a [f64],
    /// μ + 3σ_n: the signal threshold.
    thr_low: f64,
    /// μ + 10σ_n: the detection threshold.
    thr: f64,
}

impl<'a> Cells<'a> {
    /// Takes the context and the energies; gives their cells with the thresholds.
    fn new(ctx: &'a SummaryContext, e: &'a [f64]) -> Cells<'a> {
        let mu = ctx.mu;
        let thr_low = mu + 3.0 * ctx.sdn;
        let thr = mu + 10.0 * ctx.sdn;
        Cells {
            ctx,
            e,
            thr_low,
            thr,
        }
    }

    /// Takes a cell (position, direction, bin); gives its energy E.
    fn at(&self, p: usize, d: usize, b: usize) -> f64 {
        self.e[(p * self.ctx.nd + d) * self.ctx.nb + b]
    }

    /// Takes a cell; gives whether it is detected (after the gate, E > μ + 10σ_n).
    fn det(&self, p: usize, d: usize, b: usize) -> bool {
        b >= self.ctx.first_bin && self.at(p, d, b) > self.thr
    }

    /// Takes a cell; gives its signal S (E − μ after the gate where E > μ + 3σ_n, else 0).
    fn sig(&self, p: usize, d: usize, b: usize) -> f64 {
        let v = self.at(p, d, b);
        if b >= self.ctx.first_bin && v > self.thr_low {
            v - self.ctx.mu
        } else {
            0.0
        }
    }

    /// Takes a cell and its energy `v`; gives whether it is above its 8 neighbours in
    /// (direction, bin) (ties go to the earlier).
    fn is_peak(&self, p: usize, d: usize, b: usize, v: f64) -> bool {
        let (nd, nb) = (self.ctx.nd, self.ctx.nb);
        let mut is_peak = true;
        'n: for dd in -1i64..=1 {
            for db in -1i64..=1 {
                if dd == 0 && db == 0 {
                    continue;
                }
                let (d2, b2) = (d as i64 + dd, b as i64 + db);
                if d2 < 0 || d2 >= nd as i64 || b2 < 0 || b2 >= nb as i64 {
                    continue;
                }
                let w = self.at(p, d2 as usize, b2 as usize);
                // ties go to the earlier (direction, bin)
                if w > v || (w == v && (dd, db) < (0, 0)) {
                    is_peak = false;
                    break 'n;
                }
            }
        }
        is_peak
    }
}

/// The running sums and samples of the summaries, over the positions in order.
#[derive(Default)]
struct Sums {
    /// ΣS over every cell after the gate.
    total_s: f64,
    /// Detected bins.
    n_det: usize,
    /// Profiles with a detection.
    profiles_det: usize,
    /// Per position, ln(max E/μ).
    ln_max: Vec<f64>,
    /// Per profile with signal, ln(m0/μ).
    ln_m0: Vec<f64>,
    /// Per profile with signal, m1 − T_0.
    m1s: Vec<f64>,
    /// Per profile with signal, m2.
    m2s: Vec<f64>,
    /// ΣS per delay window after T_0 ([`WINDOWS_NS`]).
    shares: [f64; 8],
    /// Peaks.
    peaks_all: usize,
    /// Per peak, (τ − T_0, ln(peak power/μ)).
    peak_xy: Vec<(f64, f64)>,
    /// Per position and 5-ns window, (window start, its largest ln(peak power/μ)).
    env: Vec<(f64, f64)>,
    /// Per peak, ln(peak power/μ).
    ln_peak: Vec<f64>,
    /// Peak pairs within 6 ns.
    pairs: usize,
    /// Of them, within 5°.
    p5: usize,
    /// Within 15°.
    p15: usize,
    /// Within 30°.
    p30: usize,
    /// |Δθ| of the pairs within 2 ns.
    dth2: Vec<f64>,
    /// |Δτ| of the pairs within 5°.
    dtau5: Vec<f64>,
    /// Per peak, the gap to the next peak in delay in its direction.
    gaps: Vec<f64>,
    /// Peak power per depth class ([`DEPTH_EDGES_M`]).
    depth_pow: [f64; 6],
    /// Every peak's depth behind the wall, m.
    depths: Vec<f64>,
    /// Each profile's first peak's depth, m.
    first_depths: Vec<f64>,
    /// Per position with signal, the angular profile's normalised entropy.
    entropy: Vec<f64>,
    /// Detected bins whose next direction at the same bin is detected.
    neigh: usize,
    /// Detected bins with a next direction.
    neigh_of: usize,
    /// Per position with a detection, T_0.
    t0s: Vec<f64>,
}

impl Sums {
    /// Takes the cells, a position and the direction step (degrees); adds the position's
    /// profiles, peaks, angular entropy, envelope and peak pairs.
    fn add_position(&mut self, c: &Cells, p: usize, step: f64) {
        let ctx = c.ctx;
        let (nd, nb, tb) = (ctx.nd, ctx.nb, ctx.bin_ns);
        // T0: the earliest detection of the position
        let t0 = (ctx.first_bin..nb)
            .find(|&b| (0..nd).any(|d| c.det(p, d, b)))
            .map(|b| b as f64 * tb);
        let mut ang = vec![0.0; nd];
        let mut max_e: f64 = 0.0;
        let mut peaks: Vec<Peak> = Vec::new();
        for d in 0..nd {
            self.add_profile(c, p, d, t0, &mut ang, &mut max_e, &mut peaks);
        }
        let mu = ctx.mu;
        self.ln_max.push((max_e / mu).max(1e-12).ln());
        let ta: f64 = ang.iter().sum();
        if ta > 0.0 {
            let h: f64 = ang
                .iter()
                .filter(|a| **a > 0.0)
                .map(|a| {
                    let q = a / ta;
                    -q * q.ln()
                })
                .sum();
            self.entropy.push(h / (nd.max(2) as f64).ln());
        }
        if let Some(t0) = t0 {
            self.t0s.push(t0);
            let mut best = std::collections::BTreeMap::new();
            for pk in &peaks {
                self.peak_xy.push((pk.tau - t0, pk.ln_p));
                let w = ((pk.tau - t0) / 5.0).floor() as i64;
                let slot: &mut f64 = best.entry(w).or_insert(f64::NEG_INFINITY);
                *slot = slot.max(pk.ln_p);
            }
            self.env
                .extend(best.iter().map(|(w, v)| (*w as f64 * 5.0, *v)));
        }
        self.peaks_all += peaks.len();
        self.ln_peak.extend(peaks.iter().map(|p| p.ln_p));
        self.add_pairs(&peaks, step);
    }

    /// Takes the cells, a profile (position `p`, direction `d`) and the position's T_0;
    /// adds the profile's signal, detections, moments and peaks, its signal to the angular
    /// profile `ang`, its largest energy to `max_e` and its peaks to `peaks`.
    #[allow(clippy::too_many_arguments)]
    fn add_profile(
        &mut self,
        c: &Cells,
        p: usize,
        d: usize,
        t0: Option<f64>,
        ang: &mut [f64],
        max_e: &mut f64,
        peaks: &mut Vec<Peak>,
    ) {
        let ctx = c.ctx;
        let (nd, nb, mu, tb) = (ctx.nd, ctx.nb, ctx.mu, ctx.bin_ns);
        let (mut m0, mut m1, mut any) = (0.0, 0.0, false);
        let mut first_peak = true;
        for b in ctx.first_bin..nb {
            let s = c.sig(p, d, b);
            let tau = b as f64 * tb;
            self.total_s += s;
            m0 += s;
            m1 += s * tau;
            ang[d] += s;
            *max_e = max_e.max(c.at(p, d, b));
            if let Some(t0) = t0 {
                let k = WINDOWS_NS.iter().position(|w| tau - t0 < *w).unwrap_or(7);
                self.shares[k] += s;
            }
            if !c.det(p, d, b) {
                continue;
            }
            any = true;
            self.n_det += 1;
            if d + 1 < nd {
                self.neigh_of += 1;
                if c.det(p, d + 1, b) {
                    self.neigh += 1;
                }
            }
            let v = c.at(p, d, b);
            if c.is_peak(p, d, b, v) {
                self.add_peak(ctx, p, d, tau, v, first_peak, peaks);
                first_peak = false;
            }
        }
        if any {
            self.profiles_det += 1;
        }
        if m0 > 0.0 && any {
            let m1v = m1 / m0;
            let m2: f64 = (ctx.first_bin..nb)
                .map(|b| c.sig(p, d, b) * (b as f64 * tb - m1v).powi(2))
                .sum::<f64>()
                / m0;
            self.ln_m0.push((m0 / mu).ln());
            self.m1s.push(m1v - t0.unwrap_or(0.0));
            self.m2s.push(m2.sqrt());
        }
    }

    /// Takes a peak (position, direction, delay ns, energy `v`) and whether it is its
    /// profile's first; adds it to `peaks` and its power to its depth class behind the
    /// wall (when the direction has a wall).
    #[allow(clippy::too_many_arguments)]
    fn add_peak(
        &mut self,
        ctx: &SummaryContext,
        p: usize,
        d: usize,
        tau: f64,
        v: f64,
        first_peak: bool,
        peaks: &mut Vec<Peak>,
    ) {
        let mu = ctx.mu;
        let pw = v - mu;
        peaks.push(Peak {
            d,
            tau,
            ln_p: (pw / mu).ln(),
        });
        let wall = ctx.wall_m[p * ctx.nd + d];
        if wall.is_finite() {
            let depth = wall - C0 * tau * 1e-9 / 2.0;
            let k = DEPTH_EDGES_M.iter().position(|x| depth <= *x).unwrap_or(5);
            self.depth_pow[k] += pw;
            self.depths.push(depth);
            if first_peak {
                self.first_depths.push(depth);
            }
        }
    }

    /// Takes a position's peaks and the direction step (degrees); adds their pairs within
    /// 6 ns and each peak's gap to the next in its direction.
    fn add_pairs(&mut self, peaks: &[Peak], step: f64) {
        for (i, a) in peaks.iter().enumerate() {
            let mut next: Option<f64> = None;
            for (j, b) in peaks.iter().enumerate() {
                if i == j {
                    continue;
                }
                let dtau = (a.tau - b.tau).abs();
                if a.d == b.d && b.tau > a.tau {
                    next = Some(next.map_or(b.tau - a.tau, |x: f64| x.min(b.tau - a.tau)));
                }
                if j < i || dtau >= 6.0 {
                    continue;
                }
                let dth = (a.d as f64 - b.d as f64).abs() * step;
                self.pairs += 1;
                self.p5 += usize::from(dth <= 5.0 + 1e-9);
                self.p15 += usize::from(dth <= 15.0 + 1e-9);
                self.p30 += usize::from(dth <= 30.0 + 1e-9);
                if dtau < 2.0 {
                    self.dth2.push(dth);
                }
                if dth <= 5.0 + 1e-9 {
                    self.dtau5.push(dtau);
                }
            }
            if let Some(g) = next {
                self.gaps.push(g);
            }
        }
    }

    /// Takes the sums over every position; gives the summaries ([`NAMES`]), a value that
    /// is not finite replaced by 0.
    fn finish(self, ctx: &SummaryContext) -> Vec<f64> {
        let (np, nd, nb) = (ctx.np, ctx.nd, ctx.nb);
        let (mu, tb) = (ctx.mu, ctx.bin_ns);
        let Sums {
            total_s,
            n_det,
            profiles_det,
            ln_max,
            ln_m0,
            m1s,
            m2s,
            shares,
            peaks_all,
            peak_xy,
            env,
            ln_peak,
            pairs,
            p5,
            p15,
            p30,
            dth2,
            dtau5,
            gaps,
            depth_pow,
            depths,
            first_depths,
            entropy,
            neigh,
            neigh_of,
            t0s,
        } = self;
        let cells = (np * nd * nb.saturating_sub(ctx.first_bin)).max(1) as f64;
        let total_share: f64 = shares.iter().sum();
        let share = |x: f64| {
            if total_share > 0.0 {
                (x / total_share + 1e-6).ln()
            } else {
                1e-6f64.ln()
            }
        };
        let (m_lnm0, sd_lnm0) = mean_sd(&ln_m0, 0.0);
        let (m_m1, sd_m1) = mean_sd(&m1s, 0.0);
        let (m_m2, _) = mean_sd(&m2s, 0.0);
        let (slope, icpt) = line(&peak_xy, (0.0, 0.0));
        let (env_slope, _) = line(&env, (0.0, 0.0));
        let npk = peaks_all.max(1) as f64;
        let frac = |k: usize| {
            if pairs > 0 {
                k as f64 / pairs as f64
            } else {
                0.0
            }
        };
        let tp: f64 = depth_pow.iter().sum();
        let dshare = |x: f64| {
            if tp > 0.0 {
                (x / tp + 1e-4).ln()
            } else {
                1e-4f64.ln()
            }
        };
        let lngaps: Vec<f64> = gaps.iter().map(|g| g.max(tb).ln()).collect();
        let gaps2 = if gaps.is_empty() {
            0.0
        } else {
            gaps.iter().filter(|g| **g < 2.0).count() as f64 / gaps.len() as f64
        };
        let mut out = vec![
            (total_s / cells / mu + 1e-9).ln(),
            (1.0 + n_det as f64).ln(),
            profiles_det as f64 / (np * nd).max(1) as f64,
            median(&ln_max).unwrap_or(0.0),
            m_lnm0,
            sd_lnm0,
            m_m1,
            sd_m1,
            m_m2,
        ];
        out.extend(shares.iter().map(|s| share(*s)));
        out.extend([
            (1.0 + peaks_all as f64 / np.max(1) as f64).ln(),
            peaks_all as f64 / profiles_det.max(1) as f64,
            slope,
            icpt,
            env_slope,
            median(&ln_peak).unwrap_or(0.0),
            (pairs as f64 / npk + 0.1).ln(),
            frac(p5),
            frac(p15),
            frac(p30),
            median(&dth2).unwrap_or(90.0),
            median(&dtau5).unwrap_or(6.0),
            median(&lngaps).unwrap_or((nb as f64 * tb).ln()),
            gaps2,
        ]);
        out.extend(depth_pow.iter().map(|x| dshare(*x)));
        out.extend([
            median(&depths).unwrap_or(0.0),
            median(&first_depths).unwrap_or(0.0),
            mean_sd(&entropy, 1.0).0,
            if neigh_of > 0 {
                neigh as f64 / neigh_of as f64
            } else {
                0.0
            },
            mean_sd(&t0s, nb as f64 * tb).0.max(tb).ln(),
        ]);
        debug_assert_eq!(out.len(), NAMES.len());
        for v in &mut out {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        out
    }
}

/// The quantiles 10, 25, 50, 75, 90 % of each component of the per-profile and
/// per-position sets of the predictive check's statistics ([`super::mmd::statistic_sets`]):
/// 7 × 5 + 2 × 5 = 45 values.
pub fn quantile_summaries(ctx: &crate::check::stats::StatContext, e: &[f64]) -> Vec<f64> {
    let (pr, po) = super::mmd::statistic_sets(ctx, e);
    let mut out = Vec::with_capacity(45);
    for set in [&pr, &po] {
        for k in 0..set.dim {
            let mut v = set.column(k);
            v.sort_by(f64::total_cmp);
            for q in QUANTILES {
                out.push(crate::stats::sorted::quantile_nearest(&v, q).unwrap_or(0.0));
            }
        }
    }
    out
}

/// The quantiles of [`quantile_summaries`].
pub const QUANTILES: [f64; 5] = [0.1, 0.25, 0.5, 0.75, 0.9];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_of_the_check_statistics() {
        // one position, 5 directions; direction d has one echo of 1000·(d + 1) at bin d + 2
        let ctx = crate::check::stats::StatContext {
            np: 1,
            nd: 5,
            nb: 20,
            bin_ns: 1.0,
            first_bin: 0,
            mu: 1.0,
            angles_deg: vec![-20.0, -10.0, 0.0, 10.0, 20.0],
        };
        let mut e = vec![1.0; 5 * 20];
        for d in 0..5 {
            e[d * 20 + d + 2] = 1000.0 * (d + 1) as f64;
        }
        let q = quantile_summaries(&ctx, &e);
        assert_eq!(q.len(), 45);
        // signal energy (component 0): ranks round(q·4) = 0, 1, 2, 3, 4 → d = 0..4
        for (i, d) in [0usize, 1, 2, 3, 4].iter().enumerate() {
            let want = 10.0 * (1000.0 * (*d + 1) as f64 - 1.0).log10();
            assert!((q[i] - want).abs() < 1e-9, "{i}: {} vs {want}", q[i]);
        }
        // first arrival (component 4): d + 2 ns; the median is 4 ns
        assert!((q[4 * 5 + 2] - 4.0).abs() < 1e-12);
        // signal bins (component 3): 1 in every profile
        assert!(q[15..20].iter().all(|v| *v == 1.0));
        // per position: the share of directions with signal is 1
        assert!(q[40..45].iter().all(|v| *v == 1.0));
    }

    #[test]
    fn noise_only_and_one_echo_are_finite() {
        let layout = Layout::from_geojson(
            r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"perimeter"},"geometry":{"type":"Polygon","coordinates":[[[-5,-5],[5,-5],[5,5],[-5,5],[-5,-5]]]}}]}"#,
            std::path::Path::new("t.geojson"),
        )
        .unwrap();
        let angles: Vec<f64> = (0..7).map(|i| -30.0 + 10.0 * i as f64).collect();
        let ctx = SummaryContext::new(
            &[(0.0, 0.0, 0.0)],
            &angles,
            200,
            0.25,
            1.0,
            4.0,
            3.0,
            &layout,
        );
        assert_eq!(ctx.first_bin, 12);
        assert!((ctx.wall_m[3] - 5.0).abs() < 1e-9);
        let mut e = vec![1.0; 7 * 200];
        let s0 = summaries(&ctx, &e);
        assert_eq!(s0.len(), NAMES.len());
        assert!(s0.iter().all(|v| v.is_finite()));
        // one echo at 4.5 m (depth 0.5 m before the wall at 5 m) in direction 3
        let b = (2.0 * 4.5 / C0 * 1e9 / 0.25).round() as usize;
        e[3 * 200 + b] = 1000.0;
        let s1 = summaries(&ctx, &e);
        assert!(s1.iter().all(|v| v.is_finite()));
        let i = NAMES.iter().position(|n| *n == "median depth").unwrap();
        assert!((s1[i] - 0.5).abs() < 0.05, "{}", s1[i]);
        let i = NAMES
            .iter()
            .position(|n| *n == "ln(1 + peaks/position)")
            .unwrap();
        assert!((s1[i] - 2f64.ln()).abs() < 1e-12);
    }
}
