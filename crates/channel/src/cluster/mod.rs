//! Clustering of MPCs (DESIGN §2 "Clustering"): K-means (linfa-clustering, k-means++,
//! seeded) per position on scaled (delay, angle_rel), K from a stated criterion.
//!
//! Takes the MPCs of each position and checked parameters ([`ClusterValid`]); gives a
//! cluster label per discrete MPC (ids unique over the campaign, numbered position by
//! position; diffuse MPCs — the dense wall returns labelled by [`crate::mpc::diffuse`] —
//! are not clustered and carry no id, `cluster_id` −1 in the table) and a per-cluster
//! summary ([`Clustering`]).
//!
//! * Features ([`kmeans`]): (delay_ns, angle_rel_deg) standardised per position (z-scores).
//! * Partitions (`kmeans::partition`): for K = 2..min(K_max, n − 1), K-means with
//!   k-means++ initialisation, `n_runs` restarts, the RNG seeded from (seed, position, K),
//!   then with `adaptive_scaling` (default) refitted in the pooled within-cluster metric (the
//!   metric of a mixture with a shared diagonal covariance). K = 1 is the trivial
//!   partition. K-means is the only clustering algorithm: the criteria only choose among
//!   its partitions.
//! * Criteria ([`criteria`], [`Criterion`]), each measured on K's own partition: mean
//!   silhouette, Calinski–Harabasz, the gap statistic, ChannelBic (the channel model's
//!   exponential-delay × Laplacian-angle component), GaussBic (X-means), and the
//!   cross-validated leave-one-out likelihood with a "new cluster" term, with per-cluster
//!   (`CrossValidated`, the default) or shared (`CrossValidatedShared`) scales.
//! * Selection ([`select`]): the candidate partitions per K (four delay weights for the
//!   likelihood criteria) and the winner; K = 1 when the distance indices find no
//!   substantial structure.
//! * K_max (default 16) caps K; with the diffuse wall returns set apart it does not bind on
//!   the built-in corridor, and raising it to 2× and 3× changes K at few positions
//!   ([`Clustering::k_changed`]; figures in `docs/cluster.md`). Where a position's criterion still prefers the cap,
//!   [`Clustering::positions_at_k_max`] names it, `pradar cluster` warns and the report
//!   lists K per position.
//! * Summary per cluster ([`summary`]) and Parquet output ([`io`]); the adjusted Rand index
//!   ([`metrics`]) compares labellings.
//!
//! Positions are clustered in parallel; the result does not depend on the thread count.
//! Measurements of the criteria and of the default's choice are in `docs/cluster.md`.
//!
//! ```
//! use pradar_channel::cluster::{cluster, ClusterParams};
//! use pradar_channel::mpc::Mpc;
//! use pradar_formats::params::ParamGuard;
//! let mpc = |delay_ns: f64, angle_rel_deg: f64| Mpc {
//!     position: 0, delay_ns, angle_rel_deg, angle_global_deg: angle_rel_deg,
//!     power_db: -60.0, snr_db: 30.0, x_m: 0.0, y_m: 0.0, direction: 0, bin: 0,
//!     component: pradar_channel::mpc::Component::Discrete,
//!     wall: None,
//! };
//! let mpcs: Vec<Mpc> = (0..8)
//!     .map(|i| mpc(10.0 + 0.3 * i as f64, -50.0 + i as f64))
//!     .chain((0..8).map(|i| mpc(40.0 + 0.3 * i as f64, 45.0 - i as f64)))
//!     .collect();
//! let params = ClusterParams::default().check().unwrap();
//! let c = cluster(&mpcs, &[0.0], &params).unwrap();
//! assert_eq!(c.summary.len(), 2);
//! assert!(ClusterParams::default().k_max(0).check().is_err());
//! ```

pub mod criteria;
pub mod io;
pub mod kmeans;
pub mod metrics;
pub mod params;
pub mod select;
pub mod summary;

pub use criteria::{calinski_harabasz, likelihood_criterion, silhouette};
pub use io::{summary_path, write};
pub use kmeans::{kmeans_labels, pooled_within_sd, within_ss};
pub use metrics::adjusted_rand_index;
pub use params::{ClusterParams, ClusterValid, Criterion};
pub use select::{cluster_position, cluster_position_caps};
pub use summary::ClusterSummary;

use crate::error::Result;
use crate::mpc::{Component, Mpc};
use crate::params::ParamGuard;
use rayon::prelude::*;

/// Result of clustering one position.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionClustering {
    /// Chosen K (0 for no MPCs).
    pub k: usize,
    /// The K whose partition won (the K tried; `k` can be smaller when K-means left a
    /// cluster empty).
    pub k_tried: usize,
    /// Label per MPC (0..k).
    pub labels: Vec<usize>,
    /// Mean silhouette per tried K (K, s).
    pub silhouettes: Vec<(usize, f64)>,
    /// CH per tried K.
    pub ch: Vec<(usize, f64)>,
    /// Likelihood criterion per tried K (K, value; BIC, or −2 × the leave-one-out
    /// log-likelihood: smaller is better); empty for the other criteria.
    pub likelihood: Vec<(usize, f64)>,
}

/// Clustering of a whole campaign.
#[derive(Debug, Clone)]
pub struct Clustering {
    /// MPCs in input order.
    pub mpcs: Vec<Mpc>,
    /// Campaign-wide cluster id per MPC (None for a diffuse or folded MPC: the dense
    /// component and the echoes from beyond the unambiguous range are not clustered).
    pub cluster_id: Vec<Option<usize>>,
    /// Per-cluster summaries.
    pub summary: Vec<ClusterSummary>,
    /// Per-position details (index = position).
    pub positions: Vec<PositionClustering>,
}

impl Clustering {
    /// The positions whose chosen K is the cap `k_max` while their MPCs allowed more
    /// (K_max < n − 1): there the criterion still preferred the largest K tried, so the
    /// cluster count, and with it Λ, λ, the AoA spread and d_c, is set by K_max rather than
    /// found.
    pub fn positions_at_k_max(&self, k_max: usize) -> Vec<usize> {
        self.positions_at_k_max_inner(k_max)
    }

    /// The positions whose chosen K differs between `self` and `other` (the same MPCs
    /// clustered with another K_max): K is found, not capped, when this is nearly empty.
    pub fn k_changed(&self, other: &Clustering) -> Vec<usize> {
        self.positions
            .iter()
            .zip(&other.positions)
            .enumerate()
            .filter(|(_, (a, b))| a.k != b.k)
            .map(|(p, _)| p)
            .collect()
    }

    fn positions_at_k_max_inner(&self, k_max: usize) -> Vec<usize> {
        self.positions
            .iter()
            .enumerate()
            .filter(|(_, pc)| pc.k_tried == k_max && pc.labels.len() > k_max + 1)
            .map(|(p, _)| p)
            .collect()
    }
}

/// The discrete MPCs' indices of each position (index = position; at least `n_positions`
/// entries).
fn by_position(mpcs: &[Mpc], n_positions: usize) -> Vec<Vec<usize>> {
    let np = mpcs
        .iter()
        .map(|m| m.position + 1)
        .max()
        .unwrap_or(0)
        .max(n_positions);
    let mut by_pos: Vec<Vec<usize>> = vec![Vec::new(); np];
    for (i, m) in mpcs.iter().enumerate() {
        if m.component == Component::Discrete {
            by_pos[m.position].push(i);
        }
    }
    by_pos
}

/// Cluster every position (positions in parallel; deterministic for any thread count).
/// `headings_deg[p]` gives the pose heading for the global centroid angle.
pub fn cluster(mpcs: &[Mpc], headings_deg: &[f64], params: &ClusterValid) -> Result<Clustering> {
    let mut v = cluster_caps(mpcs, headings_deg, params, &[params.k_max])?;
    Ok(v.pop().expect("one cap"))
}

/// [`cluster`] once for each cap in `caps` (each used as `k_max` and checked as one), sharing the K-means
/// candidates of the K the caps have in common ([`select::cluster_position_caps`]): the
/// result for a cap equals [`cluster`] with `k_max` = cap.
pub fn cluster_caps(
    mpcs: &[Mpc],
    headings_deg: &[f64],
    params: &ClusterValid,
    caps: &[usize],
) -> Result<Vec<Clustering>> {
    for &k_max in caps {
        ClusterParams { k_max, ..**params }.check()?;
    }
    let by_pos = by_position(mpcs, headings_deg.len());
    let per: Vec<Vec<PositionClustering>> = by_pos
        .par_iter()
        .enumerate()
        .map(|(p, idx)| {
            let ms: Vec<&Mpc> = idx.iter().map(|&i| &mpcs[i]).collect();
            select::cluster_position_caps(&ms, params, p, caps)
        })
        .collect::<Result<_>>()?;
    // [position][cap] → [cap][position]
    let mut per_cap: Vec<Vec<PositionClustering>> = caps.iter().map(|_| Vec::new()).collect();
    for at_caps in per {
        for (v, pc) in per_cap.iter_mut().zip(at_caps) {
            v.push(pc);
        }
    }
    Ok(per_cap
        .into_iter()
        .map(|per| assemble(mpcs, &by_pos, per, headings_deg))
        .collect())
}

/// Campaign-wide cluster ids, position by position, and the summaries.
fn assemble(
    mpcs: &[Mpc],
    by_pos: &[Vec<usize>],
    per: Vec<PositionClustering>,
    headings_deg: &[f64],
) -> Clustering {
    let mut cluster_id = vec![None; mpcs.len()];
    let mut summary = Vec::new();
    for (p, (idx, pc)) in by_pos.iter().zip(&per).enumerate() {
        for c in 0..pc.k {
            let members: Vec<&Mpc> = idx
                .iter()
                .zip(&pc.labels)
                .filter(|(_, &l)| l == c)
                .map(|(&i, _)| &mpcs[i])
                .collect();
            if members.is_empty() {
                continue;
            }
            let id = summary.len();
            for (&i, &l) in idx.iter().zip(&pc.labels) {
                if l == c {
                    cluster_id[i] = Some(id);
                }
            }
            let heading = headings_deg.get(p).copied();
            summary.push(ClusterSummary::of(p, id, &members, heading));
        }
    }
    Clustering {
        mpcs: mpcs.to_vec(),
        cluster_id,
        summary,
        positions: per,
    }
}
