//! The K-selection criteria ([`Criterion`]): each scores K's own K-means partition; the
//! criteria only choose among K-means partitions, they never cluster.
//!
//! * Distance indices ([`indices`]): `Silhouette`, `CalinskiHarabasz` (largest wins; K = 1
//!   when no K ≥ 2 reaches `min_silhouette`, when n ≤ 2, or when K_max = 1).
//! * [`gap`]: the gap statistic on the z-scores (handles K = 1).
//! * Likelihood criteria, evaluated in the original units (ns, degrees) with the components
//!   of [`mixture`] (smaller [`likelihood_criterion`] is better, K = 1 included):
//!   - [`bic`]: `ChannelBic` (exponential delay × Laplacian angle, p = 5K − 1) and
//!     `GaussBic` (diagonal Gaussian, the X-means criterion);
//!   - [`cv`]: `CrossValidated` (default) and `CrossValidatedShared`, −2 × the leave-one-out
//!     predictive log-likelihood with a "new cluster" term.
//!
//! [`Criterion`]: crate::cluster::Criterion

pub mod bic;
pub mod cv;
pub mod gap;
pub mod indices;
pub mod mixture;

use crate::cluster::kmeans::n_clusters;
use crate::cluster::params::{ClusterValid, Criterion};
use mixture::{fit_component, Component, Family};

pub use indices::{calinski_harabasz, silhouette};

/// Likelihood criterion of a partition (smaller is better): BIC for `ChannelBic` /
/// `GaussBic`, −2 × leave-one-out log-likelihood for `CrossValidated` and
/// `CrossValidatedShared`. `raw` in ns and degrees.
///
/// ```
/// use pradar_channel::cluster::{likelihood_criterion, ClusterParams, Criterion};
/// use pradar_formats::params::ParamGuard;
/// let p = ClusterParams::default().check().unwrap();
/// let raw = [[10.0, -40.0], [10.5, -42.0], [30.0, 40.0], [31.0, 41.0]];
/// let one = likelihood_criterion(&raw, &[0, 0, 0, 0], Criterion::GaussBic, &p);
/// let two = likelihood_criterion(&raw, &[0, 0, 1, 1], Criterion::GaussBic, &p);
/// assert!(two < one);
/// ```
pub fn likelihood_criterion(
    raw: &[[f64; 2]],
    labels: &[usize],
    criterion: Criterion,
    params: &ClusterValid,
) -> f64 {
    let n = raw.len();
    let k = n_clusters(labels, 0);
    if n == 0 || k == 0 {
        return 0.0;
    }
    let res = [params.delay_res_ns, params.angle_res_deg];
    let fam = match criterion {
        Criterion::ChannelBic => Family::ExpLaplace,
        Criterion::GaussBic => Family::Gauss,
        _ => Family::GaussLaplace,
    };
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); k];
    for (i, &l) in labels.iter().enumerate() {
        members[l].push(i);
    }
    let comps: Vec<Option<Component>> = members
        .iter()
        .map(|m| fit_component(raw, m, fam, res))
        .collect();
    match criterion {
        Criterion::CrossValidated | Criterion::CrossValidatedShared => cv::cross_validated(
            raw,
            labels,
            &members,
            &comps,
            fam,
            params,
            criterion == Criterion::CrossValidatedShared,
        ),
        _ => bic::bic(raw, &comps, fam),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cluster::params::ClusterParams;
    use crate::params::ParamGuard;

    #[test]
    fn likelihood_criteria_choose_one_and_two_blobs() {
        // deterministic blob: delays 10..20 ns, angles spread ±10° around a centre
        let blob = |t0: f64, a0: f64| -> Vec<[f64; 2]> {
            (0..12)
                .map(|i| [t0 + i as f64 * 0.8, a0 + ((i * 7) % 12) as f64 * 1.7 - 9.0])
                .collect()
        };
        let one = blob(10.0, 0.0);
        let halves: Vec<usize> = (0..12).map(|i| usize::from(i >= 6)).collect();
        let mut two = blob(10.0, -60.0);
        two.extend(blob(12.0, 60.0));
        let split: Vec<usize> = (0..24).map(|i| usize::from(i >= 12)).collect();
        let p = ClusterParams::default().check().unwrap();
        for c in [
            Criterion::ChannelBic,
            Criterion::GaussBic,
            Criterion::CrossValidated,
            Criterion::CrossValidatedShared,
        ] {
            let l1 = likelihood_criterion(&one, &[0; 12], c, &p);
            let l2 = likelihood_criterion(&one, &halves, c, &p);
            assert!(l1 < l2, "{c:?}: one blob, K=1 {l1} vs K=2 {l2}");
            let l1 = likelihood_criterion(&two, &[0; 24], c, &p);
            let l2 = likelihood_criterion(&two, &split, c, &p);
            assert!(l2 < l1, "{c:?}: two blobs, K=2 {l2} vs K=1 {l1}");
        }
    }
}
