//! K-means partitions of one position's MPCs (linfa-clustering, k-means++, seeded) and the
//! geometry of a labelling (centroids, within-cluster spreads).
//!
//! Takes 2-D feature points; gives labels 0..K in order of first appearance (so they do not
//! depend on the order of linfa's centroids).
//!
//! * Features: (delay_ns, angle_rel_deg) standardised per position (`standardise`:
//!   z-scores, minus the position's mean, divided by its standard deviation; a feature with
//!   zero spread is only centred). Relative angles never wrap (the half-plane −90°..90°).
//! * `partition`: K-means with k-means++ initialisation and `n_runs` restarts, the RNG
//!   seeded from (seed, position, K), on the z-scores with the delay axis weighted by `w`;
//!   with `adaptive_scaling` the features are then divided by that solution's pooled
//!   within-cluster standard deviations and K-means refitted from that solution's
//!   centroids in the new metric (a warm start, one run), up to three times, stopping early
//!   at a fixed point: the metric of a mixture with a shared diagonal covariance, so a
//!   feature that does not separate clusters does not dominate.

use super::params::ClusterValid;
use crate::error::{Error, Result};
use crate::mpc::Mpc;
use linfa::prelude::*;
use linfa_clustering::{KMeans, KMeansInit};
use ndarray::Array2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// The z-scores of the MPCs' (delay, relative angle).
pub(crate) fn standardise(mpcs: &[&Mpc]) -> Vec<[f64; 2]> {
    let n = mpcs.len() as f64;
    let f = |g: &dyn Fn(&Mpc) -> f64| {
        let mean = mpcs.iter().map(|m| g(m)).sum::<f64>() / n;
        let sd = (mpcs.iter().map(|m| (g(m) - mean).powi(2)).sum::<f64>() / n).sqrt();
        (mean, if sd > 1e-12 { sd } else { 1.0 })
    };
    let (md, sd) = f(&|m| m.delay_ns);
    let (ma, sa) = f(&|m| m.angle_rel_deg);
    mpcs.iter()
        .map(|m| [(m.delay_ns - md) / sd, (m.angle_rel_deg - ma) / sa])
        .collect()
}

/// Euclidean distance of two points.
pub(crate) fn dist(a: &[f64; 2], b: &[f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// The number of clusters of a labelling (largest label + 1; `empty` for no labels).
pub(crate) fn n_clusters(labels: &[usize], empty: usize) -> usize {
    labels.iter().max().map(|m| m + 1).unwrap_or(empty)
}

/// Centroids and sizes of a labelling (k clusters, at least one slot).
pub(crate) fn centroids(x: &[[f64; 2]], labels: &[usize], k: usize) -> (Vec<[f64; 2]>, Vec<usize>) {
    let mut c = vec![[0.0f64; 2]; k.max(1)];
    let mut size = vec![0usize; k.max(1)];
    for (p, &l) in x.iter().zip(labels) {
        c[l][0] += p[0];
        c[l][1] += p[1];
        size[l] += 1;
    }
    for (ci, &s) in c.iter_mut().zip(&size) {
        if s > 0 {
            ci[0] /= s as f64;
            ci[1] /= s as f64;
        }
    }
    (c, size)
}

/// Pooled within-cluster standard deviation per feature (floored at 1e-3).
pub fn pooled_within_sd(x: &[[f64; 2]], labels: &[usize], k: usize) -> [f64; 2] {
    let (c, _) = centroids(x, labels, k);
    let mut v = [0.0f64; 2];
    for (p, &l) in x.iter().zip(labels) {
        v[0] += (p[0] - c[l][0]).powi(2);
        v[1] += (p[1] - c[l][1]).powi(2);
    }
    let dof = (x.len().saturating_sub(k)).max(1) as f64;
    [(v[0] / dof).sqrt().max(1e-3), (v[1] / dof).sqrt().max(1e-3)]
}

/// Pooled within-cluster sum of squares.
pub fn within_ss(x: &[[f64; 2]], labels: &[usize], k: usize) -> f64 {
    let (c, _) = centroids(x, labels, k);
    x.iter()
        .zip(labels)
        .map(|(p, &l)| dist(p, &c[l]).powi(2))
        .sum()
}

/// K-means labels for K clusters (linfa, k-means++, seeded).
///
/// ```
/// let x = [[0.0, 0.0], [0.1, 0.0], [5.0, 5.0], [5.1, 5.0]];
/// let l = pradar_channel::cluster::kmeans_labels(&x, 2, 1, 10).unwrap();
/// assert_eq!(l, vec![0, 0, 1, 1]);
/// ```
pub fn kmeans_labels(x: &[[f64; 2]], k: usize, seed: u64, n_runs: usize) -> Result<Vec<usize>> {
    run_kmeans(x, k, seed, n_runs, KMeansInit::KMeansPlusPlus)
}

/// K-means from given starting centroids (one run): the warm start of a refit in a new
/// metric. Labels in order of first appearance.
fn kmeans_from(x: &[[f64; 2]], init: &[[f64; 2]]) -> Result<Vec<usize>> {
    let c0 = Array2::from_shape_vec((init.len(), 2), init.concat())
        .map_err(|e| Error::param("mpcs", e.to_string()))?;
    run_kmeans(x, init.len(), 0, 1, KMeansInit::Precomputed(c0))
}

/// linfa K-means on 2-D points; labels relabelled in order of first appearance, so they do
/// not depend on the centroids' order.
fn run_kmeans(
    x: &[[f64; 2]],
    k: usize,
    seed: u64,
    n_runs: usize,
    init: KMeansInit<f64>,
) -> Result<Vec<usize>> {
    let arr = Array2::from_shape_vec((x.len(), 2), x.concat())
        .map_err(|e| Error::param("mpcs", e.to_string()))?;
    let ds = DatasetBase::from(arr);
    let model = KMeans::params_with_rng(k, ChaCha8Rng::seed_from_u64(seed))
        .n_runs(n_runs)
        .init_method(init)
        .tolerance(1e-8)
        .max_n_iterations(300)
        .fit(&ds)
        .map_err(|e| Error::param("kmeans", e.to_string()))?;
    let labels = model.predict(&ds);
    let mut map = BTreeMap::new();
    Ok(labels
        .iter()
        .map(|&l| {
            let next = map.len();
            *map.entry(l).or_insert(next)
        })
        .collect())
}

/// K's partition of the z-scores `x`: K-means (seed `seed`) with the delay axis weighted by
/// `w`, then, with `adaptive_scaling`, up to three warm-started refits in the pooled
/// within-cluster metric. Gives the labels and the features in the final metric.
pub(crate) fn partition(
    x: &[[f64; 2]],
    k: usize,
    w: f64,
    seed: u64,
    params: &ClusterValid,
) -> Result<(Vec<usize>, Vec<[f64; 2]>)> {
    let mut xs: Vec<[f64; 2]> = x.iter().map(|p| [p[0] * w, p[1]]).collect();
    let mut labels = kmeans_labels(&xs, k, seed, params.n_runs)?;
    if params.adaptive_scaling {
        for _ in 0..3 {
            let kk = n_clusters(&labels, 1);
            let sc = pooled_within_sd(x, &labels, kk);
            xs = x.iter().map(|p| [p[0] / sc[0], p[1] / sc[1]]).collect();
            // warm start: the current partition's centroids in the new metric
            let next = kmeans_from(&xs, &centroids(&xs, &labels, kk).0)?;
            // a fixed point: further rounds would refit the same metric (same labels,
            // same seed) and return the same labels
            let done = next == labels;
            labels = next;
            if done {
                break;
            }
        }
    }
    Ok((labels, xs))
}
