//! The energy matrix read back from its Parquet table, and the check that a table belongs
//! to a campaign.
//!
//! Takes an energy Parquet file (DESIGN §3 long table plus key-value metadata); gives
//! `E[position][direction][bin]` with its axes: the relative angles of the directions and
//! the heading of every position, recovered as wrap(angle_global − angle_rel). Every
//! (position, direction, bin) must appear exactly once with a non-negative energy and the
//! metadata's `schema_version` must be the one this build writes.

use super::wrap_deg;
use crate::campaign::manifest::{Campaign, SCHEMA_VERSION};
use crate::error::{Error, Result};
use crate::table;
use std::path::Path;

/// Largest bin energy accepted: a passive channel's |S21| stays below 1, so a bin's energy
/// (a sum of oversampled |h|² over one bin, per unit transmit power) stays near or below
/// 1; 10^12 (120 dB above) leaves room for any calibration and refuses corrupt values
/// that would dominate every statistic (one 10^300 bin turned a position's 138 MPCs
/// into 1).
pub const MAX_ENERGY: f64 = 1e12;

/// Metadata of an energy table.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyMeta {
    /// Schema version.
    pub schema_version: u32,
    /// Bin width T_b, ns.
    pub bin_width_ns: f64,
    /// Pulses averaged.
    pub pulses: usize,
    /// Noise spectral level N0 (mean noise bin energy = N0·TW).
    pub n0: f64,
    /// Window ENBW in frequency steps.
    pub enbw: f64,
    /// Equivalent independent samples per bin.
    pub tw: f64,
    /// Array label.
    pub array: String,
    /// Coupling removal used.
    pub coupling: String,
    /// Every key-value pair as stored.
    pub all: Vec<(String, String)>,
}

impl EnergyMeta {
    /// The noise statistics a detector or an observation model needs: `n0` a positive
    /// number, `tw` positive, `pulses` ≥ 1 (`file` names the energy table in errors).
    pub fn check_noise(&self, file: &Path) -> Result<()> {
        if !(self.n0.is_finite() && self.n0 > 0.0) {
            return Err(Error::input(
                file,
                "metadata `n0` must be a positive number",
            ));
        }
        if !(self.tw.is_finite() && self.tw > 0.0) || self.pulses == 0 {
            return Err(Error::input(
                file,
                "metadata `tw`/`pulses` must be positive",
            ));
        }
        Ok(())
    }

    /// The coupling gate applied, ns (0 unless `coupling = "gate"`).
    pub fn gate_ns(&self) -> f64 {
        if self.coupling != "gate" {
            return 0.0;
        }
        self.all
            .iter()
            .find(|(k, _)| k == "gate_ns")
            .and_then(|(_, v)| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    }

    /// Mean energy of a noise-only bin, N0·TW.
    pub fn noise_mean(&self) -> f64 {
        self.n0 * self.tw
    }
}

/// An energy matrix `E[position][direction][bin]` with its axes.
#[derive(Debug, Clone)]
pub struct EnergyMatrix {
    /// Metadata.
    pub meta: EnergyMeta,
    /// Positions.
    pub positions: usize,
    /// Relative direction angles, degrees.
    pub angles_rel_deg: Vec<f64>,
    /// Pose headings, degrees (one per position).
    pub headings_deg: Vec<f64>,
    /// Bins per profile.
    pub bins: usize,
    /// Energies, position-major.
    pub data: Vec<f64>,
}

impl EnergyMatrix {
    /// Directions.
    pub fn directions(&self) -> usize {
        self.angles_rel_deg.len()
    }
    /// The profile of one (position, direction).
    pub fn profile(&self, p: usize, d: usize) -> &[f64] {
        let i = (p * self.directions() + d) * self.bins;
        &self.data[i..i + self.bins]
    }
    /// Delay of a bin centre, ns.
    pub fn delay_ns(&self, bin: usize) -> f64 {
        bin as f64 * self.meta.bin_width_ns
    }
    /// Global angle of direction `d` at position `p`, degrees in (−180, 180].
    pub fn angle_global_deg(&self, p: usize, d: usize) -> f64 {
        wrap_deg(self.headings_deg[p] + self.angles_rel_deg[d])
    }

    /// Read an energy Parquet file; `headings_deg` may be empty (then recovered from the
    /// table's angle columns).
    pub fn read(path: &Path) -> Result<EnergyMatrix> {
        let kv = table::parquet_metadata(path)?;
        let get = |k: &str| -> Result<String> {
            kv.iter()
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
                .ok_or_else(|| {
                    Error::input(
                        path,
                        format!("metadata key `{k}` missing (not an energy table?)"),
                    )
                })
        };
        let num = |k: &str| -> Result<f64> {
            get(k)?
                .parse::<f64>()
                .map_err(|_| Error::input(path, format!("metadata `{k}` is not a number")))
        };
        let meta = EnergyMeta {
            schema_version: num("schema_version")? as u32,
            bin_width_ns: num("bin_width_ns")?,
            pulses: num("pulses")? as usize,
            n0: num("n0")?,
            enbw: num("enbw")?,
            tw: num("tw").unwrap_or(1.0),
            array: get("array")?,
            coupling: get("coupling").unwrap_or_default(),
            all: kv.clone(),
        };
        if meta.schema_version != SCHEMA_VERSION {
            return Err(Error::input(
                path,
                format!(
                    "metadata schema_version {} unsupported",
                    meta.schema_version
                ),
            ));
        }
        let df = table::read_parquet(path, None)?;
        if df.height() == 0 {
            return Err(Error::input(path, "energy table has no rows"));
        }
        let pos = table::i64_column(path, &df, "position")?;
        let dir = table::i64_column(path, &df, "direction")?;
        let bin = table::i64_column(path, &df, "bin")?;
        let arel = table::f64_column(path, &df, "angle_rel_deg")?;
        let aglob = table::f64_column(path, &df, "angle_global_deg")?;
        let energy = table::f64_column(path, &df, "energy")?;
        if pos.iter().chain(&dir).chain(&bin).any(|v| *v < 0) {
            return Err(Error::input(path, "negative position/direction/bin index"));
        }
        let np = *pos.iter().max().unwrap_or(&-1) as usize + 1;
        let nd = *dir.iter().max().unwrap_or(&-1) as usize + 1;
        let nb = *bin.iter().max().unwrap_or(&-1) as usize + 1;
        // every index fits the table: the grid np·nd·nb is the row count (checked without
        // overflow), so nothing larger than the file is allocated
        let cells = np.checked_mul(nd).and_then(|v| v.checked_mul(nb));
        if cells != Some(df.height()) {
            return Err(Error::input(
                path,
                format!(
                    "{} rows but {np} positions x {nd} directions x {nb} bins",
                    df.height()
                ),
            ));
        }
        let mut data = vec![f64::NAN; np * nd * nb];
        let mut angles = vec![f64::NAN; nd];
        let mut headings = vec![f64::NAN; np];
        for i in 0..df.height() {
            let (p, d, b) = (pos[i] as usize, dir[i] as usize, bin[i] as usize);
            let idx = (p * nd + d) * nb + b;
            if !data[idx].is_nan() {
                return Err(Error::input(
                    path,
                    format!("row {i}: duplicate (position {p}, direction {d}, bin {b})"),
                ));
            }
            if energy[i] < 0.0 {
                return Err(Error::input(path, format!("row {i}: negative energy")));
            }
            if energy[i] > MAX_ENERGY {
                return Err(Error::input(
                    path,
                    format!(
                        "column `energy` row {i}: {:e} above {MAX_ENERGY:e} (a unit-amplitude echo gives about 1)",
                        energy[i]
                    ),
                ));
            }
            data[idx] = energy[i];
            angles[d] = arel[i];
            headings[p] = wrap_deg(aglob[i] - arel[i]);
        }
        Ok(EnergyMatrix {
            meta,
            positions: np,
            angles_rel_deg: angles,
            headings_deg: headings,
            bins: nb,
            data,
        })
    }
}

/// Check that an energy table belongs to a campaign (file named in every error).
pub fn check_campaign(c: &Campaign, em: &EnergyMatrix, path: &Path) -> Result<()> {
    let m = &c.manifest;
    let (np, nd) = (m.poses.len(), m.directions.count());
    if em.positions != np || em.directions() != nd {
        return Err(Error::input(
            path,
            format!(
                "{} positions x {} directions, but campaign {} has {np} poses x {nd} directions (energy table from another campaign?)",
                em.positions,
                em.directions(),
                c.path.display()
            ),
        ));
    }
    for d in 0..nd {
        if (em.angles_rel_deg[d] - m.directions.angle_deg(d)).abs() > 1e-6 {
            return Err(Error::input(
                path,
                format!(
                    "direction {d} at {}°, campaign {} has {}° (energy table from another campaign?)",
                    em.angles_rel_deg[d],
                    c.path.display(),
                    m.directions.angle_deg(d)
                ),
            ));
        }
    }
    for (p, pose) in m.poses.iter().enumerate() {
        let diff = wrap_deg(em.headings_deg[p] - pose.heading_deg).abs();
        if diff.is_nan() || diff >= 1e-6 {
            return Err(Error::input(
                path,
                format!(
                    "position {p} heading {}°, campaign {} has {}° (energy table from another campaign?)",
                    em.headings_deg[p],
                    c.path.display(),
                    pose.heading_deg
                ),
            ));
        }
    }
    let tb = 1e9 / m.band.bandwidth_hz();
    if (em.meta.bin_width_ns - tb).abs() > 1e-6 * tb || !em.meta.bin_width_ns.is_finite() {
        return Err(Error::input(
            path,
            format!(
                "bin_width_ns {} but campaign {} has 1/B = {tb} ns",
                em.meta.bin_width_ns,
                c.path.display()
            ),
        ));
    }
    if let Some((_, v)) = em.meta.all.iter().find(|(k, _)| k == "elements") {
        if v.parse::<usize>().ok() != Some(m.array.elements) {
            return Err(Error::input(
                path,
                format!(
                    "metadata elements = {v}, but the campaign's array has {} elements (pass --elements {v}?)",
                    m.array.elements
                ),
            ));
        }
    }
    Ok(())
}
