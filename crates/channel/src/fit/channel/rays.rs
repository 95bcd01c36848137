//! The fit's input rays: read from a clustered MPC table or a simulator's truth
//! ([`read_rays`]), checked and grouped by (position, cluster) ([`group_clusters`]), and
//! each cluster's reference ray ([`strongest_of`]).
//!
//! Takes a table's path (or the rays and the campaign's position count); gives the rays,
//! or one error naming the file, the row and the field.

use super::Ray;
use crate::error::{Error, Result};
use crate::table;
use std::collections::BTreeMap;
use std::path::Path;

/// The rays of a clustered MPC table (`truth = false`: grouped by `cluster_id`, all ≥ 0)
/// or of a truth `rays.parquet` (`truth = true`: grouped by `truth_cluster`, else
/// `cluster_id` in files written before it; rows with −1 are dropped).
pub(super) fn read_rays(path: &Path, truth: bool) -> Result<Vec<Ray>> {
    let df = table::read_parquet(path, None)?;
    let pos = table::i64_column(path, &df, "position")?;
    let column = if truth && df.column("truth_cluster").is_ok() {
        "truth_cluster"
    } else {
        "cluster_id"
    };
    let cid = table::i64_column(path, &df, column)?;
    let d = table::f64_column(path, &df, "delay_ns")?;
    let a = table::f64_column(path, &df, "angle_rel_deg")?;
    let pw = table::f64_column(path, &df, "power_db")?;
    // the dense component (diffuse MPCs, cluster_id −1) is fitted apart (`fit::diffuse`);
    // folded MPCs (cluster_id −1) are not at their true range and are left out
    let apart = match table::str_column(path, &df, "component")? {
        None => vec![false; pos.len()],
        Some(c) => c
            .iter()
            .enumerate()
            .map(|(i, x)| match crate::mpc::Component::parse(x) {
                Some(k) => Ok(k != crate::mpc::Component::Discrete),
                None => Err(Error::input(
                    path,
                    format!(
                        "column `component` row {i}: {x:?} (expected discrete, diffuse or folded)"
                    ),
                )),
            })
            .collect::<Result<Vec<_>>>()?,
    };
    (0..pos.len())
        .filter(|&i| !apart[i] && (!truth || cid[i] >= 0))
        .map(|i| {
            if pos[i] < 0 || cid[i] < 0 {
                return Err(Error::input(
                    path,
                    format!("row {i}: negative position or {column}"),
                ));
            }
            Ok(Ray {
                position: pos[i] as usize,
                cluster: cid[i] as usize,
                delay_ns: d[i],
                angle_rel_deg: a[i],
                power_db: pw[i],
            })
        })
        .collect()
}

/// The rays keyed by (position, cluster): truth cluster ids name objects seen from many
/// positions. A position outside the campaign, a delay or angle that is not finite or a
/// NaN power is an error naming `path` (bad input, not a quantity left unestimated).
pub(super) fn group_clusters(
    path: &Path,
    rays: &[Ray],
    np: usize,
) -> Result<BTreeMap<(usize, usize), Vec<Ray>>> {
    let mut by_cluster: BTreeMap<(usize, usize), Vec<Ray>> = BTreeMap::new();
    for (i, r) in rays.iter().enumerate() {
        if !(r.delay_ns.is_finite() && r.angle_rel_deg.is_finite()) || r.power_db.is_nan() {
            return Err(Error::input(
                path,
                format!(
                    "ray {i} (position {}, cluster {}): delay_ns and angle_rel_deg must be finite, power_db a number",
                    r.position, r.cluster
                ),
            ));
        }
        if r.position >= np {
            return Err(Error::input(
                path,
                format!(
                    "position {} outside the campaign ({np} positions)",
                    r.position
                ),
            ));
        }
        by_cluster
            .entry((r.position, r.cluster))
            .or_default()
            .push(*r);
    }
    Ok(by_cluster)
}

/// A cluster's reference ray: its strongest member (the last of equals). `rs` is non-empty.
pub(super) fn strongest_of(rs: &[Ray]) -> &Ray {
    rs.iter()
        .max_by(|a, b| a.power_db.total_cmp(&b.power_db))
        .expect("a cluster has members")
}
