//! The gap statistic (Tibshirani, Walther & Hastie 2001) on the z-scores.
//!
//! Gap(K) = E*[ln W_K] − ln W_K, W_K the pooled within-cluster sum of squares of K-means
//! with K clusters, E* the mean over `gap_refs` (at least 2) reference sets drawn uniformly
//! over the data's bounding box; s(K) = sd*(ln W_K) · √(1 + 1/B). K is the smallest K with
//! Gap(K) ≥ Gap(K+1) − s(K+1), over 1..=K_max (K = 1 handled natively). The statistic uses
//! its own K-means runs on the unweighted z-scores (no adaptive rescaling).

use crate::cluster::kmeans::{kmeans_labels, n_clusters, within_ss};
use crate::cluster::params::ClusterValid;
use crate::error::Result;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// ln W_K of K-means with `k` clusters (the trivial partition for K = 1).
fn log_w(x: &[[f64; 2]], k: usize, seed: u64, n_runs: usize) -> Result<f64> {
    let labels = if k == 1 {
        vec![0; x.len()]
    } else {
        kmeans_labels(x, k, seed, n_runs)?
    };
    let kk = n_clusters(&labels, 1);
    Ok(within_ss(x, &labels, kk).max(1e-300).ln())
}

/// `b` reference sets of `n` points drawn uniformly over the bounding box of `x`.
fn reference_sets(x: &[[f64; 2]], b: usize, seed: u64) -> Vec<Vec<[f64; 2]>> {
    use rand::Rng;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x05EE_D6A9);
    let lo = [
        x.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min),
        x.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min),
    ];
    let hi = [
        x.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max),
        x.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max),
    ];
    (0..b)
        .map(|_| {
            (0..x.len())
                .map(|_| {
                    [
                        lo[0] + (hi[0] - lo[0]) * rng.gen::<f64>(),
                        lo[1] + (hi[1] - lo[1]) * rng.gen::<f64>(),
                    ]
                })
                .collect()
        })
        .collect()
}

/// K by the gap statistic over 1..=kmax.
pub(crate) fn gap_k(
    x: &[[f64; 2]],
    kmax: usize,
    params: &ClusterValid,
    seed: u64,
) -> Result<usize> {
    let b = params.gap_refs.max(2);
    let refs = reference_sets(x, b, seed);
    let mut gap = Vec::new();
    let mut sd = Vec::new();
    for k in 1..=(kmax + 1).min(x.len()) {
        let lw = log_w(x, k, seed ^ k as u64, params.n_runs)?;
        let lr: Vec<f64> = refs
            .iter()
            .map(|r| log_w(r, k, seed ^ k as u64, params.n_runs))
            .collect::<Result<_>>()?;
        let mean = lr.iter().sum::<f64>() / b as f64;
        let var = lr.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / b as f64;
        gap.push(mean - lw);
        sd.push(var.sqrt() * (1.0 + 1.0 / b as f64).sqrt());
    }
    for k in 0..gap.len().saturating_sub(1) {
        if gap[k] >= gap[k + 1] - sd[k + 1] {
            return Ok(k + 1);
        }
    }
    Ok(gap.len().min(kmax).max(1))
}
