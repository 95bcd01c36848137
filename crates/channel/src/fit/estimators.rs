//! Estimators of the channel fit (DESIGN §2 "Fitting").
//!
//! Takes samples (inter-arrival gaps, AoA offsets, perimeter distances, …); gives maximum-
//! likelihood fits of candidate families, their log-likelihoods and AIC = 2k − 2·ln L, the
//! Kolmogorov–Smirnov statistic, a parametric-bootstrap KS p-value (the parameters were
//! fitted, so the classical KS table does not apply: each bootstrap sample is drawn from
//! the fitted law, refitted, and its KS statistic compared) and percentile bootstrap
//! intervals that resample whole positions (groups).
//!
//! MLEs (statrs has the distributions but no fitting):
//! * exponential: rate = 1/mean;
//! * shifted exponential with resolution δ (arrivals closer than δ merge, so gaps are
//!   δ + Exp(rate)): rate = 1/(mean − δ);
//! * Laplacian: location = median, scale b = mean |x − median| (statrs' `Laplace` scale;
//!   std = √2·b);
//! * Gaussian: mean, std with 1/n; log-normal: the Gaussian MLE of ln x;
//! * gamma: shape k solving ln k − ψ(k) = ln mean − mean(ln x) (Newton, from the
//!   Minka/Choi–Wette start), rate = k/mean;
//! * Rayleigh: σ² = Σx²/(2n).

use crate::error::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, Gamma as RGamma, LogNormal as RLogNormal, Normal as RNormal};
use statrs::distribution::{
    Continuous, ContinuousCDF, Exp as SExp, Gamma as SGamma, Laplace as SLaplace,
    LogNormal as SLogNormal, Normal as SNormal,
};
use statrs::function::gamma::{digamma, ln_gamma};

/// A candidate family.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Family {
    /// Exponential (rate).
    Exponential,
    /// Exponential shifted by the resolution δ.
    ShiftedExponential {
        /// Resolution δ (same unit as the data).
        delta: f64,
    },
    /// Laplacian (location, scale b).
    Laplacian,
    /// Gaussian (mean, std).
    Gaussian,
    /// Log-normal (μ, σ of ln x).
    LogNormal,
    /// Gamma (shape, rate).
    Gamma,
    /// Rayleigh (σ).
    Rayleigh,
}

impl Family {
    /// Name used in model files and tables.
    pub fn name(&self) -> &'static str {
        match self {
            Family::Exponential => "exponential",
            Family::ShiftedExponential { .. } => "shifted_exponential",
            Family::Laplacian => "laplacian",
            Family::Gaussian => "gaussian",
            Family::LogNormal => "lognormal",
            Family::Gamma => "gamma",
            Family::Rayleigh => "rayleigh",
        }
    }
}

/// A fitted distribution.
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// Family.
    pub family: Family,
    /// Parameters: exponential `[rate]`; shifted `[rate]`; Laplacian `[location, scale]`;
    /// Gaussian `[mean, std]`; log-normal `[μ, σ]`; gamma `[shape, rate]`; Rayleigh `[σ]`.
    pub params: Vec<f64>,
    /// Log-likelihood at the MLE.
    pub loglik: f64,
    /// Sample size.
    pub n: usize,
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Fit `family` to `x` by maximum likelihood.
pub fn fit(family: Family, x: &[f64]) -> Result<Fitted> {
    let n = x.len();
    if n < 2 {
        return Err(Error::param(
            family.name(),
            format!("need at least 2 samples, got {n}"),
        ));
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err(Error::param(family.name(), "non-finite sample"));
    }
    let nf = n as f64;
    let positive = || -> Result<()> {
        if x.iter().any(|&v| v <= 0.0) {
            Err(Error::param(family.name(), "samples must be > 0"))
        } else {
            Ok(())
        }
    };
    let (params, loglik) = match family {
        Family::Exponential => {
            if x.iter().any(|&v| v < 0.0) {
                return Err(Error::param(family.name(), "samples must be >= 0"));
            }
            let m = mean(x);
            if m <= 0.0 {
                return Err(Error::param(family.name(), "mean must be > 0"));
            }
            let rate = 1.0 / m;
            (vec![rate], nf * rate.ln() - rate * m * nf)
        }
        Family::ShiftedExponential { delta } => {
            let m = mean(x) - delta;
            if m <= 0.0 || x.iter().any(|&v| v < delta) {
                return Err(Error::param(
                    family.name(),
                    format!("samples must be >= δ = {delta} with mean above it"),
                ));
            }
            let rate = 1.0 / m;
            (vec![rate], nf * rate.ln() - nf)
        }
        Family::Laplacian => {
            let loc = crate::stats::median(x).expect("at least 2 samples");
            let b = x.iter().map(|v| (v - loc).abs()).sum::<f64>() / nf;
            if b <= 0.0 {
                return Err(Error::param(family.name(), "zero spread"));
            }
            (vec![loc, b], -nf * (2.0 * b).ln() - nf)
        }
        Family::Gaussian => {
            let m = mean(x);
            let s = (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / nf).sqrt();
            if s <= 0.0 {
                return Err(Error::param(family.name(), "zero spread"));
            }
            (
                vec![m, s],
                -0.5 * nf * (2.0 * std::f64::consts::PI * s * s).ln() - 0.5 * nf,
            )
        }
        Family::LogNormal => {
            positive()?;
            let l: Vec<f64> = x.iter().map(|v| v.ln()).collect();
            let m = mean(&l);
            let s = (l.iter().map(|v| (v - m).powi(2)).sum::<f64>() / nf).sqrt();
            if s <= 0.0 {
                return Err(Error::param(family.name(), "zero spread"));
            }
            let ll = -0.5 * nf * (2.0 * std::f64::consts::PI * s * s).ln()
                - 0.5 * nf
                - l.iter().sum::<f64>();
            (vec![m, s], ll)
        }
        Family::Gamma => {
            positive()?;
            let m = mean(x);
            let ml = x.iter().map(|v| v.ln()).sum::<f64>() / nf;
            let s = m.ln() - ml;
            if s <= 0.0 {
                return Err(Error::param(family.name(), "zero spread"));
            }
            let mut k = (3.0 - s + ((s - 3.0).powi(2) + 24.0 * s).sqrt()) / (12.0 * s);
            for _ in 0..50 {
                let f = k.ln() - digamma(k) - s;
                // d/dk [ln k − ψ(k)] = 1/k − ψ'(k); ψ' by a central difference of ψ
                let h = 1e-6 * k;
                let d = 1.0 / k - (digamma(k + h) - digamma(k - h)) / (2.0 * h);
                let step = f / d;
                k = (k - step).max(1e-6);
                if step.abs() < 1e-13 * k {
                    break;
                }
            }
            let rate = k / m;
            let ll = nf * (k * rate.ln() - ln_gamma(k)) + (k - 1.0) * ml * nf - rate * m * nf;
            (vec![k, rate], ll)
        }
        Family::Rayleigh => {
            if x.iter().any(|&v| v < 0.0) {
                return Err(Error::param(family.name(), "samples must be >= 0"));
            }
            let s2 = x.iter().map(|v| v * v).sum::<f64>() / (2.0 * nf);
            if s2 <= 0.0 {
                return Err(Error::param(family.name(), "zero spread"));
            }
            let ll = x.iter().map(|v| v.max(1e-300).ln()).sum::<f64>() - nf * s2.ln() - nf;
            (vec![s2.sqrt()], ll)
        }
    };
    Ok(Fitted {
        family,
        params,
        loglik,
        n,
    })
}

impl Fitted {
    /// Number of free parameters.
    pub fn k(&self) -> usize {
        self.params.len()
    }

    /// Akaike information criterion.
    pub fn aic(&self) -> f64 {
        2.0 * self.k() as f64 - 2.0 * self.loglik
    }

    /// Probability density (statrs' closed forms; Rayleigh, which statrs lacks, written out:
    /// x/σ²·e^{−x²/(2σ²)}).
    pub fn pdf(&self, x: f64) -> f64 {
        let p = &self.params;
        match self.family {
            Family::Exponential => SExp::new(p[0]).map(|d| d.pdf(x)).unwrap_or(f64::NAN),
            Family::ShiftedExponential { delta } => SExp::new(p[0])
                .map(|d| d.pdf(x - delta))
                .unwrap_or(f64::NAN),
            Family::Laplacian => SLaplace::new(p[0], p[1])
                .map(|d| d.pdf(x))
                .unwrap_or(f64::NAN),
            Family::Gaussian => SNormal::new(p[0], p[1])
                .map(|d| d.pdf(x))
                .unwrap_or(f64::NAN),
            Family::LogNormal => SLogNormal::new(p[0], p[1])
                .map(|d| d.pdf(x))
                .unwrap_or(f64::NAN),
            Family::Gamma => SGamma::new(p[0], p[1])
                .map(|d| d.pdf(x))
                .unwrap_or(f64::NAN),
            Family::Rayleigh => {
                if x < 0.0 {
                    0.0
                } else {
                    let s2 = p[0] * p[0];
                    x / s2 * (-x * x / (2.0 * s2)).exp()
                }
            }
        }
    }

    /// Cumulative distribution function.
    pub fn cdf(&self, x: f64) -> f64 {
        let p = &self.params;
        match self.family {
            Family::Exponential => SExp::new(p[0]).map(|d| d.cdf(x)).unwrap_or(f64::NAN),
            Family::ShiftedExponential { delta } => SExp::new(p[0])
                .map(|d| d.cdf(x - delta))
                .unwrap_or(f64::NAN),
            Family::Laplacian => SLaplace::new(p[0], p[1])
                .map(|d| d.cdf(x))
                .unwrap_or(f64::NAN),
            Family::Gaussian => SNormal::new(p[0], p[1])
                .map(|d| d.cdf(x))
                .unwrap_or(f64::NAN),
            Family::LogNormal => SLogNormal::new(p[0], p[1])
                .map(|d| d.cdf(x))
                .unwrap_or(f64::NAN),
            Family::Gamma => SGamma::new(p[0], p[1])
                .map(|d| d.cdf(x))
                .unwrap_or(f64::NAN),
            Family::Rayleigh => {
                if x <= 0.0 {
                    0.0
                } else {
                    1.0 - (-x * x / (2.0 * p[0] * p[0])).exp()
                }
            }
        }
    }

    /// Draw `n` samples (rand_distr; the RNG types stay apart from statrs').
    pub fn sample(&self, n: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let p = &self.params;
        match self.family {
            Family::Exponential => {
                let d = Exp::new(p[0]).expect("fitted rate > 0");
                (0..n).map(|_| d.sample(rng)).collect()
            }
            Family::ShiftedExponential { delta } => {
                let d = Exp::new(p[0]).expect("fitted rate > 0");
                (0..n).map(|_| delta + d.sample(rng)).collect()
            }
            Family::Laplacian => (0..n)
                .map(|_| {
                    let u: f64 = rand::Rng::gen::<f64>(rng) - 0.5;
                    p[0] - p[1] * u.signum() * (1.0 - 2.0 * u.abs()).max(1e-300).ln()
                })
                .collect(),
            Family::Gaussian => {
                let d = RNormal::new(p[0], p[1]).expect("fitted std > 0");
                (0..n).map(|_| d.sample(rng)).collect()
            }
            Family::LogNormal => {
                let d = RLogNormal::new(p[0], p[1]).expect("fitted σ > 0");
                (0..n).map(|_| d.sample(rng)).collect()
            }
            Family::Gamma => {
                let d = RGamma::new(p[0], 1.0 / p[1]).expect("fitted shape, rate > 0");
                (0..n).map(|_| d.sample(rng)).collect()
            }
            Family::Rayleigh => (0..n)
                .map(|_| {
                    let u: f64 = rand::Rng::gen::<f64>(rng);
                    p[0] * (-2.0 * (1.0 - u).max(1e-300).ln()).sqrt()
                })
                .collect(),
        }
    }
}

/// One-sample Kolmogorov–Smirnov statistic D = sup |F_n − F|.
pub fn ks_statistic(x: &[f64], cdf: impl Fn(f64) -> f64) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    v.iter()
        .enumerate()
        .map(|(i, &xi)| {
            let f = cdf(xi);
            ((i + 1) as f64 / n - f).max(f - i as f64 / n)
        })
        .fold(0.0, f64::max)
}

/// KS statistic of `x` against its fit and the parametric-bootstrap p-value over `b`
/// resamples (seeded): the fraction of refitted bootstrap samples whose KS statistic is at
/// least the observed one (with the usual +1 correction).
pub fn ks_bootstrap(fitted: &Fitted, x: &[f64], b: usize, seed: u64) -> (f64, f64) {
    let d = ks_statistic(x, |v| fitted.cdf(v));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut exceed = 0usize;
    let mut used = 0usize;
    for _ in 0..b {
        let s = fitted.sample(x.len(), &mut rng);
        if let Ok(f) = fit(fitted.family, &s) {
            used += 1;
            if ks_statistic(&s, |v| f.cdf(v)) >= d {
                exceed += 1;
            }
        }
    }
    (d, (exceed + 1) as f64 / (used + 1) as f64)
}

/// Bootstrap interval (level 0.95) of `stat` over `b` resamples of whole groups
/// (positions), seeded; `None` when fewer than 2 groups or the statistic fails on most
/// resamples. Groups are drawn in circular blocks of `block` consecutive groups (the
/// moving-block bootstrap of Künsch 1989 in the circular form of Politis & Romano 1992, for
/// dependent neighbours), until as many groups as the data have are drawn; `block` = 1 is
/// the ordinary bootstrap of groups. A block of all the groups only rotates them (a
/// zero-width interval): callers keep it well below the group count.
///
/// The interval is the percentile interval [q₀.₀₂₅, q₀.₉₇₅] of the resampled statistic,
/// widened about the full-sample estimate θ̂ by the few-blocks factor
/// f = t₀.₉₇₅(G − 1)/z₀.₉₇₅ · √(G/(G − 1)), G = groups/block the number of (nearly
/// independent) blocks: θ̂ − f·(θ̂ − q₀.₀₂₅) .. θ̂ + f·(q₀.₉₇₅ − θ̂), on the log scale when θ̂
/// and the quantiles are positive (a positive quantity keeps a positive interval). With G
/// independent units the bootstrap variance is (G − 1)/G of the unbiased one, and a
/// pivot estimated from G units has G − 1 degrees of freedom (the few-clusters correction
/// of cluster-robust inference: Cameron, Gelbach & Miller 2008; Bester, Conley & Hansen 2011
/// for spatial blocks). For the ordinary bootstrap of 60 positions (G = 60) f = 1.03, near
/// the percentile interval; at G = 5 (a 60-pose walk in blocks of 12) f = 1.58.
pub fn bootstrap_groups(
    groups: &[Vec<f64>],
    stat: impl Fn(&[f64]) -> Option<f64>,
    b: usize,
    seed: u64,
    block: usize,
) -> Option<[f64; 2]> {
    use rand::Rng;
    let n = groups.len();
    if n < 2 {
        return None;
    }
    let block = block.clamp(1, n);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut vals = Vec::with_capacity(b);
    let mut pooled = Vec::new();
    for _ in 0..b {
        pooled.clear();
        let mut drawn = 0;
        while drawn < n {
            let start = rng.gen_range(0..n);
            for j in 0..block.min(n - drawn) {
                pooled.extend_from_slice(&groups[(start + j) % n]);
            }
            drawn += block;
        }
        if let Some(v) = stat(&pooled) {
            if v.is_finite() {
                vals.push(v);
            }
        }
    }
    if vals.is_empty() || vals.len() < b / 2 {
        return None;
    }
    vals.sort_by(f64::total_cmp);
    let q = |p: f64| crate::stats::sorted::quantile_nearest(&vals, p).expect("resamples");
    let (lo, hi) = (q(0.025), q(0.975));
    let all: Vec<f64> = groups.iter().flatten().copied().collect();
    let est = match stat(&all) {
        Some(v) if v.is_finite() => v,
        _ => return Some([lo, hi]),
    };
    let f = few_blocks_factor(n as f64 / block as f64);
    if est > 0.0 && lo > 0.0 {
        let (e, l, h) = (est.ln(), lo.ln(), hi.ln());
        Some([(e - f * (e - l)).exp(), (e + f * (h - e)).exp()])
    } else {
        Some([est - f * (est - lo), est + f * (hi - est)])
    }
}

/// Widening of a bootstrap interval estimated from `g` blocks (see [`bootstrap_groups`]):
/// t₀.₉₇₅(g − 1)/z₀.₉₇₅ · √(g/(g − 1)); g is floored at 2 (one degree of freedom), and
/// the factor is 1 from g = 1000 on.
pub fn few_blocks_factor(g: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
    if !g.is_finite() || g >= 1000.0 {
        return 1.0;
    }
    let g = g.max(2.0);
    let df = g - 1.0;
    match (Normal::new(0.0, 1.0), StudentsT::new(0.0, 1.0, df)) {
        (Ok(z), Ok(t)) => t.inverse_cdf(0.975) / z.inverse_cdf(0.975) * (g / df).sqrt(),
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_blocks_factor_is_the_t_over_z_correction() {
        // t(4) 97.5 % = 2.776445, z = 1.959964: 2.776445/1.959964 · √(5/4) = 1.583784
        assert!((few_blocks_factor(5.0) - 1.583784).abs() < 1e-5);
        // t(59) = 2.000995: · √(60/59)
        assert!(
            (few_blocks_factor(60.0) - 2.000995 / 1.959964 * (60f64 / 59.0).sqrt()).abs() < 1e-5
        );
        assert_eq!(few_blocks_factor(5000.0), 1.0);
        // a widened interval keeps its percentile shape about the estimate, on the log scale
        let groups: Vec<Vec<f64>> = (0..12).map(|i| vec![1.0 + i as f64 * 0.1]).collect();
        let mean = |s: &[f64]| Some(s.iter().sum::<f64>() / s.len() as f64);
        let plain = bootstrap_groups(&groups, mean, 400, 3, 1).unwrap();
        let wide = bootstrap_groups(&groups, mean, 400, 3, 4).unwrap();
        assert!(plain[0] < 1.55 && plain[1] > 1.55 && wide[0] > 0.0);
        assert!(wide[1] - wide[0] > plain[1] - plain[0]);
    }

    #[test]
    fn pdf_is_the_derivative_of_the_cdf() {
        // the closed forms against the central difference of the CDF they replaced, at
        // points away from the support's edge and the Laplacian's peak
        let fits = [
            (Family::Exponential, vec![0.43]),
            (Family::ShiftedExponential { delta: 0.3 }, vec![0.21]),
            (Family::Laplacian, vec![2.0, 12.0]),
            (Family::Gaussian, vec![1.5, 0.4]),
            (Family::LogNormal, vec![0.2, 0.5]),
            (Family::Gamma, vec![2.5, 1.7]),
            (Family::Rayleigh, vec![0.8]),
        ];
        let mut worst: f64 = 0.0;
        for (family, params) in fits {
            let f = Fitted {
                family,
                params,
                loglik: 0.0,
                n: 0,
            };
            for x in [0.4, 0.9, 1.7, 2.6, 4.0, 7.5, 15.0] {
                let h = 1e-5 * (1.0 + f64::abs(x));
                let numeric = (f.cdf(x + h) - f.cdf(x - h)) / (2.0 * h);
                let closed = f.pdf(x);
                if closed > 1e-6 {
                    worst = worst.max((closed - numeric).abs() / closed);
                }
            }
            if !matches!(family, Family::Laplacian | Family::Gaussian) {
                assert_eq!(f.pdf(-1.0), 0.0, "{family:?} below its support");
            }
        }
        // the difference's own error: rounding ε·F/(2h) relative to f, ~1e-8 in the tails
        assert!(worst < 1e-7, "worst relative difference {worst:e}");
        eprintln!("closed-form pdf vs central difference: worst {worst:e}");
    }

    #[test]
    fn closed_forms() {
        let x = [1.0, 2.0, 3.0, 6.0];
        let e = fit(Family::Exponential, &x).unwrap();
        assert!((e.params[0] - 1.0 / 3.0).abs() < 1e-15);
        let s = fit(Family::ShiftedExponential { delta: 0.5 }, &x).unwrap();
        assert!((s.params[0] - 1.0 / 2.5).abs() < 1e-15);
        let l = fit(Family::Laplacian, &[-1.0, 0.0, 0.5, 2.0, 10.0]).unwrap();
        assert_eq!(l.params[0], 0.5);
        assert!((l.params[1] - (1.5 + 0.5 + 0.0 + 1.5 + 9.5) / 5.0).abs() < 1e-15);
        // statrs' Laplace scale convention: variance 2b², so std = √2·b
        let d = SLaplace::new(0.0, 16.9 / 2f64.sqrt()).unwrap();
        use statrs::statistics::Distribution as _;
        assert!((d.std_dev().unwrap() - 16.9).abs() < 1e-12);
        // KS of a known case: one sample at the median of U(0,1) gives D = 0.5
        assert!((ks_statistic(&[0.5], |v| v.clamp(0.0, 1.0)) - 0.5).abs() < 1e-15);
        // and {0.1, 0.6} against U(0,1): max(0.5-0.1, 1-0.6, 0.6-0.5, 0.1-0) = 0.4
        assert!((ks_statistic(&[0.1, 0.6], |v| v) - 0.4).abs() < 1e-15);
        assert!(fit(Family::Gamma, &[1.0]).is_err());
        assert!(fit(Family::LogNormal, &[1.0, -2.0]).is_err());
    }

    #[test]
    fn bootstrap_p_is_uniformish_under_the_null_and_small_off_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let f = Fitted {
            family: Family::Exponential,
            params: vec![0.43],
            loglik: 0.0,
            n: 0,
        };
        let x = f.sample(200, &mut rng);
        let fe = fit(Family::Exponential, &x).unwrap();
        let (_, p_null) = ks_bootstrap(&fe, &x, 199, 1);
        let fg = fit(Family::Gaussian, &x).unwrap();
        let (_, p_wrong) = ks_bootstrap(&fg, &x, 199, 1);
        assert!(
            p_null > 0.05,
            "exponential data vs exponential fit: p {p_null}"
        );
        assert!(
            p_wrong < 0.01,
            "exponential data vs Gaussian fit: p {p_wrong}"
        );
    }
}
