//! Parquet output of a clustering (DESIGN §3): the clustered MPC table (the MPC columns plus
//! `cluster_id`, −1 for diffuse MPCs) and the per-cluster summary `<stem>_summary.parquet`, both with
//! `schema_version` 1. The clustered table also carries the MPC table's `energy` key (the
//! energy table it came from, [`ENERGY_KEY`]) when given ([`write_with()`]): `fit` reads the
//! model's levels from that table.

use super::Clustering;
use crate::error::{Error, Result};
use crate::table;
use std::path::{Path, PathBuf};

/// Where the summary of the clustered MPC table `path` goes: `<stem>_summary.parquet`.
pub fn summary_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "clusters".into());
    path.with_file_name(format!("{stem}_summary.parquet"))
}

/// The metadata key naming the energy table an MPC or clustered MPC table came from
/// (its absolute path).
pub const ENERGY_KEY: &str = "energy";

/// The energy table an MPC or clustered MPC table names in its metadata (`energy`), if any.
pub fn energy_of(path: &Path) -> Result<Option<PathBuf>> {
    Ok(table::parquet_metadata(path)?
        .into_iter()
        .find(|(k, _)| k == ENERGY_KEY)
        .map(|(_, v)| PathBuf::from(v)))
}

/// Write the clustered MPC table (`path`) and the summary (`<stem>_summary.parquet`).
pub fn write(path: &Path, c: &Clustering) -> Result<PathBuf> {
    write_with(path, c, None)
}

/// [`write()`], the clustered table naming the energy table `energy` in its metadata.
pub fn write_with(path: &Path, c: &Clustering, energy: Option<&Path>) -> Result<PathBuf> {
    let mut df = crate::mpc::mpc_frame(path, &c.mpcs)?;
    df.with_column(table::col(
        "cluster_id",
        c.cluster_id
            .iter()
            .map(|i| i.map_or(-1, |i| i as i64))
            .collect::<Vec<_>>(),
    ))
    .map_err(|e| Error::table(path, e))?;
    let mut meta = vec![("schema_version".to_string(), "1".to_string())];
    if let Some(e) = energy {
        meta.push((ENERGY_KEY.into(), e.display().to_string()));
    }
    table::write_parquet(path, &df, meta)?;
    let spath = summary_path(path);
    let s = &c.summary;
    let f64s = |name: &str, g: fn(&super::ClusterSummary) -> f64| {
        table::col(name, s.iter().map(g).collect::<Vec<_>>())
    };
    let sdf = table::frame(
        &spath,
        vec![
            table::col(
                "position",
                s.iter().map(|x| x.position as i32).collect::<Vec<_>>(),
            ),
            table::col(
                "cluster_id",
                s.iter().map(|x| x.cluster_id as i64).collect::<Vec<_>>(),
            ),
            table::col(
                "members",
                s.iter().map(|x| x.members as i64).collect::<Vec<_>>(),
            ),
            f64s("centroid_delay_ns", |x| x.centroid_delay_ns),
            f64s("centroid_angle_rel_deg", |x| x.centroid_angle_rel_deg),
            f64s("centroid_angle_global_deg", |x| x.centroid_angle_global_deg),
            f64s("first_arrival_ns", |x| x.first_arrival_ns),
            f64s("ref_delay_ns", |x| x.ref_delay_ns),
            f64s("ref_angle_rel_deg", |x| x.ref_angle_rel_deg),
            f64s("power_db", |x| x.power_db),
            f64s("centroid_x_m", |x| x.centroid_x_m),
            f64s("centroid_y_m", |x| x.centroid_y_m),
        ],
    )?;
    table::write_parquet(&spath, &sdf, vec![("schema_version".into(), "1".into())])?;
    Ok(spath)
}
