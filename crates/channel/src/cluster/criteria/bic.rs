//! The BIC criteria, ChannelBic and GaussBic: BIC = −2 ln L + p ln n of the mixture fitted to
//! K's partition, ln L = Σ_i ln Σ_k π_k f_k(τ_i, θ_i) with weights π_k = n_k/n and per-cluster
//! MLE components ([`super::mixture`]); p = 5K − 1 (four scale/location parameters per
//! component and K − 1 free weights). The smallest wins, K = 1 included. ChannelBic is the
//! X-means criterion (Pelleg & Moore 2000) with the channel model's component; GaussBic with
//! per-cluster diagonal covariances.

use super::mixture::{log_density, log_sum_exp, Component, Family};

/// BIC of the mixture of `comps` (empty clusters are `None` and do not count) at `raw`.
pub(crate) fn bic(raw: &[[f64; 2]], comps: &[Option<Component>], fam: Family) -> f64 {
    let n = raw.len();
    let ll: f64 = raw
        .iter()
        .map(|p| {
            log_sum_exp(
                comps
                    .iter()
                    .flatten()
                    .map(|q| (q.members / n as f64).ln() + log_density(q, p, fam)),
            )
        })
        .sum();
    let kk = comps.iter().flatten().count();
    -2.0 * ll + (5 * kk - 1) as f64 * (n as f64).ln()
}
