//! K selection at one position: the candidate partitions for K = 1..min(K_max, n − 1) and
//! the choice among them by the stated [`Criterion`].
//!
//! * K = 1 is the trivial partition; for K ≥ 2 the partitions are K-means's
//!   (`kmeans::partition`), seeded from (seed, position, K).
//! * Distance indices (silhouette, CH): K's partition from the unweighted z-scores, the index
//!   measured in K's own (adaptively rescaled) metric; the largest wins, and K = 1 when the
//!   winner's silhouette is below `min_silhouette` (or no K ≥ 2 is possible).
//! * Likelihood criteria: for each K, K-means from the z-scores with the delay axis weighted
//!   by 1, 0.5, 0.25 and 2 ([`DELAY_WEIGHTS`]), each then adaptively rescaled; the partition
//!   with the best criterion value is K's candidate (clusters that overlap in delay and are
//!   separated in angle are found from the lower weights). The best over K = 1..K_max wins.
//! * Gap: the statistic picks K with its own K-means runs; K's partition is then K-means on
//!   the z-scores.
//!
//! The candidates of different K are independent (each seeded from its own K), so they are
//! made in parallel and scanned in order of K; [`cluster_position_caps`] stops one scan at
//! several caps, which is how the K_max refits share their K-means runs.

use super::criteria::{calinski_harabasz, gap::gap_k, likelihood_criterion, silhouette};
use super::kmeans::{kmeans_labels, n_clusters, partition, standardise};
use super::params::{ClusterValid, Criterion};
use super::PositionClustering;
use crate::error::Result;
use crate::mpc::Mpc;
use rayon::prelude::*;

/// Starting weights of the delay z-score against the angle z-score for the likelihood
/// criteria's candidate partitions (the best of them per K is kept).
pub const DELAY_WEIGHTS: &[f64] = &[1.0, 0.5, 0.25, 2.0];

/// The best partition so far: its score (larger is better), cluster count, labels, mean
/// silhouette (∞ for the likelihood criteria) and the K tried.
#[derive(Clone)]
struct Candidate {
    score: f64,
    k: usize,
    labels: Vec<usize>,
    silhouette: f64,
    k_tried: usize,
}

/// The scan over K: the per-K criterion values and the best candidate.
#[derive(Default, Clone)]
struct Scan {
    silhouettes: Vec<(usize, f64)>,
    ch: Vec<(usize, f64)>,
    likelihood: Vec<(usize, f64)>,
    best: Option<Candidate>,
}

impl Scan {
    /// Keep `labels` (K tried `k_tried`, score `score`) if it beats the best so far.
    fn offer(&mut self, score: f64, labels: Vec<usize>, silhouette: f64, k_tried: usize) {
        if self.best.as_ref().map(|b| score > b.score).unwrap_or(true) {
            self.best = Some(Candidate {
                score,
                k: n_clusters(&labels, 0),
                labels,
                silhouette,
                k_tried,
            });
        }
    }

    /// The winning partition; K = 1 when the distance indices found no substantial
    /// structure (or there was no candidate).
    fn finish(self, like: bool, n: usize, min_silhouette: f64) -> PositionClustering {
        let (k, k_tried, labels) = match self.best {
            Some(b) if like || b.silhouette >= min_silhouette => (b.k, b.k_tried, b.labels),
            _ => (1, 1, vec![0; n]),
        };
        PositionClustering {
            k,
            k_tried,
            labels,
            silhouettes: self.silhouettes,
            ch: self.ch,
            likelihood: self.likelihood,
        }
    }
}

/// The clustering of a position with no MPCs.
fn no_mpcs() -> PositionClustering {
    PositionClustering {
        k: 0,
        k_tried: 0,
        labels: vec![],
        silhouettes: vec![],
        ch: vec![],
        likelihood: vec![],
    }
}

/// K by the gap statistic and K's K-means partition of the z-scores `x`.
fn by_gap(
    x: &[[f64; 2]],
    kmax: usize,
    params: &ClusterValid,
    pos_seed: u64,
) -> Result<PositionClustering> {
    let k_tried = if kmax >= 2 {
        gap_k(x, kmax, params, pos_seed)?
    } else {
        1
    };
    let labels = if k_tried >= 2 {
        kmeans_labels(x, k_tried, pos_seed ^ k_tried as u64, params.n_runs)?
    } else {
        vec![0; x.len()]
    };
    Ok(PositionClustering {
        k: n_clusters(&labels, 1),
        k_tried,
        labels,
        silhouettes: vec![],
        ch: vec![],
        likelihood: vec![],
    })
}

/// K's candidate under a likelihood criterion: the best (smallest) criterion value over the
/// starting delay weights, compared in the original units `raw`.
fn likelihood_candidate(
    x: &[[f64; 2]],
    raw: &[[f64; 2]],
    k: usize,
    pos_seed: u64,
    params: &ClusterValid,
) -> Result<(Vec<usize>, f64)> {
    let mut bestk: Option<(Vec<usize>, f64)> = None;
    for &w in DELAY_WEIGHTS {
        let (l, _) = partition(x, k, w, pos_seed ^ k as u64, params)?;
        let v = likelihood_criterion(raw, &l, params.criterion, params);
        if bestk.as_ref().map(|b| v < b.1).unwrap_or(true) {
            bestk = Some((l, v));
        }
    }
    Ok(bestk.expect("at least one weight"))
}

/// K's partition for the distance indices and its (silhouette, CH), both measured in K's
/// own metric.
fn index_candidate(
    x: &[[f64; 2]],
    k: usize,
    pos_seed: u64,
    params: &ClusterValid,
) -> Result<(Vec<usize>, f64, f64)> {
    let (l, xs) = partition(x, k, 1.0, pos_seed ^ k as u64, params)?;
    let kk = n_clusters(&l, 0);
    let s = silhouette(&xs, &l, kk);
    let c = calinski_harabasz(&xs, &l, kk);
    Ok((l, s, c))
}

/// Cluster the MPCs of one position.
///
/// ```
/// use pradar_channel::cluster::{cluster_position, ClusterParams};
/// use pradar_channel::mpc::Mpc;
/// use pradar_formats::params::ParamGuard;
/// let mpc = |delay_ns: f64, angle_rel_deg: f64| Mpc {
///     position: 0, delay_ns, angle_rel_deg, angle_global_deg: angle_rel_deg,
///     power_db: -60.0, snr_db: 30.0, x_m: 0.0, y_m: 0.0, direction: 0, bin: 0,
///     component: pradar_channel::mpc::Component::Discrete,
///     wall: None,
/// };
/// let ms: Vec<Mpc> = (0..8)
///     .map(|i| mpc(10.0 + 0.3 * i as f64, -50.0 + i as f64))
///     .chain((0..8).map(|i| mpc(40.0 + 0.3 * i as f64, 45.0 - i as f64)))
///     .collect();
/// let refs: Vec<&Mpc> = ms.iter().collect();
/// let pc = cluster_position(&refs, &ClusterParams::default().check().unwrap(), 0).unwrap();
/// assert_eq!(pc.k, 2);
/// ```
pub fn cluster_position(
    mpcs: &[&Mpc],
    params: &ClusterValid,
    position: usize,
) -> Result<PositionClustering> {
    let mut v = cluster_position_caps(mpcs, params, position, &[params.k_max])?;
    Ok(v.pop().expect("one cap"))
}

/// One K's candidate: labels, and the criterion values it adds to the scan.
enum KCandidate {
    Likelihood(Vec<usize>, f64),
    Index(Vec<usize>, f64, f64),
}

/// Cluster the MPCs of one position once for each cap in `caps` (each used as `k_max`; the
/// other parameters from `params`). The candidates of K = 2..max(caps) are made once (in
/// parallel: each is seeded from (seed, position, K) alone) and scanned in order of K; the
/// result for a cap is the scan stopped at that cap, the same as [`cluster_position`] with
/// `k_max` = cap. The gap statistic's choice depends on the whole range, so it is run per
/// cap.
pub fn cluster_position_caps(
    mpcs: &[&Mpc],
    params: &ClusterValid,
    position: usize,
    caps: &[usize],
) -> Result<Vec<PositionClustering>> {
    let n = mpcs.len();
    if n == 0 {
        return Ok(caps.iter().map(|_| no_mpcs()).collect());
    }
    let x = standardise(mpcs);
    let cap_of = |k_max: usize| k_max.min(n.saturating_sub(1));
    let pos_seed = params.seed ^ (position as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    if params.criterion == Criterion::Gap {
        // the gap statistic uses its own K-means runs on the z-scores: no silhouette scan
        return (caps.iter())
            .map(|&c| by_gap(&x, cap_of(c), params, pos_seed))
            .collect();
    }
    let raw: Vec<[f64; 2]> = mpcs.iter().map(|m| [m.delay_ns, m.angle_rel_deg]).collect();
    let like = params.criterion.is_likelihood();
    let top = caps.iter().map(|&c| cap_of(c)).max().unwrap_or(0);
    let candidates: Vec<KCandidate> = (2..=top.max(1))
        .into_par_iter()
        .map(|k| {
            Ok(if like {
                let (l, v) = likelihood_candidate(&x, &raw, k, pos_seed, params)?;
                KCandidate::Likelihood(l, v)
            } else {
                let (l, s, c) = index_candidate(&x, k, pos_seed, params)?;
                KCandidate::Index(l, s, c)
            })
        })
        .collect::<Result<_>>()?;
    let mut scan = Scan::default();
    if like {
        let ones = vec![0; n];
        let v = likelihood_criterion(&raw, &ones, params.criterion, params);
        scan.likelihood.push((1, v));
        scan.offer(-v, ones, f64::INFINITY, 1);
    }
    // the scan as it stands at each cap (K = 1: before any candidate)
    let stops: Vec<usize> = caps.iter().map(|&c| cap_of(c).max(1)).collect();
    let mut at: Vec<Option<Scan>> = vec![None; caps.len()];
    let mut keep = |k: usize, scan: &Scan| {
        for (slot, _) in at.iter_mut().zip(&stops).filter(|(_, &s)| s == k) {
            *slot = Some(scan.clone());
        }
    };
    keep(1, &scan);
    for (k, cand) in (2..).zip(candidates) {
        match cand {
            KCandidate::Likelihood(l, v) => {
                scan.likelihood.push((k, v));
                scan.offer(-v, l, f64::INFINITY, k);
            }
            KCandidate::Index(l, s, c) => {
                scan.silhouettes.push((k, s));
                scan.ch.push((k, c));
                let score = if params.criterion == Criterion::Silhouette {
                    s
                } else {
                    c
                };
                scan.offer(score, l, s, k);
            }
        }
        keep(k, &scan);
    }
    Ok(at
        .into_iter()
        .map(|s| (s.expect("every cap is scanned up to")).finish(like, n, params.min_silhouette))
        .collect())
}
