//! The check's statistics of one energy matrix E[p][d][b] (positions × directions × bins),
//! computed the same way on the measured table and on every draw ([`Statistics::of`]).
//!
//! A bin is *signal* when it lies after the coupling gate and E > 10·μ (10 dB above the
//! detector's noise mean μ = N0·TW of **the table itself**: the measured table's recorded
//! N0, a draw's the N0 it was drawn with, which `check` sets to the measured one; whether
//! the recorded N0 is the one the table's bins hold is the check's noise-floor rule); its
//! signal energy is S = E − μ. With τ_b = b·T_b:
//!
//! * per profile (position, direction) with at least one signal bin: the signal energy
//!   10·log10 Σ S (dB), the mean delay τ̄ = Σ τ S / Σ S, the RMS delay spread
//!   (Σ (τ − τ̄)² S / Σ S)^½ and the first arrival (the earliest signal bin), in ns;
//! * per profile (every profile, 0 when silent): the number of signal bins and of peaks
//!   (signal bins above the bin before and at least the bin after);
//! * per position with signal: the angular spread, the power-weighted standard deviation
//!   of the relative direction angle with weights Σ_b S of each direction (deg);
//! * per (position, direction): the angular power profile, the direction's share of its
//!   position's signal energy in dB (floored at −60 dB; silent positions give no values);
//! * per campaign: the mean delay power profile P(τ_b) = mean over profiles of S(τ_b),
//!   compared as the distribution over delay it defines (its normalised cumulative sum),
//!   so its KS distance is max_b |C₁(b) − C₂(b)| and its "median" is the delay where C
//!   crosses ½.

/// The statistics' names and units, in order (`Statistics::values` has one entry each).
pub const NAMES: [(&str, &str); 9] = [
    ("signal energy", "dB"),
    ("mean delay", "ns"),
    ("RMS delay spread", "ns"),
    ("signal bins", "bins"),
    ("first arrival", "ns"),
    ("peaks", "count"),
    ("angular spread", "deg"),
    ("angular power profile", "dB"),
    ("mean delay power profile", "ns"),
];

/// Index of the campaign-level delay power profile in [`NAMES`].
pub const PROFILE: usize = 8;

/// Floor of the angular power profile, dB.
pub const SHARE_FLOOR_DB: f64 = -60.0;

/// What the statistics need besides the energies.
#[derive(Debug, Clone)]
pub struct StatContext {
    /// Positions.
    pub np: usize,
    /// Directions.
    pub nd: usize,
    /// Bins.
    pub nb: usize,
    /// Bin width, ns.
    pub bin_ns: f64,
    /// First bin after the coupling gate.
    pub first_bin: usize,
    /// Noise mean μ of the table the statistics are of (N0·TW).
    pub mu: f64,
    /// Relative direction angles, degrees.
    pub angles_deg: Vec<f64>,
}

/// The signal bins of one profile (E > 10μ after the gate; [`StatContext::moments`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileMoments {
    /// Σ (E − μ) over the signal bins (0 without any).
    pub m0: f64,
    /// Signal bins.
    pub bins: usize,
    /// Local maxima among them.
    pub peaks: usize,
    /// The energy-weighted moments, when there is a signal bin.
    pub signal: Option<ProfileSignal>,
}

/// The moments of a profile with signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileSignal {
    /// 10·log10 m0, dB.
    pub energy_db: f64,
    /// Mean delay m1/m0, ns.
    pub mean_ns: f64,
    /// RMS delay spread √(m2/m0), ns.
    pub rms_ns: f64,
    /// Delay of the first signal bin, ns.
    pub first_ns: f64,
}

impl StatContext {
    /// The per-profile statistics of one profile: its signal bins (E > 10μ after the
    /// gate), their local maxima, and the moments of E − μ over delay. Shared by the
    /// check's samples and the calibration's MMD sets, so both read a profile alike.
    #[allow(clippy::needless_range_loop)] // bins index the profile and its neighbours
    pub fn moments(&self, prof: &[f64]) -> ProfileMoments {
        let nb = prof.len();
        let thr = 10.0 * self.mu;
        let (mut m0, mut m1, mut n, mut k) = (0.0, 0.0, 0usize, 0usize);
        let mut t0 = None;
        for b in self.first_bin..nb {
            let v = prof[b];
            if v <= thr || v.is_nan() {
                continue;
            }
            let s = v - self.mu;
            let tau = b as f64 * self.bin_ns;
            t0.get_or_insert(tau);
            m0 += s;
            m1 += s * tau;
            n += 1;
            let before = if b > self.first_bin { prof[b - 1] } else { 0.0 };
            let after = if b + 1 < nb { prof[b + 1] } else { 0.0 };
            if v > before && v >= after {
                k += 1;
            }
        }
        let signal = t0.map(|t0| {
            let mu1 = m1 / m0;
            let mut m2 = 0.0;
            for b in self.first_bin..nb {
                let v = prof[b];
                if v > thr {
                    let tau = b as f64 * self.bin_ns;
                    m2 += (v - self.mu) * (tau - mu1).powi(2);
                }
            }
            ProfileSignal {
                energy_db: 10.0 * m0.log10(),
                mean_ns: mu1,
                rms_ns: (m2 / m0).max(0.0).sqrt(),
                first_ns: t0,
            }
        });
        ProfileMoments {
            m0,
            bins: n,
            peaks: k,
            signal,
        }
    }
}

/// One statistic of one matrix: a sample of values, or (the delay power profile) a
/// non-negative curve over the bins.
#[derive(Debug, Clone, PartialEq)]
pub enum Stat {
    /// Values, sorted ascending.
    Sample(Vec<f64>),
    /// Non-negative weights per bin.
    Curve(Vec<f64>),
}

/// The statistics of one matrix, one [`Stat`] per entry of [`NAMES`].
#[derive(Debug, Clone, PartialEq)]
pub struct Statistics {
    /// In the order of [`NAMES`].
    pub values: Vec<Stat>,
    /// Delay of bin b is `b · bin_ns` (for the curve).
    pub bin_ns: f64,
}

impl Statistics {
    /// The statistics of energies `e` (position-major, then direction, then bin).
    pub fn of(ctx: &StatContext, e: &[f64]) -> Statistics {
        let (np, nd, nb) = (ctx.np, ctx.nd, ctx.nb);
        debug_assert_eq!(e.len(), np * nd * nb);
        let thr = 10.0 * ctx.mu;
        let mut energy = Vec::new();
        let mut mean = Vec::new();
        let mut rms = Vec::new();
        let mut bins = Vec::with_capacity(np * nd);
        let mut first = Vec::new();
        let mut peaks = Vec::with_capacity(np * nd);
        let mut spread = Vec::new();
        let mut shares = Vec::new();
        let mut curve = vec![0.0; nb];
        let mut per_dir = vec![0.0; nd];
        let mut swept = vec![true; nd];
        let mut n_present = 0usize;
        for p in 0..np {
            for (d, w) in per_dir.iter_mut().enumerate() {
                let prof = &e[(p * nd + d) * nb..(p * nd + d + 1) * nb];
                swept[d] = !prof.first().is_some_and(|v| v.is_nan());
                if !swept[d] {
                    // no sweep (`[sweeps] missing`): not a profile of the sample
                    *w = 0.0;
                    continue;
                }
                n_present += 1;
                let m = ctx.moments(prof);
                for (c, &v) in curve[ctx.first_bin..]
                    .iter_mut()
                    .zip(&prof[ctx.first_bin..])
                {
                    if v > thr {
                        *c += v - ctx.mu;
                    }
                }
                bins.push(m.bins as f64);
                peaks.push(m.peaks as f64);
                *w = m.m0;
                if let Some(sig) = m.signal {
                    energy.push(sig.energy_db);
                    mean.push(sig.mean_ns);
                    rms.push(sig.rms_ns);
                    first.push(sig.first_ns);
                }
            }
            let total: f64 = per_dir.iter().sum();
            if total > 0.0 {
                let m = ctx
                    .angles_deg
                    .iter()
                    .zip(&per_dir)
                    .map(|(a, w)| a * w)
                    .sum::<f64>()
                    / total;
                let var = ctx
                    .angles_deg
                    .iter()
                    .zip(&per_dir)
                    .map(|(a, w)| (a - m).powi(2) * w)
                    .sum::<f64>()
                    / total;
                spread.push(var.max(0.0).sqrt());
                shares.extend(
                    per_dir
                        .iter()
                        .zip(&swept)
                        .filter(|(_, &s)| s)
                        .map(|(w, _)| (10.0 * (w / total).log10()).max(SHARE_FLOOR_DB)),
                );
            }
        }
        let n_prof = n_present.max(1) as f64;
        curve.iter_mut().for_each(|v| *v /= n_prof);
        let sorted = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            Stat::Sample(v)
        };
        Statistics {
            values: vec![
                sorted(energy),
                sorted(mean),
                sorted(rms),
                sorted(bins),
                sorted(first),
                sorted(peaks),
                sorted(spread),
                sorted(shares),
                Stat::Curve(curve),
            ],
            bin_ns: ctx.bin_ns,
        }
    }
}

impl Stat {
    /// The statistic's median: the sample median, or the delay (ns, with bin width
    /// `bin_ns`) where the curve's normalised cumulative sum reaches ½. NaN when empty.
    pub fn median(&self, bin_ns: f64) -> f64 {
        match self {
            Stat::Sample(v) => crate::stats::sorted::median(v).unwrap_or(f64::NAN),
            Stat::Curve(c) => {
                let total: f64 = c.iter().sum();
                if total <= 0.0 {
                    return f64::NAN;
                }
                let mut acc = 0.0;
                for (b, v) in c.iter().enumerate() {
                    acc += v;
                    if acc >= 0.5 * total {
                        return b as f64 * bin_ns;
                    }
                }
                (c.len() - 1) as f64 * bin_ns
            }
        }
    }

    /// The empirical CDF at the points `xs` (the curve's: its normalised cumulative sum
    /// at delay x ns, bin width `bin_ns`). An empty statistic gives NaN.
    pub fn cdf_at(&self, xs: &[f64], bin_ns: f64) -> Vec<f64> {
        match self {
            Stat::Sample(v) => {
                let n = v.len() as f64;
                xs.iter()
                    .map(|&x| {
                        if v.is_empty() {
                            f64::NAN
                        } else {
                            v.partition_point(|&y| y <= x) as f64 / n
                        }
                    })
                    .collect()
            }
            Stat::Curve(c) => {
                let cum = cumulative(c);
                xs.iter()
                    .map(|&x| match &cum {
                        None => f64::NAN,
                        Some(cum) => {
                            let b = (x / bin_ns).floor();
                            if b < 0.0 {
                                0.0
                            } else {
                                cum[(b as usize).min(cum.len() - 1)]
                            }
                        }
                    })
                    .collect()
            }
        }
    }

    /// The range of values the CDF moves over (the curve's: its first and last delay
    /// with weight), None when empty.
    pub fn range(&self, bin_ns: f64) -> Option<(f64, f64)> {
        match self {
            Stat::Sample(v) => Some((*v.first()?, *v.last()?)),
            Stat::Curve(c) => {
                let lo = c.iter().position(|v| *v > 0.0)?;
                let hi = c.iter().rposition(|v| *v > 0.0)?;
                Some((lo as f64 * bin_ns, hi as f64 * bin_ns))
            }
        }
    }
}

/// The normalised cumulative sum of a non-negative curve (None when it sums to 0).
fn cumulative(c: &[f64]) -> Option<Vec<f64>> {
    let total: f64 = c.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut acc = 0.0;
    Some(
        c.iter()
            .map(|v| {
                acc += v;
                acc / total
            })
            .collect(),
    )
}

/// The Kolmogorov–Smirnov distance between two statistics of the same kind: the
/// two-sample sup |F₁ − F₂| of two samples, or max_b |C₁(b) − C₂(b)| of two curves. Two
/// empty statistics are at 0, an empty and a non-empty one at 1.
pub fn ks_distance(a: &Stat, b: &Stat) -> f64 {
    match (a, b) {
        (Stat::Sample(x), Stat::Sample(y)) => ks_two_sample(x, y),
        (Stat::Curve(x), Stat::Curve(y)) => match (cumulative(x), cumulative(y)) {
            (None, None) => 0.0,
            (Some(_), None) | (None, Some(_)) => 1.0,
            (Some(cx), Some(cy)) => cx
                .iter()
                .zip(&cy)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max),
        },
        _ => 1.0,
    }
}

/// Two-sample KS statistic of two ascending samples (ties handled: both ECDFs step at a
/// shared value before the difference is taken).
pub fn ks_two_sample(x: &[f64], y: &[f64]) -> f64 {
    match (x.is_empty(), y.is_empty()) {
        (true, true) => return 0.0,
        (true, false) | (false, true) => return 1.0,
        _ => {}
    }
    let (nx, ny) = (x.len() as f64, y.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < x.len() && j < y.len() {
        let v = x[i].min(y[j]);
        while i < x.len() && x[i] <= v {
            i += 1;
        }
        while j < y.len() && y[j] <= v {
            j += 1;
        }
        d = d.max((i as f64 / nx - j as f64 / ny).abs());
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx(np: usize, nd: usize, nb: usize) -> StatContext {
        StatContext {
            np,
            nd,
            nb,
            bin_ns: 0.5,
            first_bin: 2,
            mu: 1.0,
            angles_deg: (0..nd).map(|d| -10.0 + 10.0 * d as f64).collect(),
        }
    }

    #[test]
    fn profile_statistics_of_a_known_matrix() {
        // one position, three directions, 10 bins; noise 1, threshold 10
        let c = ctx(1, 3, 10);
        let mut e = vec![1.0; 30];
        // direction 0: bins 4 (S = 99) and 6 (S = 299): a peak each
        e[4] = 100.0;
        e[6] = 300.0;
        // bin 1 is inside the gate: never signal
        e[1] = 1e6;
        // direction 2: one bin of S = 99 at bin 8, a shoulder at 9 (S = 19)
        e[20 + 8] = 100.0;
        e[20 + 9] = 20.0;
        let s = Statistics::of(&c, &e);
        let Stat::Sample(energy) = &s.values[0] else {
            panic!()
        };
        assert_eq!(energy.len(), 2);
        assert!((energy[1] - 10.0 * 398f64.log10()).abs() < 1e-12);
        assert!((energy[0] - 10.0 * 118f64.log10()).abs() < 1e-12);
        // mean delay of direction 0: (2·99 + 3·299)/398
        let m = (2.0 * 99.0 + 3.0 * 299.0) / 398.0;
        assert_eq!(
            s.values[1],
            Stat::Sample({
                let mut v = vec![m, (4.0 * 99.0 + 4.5 * 19.0) / 118.0];
                v.sort_by(f64::total_cmp);
                v
            })
        );
        let rms0 = ((99.0 * (2.0 - m).powi(2) + 299.0 * (3.0 - m).powi(2)) / 398.0).sqrt();
        let Stat::Sample(rms) = &s.values[2] else {
            panic!()
        };
        assert!(rms.iter().any(|r| (r - rms0).abs() < 1e-12), "{rms:?}");
        assert_eq!(s.values[3], Stat::Sample(vec![0.0, 2.0, 2.0]));
        assert_eq!(s.values[4], Stat::Sample(vec![2.0, 4.0]));
        assert_eq!(s.values[5], Stat::Sample(vec![0.0, 1.0, 2.0]));
        // angular spread: weights 398 at −10°, 118 at +10°
        let mean_a: f64 = (-10.0 * 398.0 + 10.0 * 118.0) / 516.0;
        let sd =
            ((398.0 * (-10.0 - mean_a).powi(2) + 118.0 * (10.0 - mean_a).powi(2)) / 516.0).sqrt();
        let Stat::Sample(sp) = &s.values[6] else {
            panic!()
        };
        assert!((sp[0] - sd).abs() < 1e-12);
        let Stat::Sample(sh) = &s.values[7] else {
            panic!()
        };
        assert_eq!(sh[0], SHARE_FLOOR_DB);
        // the curve's median delay: cumulative reaches ½ of 516 at bin 6 (99 + 299 > 258)
        assert_eq!(s.values[PROFILE].median(0.5), 3.0);
    }

    #[test]
    fn ks_distances() {
        assert_eq!(ks_two_sample(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]), 0.0);
        assert_eq!(ks_two_sample(&[1.0, 2.0], &[3.0, 4.0]), 1.0);
        // ties: {1,1,2} vs {1,2,2}: F at 1 = 2/3 vs 1/3
        assert!((ks_two_sample(&[1.0, 1.0, 2.0], &[1.0, 2.0, 2.0]) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(ks_two_sample(&[], &[1.0]), 1.0);
        let a = Stat::Curve(vec![0.0, 1.0, 1.0, 0.0]);
        let b = Stat::Curve(vec![0.0, 0.0, 1.0, 1.0]);
        assert!((ks_distance(&a, &b) - 0.5).abs() < 1e-12);
        assert_eq!(ks_distance(&a, &a), 0.0);
    }
}
