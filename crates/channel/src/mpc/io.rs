//! The MPC table (DESIGN §3): Parquet columns [`MPC_COLUMNS`], its file metadata
//! (schema version, method, floor, margins, positions, the scanned sector's width) and the
//! reader (extra columns such as `cluster_id` are ignored; missing `snr_db`, `direction`,
//! `bin`, `component` read as NaN, 0, 0, discrete; `wall_unit_db`, `incidence_deg` are NaN
//! for an MPC on no wall curve).

use super::{Component, ExtractParams, Mpc, WallCell};
use crate::campaign::manifest::limits::MAX_POSITIONS;
use crate::campaign::manifest::Campaign;
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::table;
use std::path::Path;

/// Columns of the MPC table.
pub const MPC_COLUMNS: [&str; 13] = [
    "position",
    "delay_ns",
    "angle_rel_deg",
    "angle_global_deg",
    "power_db",
    "snr_db",
    "x_m",
    "y_m",
    "direction",
    "bin",
    "component",
    "wall_unit_db",
    "incidence_deg",
];

/// The MPC table as a frame.
pub fn mpc_frame(path: &Path, mpcs: &[Mpc]) -> Result<polars::prelude::DataFrame> {
    table::frame(
        path,
        vec![
            table::col(
                "position",
                mpcs.iter().map(|m| m.position as i32).collect::<Vec<_>>(),
            ),
            table::col(
                "delay_ns",
                mpcs.iter().map(|m| m.delay_ns).collect::<Vec<_>>(),
            ),
            table::col(
                "angle_rel_deg",
                mpcs.iter().map(|m| m.angle_rel_deg).collect::<Vec<_>>(),
            ),
            table::col(
                "angle_global_deg",
                mpcs.iter().map(|m| m.angle_global_deg).collect::<Vec<_>>(),
            ),
            table::col(
                "power_db",
                mpcs.iter().map(|m| m.power_db).collect::<Vec<_>>(),
            ),
            table::col("snr_db", mpcs.iter().map(|m| m.snr_db).collect::<Vec<_>>()),
            table::col("x_m", mpcs.iter().map(|m| m.x_m).collect::<Vec<_>>()),
            table::col("y_m", mpcs.iter().map(|m| m.y_m).collect::<Vec<_>>()),
            table::col(
                "direction",
                mpcs.iter().map(|m| m.direction as i32).collect::<Vec<_>>(),
            ),
            table::col("bin", mpcs.iter().map(|m| m.bin as i32).collect::<Vec<_>>()),
            table::col(
                "component",
                mpcs.iter()
                    .map(|m| m.component.name().to_string())
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "wall_unit_db",
                mpcs.iter()
                    .map(|m| m.wall.map_or(f64::NAN, |w| w.unit_db))
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "incidence_deg",
                mpcs.iter()
                    .map(|m| m.wall.map_or(f64::NAN, |w| w.incidence_deg))
                    .collect::<Vec<_>>(),
            ),
        ],
    )
}

/// Write MPCs as Parquet (metadata: schema_version, method, floor, positions).
pub fn write_mpcs(path: &Path, mpcs: &[Mpc], meta: Vec<(String, String)>) -> Result<()> {
    let df = mpc_frame(path, mpcs)?;
    table::write_parquet(path, &df, meta)
}

/// File metadata of an MPC table (`extract`, and `reproduce`'s `work/mpcs.parquet`):
/// schema version, method, the energy floor, margins, positions and the scanned sector's
/// width (`sector_deg`, read back by [`read_sector_deg`] for `cluster`).
pub fn table_metadata(
    em: &EnergyMatrix,
    c: &Campaign,
    params: &ExtractParams,
) -> Vec<(String, String)> {
    vec![
        ("schema_version".to_string(), "1".to_string()),
        (
            "method".into(),
            format!("{:?}", params.method).to_lowercase(),
        ),
        ("floor".into(), format!("{:.17e}", em.meta.noise_mean())),
        ("margin_db".into(), params.margin_db.to_string()),
        (
            "dynamic_range_db".into(),
            params.dynamic_range_db.to_string(),
        ),
        ("positions".into(), em.positions.to_string()),
        (
            "sector_deg".into(),
            c.manifest.directions.width_deg().to_string(),
        ),
        (
            "diffuse".into(),
            if params.diffuse.enabled {
                "layout"
            } else {
                "off"
            }
            .into(),
        ),
        ("diffuse_db".into(), params.diffuse.discrete_db.to_string()),
    ]
}

/// The scanned sector's width (degrees) recorded in an MPC table's `sector_deg` metadata by
/// `extract`; None for tables written without it.
pub fn read_sector_deg(path: &Path) -> Result<Option<f64>> {
    let meta = table::parquet_metadata(path)?;
    let Some((_, v)) = meta.iter().find(|(k, _)| k == "sector_deg") else {
        return Ok(None);
    };
    match v.parse::<f64>() {
        Ok(w) if w > 0.0 && w <= 360.0 => Ok(Some(w)),
        _ => Err(Error::input(
            path,
            format!("metadata sector_deg = {v:?}: not a width in (0, 360] degrees"),
        )),
    }
}

/// Read an MPC table (extra columns such as `cluster_id` are ignored).
pub fn read_mpcs(path: &Path) -> Result<Vec<Mpc>> {
    let df = table::read_parquet(path, None)?;
    let pos = table::i64_column(path, &df, "position")?;
    let delay = table::f64_column(path, &df, "delay_ns")?;
    let arel = table::f64_column(path, &df, "angle_rel_deg")?;
    let aglob = table::f64_column(path, &df, "angle_global_deg")?;
    let pw = table::f64_column(path, &df, "power_db")?;
    let snr = table::f64_column(path, &df, "snr_db").unwrap_or_else(|_| vec![f64::NAN; pos.len()]);
    let x = table::f64_column(path, &df, "x_m")?;
    let y = table::f64_column(path, &df, "y_m")?;
    let dir = table::i64_column(path, &df, "direction").unwrap_or_else(|_| vec![0; pos.len()]);
    let bin = table::i64_column(path, &df, "bin").unwrap_or_else(|_| vec![0; pos.len()]);
    let component = table::str_column(path, &df, "component")?;
    let unit = table::f64_column_or_nan(path, &df, "wall_unit_db")?;
    let inc = table::f64_column_or_nan(path, &df, "incidence_deg")?;
    (0..pos.len())
        .map(|i| {
            if pos[i] < 0 {
                return Err(Error::input(path, format!("row {i}: negative position")));
            }
            if pos[i] as u64 >= MAX_POSITIONS as u64 {
                return Err(Error::input(
                    path,
                    format!(
                        "column `position` row {i}: {} beyond the largest campaign ({MAX_POSITIONS} positions)",
                        pos[i]
                    ),
                ));
            }
            let component = match &component {
                None => Component::Discrete,
                Some(c) => Component::parse(&c[i]).ok_or_else(|| {
                    Error::input(
                        path,
                        format!(
                            "column `component` row {i}: {:?} (expected discrete, diffuse or folded)",
                            c[i]
                        ),
                    )
                })?,
            };
            Ok(Mpc {
                position: pos[i] as usize,
                delay_ns: delay[i],
                angle_rel_deg: arel[i],
                angle_global_deg: aglob[i],
                power_db: pw[i],
                snr_db: snr[i],
                x_m: x[i],
                y_m: y[i],
                direction: dir[i].max(0) as usize,
                bin: bin[i].max(0) as usize,
                component,
                wall: match (&unit, &inc) {
                    (Some(u), Some(a)) if u[i].is_finite() && a[i].is_finite() => Some(WallCell {
                        unit_db: u[i],
                        incidence_deg: a[i],
                    }),
                    _ => None,
                },
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_mpc() -> Mpc {
        Mpc {
            position: 0,
            delay_ns: 20.0,
            angle_rel_deg: 10.0,
            angle_global_deg: 10.0,
            power_db: -70.0,
            snr_db: 30.0,
            x_m: 2.9,
            y_m: 0.5,
            direction: 20,
            bin: 120,
            component: Component::Discrete,
            wall: None,
        }
    }

    #[test]
    fn sector_metadata_is_read_checked_or_absent() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.parquet");
        write_mpcs(&p, &[one_mpc()], vec![("sector_deg".into(), "120".into())]).unwrap();
        assert_eq!(read_sector_deg(&p).unwrap(), Some(120.0));
        assert_eq!(read_mpcs(&p).unwrap(), vec![one_mpc()]);
        write_mpcs(&p, &[one_mpc()], vec![]).unwrap();
        assert_eq!(read_sector_deg(&p).unwrap(), None);
        for bad in ["wide", "0", "400", "NaN"] {
            write_mpcs(&p, &[one_mpc()], vec![("sector_deg".into(), bad.into())]).unwrap();
            let e = read_sector_deg(&p).unwrap_err().to_string();
            assert!(e.contains("sector_deg") && e.contains("m.parquet"), "{e}");
        }
    }

    #[test]
    fn component_and_wall_round_trip_old_tables_read_discrete_bad_values_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.parquet");
        let mut m = one_mpc();
        m.component = Component::Diffuse;
        m.wall = Some(WallCell {
            unit_db: -95.5,
            incidence_deg: 30.0,
        });
        let mut f = one_mpc();
        f.component = Component::Folded;
        write_mpcs(&p, &[m.clone(), one_mpc(), f.clone()], vec![]).unwrap();
        assert_eq!(read_mpcs(&p).unwrap(), vec![m, one_mpc(), f]);
        // a table of the original ten columns: discrete, no wall
        let mut df = mpc_frame(&p, &[one_mpc()]).unwrap();
        for c in ["component", "wall_unit_db", "incidence_deg"] {
            df = df.drop(c).unwrap();
        }
        table::write_parquet(&p, &df, vec![]).unwrap();
        assert_eq!(read_mpcs(&p).unwrap(), vec![one_mpc()]);
        // an unknown component is one error naming the column and row
        let mut df = mpc_frame(&p, &[one_mpc()]).unwrap();
        df.with_column(table::col("component", vec!["Diffuse".to_string()]))
            .unwrap();
        table::write_parquet(&p, &df, vec![]).unwrap();
        let e = read_mpcs(&p).unwrap_err().to_string();
        assert!(e.contains("component") && e.contains("row 0"), "{e}");
    }
}
