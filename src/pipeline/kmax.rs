//! Table 1's cluster-count quantities against the clustering cap K_max
//! ([`k_max_sensitivity`]).
//!
//! Where the clustering criterion keeps preferring more clusters, Λ, λ, the AoA spread and
//! d_c are set by K_max rather than found; refitting with the cap raised to 2× and 3× the
//! default, beside the default fit and the simulator's truth through the same
//! estimators, shows by how much (README "Corridor and K_max"). With K found rather than
//! capped the rows agree: the table is the check that K no longer moves (the count of
//! positions whose K changed against the default is its own column).

use crate::campaign::manifest::Campaign;
use crate::cluster;
use crate::error::Result;
use crate::export::{Cell, Column, Table};
use crate::fit::channel::ChannelFit;
use crate::model::file::{ModelConfig, Quantity};
use crate::params::ParamGuard;
use std::path::Path;

/// The larger caps of the K_max sensitivity table, as multiples of the default.
pub(crate) const K_MAX_FACTORS: [usize; 2] = [2, 3];

/// The text before the table in `table1_kmax.md`.
const KMAX_MD_HEAD: &str = "# Table 1 against the clustering cap K_max\n\nThe cluster-count quantities refitted with K_max raised; where positions end at the cap, the criterion still preferred more clusters and the values are set by K_max.\n\n";

/// Table 1's cluster-count quantities refitted with the clustering cap raised to 2× and 3×
/// the default, beside the default fit and the truth; written as
/// `out/table1_kmax.md` (clusterings in `work/clusters_kmax<K>.parquet`) and returned for the
/// report.
pub(crate) fn k_max_sensitivity(
    sc: &Campaign,
    base: &cluster::Clustering,
    params: &cluster::ClusterParams,
    default_fit: Option<&ChannelFit>,
    truth: Option<&ChannelFit>,
    work: &Path,
    out: &Path,
) -> Result<Table> {
    let headings: Vec<f64> = sc.manifest.poses.iter().map(|p| p.heading_deg).collect();
    let mut t = kmax_table();
    t.push(kmax_row(
        format!("{} (default)", params.k_max),
        ks_of(base, params.k_max),
        Cell::count(0),
        default_fit,
    ));
    // both refits from one scan per position (the 2× cap's candidates serve the 3× too)
    let ks: Vec<usize> = K_MAX_FACTORS.iter().map(|f| f * params.k_max).collect();
    let clusterings = cluster::cluster_caps(&base.mpcs, &headings, &params.check()?, &ks)?;
    for (k, c) in ks.into_iter().zip(clusterings) {
        let path = work.join(format!("clusters_kmax{k}.parquet"));
        cluster::write(&path, &c)?;
        let f = crate::fit::channel::fit_clustering(&path, &c, sc, &Default::default()).ok();
        let changed = Cell::count(c.k_changed(base).len());
        t.push(kmax_row(k.to_string(), ks_of(&c, k), changed, f.as_ref()));
    }
    if let Some(f) = truth {
        t.push(kmax_row(
            "simulator truth (same estimators)".into(),
            "—".into(),
            Cell::missing("—"),
            Some(f),
        ));
    }
    let md = format!("{KMAX_MD_HEAD}{}", t.to_markdown());
    crate::io::write_bytes(&out.join("table1_kmax.md"), md.as_bytes())?;
    Ok(t)
}

/// The K_max table's columns.
fn kmax_table() -> Table {
    Table::new(vec![
        Column::new("K_max", "k_max"),
        Column::new("K per position", "k_per_position"),
        Column::new("positions whose K changed", "k_changed"),
        Column::new("Λ (1/ns)", "inter_cluster_rate_per_ns"),
        Column::new("d_c (m)", "perimeter_spacing_m"),
        Column::new("λ (1/ns)", "intra_cluster_rate_per_ns"),
        Column::new("AoA std (deg)", "intra_cluster_aoa_std_deg"),
        Column::new("γ (ns)", "ray_decay_ns"),
    ])
}

/// One row: the cap, the K range, and the fit's cluster-count quantities ("—" without a fit,
/// "not estimable" where the fit could not estimate one; both empty in a CSV).
fn kmax_row(label: String, ks: String, changed: Cell, f: Option<&ChannelFit>) -> Vec<Cell> {
    let v = |g: fn(&ModelConfig) -> &Quantity, digits: usize| match f.map(|f| g(&f.model)) {
        None => Cell::missing("—"),
        Some(q) if !q.is_estimable() => Cell::missing("not estimable"),
        Some(q) => Cell::fixed(q.value, digits),
    };
    vec![
        Cell::text(label),
        Cell::text(ks),
        changed,
        v(|m| &m.inter_cluster_rate, 3),
        v(|m| &m.perimeter_spacing, 2),
        v(|m| &m.intra_cluster_rate, 3),
        v(|m| &m.intra_cluster_aoa, 1),
        v(|m| &m.ray_decay, 2),
    ]
}

/// "lo–hi (n of N at the cap)" of the K chosen per position.
fn ks_of(c: &cluster::Clustering, k_max: usize) -> String {
    let ks: Vec<usize> = c.positions.iter().map(|p| p.k).collect();
    let (lo, hi) = (
        ks.iter().min().copied().unwrap_or(0),
        ks.iter().max().copied().unwrap_or(0),
    );
    format!(
        "{lo}–{hi} ({} of {} at the cap)",
        c.positions_at_k_max(k_max).len(),
        c.positions.len()
    )
}
