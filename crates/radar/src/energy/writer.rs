//! Writing the energy Parquet table: the long table `position, direction, angle_rel_deg,
//! angle_global_deg, bin, delay_ns, energy` and its key-value metadata.
//!
//! Floating-point metadata values are written with 17 significant digits (`{:.17e}`) so
//! they read back bit for bit; rows come in `[position][direction][bin]` order, whole
//! positions per row group (as many as fit in [`GROUP_ROWS`] rows, at least one), written
//! atomically. [`EnergyWriter`] takes the positions one at a time as the stage produces
//! them and the metadata at the end, so the stage never holds the whole table; readers
//! ([`super::EnergyTable`]) fetch a few positions at a time from the row groups.

use super::processor::EnergyProcessor;
use super::wrap_deg;
use crate::campaign::manifest::{Manifest, SCHEMA_VERSION};
use crate::error::{Error, Result};
use crate::table;
use std::path::Path;

/// The key-value metadata of an energy table (DESIGN §3 plus `tw`, `window`, `coupling`,
/// `gate_ns`, `oversample`, `noise_from_ns`, `noise_bin_mean`, `noise_bin_median`,
/// `n0_estimator`, `campaign`, `band`,
/// `parameter` when `[sweeps] parameter` is not S21, and `missing` — the `position:direction`
/// pairs without a sweep, space-separated — when the campaign lists any).
pub fn table_metadata(
    m: &Manifest,
    proc: &EnergyProcessor,
    noise: &super::noise::NoiseEstimate,
) -> Vec<(String, String)> {
    let (n0, noise_bin_mean) = (noise.n0, noise.bin_mean);
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
        (
            "noise_bin_median".into(),
            format!("{:.17e}", noise.bin_median),
        ),
        ("n0_estimator".into(), noise.estimator.to_string()),
        ("campaign".into(), m.name.clone()),
        (
            "band".into(),
            format!("{} {} {}", m.band.start_hz, m.band.stop_hz, m.band.points),
        ),
    ];
    // the (position, direction) profiles without a sweep, NaN in the table; absent when
    // every sweep is there (a complete campaign's table is unchanged)
    let missing = m.missing();
    if !missing.is_empty() {
        let v: Vec<String> = missing.iter().map(|(p, d)| format!("{p}:{d}")).collect();
        meta.push(("missing".into(), v.join(" ")));
    }
    // recorded only when not the default, so default campaigns' tables are unchanged
    if let Some(p) = m.sweeps.as_ref().and_then(|s| s.parameter) {
        if p != crate::campaign::touchstone::SParam::S21 {
            meta.push(("parameter".into(), p.to_string()));
        }
    }
    meta
}

/// Rows per row group aimed at: whole positions up to this many rows (at least one
/// position), so a reader of a few positions decodes little more than those (a 37 × 481
/// corridor position is 17,797 rows: 3 per group).
pub const GROUP_ROWS: usize = 1 << 16;

/// Positions per row group for `nd` directions of `nb` bins.
pub fn group_positions(nd: usize, nb: usize) -> usize {
    (GROUP_ROWS / (nd * nb).max(1)).max(1)
}

/// A streaming energy-table writer: positions in order, one at a time
/// ([`EnergyWriter::push`]), the metadata at [`EnergyWriter::finish`].
pub struct EnergyWriter<'a> {
    out: std::path::PathBuf,
    m: &'a Manifest,
    nb: usize,
    stream: table::ParquetStream,
    /// Energies of the positions not yet written, `[position][direction][bin]`.
    pending: Vec<f64>,
    /// First position of `pending`.
    first: usize,
    /// Positions pushed.
    pushed: usize,
    group: usize,
}

impl<'a> EnergyWriter<'a> {
    /// Start the table `out` of the campaign `m` with `nb` bins per profile.
    pub fn create(out: &Path, m: &'a Manifest, nb: usize) -> Result<Self> {
        let nd = m.directions.count();
        let group = group_positions(nd, nb);
        Ok(EnergyWriter {
            out: out.to_path_buf(),
            m,
            nb,
            stream: table::ParquetStream::create(out)?,
            pending: Vec::with_capacity(group * nd * nb),
            first: 0,
            pushed: 0,
            group,
        })
    }

    /// Append the next position's energies (`[direction][bin]`, directions × `nb` values).
    pub fn push(&mut self, energies: &[f64]) -> Result<()> {
        let nd = self.m.directions.count();
        if energies.len() != nd * self.nb || self.pushed >= self.m.positions() {
            return Err(Error::input(
                &self.out,
                format!(
                    "energy table: position {} of {} values for {} positions x {nd} directions x {} bins",
                    self.pushed,
                    energies.len(),
                    self.m.positions(),
                    self.nb
                ),
            ));
        }
        self.pending.extend_from_slice(energies);
        self.pushed += 1;
        if self.pushed - self.first == self.group {
            self.flush()?;
        }
        Ok(())
    }

    /// Write the pending positions as one row group.
    fn flush(&mut self) -> Result<()> {
        let (m, nb) = (self.m, self.nb);
        let ps = self.first..self.pushed;
        if ps.is_empty() {
            return Ok(());
        }
        let nd = m.directions.count();
        let tb = 1e9 / m.band.bandwidth_hz();
        let angles = m.directions.angles_deg();
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
        let energy = std::mem::take(&mut self.pending);
        let df = table::frame(
            &self.out,
            vec![
                table::col("position", pos),
                table::col("direction", dir),
                table::col("angle_rel_deg", arel),
                table::col("angle_global_deg", aglob),
                table::col("bin", bin),
                table::col("delay_ns", delay),
                table::col("energy", energy),
            ],
        )?;
        self.stream.write(&df)?;
        self.pending = Vec::with_capacity(self.group * nd * nb);
        self.first = self.pushed;
        Ok(())
    }

    /// Write the last row group and the metadata, and rename the table into place; every
    /// position of the campaign must have been pushed.
    pub fn finish(mut self, meta: Vec<(String, String)>) -> Result<()> {
        if self.pushed != self.m.positions() {
            return Err(Error::input(
                &self.out,
                format!(
                    "energy table: {} of {} positions written",
                    self.pushed,
                    self.m.positions()
                ),
            ));
        }
        self.flush()?;
        self.stream.set_metadata(meta);
        self.stream.finish(None)
    }
}

/// Write an energy table (`energies` as `[position][direction][bin]`, `nb` bins per
/// profile) with its metadata, atomically (through [`EnergyWriter`]).
pub fn write_table(
    out: &Path,
    m: &Manifest,
    nb: usize,
    energies: &[f64],
    meta: Vec<(String, String)>,
) -> Result<()> {
    let np = m.positions();
    let nd = m.directions.count();
    if energies.len() != np * nd * nb {
        return Err(Error::input(
            out,
            format!(
                "energy table: {} values for {np} positions x {nd} directions x {nb} bins",
                energies.len()
            ),
        ));
    }
    let mut w = EnergyWriter::create(out, m, nb)?;
    for p in 0..np {
        w.push(&energies[p * nd * nb..(p + 1) * nd * nb])?;
    }
    w.finish(meta)
}
