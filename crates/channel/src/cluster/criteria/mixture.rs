//! The mixture components of the likelihood criteria: per-cluster MLEs and log densities in
//! the original units (ns, degrees).
//!
//! * `Family::ExpLaplace` (ChannelBic, the channel model's cluster shape, DESIGN §2 and
//!   the Table 1 families): delay after the cluster's first arrival exponential, angle
//!   Laplacian around the cluster's median angle,
//!   f(τ, θ) = μ e^{−μ(τ − τ0)} · e^{−|θ − θ_c|/b} / (2b) for τ ≥ τ0, with τ0 the first
//!   arrival, 1/μ the mean excess delay, θ_c the median, b the mean |θ − θ_c|.
//! * `Family::Gauss` (GaussBic, X-means): diagonal Gaussian (means, variances).
//! * `Family::GaussLaplace` (the cross-validated criteria): Gaussian delay × Laplacian
//!   angle.
//!
//! Likelihoods are evaluated in the original units: rescaling a feature adds the same
//! constant for every K, so only the partitions depend on the scaling. Scales (exponential
//! mean, Laplacian b, Gaussian sd) are floored at the measurement resolution
//! (`delay_res_ns`, `angle_res_deg`) so that a singleton or a tight pair has a finite
//! likelihood.

/// Component families of the likelihood criteria.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Family {
    /// Shifted exponential delay × Laplacian angle.
    ExpLaplace,
    /// Gaussian delay × Gaussian angle.
    Gauss,
    /// Gaussian delay × Laplacian angle.
    GaussLaplace,
}

/// One fitted mixture component: log weight numerator (members) and (location, scale) per
/// feature.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Component {
    pub(crate) members: f64,
    pub(crate) delay: (f64, f64),
    pub(crate) angle: (f64, f64),
}

/// Median of non-empty `v` (sorts it: the callers sum over it in that order).
pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    crate::stats::sorted::median(v).expect("a non-empty group")
}

/// MLE of one component from its members (`raw` = (delay ns, angle deg)); None if empty.
pub(crate) fn fit_component(
    raw: &[[f64; 2]],
    members: &[usize],
    fam: Family,
    res: [f64; 2],
) -> Option<Component> {
    if members.is_empty() {
        return None;
    }
    let m = members.len() as f64;
    let gauss = |j: usize| {
        let mean = members.iter().map(|&i| raw[i][j]).sum::<f64>() / m;
        let var = members
            .iter()
            .map(|&i| (raw[i][j] - mean).powi(2))
            .sum::<f64>()
            / m;
        (mean, var.sqrt().max(res[j]))
    };
    let laplace = || {
        let mut a: Vec<f64> = members.iter().map(|&i| raw[i][1]).collect();
        let med = median(&mut a);
        let b = a.iter().map(|v| (v - med).abs()).sum::<f64>() / m;
        (med, b.max(res[1]))
    };
    let (delay, angle) = match fam {
        Family::ExpLaplace => {
            let t0 = members
                .iter()
                .map(|&i| raw[i][0])
                .fold(f64::INFINITY, f64::min);
            let excess = members.iter().map(|&i| raw[i][0] - t0).sum::<f64>() / m;
            ((t0, excess.max(res[0])), laplace())
        }
        Family::Gauss => (gauss(0), gauss(1)),
        Family::GaussLaplace => (gauss(0), laplace()),
    };
    Some(Component {
        members: m,
        delay,
        angle,
    })
}

/// Log density of one component at `p`.
pub(crate) fn log_density(c: &Component, p: &[f64; 2], fam: Family) -> f64 {
    const LN_2PI: f64 = 1.837_877_066_409_345_5;
    let gauss =
        |x: f64, (mu, sd): (f64, f64)| -0.5 * LN_2PI - sd.ln() - 0.5 * ((x - mu) / sd).powi(2);
    let laplace = |x: f64, (mu, b): (f64, f64)| -(2.0 * b).ln() - (x - mu).abs() / b;
    match fam {
        Family::ExpLaplace => {
            let (t0, mean) = c.delay;
            if p[0] < t0 {
                return f64::NEG_INFINITY;
            }
            -mean.ln() - (p[0] - t0) / mean + laplace(p[1], c.angle)
        }
        Family::Gauss => gauss(p[0], c.delay) + gauss(p[1], c.angle),
        Family::GaussLaplace => gauss(p[0], c.delay) + laplace(p[1], c.angle),
    }
}

/// ln Σ e^{v_i}, stable (−∞ for no terms or all −∞).
pub(crate) fn log_sum_exp(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    let m = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !m.is_finite() {
        return m;
    }
    m + v.iter().map(|x| (x - m).exp()).sum::<f64>().ln()
}
