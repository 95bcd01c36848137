//! Partition stability: how reproducible the chain's clusters of a campaign are.
//!
//! Takes the clustered MPCs (their labels as the data's chain gave them), the poses'
//! headings and the clustering parameters; gives a [`PartitionStability`]: per position
//! the mean adjusted Rand index (`cluster::adjusted_rand_index`) between the data's
//! partition and the chain's partition of a resample of that position's discrete MPCs
//! (a random 80 % of them, without replacement; the two partitions compared on the drawn
//! MPCs), over `resamples` resamples, and the MPC-weighted mean over positions. Every position is resampled in each replicate and the replicate
//! clustered as a whole campaign (`cluster::cluster`, positions in parallel).
//!
//! Why: a partition that a resample of its own points does not reproduce carries little
//! about the physical clusters, and Table 1's cluster quantities then rest on the bias
//! correction rather than on the clusters (Ben-Hur, Elisseeff & Guyon 2002 compare
//! subsample clusterings so; Hennig 2007 per cluster). Subsamples rather than bootstrap
//! resamples with replacement: a duplicated MPC is a zero-spread pair that the
//! cross-validated criterion can read as a cluster of its own, so three well-separated
//! blobs read ARI 0.79 with duplicates (the unit test's scene). A position with fewer
//! than 2 discrete MPCs has no partition to compare (NaN).

use crate::cluster::{adjusted_rand_index, ClusterValid};
use crate::error::Result;
use crate::fit::corrected::PartitionStability;
use crate::mpc::{Component, Mpc};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// The share of each position's MPCs a subsample keeps.
const SUBSAMPLE: f64 = 0.8;

/// The partition stability of `mpcs` labelled `labels` (`None` for a diffuse MPC), their
/// poses' headings `headings_deg`, clustered with `params`; `resamples` subsamples
/// seeded by `seed`.
pub fn partition_stability(
    mpcs: &[Mpc],
    labels: &[Option<usize>],
    headings_deg: &[f64],
    params: &ClusterValid,
    resamples: usize,
    seed: u64,
) -> Result<PartitionStability> {
    let np = headings_deg.len();
    // the discrete MPCs of each position
    let mut by_pos: Vec<Vec<usize>> = vec![Vec::new(); np];
    for (i, m) in mpcs.iter().enumerate() {
        if m.component == Component::Discrete && labels[i].is_some() && m.position < np {
            by_pos[m.position].push(i);
        }
    }
    let mut sums = vec![0.0; np];
    let mut counts = vec![0usize; np];
    for b in 0..resamples {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5354_4142);
        rng.set_stream(b as u64 + 1);
        // the drawn MPCs (indices into `mpcs`), position by position: a random 80 % of
        // each position's, without replacement
        let mut drawn: Vec<usize> = Vec::new();
        for idx in &by_pos {
            let keep = ((SUBSAMPLE * idx.len() as f64).round() as usize).max(2.min(idx.len()));
            let mut pick = idx.clone();
            pick.shuffle(&mut rng);
            pick.truncate(keep);
            pick.sort_unstable();
            drawn.extend(pick);
        }
        let resample: Vec<Mpc> = drawn.iter().map(|&i| mpcs[i].clone()).collect();
        let c = crate::cluster::cluster(&resample, headings_deg, params)?;
        let mut per: BTreeMap<usize, (Vec<usize>, Vec<usize>)> = BTreeMap::new();
        for (k, &i) in drawn.iter().enumerate() {
            if let (Some(a), Some(n)) = (labels[i], c.cluster_id[k]) {
                let e = per.entry(mpcs[i].position).or_default();
                e.0.push(a);
                e.1.push(n);
            }
        }
        for (p, (a, n)) in per {
            if a.len() >= 2 {
                sums[p] += adjusted_rand_index(&a, &n);
                counts[p] += 1;
            }
        }
    }
    let per_position: Vec<f64> = (0..np)
        .map(|p| {
            if counts[p] > 0 {
                sums[p] / counts[p] as f64
            } else {
                f64::NAN
            }
        })
        .collect();
    let (mut w, mut s) = (0.0, 0.0);
    for (p, a) in per_position.iter().enumerate() {
        if a.is_finite() {
            w += by_pos[p].len() as f64;
            s += by_pos[p].len() as f64 * a;
        }
    }
    Ok(PartitionStability {
        per_position,
        overall: if w > 0.0 { s / w } else { f64::NAN },
        resamples,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cluster::ClusterParams;
    use crate::params::ParamGuard;

    fn mpc(position: usize, delay_ns: f64, angle: f64) -> Mpc {
        Mpc {
            position,
            delay_ns,
            angle_rel_deg: angle,
            angle_global_deg: angle,
            power_db: -60.0,
            snr_db: 20.0,
            x_m: 0.0,
            y_m: 0.0,
            direction: 0,
            bin: 0,
            component: Component::Discrete,
            wall: None,
        }
    }

    /// Three well-separated blobs are found again in every resample (ARI 1); one
    /// position's labels scrambled against its geometry read far lower.
    #[test]
    fn separated_clusters_are_stable_and_scrambled_labels_are_not() {
        let mut mpcs = Vec::new();
        let mut labels = Vec::new();
        for p in 0..2 {
            for (k, (d, a)) in [(20.0, -40.0), (60.0, 0.0), (100.0, 40.0)]
                .iter()
                .enumerate()
            {
                for i in 0..8 {
                    let j = i as f64;
                    mpcs.push(mpc(p, d + 0.3 * (j - 3.5), a + 0.5 * (j - 3.5)));
                    // position 1's labels cycle, whatever the geometry
                    labels.push(Some(if p == 0 { k } else { i % 3 }));
                }
            }
        }
        let params = ClusterParams::default().check().unwrap();
        let s = partition_stability(&mpcs, &labels, &[0.0, 0.0], &params, 4, 1).unwrap();
        assert!((s.per_position[0] - 1.0).abs() < 1e-9, "{s:?}");
        assert!(s.per_position[1] < 0.2, "{s:?}");
        assert!((s.overall - 0.5 * (s.per_position[0] + s.per_position[1])).abs() < 1e-9);
        assert_eq!(s.resamples, 4);
        let again = partition_stability(&mpcs, &labels, &[0.0, 0.0], &params, 4, 1).unwrap();
        assert_eq!(s, again);
    }
}
