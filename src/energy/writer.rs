//! Writing the energy Parquet table: the long table `position, direction, angle_rel_deg,
//! angle_global_deg, bin, delay_ns, energy` and its key-value metadata.
//!
//! Floating-point metadata values are written with 17 significant digits (`{:.17e}`) so
//! they read back bit for bit; rows come in `[position][direction][bin]` order, about 2^20
//! per row group, written atomically.

use super::processor::EnergyProcessor;
use super::wrap_deg;
use crate::campaign::manifest::{Manifest, SCHEMA_VERSION};
use crate::error::{Error, Result};
use crate::table;
use std::path::Path;

/// The key-value metadata of an energy table (DESIGN §3 plus `tw`, `window`, `coupling`,
/// `gate_ns`, `oversample`, `noise_from_ns`, `noise_bin_mean`, `campaign`, `band`, and
/// `parameter` when `[sweeps] parameter` is not S21).
pub fn table_metadata(
    m: &Manifest,
    proc: &EnergyProcessor,
    n0: f64,
    noise_bin_mean: f64,
) -> Vec<(String, String)> {
    let mut meta = vec![
        ("schema_version".to_string(), SCHEMA_VERSION.to_string()),
        (
            "bin_width_ns".into(),
            format!("{:.17e}", proc.bin_width_ns()),
        ),
        ("pulses".into(), m.pulses.to_string()),
        ("n0".into(), format!("{n0:.17e}")),
        ("enbw".into(), format!("{:.17e}", proc.enbw())),
        ("tw".into(), format!("{:.17e}", proc.tw())),
        ("array".into(), m.array.label()),
        ("elements".into(), m.array.elements.to_string()),
        (
            "window".into(),
            format!("{:?}", m.processing.window).to_lowercase(),
        ),
        (
            "coupling".into(),
            format!("{:?}", m.processing.coupling).to_lowercase(),
        ),
        ("gate_ns".into(), m.processing.gate_ns.to_string()),
        ("oversample".into(), m.processing.oversample.to_string()),
        (
            "noise_from_ns".into(),
            m.processing.noise_from_ns.to_string(),
        ),
        ("noise_bin_mean".into(), format!("{noise_bin_mean:.17e}")),
        ("campaign".into(), m.name.clone()),
        (
            "band".into(),
            format!("{} {} {}", m.band.start_hz, m.band.stop_hz, m.band.points),
        ),
    ];
    // recorded only when not the default, so default campaigns' tables are unchanged
    if let Some(p) = m.sweeps.as_ref().and_then(|s| s.parameter) {
        if p != crate::campaign::touchstone::SParam::S21 {
            meta.push(("parameter".into(), p.to_string()));
        }
    }
    meta
}

/// Write an energy table (`energies` as `[position][direction][bin]`, `nb` bins per
/// profile) with its metadata, atomically, about 2^20 rows per row group.
pub fn write_table(
    out: &Path,
    m: &Manifest,
    nb: usize,
    energies: &[f64],
    meta: Vec<(String, String)>,
) -> Result<()> {
    let np = m.positions();
    let nd = m.directions.count();
    let tb = 1e9 / m.band.bandwidth_hz();
    if energies.len() != np * nd * nb {
        return Err(Error::input(
            out,
            format!(
                "energy table: {} values for {np} positions x {nd} directions x {nb} bins",
                energies.len()
            ),
        ));
    }
    let mut stream = table::ParquetStream::create(out)?;
    stream.set_metadata(meta);
    let angles = m.directions.angles_deg();
    // about 2^20 rows per row group
    let group = ((1usize << 20) / (nd * nb).max(1)).max(1);
    for g0 in (0..np).step_by(group) {
        let ps = g0..(g0 + group).min(np);
        let n = ps.len() * nd * nb;
        let mut pos = Vec::with_capacity(n);
        let mut dir = Vec::with_capacity(n);
        let mut arel = Vec::with_capacity(n);
        let mut aglob = Vec::with_capacity(n);
        let mut bin = Vec::with_capacity(n);
        let mut delay = Vec::with_capacity(n);
        for p in ps.clone() {
            for (d, a) in angles.iter().enumerate() {
                let g = wrap_deg(m.poses[p].heading_deg + a);
                for b in 0..nb {
                    pos.push(p as i32);
                    dir.push(d as i32);
                    arel.push(*a);
                    aglob.push(g);
                    bin.push(b as i32);
                    delay.push(b as f64 * tb);
                }
            }
        }
        let df = table::frame(
            out,
            vec![
                table::col("position", pos),
                table::col("direction", dir),
                table::col("angle_rel_deg", arel),
                table::col("angle_global_deg", aglob),
                table::col("bin", bin),
                table::col("delay_ns", delay),
                table::col(
                    "energy",
                    energies[ps.start * nd * nb..ps.end * nd * nb].to_vec(),
                ),
            ],
        )?;
        stream.write(&df)?;
    }
    stream.finish(None)?;
    Ok(())
}
