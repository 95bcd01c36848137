//! The AoA samples: each cluster's offsets from its reference (strongest) ray
//! ([`aoa_offsets`]), the sector-edge margin 2·b̂₀ ([`aoa_margin`]) and the samples per
//! position from the clusters that lie that far inside the sector ([`aoa_groups`]).
//!
//! Takes the rays grouped by (position, cluster) and the scanned sector; gives the
//! offsets, the margin and the AoA sample groups.

use super::rays::strongest_of;
use super::Ray;
use crate::fit::estimators::{fit, Family};
use crate::fit::quantities::Groups;
use std::collections::BTreeMap;

/// One cluster's AoA: its position, its reference (strongest) ray's angle and the other
/// rays' offsets from it.
type ClusterAoa = (usize, f64, Vec<f64>);

/// The AoA offsets of every cluster (the reference ray left out).
pub(super) fn aoa_offsets(by_cluster: &BTreeMap<(usize, usize), Vec<Ray>>) -> Vec<ClusterAoa> {
    by_cluster
        .values()
        .map(|rs| {
            let strongest = strongest_of(rs);
            let mut skipped = false;
            let mut offsets = Vec::with_capacity(rs.len());
            for r in rs {
                if !skipped && std::ptr::eq(r, strongest) {
                    skipped = true;
                    continue;
                }
                offsets.push(r.angle_rel_deg - strongest.angle_rel_deg);
            }
            (rs[0].position, strongest.angle_rel_deg, offsets)
        })
        .collect()
}

/// The sector-edge margin 2·b̂₀ (degrees), b̂₀ the Laplacian scale fitted to the AoA
/// offsets of all clusters (0 when they cannot be fitted). A ray lies beyond 2b of its
/// cluster's reference with probability e^{−2}/2 = 7 % on each side.
pub(super) fn aoa_margin(clusters: &[ClusterAoa]) -> f64 {
    let all: Vec<f64> = clusters.iter().flat_map(|c| c.2.iter().copied()).collect();
    fit(Family::Laplacian, &all).map_or(0.0, |f| 2.0 * f.params[1])
}

/// The AoA samples per position, from the clusters whose reference ray lies at least 2·b̂₀
/// inside the scanned sector, b̂₀ the Laplacian scale fitted to all clusters (the margin
/// at most a quarter of the sector; all clusters when none lies that far in). A cluster
/// whose reference is near a sector edge loses the rays beyond the edge, and what is left
/// is mostly one side of the Laplacian. A Laplacian tail beyond 2b holds e^{−2}/2 = 7 % of
/// the rays.
pub(super) fn aoa_groups(
    clusters: &[ClusterAoa],
    np: usize,
    lo: f64,
    hi: f64,
    margin: f64,
) -> Groups {
    let mut groups: Groups = vec![Vec::new(); np];
    let margin = margin.min((hi - lo) / 4.0);
    let inner = |a: f64| a >= lo + margin && a <= hi - margin;
    let any_inner = clusters.iter().any(|c| inner(c.1) && !c.2.is_empty());
    for (pos, reference, offsets) in clusters {
        if !any_inner || inner(*reference) {
            groups[*pos].extend_from_slice(offsets);
        }
    }
    groups
}
