//! The MMD distance of `calibrate --distance mmd`: the maximum mean discrepancy
//! between the empirical distribution of the measured table's per-profile (and
//! per-position) statistics and a simulated table's (Bharti, Briol & Pedersen, "A general
//! method for calibrating stochastic radio channel models with kernels", IEEE TAP 70(6),
//! 2022; Gretton, Borgwardt, Rasch, Schölkopf & Smola, JMLR 2012, for the estimator).
//!
//! **Sets.** A campaign is two sets of vectors, computed from its energy matrix with the
//! definitions of `pradar check` ([`crate::check::stats`]: a bin is signal when after the
//! coupling gate and E > 10·μ, μ the measured table's noise mean, S = E − μ), kept per
//! profile instead of sorted per statistic:
//!
//! * one vector per profile (position, direction) with a sweep, [`PROFILE_NAMES`]: signal
//!   energy 10·log10 Σ S (dB), mean delay, RMS delay spread, signal bins, first arrival,
//!   peaks, and the angular power profile (the direction's share of its position's signal
//!   energy, dB, floored at −60 dB). A silent profile (no signal bin) is the censored point
//!   energy 10·log10(9μ) (the least a signal bin carries), mean delay and first arrival at
//!   the window's end (nb·T_b), RMS 0, bins 0, peaks 0, share −60 dB: the share of silent
//!   profiles is part of the distribution compared.
//! * one vector per position with a sweep, [`POSITION_NAMES`]: the angular spread (deg, 0
//!   for a silent position) and the share of its directions with signal.
//!
//! **Standardisation.** Each component is standardised by the measured set's median and
//! MAD (×1.4826; the standard deviation when the MAD is 0, then 1), fixed for the run: the
//! simulated sets are standardised with the measured table's scales.
//!
//! **Kernel.** Gaussian, k(x, y) = exp(−‖x − y‖² / (2ℓ²)) on the standardised vectors,
//! with one length scale per set by the median heuristic: ℓ = the median Euclidean
//! distance between pairs of distinct vectors of the measured set (of its subsample when
//! subsampled; 1 when that median is 0).
//!
//! **Estimator.** The unbiased U-statistic (Gretton et al. 2012, eq. 3)
//! MMD²_u(X, Y) = Σ_{i≠j} k(x_i, x_j)/(m(m−1)) + Σ_{i≠j} k(y_i, y_j)/(n(n−1))
//! − 2 Σ_{i,j} k(x_i, y_j)/(mn); its expectation is MMD²(P, Q), 0 when the two laws are
//! equal, so it can be negative. The ABC distance is
//! ρ = MMD²_u(profiles) + MMD²_u(positions) (ABC ranks particles by ρ: no square root is
//! needed, and a negative value is simply a very close simulation).
//!
//! **Cost and subsampling.** Per simulation O(n² + nm) kernel evaluations of 7-vectors
//! (the measured set's own sum is computed once). A set larger than [`MAX_SET`] = 1000
//! vectors is replaced by a uniform subsample of 1000 without replacement — the measured
//! set once (a fixed stream), each simulated set from its simulation's seed — so one
//! distance costs at most 1.5·10⁶ kernel evaluations (measured, `tests::cost`: 21 ms on
//! one core). The corridor's 444 profiles are never subsampled (4.4 ms per distance beside
//! synth's ~31 ms); the closed loop's hall (240 poses × 61 directions = 14 640 profiles)
//! is, and the subsample adds to MMD²_u a variance of order 1/1000 (the estimator's own at
//! n = 1000).

use super::abc::median_mad;
use crate::check::stats::StatContext;
use rand::seq::index::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The per-profile components, in order.
pub const PROFILE_NAMES: [&str; 7] = [
    "signal energy (dB)",
    "mean delay (ns)",
    "RMS delay spread (ns)",
    "signal bins",
    "first arrival (ns)",
    "peaks",
    "angular power profile (dB)",
];

/// The per-position components, in order.
pub const POSITION_NAMES: [&str; 2] = ["angular spread (deg)", "share of directions with signal"];

/// The largest set compared whole; larger sets are subsampled to this many vectors.
pub const MAX_SET: usize = 1000;

/// Floor of the angular power profile, dB (as the check's).
const SHARE_FLOOR_DB: f64 = crate::check::stats::SHARE_FLOOR_DB;

/// A set of vectors of one dimension, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct VecSet {
    /// Dimension.
    pub dim: usize,
    /// The vectors, row after row.
    pub data: Vec<f64>,
}

impl VecSet {
    /// An empty set of dimension `dim`.
    pub fn new(dim: usize) -> VecSet {
        VecSet {
            dim,
            data: Vec::new(),
        }
    }
    /// Number of vectors.
    pub fn len(&self) -> usize {
        self.data.len() / self.dim.max(1)
    }
    /// Whether it has no vector.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// Vector i.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.dim..(i + 1) * self.dim]
    }
    fn push(&mut self, v: &[f64]) {
        debug_assert_eq!(v.len(), self.dim);
        self.data.extend_from_slice(v);
    }
    /// Component k of every vector.
    pub fn column(&self, k: usize) -> Vec<f64> {
        (0..self.len()).map(|i| self.row(i)[k]).collect()
    }
    /// At most `max` vectors: the set itself when small enough, else a uniform subsample
    /// without replacement drawn from `ChaCha8Rng::seed_from_u64(seed)`, in index order.
    pub fn subsample(&self, max: usize, seed: u64) -> VecSet {
        let n = self.len();
        if n <= max {
            return self.clone();
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut idx = sample(&mut rng, n, max).into_vec();
        idx.sort_unstable();
        let mut out = VecSet::new(self.dim);
        for i in idx {
            out.push(self.row(i));
        }
        out
    }
}

/// The per-profile and per-position sets of energies `e` (position-major, then direction,
/// then bin), module docs' definitions; profiles without a sweep (NaN) are left out.
pub fn statistic_sets(ctx: &StatContext, e: &[f64]) -> (VecSet, VecSet) {
    let (np, nd, nb) = (ctx.np, ctx.nd, ctx.nb);
    let silent_db = 10.0 * (9.0 * ctx.mu).max(1e-300).log10();
    let t_end = nb as f64 * ctx.bin_ns;
    let mut profiles = VecSet::new(PROFILE_NAMES.len());
    let mut positions = VecSet::new(POSITION_NAMES.len());
    let mut rows: Vec<[f64; 7]> = Vec::with_capacity(nd);
    let mut m0s: Vec<f64> = Vec::with_capacity(nd);
    for p in 0..np {
        rows.clear();
        m0s.clear();
        let mut dirs = Vec::with_capacity(nd);
        for d in 0..nd {
            let prof = &e[(p * nd + d) * nb..(p * nd + d + 1) * nb];
            if prof.first().is_some_and(|v| v.is_nan()) {
                continue;
            }
            let m = ctx.moments(prof);
            let row = match m.signal {
                Some(sig) => [
                    sig.energy_db,
                    sig.mean_ns,
                    sig.rms_ns,
                    m.bins as f64,
                    sig.first_ns,
                    m.peaks as f64,
                    0.0,
                ],
                None => [silent_db, t_end, 0.0, 0.0, t_end, 0.0, 0.0],
            };
            rows.push(row);
            m0s.push(m.m0);
            dirs.push(d);
        }
        if rows.is_empty() {
            continue;
        }
        let total: f64 = m0s.iter().sum();
        for (row, w) in rows.iter_mut().zip(&m0s) {
            row[6] = if total > 0.0 {
                (10.0 * (w / total).log10()).max(SHARE_FLOOR_DB)
            } else {
                SHARE_FLOOR_DB
            };
            profiles.push(row);
        }
        let spread = if total > 0.0 {
            let ang = |i: usize| ctx.angles_deg[dirs[i]];
            let m = (0..dirs.len()).map(|i| ang(i) * m0s[i]).sum::<f64>() / total;
            let var = (0..dirs.len())
                .map(|i| (ang(i) - m).powi(2) * m0s[i])
                .sum::<f64>()
                / total;
            var.max(0.0).sqrt()
        } else {
            0.0
        };
        let lit = m0s.iter().filter(|w| **w > 0.0).count() as f64 / m0s.len() as f64;
        positions.push(&[spread, lit]);
    }
    (profiles, positions)
}

/// Gaussian kernel exp(−‖x − y‖² / (2ℓ²)), given 1/(2ℓ²).
#[inline]
fn kernel(x: &[f64], y: &[f64], inv2l2: f64) -> f64 {
    let d2: f64 = x.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum();
    (-d2 * inv2l2).exp()
}

/// Σ_{i≠j} k(x_i, x_j) / (m(m−1)) (0 with fewer than 2 vectors).
fn within(x: &VecSet, inv2l2: f64) -> f64 {
    let m = x.len();
    if m < 2 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..m {
        for j in i + 1..m {
            s += kernel(x.row(i), x.row(j), inv2l2);
        }
    }
    2.0 * s / (m as f64 * (m - 1) as f64)
}

/// Σ_{i,j} k(x_i, y_j) / (mn).
fn between(x: &VecSet, y: &VecSet, inv2l2: f64) -> f64 {
    let (m, n) = (x.len(), y.len());
    if m == 0 || n == 0 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..m {
        for j in 0..n {
            s += kernel(x.row(i), y.row(j), inv2l2);
        }
    }
    s / (m as f64 * n as f64)
}

/// The unbiased estimate MMD²_u(X, Y) with the Gaussian kernel of length scale `l`
/// (module docs). Sets with fewer than 2 vectors contribute no within-set term.
pub fn mmd2_unbiased(x: &VecSet, y: &VecSet, l: f64) -> f64 {
    let inv = 1.0 / (2.0 * l * l);
    within(x, inv) + within(y, inv) - 2.0 * between(x, y, inv)
}

/// The biased (V-statistic) estimate MMD²_b(X, Y) = ‖μ̂_X − μ̂_Y‖² ≥ 0, for comparison.
pub fn mmd2_biased(x: &VecSet, y: &VecSet, l: f64) -> f64 {
    let inv = 1.0 / (2.0 * l * l);
    between(x, x, inv) + between(y, y, inv) - 2.0 * between(x, y, inv)
}

/// The median heuristic: the median Euclidean distance between distinct vectors of `x`
/// (1 when it is 0 or `x` has fewer than 2 vectors).
pub fn median_heuristic(x: &VecSet) -> f64 {
    let m = x.len();
    let mut d = Vec::with_capacity(m * m.saturating_sub(1) / 2);
    for i in 0..m {
        for j in i + 1..m {
            d.push(
                x.row(i)
                    .iter()
                    .zip(x.row(j))
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt(),
            );
        }
    }
    match crate::stats::median(&d) {
        Some(l) if l > 1e-12 => l,
        _ => 1.0,
    }
}

/// One standardised set of the measured table, its length scale and its within-set sum.
#[derive(Debug, Clone)]
struct Reference {
    centre: Vec<f64>,
    scale: Vec<f64>,
    set: VecSet,
    length: f64,
    within: f64,
}

impl Reference {
    fn new(measured: &VecSet, seed: u64) -> Reference {
        let (centre, scale) = (0..measured.dim)
            .map(|k| median_mad(&measured.column(k)))
            .unzip();
        let mut r = Reference {
            centre,
            scale,
            set: VecSet::new(measured.dim),
            length: 1.0,
            within: 0.0,
        };
        r.set = r.standard(&measured.subsample(MAX_SET, seed));
        r.length = median_heuristic(&r.set);
        r.within = within(&r.set, 1.0 / (2.0 * r.length * r.length));
        r
    }

    fn standard(&self, x: &VecSet) -> VecSet {
        let mut out = x.clone();
        for row in out.data.chunks_mut(x.dim) {
            for ((v, c), s) in row.iter_mut().zip(&self.centre).zip(&self.scale) {
                *v = (*v - c) / s;
            }
        }
        out
    }

    /// MMD²_u between the measured set and `y` (raw, subsampled with `seed`).
    fn mmd2(&self, y: &VecSet, seed: u64) -> f64 {
        let y = self.standard(&y.subsample(MAX_SET, seed));
        let inv = 1.0 / (2.0 * self.length * self.length);
        self.within + within(&y, inv) - 2.0 * between(&self.set, &y, inv)
    }
}

/// The distance ρ = MMD²_u(profiles) + MMD²_u(positions) to a measured table (module
/// docs), with the measured sets' scales and length scales fixed at construction.
#[derive(Debug, Clone)]
pub struct MmdDistance {
    profiles: Reference,
    positions: Reference,
}

impl MmdDistance {
    /// The distance to the measured energies `e` (subsampled, when larger than
    /// [`MAX_SET`], from a fixed stream).
    pub fn new(ctx: &StatContext, e: &[f64]) -> MmdDistance {
        let (pr, po) = statistic_sets(ctx, e);
        MmdDistance {
            profiles: Reference::new(&pr, 0x4d4d_4450),
            positions: Reference::new(&po, 0x4d4d_4451),
        }
    }

    /// The length scales ℓ (profiles, positions), in standardised units.
    pub fn length_scales(&self) -> (f64, f64) {
        (self.profiles.length, self.positions.length)
    }

    /// ρ of simulated energies `e`; `seed` drives the subsampling of sets over
    /// [`MAX_SET`] (unused otherwise).
    pub fn distance(&self, ctx: &StatContext, e: &[f64], seed: u64) -> f64 {
        let (pr, po) = statistic_sets(ctx, e);
        self.profiles.mmd2(&pr, seed) + self.positions.mmd2(&po, seed ^ 0x5a5a_5a5a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::stats::{Stat, Statistics};
    use rand::Rng;
    use rand_distr::StandardNormal;

    fn gauss(n: usize, dim: usize, shift: f64, seed: u64) -> VecSet {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        VecSet {
            dim,
            data: (0..n * dim)
                .map(|i| {
                    rng.sample::<f64, _>(StandardNormal) + if i % dim == 0 { shift } else { 0.0 }
                })
                .collect(),
        }
    }

    #[test]
    fn identical_sets_are_at_zero() {
        let x = gauss(200, 3, 0.0, 1);
        let l = median_heuristic(&x);
        // the U-statistic of a set against itself is −(2/m)(1 − mean within-kernel)·…: O(1/m)
        let u = mmd2_unbiased(&x, &x, l);
        assert!(u.abs() < 2.0 / 200.0, "{u}");
        assert!(mmd2_biased(&x, &x, l).abs() < 1e-12);
        // two samples of one law: near 0, far below a shifted one
        let y = gauss(200, 3, 0.0, 2);
        assert!(mmd2_unbiased(&x, &y, l).abs() < 0.01);
    }

    #[test]
    fn grows_with_the_shift() {
        let x = gauss(300, 3, 0.0, 3);
        let l = median_heuristic(&x);
        let d: Vec<f64> = [0.0, 0.25, 0.5, 1.0, 2.0, 4.0]
            .iter()
            .map(|s| mmd2_unbiased(&x, &gauss(300, 3, *s, 4), l))
            .collect();
        for w in d.windows(2) {
            assert!(w[1] > w[0], "{d:?}");
        }
        assert!(d[0].abs() < 0.01 && d[5] > 0.3, "{d:?}");
    }

    #[test]
    fn unbiased_estimator_centres_on_zero_the_biased_does_not() {
        // 400 pairs of samples (m = n = 20) of one law: the mean of MMD²_u is 0 within
        // 3 standard errors and takes both signs; MMD²_b is always > 0
        let (mut u, mut b) = (Vec::new(), Vec::new());
        for r in 0..400u64 {
            let x = gauss(20, 2, 0.0, 100 + 2 * r);
            let y = gauss(20, 2, 0.0, 101 + 2 * r);
            u.push(mmd2_unbiased(&x, &y, 1.0));
            b.push(mmd2_biased(&x, &y, 1.0));
        }
        let n = u.len() as f64;
        let m = u.iter().sum::<f64>() / n;
        let se = (u.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt();
        assert!(m.abs() < 3.0 * se, "mean {m}, se {se}");
        assert!(u.iter().any(|v| *v < 0.0) && u.iter().any(|v| *v > 0.0));
        let mb = b.iter().sum::<f64>() / n;
        assert!(b.iter().all(|v| *v > 0.0) && mb > 10.0 * se, "{mb}");
        // symmetric
        let (x, y) = (gauss(30, 2, 0.0, 7), gauss(25, 2, 0.5, 8));
        assert!((mmd2_unbiased(&x, &y, 1.3) - mmd2_unbiased(&y, &x, 1.3)).abs() < 1e-12);
    }

    #[test]
    fn median_heuristic_of_known_points() {
        // points 0, 1, 3 on a line: distances 1, 2, 3
        let x = VecSet {
            dim: 1,
            data: vec![0.0, 1.0, 3.0],
        };
        assert_eq!(median_heuristic(&x), 2.0);
        assert_eq!(median_heuristic(&VecSet::new(2)), 1.0);
    }

    #[test]
    fn subsample_is_deterministic_and_uniform_size() {
        let x = gauss(2500, 2, 0.0, 9);
        let a = x.subsample(MAX_SET, 5);
        assert_eq!(a.len(), MAX_SET);
        assert_eq!(a, x.subsample(MAX_SET, 5));
        assert_ne!(a, x.subsample(MAX_SET, 6));
        assert_eq!(gauss(10, 2, 0.0, 1).subsample(MAX_SET, 5).len(), 10);
        // the subsample's MMD to the whole set is small
        let l = median_heuristic(&a);
        assert!(mmd2_unbiased(&a, &x, l).abs() < 0.01);
    }

    /// The cost of one distance (the reference's within-set sum precomputed, as in a run):
    /// 7-vectors, the corridor's 444 profiles and a subsampled set of 1000. Prints ms per
    /// distance; `cargo test --release --lib calibrate::mmd::tests::cost -- --ignored
    /// --nocapture` (about 5 s).
    #[test]
    #[ignore = "a timing, about 5 s"]
    fn cost() {
        for n in [444usize, 1000, 14_640] {
            let x = gauss(n, 7, 0.0, 1);
            let y = gauss(n, 7, 0.3, 2);
            let r = Reference::new(&x, 3);
            let t = std::time::Instant::now();
            let reps = 5;
            let mut acc = 0.0;
            for k in 0..reps {
                acc += r.mmd2(&y, k);
            }
            eprintln!(
                "n = {n} (compared: {}): {:.1} ms per distance (mean MMD² {:.4})",
                n.min(MAX_SET),
                1e3 * t.elapsed().as_secs_f64() / reps as f64,
                acc / reps as f64
            );
        }
    }

    fn ctx() -> StatContext {
        StatContext {
            np: 2,
            nd: 3,
            nb: 10,
            bin_ns: 0.5,
            first_bin: 2,
            mu: 1.0,
            angles_deg: vec![-10.0, 0.0, 10.0],
        }
    }

    fn matrix() -> Vec<f64> {
        let mut e = vec![1.0; 60];
        e[4] = 100.0;
        e[6] = 300.0;
        e[20 + 8] = 100.0;
        e[20 + 9] = 20.0;
        e[30 + 5] = 50.0; // position 1, direction 0
        e
    }

    #[test]
    fn sets_hold_the_checks_statistics() {
        // sorted per component, the signal profiles' values are the check's samples
        let c = ctx();
        let e = matrix();
        let (pr, po) = statistic_sets(&c, &e);
        assert_eq!((pr.len(), po.len()), (6, 2));
        let s = Statistics::of(&c, &e);
        let signal: Vec<usize> = (0..pr.len()).filter(|i| pr.row(*i)[3] > 0.0).collect();
        for (k, check_k) in [(0, 0), (1, 1), (2, 2), (4, 4)] {
            let mut v: Vec<f64> = signal.iter().map(|i| pr.row(*i)[k]).collect();
            v.sort_by(f64::total_cmp);
            assert_eq!(Stat::Sample(v), s.values[check_k], "component {k}");
        }
        for (k, check_k) in [(3, 3), (5, 5), (6, 7)] {
            let mut v = pr.column(k);
            v.sort_by(f64::total_cmp);
            assert_eq!(Stat::Sample(v), s.values[check_k], "component {k}");
        }
        let mut sp = po.column(0);
        sp.sort_by(f64::total_cmp);
        assert_eq!(Stat::Sample(sp), s.values[6]);
        // silent profiles are the censored point; the share of lit directions
        let silent = pr.row(1);
        assert_eq!(silent[1], 5.0);
        assert_eq!(silent[3], 0.0);
        assert!((po.row(0)[1] - 2.0 / 3.0).abs() < 1e-12);
        assert!((po.row(1)[1] - 1.0 / 3.0).abs() < 1e-12);
        // a missing sweep is left out
        let mut m = e.clone();
        m[50..60].iter_mut().for_each(|v| *v = f64::NAN);
        assert_eq!(statistic_sets(&c, &m).0.len(), 5);
    }

    #[test]
    fn distance_is_deterministic_and_zero_ish_on_the_measured_table() {
        let c = ctx();
        let e = matrix();
        let d = MmdDistance::new(&c, &e);
        let a = d.distance(&c, &e, 3);
        assert_eq!(a.to_bits(), d.distance(&c, &e, 3).to_bits());
        let mut f = e.clone();
        f[4] = 1.0;
        f[6] = 1.0;
        f[20 + 8] = 1e4;
        assert!(d.distance(&c, &f, 3) > a);
        let (lp, lq) = d.length_scales();
        assert!(lp > 0.0 && lq > 0.0);
    }
}
