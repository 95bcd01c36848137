//! Each Table 1 quantity from its samples per position: the value, the 95 %
//! position-bootstrap interval, the KS statistic with its parametric-bootstrap p-value and
//! the candidate families ranked by AIC (the [`FittedQuantity`]); the decay constants and
//! the means (rays per cluster, σ) with their intervals.
//!
//! * Λ, λ: shifted-exponential MLE rate; the AoA: √2 times the Laplacian scale.
//! * d_p: the mean signed offset (floored at 1 mm) and its interval; the families, KS and
//!   plots from the offsets folded at the wall.
//! * d_c: the censored estimate Σ L / Σ k and its interval; the families, KS and plots
//!   from the complete gaps (none when fewer than two).
//! * Γ: least-squares excess decay of the range-corrected cluster powers, ∞ without an
//!   excess ([`excess_decay_quantity`]); γ: least-absolute-deviation decay through the
//!   origin (see [`channel`](super::channel) for why).
//!
//! Every resampling stream is keyed by the seed and the quantity's own offset, so the
//! quantities do not depend on the order they are fitted in.
//!
//! None of these estimators fails: a quantity the samples cannot give (fewer than 2
//! samples, a family that does not fit them, no decaying trend, no samples at all) comes
//! back not estimable ([`Quantity::not_estimable`]) with the reason in one short line, and
//! the others are fitted as usual. Bad input is refused before the samples are gathered
//! ([`channel`](super::channel)).

use crate::error::Error;
use crate::fit::estimators::{bootstrap_groups, fit, ks_bootstrap, Family, Fitted};
use crate::model::file::Quantity;

/// A fitted quantity with its diagnostics.
#[derive(Debug, Clone)]
pub struct FittedQuantity {
    /// Model-file entry.
    pub q: Quantity,
    /// Families by AIC, best first (name, AIC).
    pub aic: Vec<(String, f64)>,
    /// Samples per position (for plots).
    pub samples: Vec<f64>,
    /// The fitted law of the samples (no parameters when not estimable).
    pub fitted: Fitted,
}

impl FittedQuantity {
    /// A quantity the samples cannot give: `reason` in the model entry, no samples, no
    /// families; `n` the samples there were.
    pub fn not_estimable(
        unit: &str,
        family: Family,
        reason: impl Into<String>,
        n: usize,
    ) -> FittedQuantity {
        FittedQuantity {
            q: Quantity {
                n: Some(n),
                ..Quantity::not_estimable(unit, family.name(), reason)
            },
            aic: Vec::new(),
            samples: Vec::new(),
            fitted: Fitted {
                family,
                params: Vec::new(),
                loglik: 0.0,
                n: 0,
            },
        }
    }
}

/// Samples grouped by position.
pub(super) type Groups = Vec<Vec<f64>>;

/// (x, y) pairs grouped by position.
pub(super) type PairGroups = Vec<Vec<(f64, f64)>>;

/// All samples of all positions.
pub(super) fn flat(g: &Groups) -> Vec<f64> {
    g.iter().flatten().copied().collect()
}

/// The mean, `None` for no samples.
pub(super) fn mean(s: &[f64]) -> Option<f64> {
    (!s.is_empty()).then(|| s.iter().sum::<f64>() / s.len() as f64)
}

/// How the intervals and p-values resample: `bootstrap` resamples of whole positions in
/// blocks of `block`, streams keyed by `seed` and each quantity's offset.
pub(super) struct Resampling {
    pub(super) bootstrap: usize,
    pub(super) seed: u64,
    pub(super) block: usize,
}

/// What to fit to a quantity's samples: its unit, the family whose fit gives the value,
/// the candidate families ranked by AIC, and the samples' names for the reasons of a
/// quantity that is not estimable.
struct Spec<'a> {
    unit: &'a str,
    family: Family,
    candidates: &'a [Family],
    /// The samples (plural, e.g. "inter-cluster gaps").
    what: &'a str,
    /// Why there are none (e.g. "fewer than 2 clusters at every position").
    none: &'a str,
}

/// The message of an estimator error (a parameter error's text without its field).
fn message(e: &Error) -> String {
    match e {
        Error::Param { msg, .. } => msg.clone(),
        other => other.to_string(),
    }
}

/// Fit one sampled quantity: `spec.family` gives the estimate through `value` (from the
/// fit) and its interval by the position bootstrap, unless another estimator `given` them
/// (value, interval): then the samples give only the families, KS and plots (d_p, d_c).
/// Fewer than 2 samples, a family that does not fit them or a value that is not finite
/// and positive: not estimable, with the reason.
fn quantity(
    spec: &Spec,
    groups: &Groups,
    value: impl Fn(&Fitted) -> f64 + Copy,
    given: Option<(f64, Option<[f64; 2]>)>,
    r: &Resampling,
    seed_off: u64,
) -> FittedQuantity {
    let family = spec.family;
    let x = flat(groups);
    let n = x.len();
    let not_estimable =
        |reason: String| FittedQuantity::not_estimable(spec.unit, family, reason, n);
    if n == 0 {
        return not_estimable(format!("no {} ({})", spec.what, spec.none));
    }
    if n < 2 {
        return not_estimable(format!("{}: 1 sample, at least 2 needed", spec.what));
    }
    let f = match fit(family, &x) {
        Ok(f) => f,
        Err(e) => {
            return not_estimable(format!(
                "no {} fit to {n} {}: {}",
                family.name(),
                spec.what,
                message(&e)
            ))
        }
    };
    let v = given.map_or_else(|| value(&f), |g| g.0);
    if !v.is_finite() || v <= 0.0 {
        return not_estimable(format!(
            "the {} fit to {n} {} gave {v}",
            family.name(),
            spec.what
        ));
    }
    let interval = match given {
        Some(g) => g.1,
        None => bootstrap_groups(
            groups,
            |s| fit(family, s).ok().map(|f| value(&f)),
            r.bootstrap,
            r.seed ^ seed_off,
            r.block,
        ),
    };
    let (ks, ks_p) = ks_bootstrap(&f, &x, r.bootstrap.min(500), r.seed ^ seed_off ^ 0xB5);
    let mut aic: Vec<(String, f64)> = spec
        .candidates
        .iter()
        .filter_map(|c| fit(*c, &x).ok().map(|f| (c.name().to_string(), f.aic())))
        .collect();
    aic.sort_by(|a, b| a.1.total_cmp(&b.1));
    FittedQuantity {
        q: Quantity {
            interval,
            ks: Some(ks),
            ks_p: Some(ks_p),
            n: Some(n),
            ..Quantity::new(v, spec.unit, family.name())
        },
        aic,
        samples: x,
        fitted: f,
    }
}

/// Λ, λ (shifted-exponential rates) and the AoA std (√2 times the Laplacian scale).
pub(super) fn fit_arrivals(
    inter: &Groups,
    intra: &Groups,
    aoa: &Groups,
    delta: f64,
    r: &Resampling,
) -> Vec<(&'static str, FittedQuantity)> {
    let sh = Family::ShiftedExponential { delta };
    let arrival_cands = [sh, Family::Gamma, Family::LogNormal, Family::Rayleigh];
    let arrivals = |what, none| Spec {
        unit: "1/ns",
        family: sh,
        candidates: &arrival_cands,
        what,
        none,
    };
    let rate = |f: &Fitted| f.params[0];
    let inter_spec = arrivals(
        "inter-cluster gaps",
        "fewer than 2 clusters at every position",
    );
    let inter = quantity(&inter_spec, inter, rate, None, r, 1);
    let intra_spec = arrivals("intra-cluster gaps", "every cluster has a single ray");
    let intra = quantity(&intra_spec, intra, rate, None, r, 2);
    let aoa_spec = Spec {
        unit: "deg",
        family: Family::Laplacian,
        candidates: &[Family::Laplacian, Family::Gaussian],
        what: "AoA offsets",
        none: "every cluster has a single ray",
    };
    let aoa = quantity(&aoa_spec, aoa, |f| 2f64.sqrt() * f.params[1], None, r, 3);
    vec![
        ("inter_cluster_rate", inter),
        ("intra_cluster_rate", intra),
        ("intra_cluster_aoa", aoa),
    ]
}

/// Families of the perimeter statistics.
const PERIMETER_CANDIDATES: [Family; 4] = [
    Family::Exponential,
    Family::Gamma,
    Family::LogNormal,
    Family::Rayleigh,
];

/// The mean of an exponential fit (NaN for another family).
fn exponential_mean(f: &Fitted) -> f64 {
    match f.family {
        Family::Exponential => 1.0 / f.params[0],
        _ => f64::NAN,
    }
}

/// d_p: families, KS and samples from the folded offsets; the value and its interval from
/// the mean signed offset (floored at 1 mm). Not estimable when the folded offsets give no
/// exponential fit (fewer than 2 clusters inside the observed interior).
pub(super) fn fit_offset(dp: &Groups, dp_signed: &Groups, r: &Resampling) -> FittedQuantity {
    let signed = (
        mean(&flat(dp_signed)).map_or(1e-3, |v| v.max(1e-3)),
        bootstrap_groups(dp_signed, mean, r.bootstrap, r.seed ^ 4, r.block)
            .map(|[lo, hi]| [lo.max(1e-3), hi.max(1e-3)]),
    );
    let spec = Spec {
        unit: "m",
        family: Family::Exponential,
        candidates: &PERIMETER_CANDIDATES,
        what: "perimeter offsets",
        none: "no cluster inside the observed interior",
    };
    quantity(&spec, dp, exponential_mean, Some(signed), r, 4)
}

/// d_c: families, KS and samples from the complete gaps; the value and its interval from
/// the censored (exposure) estimate Σ L / Σ k. Fewer than two complete gaps (a gap needs
/// two clusters on one observed stretch), or gaps no exponential fits, leave the families
/// and KS empty ("—" in the table, no plot), not the value. No cluster on the observed
/// perimeter: not estimable.
pub(super) fn fit_spacing(dc: &Groups, exposure: &Groups, r: &Resampling) -> FittedQuantity {
    let per_cluster = |s: &[f64]| {
        let (l, k) = s
            .chunks(2)
            .fold((0.0, 0.0), |(l, k), c| (l + c[0], k + c[1]));
        (k > 0.0).then(|| l / k)
    };
    let complete_gaps = flat(dc);
    let Some(censored) = per_cluster(&flat(exposure)).filter(|v| v.is_finite() && *v > 0.0) else {
        return FittedQuantity::not_estimable(
            "m",
            Family::Exponential,
            "no cluster on the observed perimeter",
            complete_gaps.len(),
        );
    };
    let censored_iv = bootstrap_groups(exposure, per_cluster, r.bootstrap, r.seed ^ 5, r.block);
    if complete_gaps.len() >= 2 {
        let spec = Spec {
            unit: "m",
            family: Family::Exponential,
            candidates: &PERIMETER_CANDIDATES,
            what: "complete perimeter gaps",
            none: "",
        };
        let q = quantity(
            &spec,
            dc,
            exponential_mean,
            Some((censored, censored_iv)),
            r,
            5,
        );
        if q.q.is_estimable() {
            return q;
        }
    }
    FittedQuantity {
        q: Quantity {
            interval: censored_iv,
            n: Some(complete_gaps.len()),
            ..Quantity::new(censored, "m", Family::Exponential.name())
        },
        aic: Vec::new(),
        samples: complete_gaps,
        // the exponential law with the censored mean (for the report; no plot)
        fitted: Fitted {
            family: Family::Exponential,
            params: vec![1.0 / censored],
            loglik: 0.0,
            n: 0,
        },
    }
}

/// The ray decay γ ([`decay_lad0`]) from (excess delay, power relative to the cluster's first
/// ray dB) pairs per position, with its position-bootstrap interval; not estimable when
/// there is no decaying trend (or fewer than 3 pairs).
pub(super) fn ray_decay_quantity(pairs: &[Vec<(f64, f64)>], seed: u64, r: &Resampling) -> Quantity {
    let decay = decay_lad0;
    let all: Vec<(f64, f64)> = pairs.iter().flatten().copied().collect();
    let Some(v) = decay(&all).filter(|v| v.is_finite() && *v > 0.0) else {
        return Quantity {
            n: Some(all.len()),
            ..Quantity::not_estimable(
                "ns",
                "exponential",
                format!("no decaying trend in {} ray powers", all.len()),
            )
        };
    };
    let iv = bootstrap_pairs(pairs, decay, seed, r);
    Quantity {
        interval: iv,
        n: Some(all.len()),
        ..Quantity::new(v, "ns", "exponential")
    }
}

/// The position-bootstrap interval of `stat` over (x, y) pairs per position (the pairs of a
/// position resampled together).
fn bootstrap_pairs(
    pairs: &[Vec<(f64, f64)>],
    stat: impl Fn(&[(f64, f64)]) -> Option<f64>,
    seed: u64,
    r: &Resampling,
) -> Option<[f64; 2]> {
    let enc: Groups = pairs
        .iter()
        .map(|g| g.iter().flat_map(|x| [x.0, x.1]).collect())
        .collect();
    bootstrap_groups(
        &enc,
        |s| stat(&s.chunks(2).map(|c| (c[0], c[1])).collect::<Vec<_>>()),
        r.bootstrap,
        r.seed ^ seed,
        r.block,
    )
}

/// Excess decay rates below this (1/ns; Γ above 10 µs, the schema's bound) are no excess
/// decay (Γ = ∞): over an indoor profile of a few hundred ns they change no power by
/// more than a few percent.
pub const NO_EXCESS_RATE_PER_NS: f64 = 1e-4;

/// The excess cluster decay Γ (model schema 2) from (excess delay ns, range-corrected
/// relative power dB) pairs per position: the least-squares slope s (dB/ns) as a rate
/// k = max(−s/(10·log10 e), 0) (1/ns), Γ = 1/k, and Γ = ∞ (no excess decay) where
/// k < [`NO_EXCESS_RATE_PER_NS`]. The interval bootstraps the rate (finite, so every
/// resample counts) and inverts its ends, the upper one ∞ when the rate's lower end is 0;
/// none when the whole rate interval is 0. Not estimable with fewer than 3 powers (the
/// stated value ∞ is then drawn).
pub(super) fn excess_decay_quantity(
    pairs: &[Vec<(f64, f64)>],
    seed: u64,
    r: &Resampling,
) -> Quantity {
    let rate = |p: &[(f64, f64)]| -> Option<f64> {
        if p.len() < 3 {
            return None;
        }
        let (slope, _) = ls_line(p)?;
        slope
            .is_finite()
            .then(|| (-slope / (10.0 * std::f64::consts::LOG10_E)).max(0.0))
    };
    let decay_of = |k: f64| {
        if k >= NO_EXCESS_RATE_PER_NS {
            1.0 / k
        } else {
            f64::INFINITY
        }
    };
    // a power that is not finite (a −inf dB) carries no slope
    let pairs: Vec<Vec<(f64, f64)>> = pairs
        .iter()
        .map(|g| {
            g.iter()
                .copied()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect()
        })
        .collect();
    let all: Vec<(f64, f64)> = pairs.iter().flatten().copied().collect();
    let Some(k) = rate(&all) else {
        let reason = if all.len() < 3 {
            format!("{} cluster powers, at least 3 needed", all.len())
        } else {
            format!(
                "{} cluster powers, all at their position's first delay (no delay spread)",
                all.len()
            )
        };
        return Quantity {
            n: Some(all.len()),
            ..Quantity::not_estimable("ns", "exponential", reason)
        };
    };
    let iv = bootstrap_pairs(&pairs, rate, seed, r)
        .filter(|[_, hi]| *hi >= NO_EXCESS_RATE_PER_NS)
        .map(|[lo, hi]| [decay_of(hi), decay_of(lo.max(0.0))]);
    Quantity {
        interval: iv,
        n: Some(all.len()),
        ..Quantity::new(decay_of(k), "ns", "exponential")
    }
}

/// The mean of the samples with its position-bootstrap interval (rays per cluster, σ); not
/// estimable without clusters (or when the mean is not finite and positive).
pub(super) fn mean_quantity(
    g: &Groups,
    unit: &str,
    family: &str,
    seed: u64,
    r: &Resampling,
) -> Quantity {
    let x = flat(g);
    let reason = match mean(&x) {
        None => "no clusters".to_string(),
        Some(v) if v.is_finite() && v > 0.0 => {
            return Quantity {
                interval: bootstrap_groups(g, mean, r.bootstrap, r.seed ^ seed, r.block),
                n: Some(x.len()),
                ..Quantity::new(v, unit, family)
            }
        }
        Some(v) => format!("the mean of {} clusters is {v}", x.len()),
    };
    Quantity {
        n: Some(x.len()),
        ..Quantity::not_estimable(unit, family, reason)
    }
}

/// Least-squares decay constant from (delay, dB) pairs: −10·log10(e)/slope (the tests'
/// foil for [`decay_lad0`]).
#[cfg(test)]
pub(super) fn decay(pairs: &[(f64, f64)]) -> Option<f64> {
    if pairs.len() < 3 {
        return None;
    }
    let (slope, _) = ls_line(pairs)?;
    (slope < 0.0).then(|| -10.0 * std::f64::consts::LOG10_E / slope)
}

/// Least-squares line (slope, intercept) of y on x; None for fewer than 2 pairs or no spread
/// in x.
pub(super) fn ls_line(pairs: &[(f64, f64)]) -> Option<(f64, f64)> {
    if pairs.len() < 2 {
        return None;
    }
    let n = pairs.len() as f64;
    let mx = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pairs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pairs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| (sxy / sxx, my - sxy / sxx * mx))
}

/// Least-absolute-deviation decay constant of a line through the origin from (excess delay,
/// relative dB) pairs: the slope minimising Σ|y − s·x| is the x-weighted median of y/x
/// (pairs with x ≤ 0 carry no slope); −10·log10(e)/slope.
pub(super) fn decay_lad0(pairs: &[(f64, f64)]) -> Option<f64> {
    let mut r: Vec<(f64, f64)> = pairs
        .iter()
        .filter(|p| p.0 > 0.0 && p.1.is_finite())
        .map(|p| (p.1 / p.0, p.0))
        .collect();
    if r.len() < 3 {
        return None;
    }
    r.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * r.iter().map(|v| v.1).sum::<f64>();
    let mut acc = 0.0;
    let slope = r
        .iter()
        .find(|v| {
            acc += v.1;
            acc >= half
        })
        .map(|v| v.0)?;
    (slope < 0.0).then(|| -10.0 * std::f64::consts::LOG10_E / slope)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excess_decay_is_infinite_without_a_trend_and_the_rate_inverse_with_one() {
        let r = Resampling {
            bootstrap: 200,
            seed: 3,
            block: 1,
        };
        let k = 10.0 * std::f64::consts::LOG10_E;
        // 8 positions, clusters on a 25 ns excess decay with ±2 dB alternating scatter
        let decaying: Vec<Vec<(f64, f64)>> = (0..8)
            .map(|p| {
                (0..6)
                    .map(|i| {
                        let t = 7.0 * i as f64 + p as f64;
                        (t, -k * t / 25.0 + if (i + p) % 2 == 0 { 2.0 } else { -2.0 })
                    })
                    .collect()
            })
            .collect();
        let q = excess_decay_quantity(&decaying, 6, &r);
        assert!((q.value - 25.0).abs() < 2.0, "Γ {}", q.value);
        let [lo, hi] = q.interval.expect("interval");
        assert!(lo < q.value && q.value < hi && hi.is_finite(), "{lo} {hi}");
        // flat (range-corrected powers that only scatter): Γ = ∞, a value, not a refusal
        let flat: Vec<Vec<(f64, f64)>> = (0..8)
            .map(|p| {
                (0..6)
                    .map(|i| {
                        (
                            7.0 * i as f64 + p as f64,
                            if (i + p) % 2 == 0 { 1.5 } else { -1.5 },
                        )
                    })
                    .collect()
            })
            .collect();
        let q = excess_decay_quantity(&flat, 6, &r);
        assert!(q.is_estimable() && q.value == f64::INFINITY, "{q:?}");
        if let Some([lo, hi]) = q.interval {
            assert!(lo.is_finite() && hi == f64::INFINITY, "{lo} {hi}");
        }
        // rising powers are no excess decay either; two powers are not enough
        let rising = vec![vec![(0.0, 0.0), (5.0, 3.0), (9.0, 6.0)]];
        assert_eq!(excess_decay_quantity(&rising, 6, &r).value, f64::INFINITY);
        let two = vec![vec![(0.0, 0.0), (5.0, -3.0)]];
        let q = excess_decay_quantity(&two, 6, &r);
        assert!(!q.is_estimable() && q.value.is_nan());
    }

    #[test]
    fn lad_decay_ignores_one_sided_contamination() {
        // rays on a 4 ns decay, plus a merged second cluster whose rays sit 7.7 dB above it
        let k = 10.0 * std::f64::consts::LOG10_E;
        let mut pairs: Vec<(f64, f64)> = (1..=40)
            .map(|i| (i as f64 * 0.5, -k * i as f64 * 0.5 / 4.0))
            .collect();
        pairs.extend((1..=12).map(|i| (8.0 + i as f64, -k * i as f64 / 4.0 - 1.0)));
        let lad = decay_lad0(&pairs).unwrap();
        assert!((lad - 4.0).abs() < 1e-9, "LAD γ {lad}");
        let ols = decay(&pairs).unwrap();
        assert!(
            ols > 4.5,
            "least squares is pulled up by the merged cluster: {ols}"
        );
        // no trend or too few pairs: None, never NaN
        assert!(decay_lad0(&[(1.0, 1.0), (2.0, 2.0), (3.0, 1.0)]).is_none());
        assert!(decay_lad0(&[(1.0, -1.0), (0.0, 0.0)]).is_none());
    }
}
