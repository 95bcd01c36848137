//! Parquet output of a clustering (DESIGN §3): the clustered MPC table (the MPC columns plus
//! `cluster_id`, −1 for diffuse and folded MPCs) and the per-cluster summary
//! `<stem>_summary.parquet`, both with `schema_version` 1. The clustered table also carries
//! the MPC table's `energy` key (the energy table it came from, [`ENERGY_KEY`]) when given
//! ([`write_with()`]): `fit` reads the model's levels from that table.
//!
//! The key names the energy table relative to the folder of the table that carries it
//! ([`energy_entry`]; absolute only when no relative path exists, another drive say), and a
//! relative key is read against the folder of the table being read ([`energy_of`]): a
//! project folder moved or copied whole still names its own energy table, not the old
//! place's (which a moved project would not find, and a copied one would read stale).
//! An absolute key (tables written before) is read as it stands.

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
/// (relative to the folder of the table carrying it, or absolute; [`energy_entry`]).
pub const ENERGY_KEY: &str = "energy";

/// The energy table an MPC or clustered MPC table (`path`) names in its metadata (`energy`),
/// if any: a relative key is joined to the folder of `path` (its real folder, symlinks
/// resolved, when it can be found), an absolute one is returned as it stands.
pub fn energy_of(path: &Path) -> Result<Option<PathBuf>> {
    let Some(v) = table::parquet_metadata(path)?
        .into_iter()
        .find(|(k, _)| k == ENERGY_KEY)
        .map(|(_, v)| PathBuf::from(v))
    else {
        return Ok(None);
    };
    if v.is_absolute() {
        return Ok(Some(v));
    }
    let real = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    Ok(Some(folder_of(&real).join(v)))
}

/// The `energy` metadata entry ([`ENERGY_KEY`]) of a table to be written at `table`, naming
/// the energy table `energy`: its path relative to the folder of `table` (both with symlinks
/// resolved), or its absolute path when there is no relative one (another drive); `None`
/// when `energy` has no absolute path either (no current folder).
pub fn energy_entry(table: &Path, energy: &Path) -> Option<(String, String)> {
    let abs = std::fs::canonicalize(energy)
        .or_else(|_| std::path::absolute(energy))
        .ok()?;
    let value = real_folder(table)
        .and_then(|folder| relative_path(&abs, &folder))
        .unwrap_or(abs);
    Some((ENERGY_KEY.into(), value.display().to_string()))
}

/// The folder of `path` (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The absolute folder of `table` with symlinks resolved, the table not yet written: its
/// deepest existing ancestor, canonical, and the components below it (which do not exist,
/// so hold no symlink).
fn real_folder(table: &Path) -> Option<PathBuf> {
    let folder = std::path::absolute(folder_of(table)).ok()?;
    let mut rest = Vec::new();
    let mut at = folder.as_path();
    loop {
        if let Ok(real) = std::fs::canonicalize(at) {
            return Some(rest.iter().rev().fold(real, |p, c| p.join(c)));
        }
        rest.push(at.file_name()?.to_os_string());
        at = at.parent()?;
    }
}

/// The path of `target` relative to the folder `base` (both absolute, without `.` or `..`):
/// `..` for each component of `base` below their common ancestor, then the rest of `target`.
/// `None` when they share no root (another drive or share).
fn relative_path(target: &Path, base: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let t: Vec<Component> = target.components().collect();
    let b: Vec<Component> = base.components().collect();
    let plain = |c: &[Component]| c.iter().all(|c| matches!(c, Component::Normal(_)));
    let root = |c: &[Component]| {
        c.iter()
            .take_while(|c| !matches!(c, Component::Normal(_)))
            .count()
    };
    let (rt, rb) = (root(&t), root(&b));
    if rt == 0 || t[..rt] != b[..rb] || !plain(&t[rt..]) || !plain(&b[rb..]) {
        return None;
    }
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut r: PathBuf = b[common..].iter().map(|_| "..").collect();
    r.extend(&t[common..]);
    (!r.as_os_str().is_empty()).then_some(r)
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
    meta.extend(energy.and_then(|e| energy_entry(path, e)));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_climb_to_the_common_folder() {
        let rel = |t: &str, b: &str| relative_path(Path::new(t), Path::new(b));
        let p = |s: &str| Some(PathBuf::from(s));
        assert_eq!(rel("/p/e.parquet", "/p"), p("e.parquet"));
        assert_eq!(rel("/p/e.parquet", "/p/a/b"), p("../../e.parquet"));
        assert_eq!(rel("/p/x/e.parquet", "/p/a"), p("../x/e.parquet"));
        assert_eq!(rel("/p/e.parquet", "/"), p("p/e.parquet"));
        // no relative path without a shared root, or from unresolved components
        assert_eq!(rel("e.parquet", "/p"), None);
        assert_eq!(rel("/p/../e.parquet", "/p"), None);
    }

    /// A table naming `energy` (`energy_entry`), written at `table`.
    fn write_naming(table: &Path, energy: &Path) -> String {
        let entry = energy_entry(table, energy).unwrap();
        let df = table::frame(table, vec![table::col("x", vec![1i64])]).unwrap();
        table::write_parquet(table, &df, vec![entry.clone()]).unwrap();
        entry.1
    }

    /// A project folder moved whole (or copied) still names its own energy table: the key
    /// is relative to the table's folder and read against the folder it is read from.
    #[test]
    fn the_energy_key_follows_a_moved_or_copied_folder() {
        let tmp = tempfile::tempdir().unwrap();
        let old = tmp.path().join("old");
        std::fs::create_dir_all(old.join("work")).unwrap();
        std::fs::write(old.join("energy.parquet"), b"e").unwrap();
        let beside = write_naming(&old.join("m.parquet"), &old.join("energy.parquet"));
        // the output's folder need not exist yet
        let below = write_naming(&old.join("work/new/c.parquet"), &old.join("energy.parquet"));
        assert_eq!(beside, "energy.parquet");
        assert_eq!(
            below,
            Path::new("../..")
                .join("energy.parquet")
                .display()
                .to_string()
        );
        let new = tmp.path().join("moved");
        std::fs::rename(&old, &new).unwrap();
        let real = |p: &Path| std::fs::canonicalize(p).unwrap();
        for t in ["m.parquet", "work/new/c.parquet"] {
            let e = energy_of(&new.join(t)).unwrap().unwrap();
            assert_eq!(real(&e), real(&new.join("energy.parquet")), "{t}");
        }
        // an absolute key (tables written before) stands as it is
        let abs = new.join("abs.parquet");
        let df = table::frame(&abs, vec![table::col("x", vec![1i64])]).unwrap();
        let key = (ENERGY_KEY.to_string(), "/elsewhere/e.parquet".to_string());
        table::write_parquet(&abs, &df, vec![key]).unwrap();
        assert_eq!(
            energy_of(&abs).unwrap(),
            Some(PathBuf::from("/elsewhere/e.parquet"))
        );
    }
}
