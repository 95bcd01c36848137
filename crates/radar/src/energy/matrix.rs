//! The energy matrix read back from its Parquet table, and the check that a table belongs
//! to a campaign.
//!
//! Takes an energy Parquet file (DESIGN §3 long table plus key-value metadata); gives
//! `E[position][direction][bin]` with its axes: the relative angles of the directions and
//! the heading of every position, recovered as wrap(angle_global − angle_rel). Every
//! (position, direction, bin) must appear exactly once with a non-negative energy and the
//! metadata's `schema_version` must be the one this build writes.
//!
//! Two ways in: [`EnergyMatrix::read`] loads the whole table; [`EnergyTable::open`] checks
//! the table in two streaming passes over its row groups (the indices, then the values and
//! axes) and then serves a few positions at a time ([`EnergySource::load`]), decoding only
//! the `energy` column of the row groups that hold them, so `extract` and `map` run in
//! memory that does not grow with the number of poses. Streaming needs the rows in the
//! order the writer uses (`[position][direction][bin]`); a table in another order (written
//! by another tool) is checked the same way and then loaded whole.

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
    /// The (position, direction) profiles without a sweep (metadata `missing`), sorted:
    /// their energies are NaN.
    pub missing: Vec<(usize, usize)>,
}

impl EnergyMeta {
    /// Set the profiles this table lacks to NaN in energies `e` of the same grid (`nd`
    /// directions of `nb` bins per position): a model's draws then miss what the
    /// measurement misses.
    pub fn mask_missing(&self, nd: usize, nb: usize, e: &mut [f64]) {
        for &(p, d) in &self.missing {
            let i = (p * nd + d) * nb;
            if let Some(prof) = e.get_mut(i..i + nb) {
                prof.fill(f64::NAN);
            }
        }
    }

    /// Whether (position `p`, direction `d`) has no sweep (its profile is NaN).
    pub fn is_missing(&self, p: usize, d: usize) -> bool {
        !self.missing.is_empty() && self.missing.binary_search(&(p, d)).is_ok()
    }

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
    /// First position whose energies `data` holds (0 for a whole matrix; a matrix of
    /// [`EnergySource::load`] holds a run of positions).
    pub first: usize,
    /// Energies, position-major, of the positions `first..` (all of them for a whole
    /// matrix).
    pub data: Vec<f64>,
}

impl EnergyMatrix {
    /// Directions.
    pub fn directions(&self) -> usize {
        self.angles_rel_deg.len()
    }
    /// The positions whose energies this matrix holds.
    pub fn held(&self) -> std::ops::Range<usize> {
        let per = (self.directions() * self.bins).max(1);
        self.first..self.first + self.data.len() / per
    }
    /// Whether the campaign has a sweep of (position `p`, direction `d`): a missing one's
    /// profile is NaN, and every reader of profiles skips it.
    pub fn has(&self, p: usize, d: usize) -> bool {
        !self.meta.is_missing(p, d)
    }
    /// The profile of one (position, direction); `p` must be [`held`](Self::held).
    pub fn profile(&self, p: usize, d: usize) -> &[f64] {
        debug_assert!(
            self.held().contains(&p),
            "position {p} not held ({:?})",
            self.held()
        );
        let i = ((p - self.first) * self.directions() + d) * self.bins;
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

    /// Read a whole energy Parquet file.
    pub fn read(path: &Path) -> Result<EnergyMatrix> {
        let meta = read_meta(path)?;
        Self::read_with(path, meta)
    }

    /// Read a whole energy Parquet file whose metadata has been read.
    fn read_with(path: &Path, meta: EnergyMeta) -> Result<EnergyMatrix> {
        let df = table::read_parquet(path, None)?;
        if df.height() == 0 {
            return Err(Error::input(path, "energy table has no rows"));
        }
        let Columns {
            pos,
            dir,
            bin,
            arel,
            aglob,
            energy,
        } = Columns::read(path, &df)?;
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
        check_missing_shape(path, &meta, np, nd)?;
        let mut data = vec![f64::NAN; np * nd * nb];
        let mut filled = vec![false; np * nd * nb];
        let mut angles = vec![f64::NAN; nd];
        let mut headings = vec![f64::NAN; np];
        for i in 0..df.height() {
            let (p, d, b) = (pos[i] as usize, dir[i] as usize, bin[i] as usize);
            let idx = (p * nd + d) * nb + b;
            if std::mem::replace(&mut filled[idx], true) {
                return Err(Error::input(
                    path,
                    format!("row {i}: duplicate (position {p}, direction {d}, bin {b})"),
                ));
            }
            check_energy(path, i, energy[i], meta.is_missing(p, d))?;
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
            first: 0,
            data,
        })
    }
}

/// The columns of an energy table (or of some of its rows) that the readers check.
struct Columns {
    pos: Vec<i64>,
    dir: Vec<i64>,
    bin: Vec<i64>,
    arel: Vec<f64>,
    aglob: Vec<f64>,
    energy: Vec<f64>,
}

impl Columns {
    /// Their names, in the order of the fields.
    const NAMES: [&'static str; 6] = [
        "position",
        "direction",
        "bin",
        "angle_rel_deg",
        "angle_global_deg",
        "energy",
    ];

    /// Read them from a frame of `path` (each error names the file and column).
    fn read(path: &Path, df: &polars::prelude::DataFrame) -> Result<Columns> {
        let [p, d, b, ar, ag, e] = Self::NAMES;
        Ok(Columns {
            pos: table::i64_column(path, df, p)?,
            dir: table::i64_column(path, df, d)?,
            bin: table::i64_column(path, df, b)?,
            arel: table::f64_column(path, df, ar)?,
            aglob: table::f64_column(path, df, ag)?,
            // NaN only where the metadata lists the profile as missing (check_energy)
            energy: table::f64_column_nan(path, df, e)?,
        })
    }
}

/// The key-value metadata of an energy table, checked (schema version, numbers).
fn read_meta(path: &Path) -> Result<EnergyMeta> {
    meta_from(path, table::parquet_metadata(path)?)
}

/// The metadata of an energy table from its key-value pairs, checked.
fn meta_from(path: &Path, kv: Vec<(String, String)>) -> Result<EnergyMeta> {
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
        missing: missing_from(path, &kv)?,
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
    check_physical(path, &meta)?;
    Ok(meta)
}

/// The `missing` metadata: space-separated `position:direction` pairs, sorted on return.
fn missing_from(path: &Path, kv: &[(String, String)]) -> Result<Vec<(usize, usize)>> {
    let Some((_, v)) = kv.iter().find(|(k, _)| k == "missing") else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for tok in v.split_ascii_whitespace() {
        let pair = tok
            .split_once(':')
            .and_then(|(p, d)| Some((p.parse::<usize>().ok()?, d.parse::<usize>().ok()?)));
        let Some(pd) = pair else {
            return Err(Error::input(
                path,
                format!(
                    "metadata `missing`: `{}` is not position:direction",
                    tok.chars().take(40).collect::<String>()
                ),
            ));
        };
        if out.len() >= crate::campaign::manifest::limits::MAX_SWEEPS {
            return Err(Error::input(
                path,
                "metadata `missing`: more pairs than a campaign has sweeps",
            ));
        }
        out.push(pd);
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The `missing` pairs inside the table's grid (`np` positions, `nd` directions).
fn check_missing_shape(path: &Path, meta: &EnergyMeta, np: usize, nd: usize) -> Result<()> {
    match meta.missing.iter().find(|&&(p, d)| p >= np || d >= nd) {
        Some((p, d)) => Err(Error::input(
            path,
            format!(
                "metadata `missing`: {p}:{d} outside the table ({np} positions, {nd} directions)"
            ),
        )),
        None => Ok(()),
    }
}

/// Relative tolerance of the bin width against `1e9 / B` of the recorded band.
const BIN_WIDTH_TOL: f64 = 1e-6;

/// The window ENBW range, in frequency steps, of the windows the energy stage has: 1 for
/// the rectangular window, about 1.5·N/(N − 1) for an N-point Hann (at most 1.71 at the
/// 8 points a band needs); 3 leaves room for any window, not for a corrupt number.
const ENBW_RANGE: [f64; 2] = [1.0, 3.0];

/// The metadata numbers an energy table's readers rely on, against their physical ranges
/// (a table whose `tw` is absurd would silently detect nothing): `bin_width_ns` finite
/// and positive and, where the `band` is recorded, 1e9/B within [`BIN_WIDTH_TOL`];
/// `enbw` within [`ENBW_RANGE`]; `tw` finite with 1 ≤ TW ≤ the oversampling (samples per
/// bin; the recorded `oversample`, else the largest accepted). Names the file and the key.
fn check_physical(path: &Path, meta: &EnergyMeta) -> Result<()> {
    let value = |k: &str| {
        meta.all
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.as_str())
    };
    // the value as stored (a number printed back could be 300 digits long)
    let bad = |k: &str, v: f64, why: String| {
        let v = value(k).map_or_else(|| v.to_string(), |s| s.trim().to_string());
        Error::input(
            path,
            format!("metadata `{k}` = {v} is outside its physical range: {why}"),
        )
    };
    let tb = meta.bin_width_ns;
    if !(tb.is_finite() && tb > 0.0) {
        return Err(bad("bin_width_ns", tb, "must be finite and > 0".into()));
    }
    // `band` = "start_hz stop_hz points", as the writer records it
    let band: Option<Vec<f64>> = value("band").map(|b| {
        b.split_ascii_whitespace()
            .filter_map(|v| v.parse().ok())
            .collect()
    });
    if let Some(b) = band.filter(|b| b.len() == 3) {
        let bw = b[1] - b[0];
        if bw.is_finite() && bw > 0.0 {
            let want = 1e9 / bw;
            if ((tb - want) / want).abs() > BIN_WIDTH_TOL {
                return Err(bad(
                    "bin_width_ns",
                    tb,
                    format!(
                        "the recorded band ({} to {} Hz) gives 1e9/B = {want} ns",
                        b[0], b[1]
                    ),
                ));
            }
        }
    }
    let [lo, hi] = ENBW_RANGE;
    if !(meta.enbw.is_finite() && meta.enbw >= lo * (1.0 - 1e-9) && meta.enbw <= hi) {
        return Err(bad(
            "enbw",
            meta.enbw,
            format!("a window's ENBW is within [{lo}, {hi}] frequency steps"),
        ));
    }
    let oversample = value("oversample")
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&l| l >= 1)
        .unwrap_or(crate::campaign::manifest::limits::MAX_OVERSAMPLE);
    let tw = meta.tw;
    if !(tw.is_finite() && tw >= 1.0 - 1e-9 && tw <= oversample as f64 * (1.0 + 1e-9)) {
        return Err(bad(
            "tw",
            tw,
            format!("independent samples per bin are within [1, {oversample}] (the oversampling)"),
        ));
    }
    Ok(())
}

/// Energy matrices served a run of positions at a time: a whole [`EnergyMatrix`] in
/// memory, or an [`EnergyTable`] read from its file as needed.
pub trait EnergySource: Sync {
    /// The axes and metadata (positions, directions, bins, angles, headings, `meta`); the
    /// energies it holds, if any, are not to be read through it.
    fn header(&self) -> &EnergyMatrix;
    /// The energies of positions `p0..p1` (a matrix whose [`EnergyMatrix::held`] covers
    /// them).
    fn load(&self, p0: usize, p1: usize) -> Result<std::borrow::Cow<'_, EnergyMatrix>>;
}

impl EnergySource for EnergyMatrix {
    fn header(&self) -> &EnergyMatrix {
        self
    }
    fn load(&self, p0: usize, p1: usize) -> Result<std::borrow::Cow<'_, EnergyMatrix>> {
        let held = self.held();
        if p0 > p1 || p0 < held.start || p1 > held.end {
            return Err(Error::param(
                "energy",
                format!("positions {p0}..{p1} not held (the matrix holds {held:?})"),
            ));
        }
        Ok(std::borrow::Cow::Borrowed(self))
    }
}

/// An energy table checked on opening and read a run of positions at a time (see the
/// module docs).
#[derive(Debug)]
pub struct EnergyTable {
    path: std::path::PathBuf,
    /// Axes and metadata; `data` empty.
    header: EnergyMatrix,
    /// The file, opened once (its footer and pages checked then).
    file: std::fs::File,
    /// The file's Parquet metadata, parsed once.
    md: polars::prelude::FileMetadataRef,
    /// The whole matrix, when the rows are not in the writer's order.
    whole: Option<EnergyMatrix>,
    /// First row of every row group, then the row count.
    group_starts: Vec<usize>,
    /// The last run of positions decoded (`first` and `data` only): the whole row groups
    /// around the positions asked for, served again without decoding (the EKF asks for
    /// one pose at a time, and a row group may hold many).
    cache: std::sync::Mutex<Option<DecodedRun>>,
}

/// A decoded run of positions: the first position and its energies.
type DecodedRun = std::sync::Arc<(usize, Vec<f64>)>;

/// Most rows [`EnergyTable`] decodes ahead of a request to finish a row group (2^21: 16 MB
/// of energies); past that only the rows asked for are decoded.
const MAX_AHEAD_ROWS: usize = 1 << 21;

impl EnergyTable {
    /// Open and check an energy table: footer and page headers ([`table::open_checked`]),
    /// metadata, then the index columns and the values row group by row group.
    pub fn open(path: &Path) -> Result<EnergyTable> {
        // one handle for every read: a table renamed over the path meanwhile is not mixed in
        let (file, md) = table::open_checked(path)?;
        let meta = meta_from(path, table::key_values(&md))?;
        let groups: Vec<usize> = md.row_groups.iter().map(|g| g.num_rows()).collect();
        let rows: usize = groups.iter().sum();
        let group_starts: Vec<usize> = std::iter::once(0)
            .chain(groups.iter().scan(0usize, |acc, &n| {
                *acc += n;
                Some(*acc)
            }))
            .collect();
        if rows == 0 {
            return Err(Error::input(path, "energy table has no rows"));
        }
        // pass 1: the grid from the index columns
        let (mut np, mut nd, mut nb) = (0usize, 0usize, 0usize);
        let mut off = 0;
        for &n in &groups {
            let df = table::read_parquet_part(
                path,
                &file,
                &md,
                (off, n),
                &["position", "direction", "bin"],
            )?;
            let pos = table::i64_column(path, &df, "position")?;
            let dir = table::i64_column(path, &df, "direction")?;
            let bin = table::i64_column(path, &df, "bin")?;
            for i in 0..df.height() {
                let (p, d, b) = (pos[i], dir[i], bin[i]);
                if p < 0 || d < 0 || b < 0 {
                    return Err(Error::input(path, "negative position/direction/bin index"));
                }
                // indices past the row count cannot fit the grid (checked below) and
                // would size the axes beyond the file
                let big = p.max(d).max(b);
                if big as u64 >= rows as u64 {
                    return Err(Error::input(
                        path,
                        format!(
                            "{rows} rows but row {} holds index {big} (position, direction or bin)",
                            off + i
                        ),
                    ));
                }
                np = np.max(p as usize + 1);
                nd = nd.max(d as usize + 1);
                nb = nb.max(b as usize + 1);
            }
            if df.height() != n {
                return Err(Error::input(
                    path,
                    format!(
                        "row group at row {off} claims {n} rows but holds {}",
                        df.height()
                    ),
                ));
            }
            off += n;
        }
        let cells = np.checked_mul(nd).and_then(|v| v.checked_mul(nb));
        if cells != Some(rows) {
            return Err(Error::input(
                path,
                format!("{rows} rows but {np} positions x {nd} directions x {nb} bins"),
            ));
        }
        check_missing_shape(path, &meta, np, nd)?;
        // pass 2: order, values and axes
        let mut angles = vec![f64::NAN; nd];
        let mut headings = vec![f64::NAN; np];
        let mut canonical = true;
        let mut off = 0;
        for &n in &groups {
            if !canonical {
                break;
            }
            let df = table::read_parquet_part(path, &file, &md, (off, n), &Columns::NAMES)?;
            let Columns {
                pos,
                dir,
                bin,
                arel,
                aglob,
                energy,
            } = Columns::read(path, &df)?;
            for i in 0..df.height() {
                let row = off + i;
                let (p, d, b) = (pos[i] as usize, dir[i] as usize, bin[i] as usize);
                if p >= np || d >= nd || b >= nb || (p * nd + d) * nb + b != row {
                    canonical = false;
                    break;
                }
                check_energy(path, row, energy[i], meta.is_missing(p, d))?;
                angles[d] = arel[i];
                headings[p] = wrap_deg(aglob[i] - arel[i]);
            }
            off += n;
        }
        if !canonical {
            // another tool's row order: checked and held whole
            let whole = EnergyMatrix::read_with(path, meta)?;
            let header = EnergyMatrix {
                meta: whole.meta.clone(),
                positions: whole.positions,
                angles_rel_deg: whole.angles_rel_deg.clone(),
                headings_deg: whole.headings_deg.clone(),
                bins: whole.bins,
                first: 0,
                data: Vec::new(),
            };
            return Ok(EnergyTable {
                path: path.to_path_buf(),
                header,
                file,
                md,
                whole: Some(whole),
                group_starts,
                cache: Default::default(),
            });
        }
        Ok(EnergyTable {
            path: path.to_path_buf(),
            file,
            header: EnergyMatrix {
                meta,
                positions: np,
                angles_rel_deg: angles,
                headings_deg: headings,
                bins: nb,
                first: 0,
                data: Vec::new(),
            },
            md,
            whole: None,
            group_starts,
            cache: Default::default(),
        })
    }

    /// The table's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether positions are read from the file as needed (false: held whole, the rows
    /// being in another order than the writer's).
    pub fn streams(&self) -> bool {
        self.whole.is_none()
    }
}

impl EnergySource for EnergyTable {
    fn header(&self) -> &EnergyMatrix {
        &self.header
    }

    fn load(&self, p0: usize, p1: usize) -> Result<std::borrow::Cow<'_, EnergyMatrix>> {
        if let Some(w) = &self.whole {
            return w.load(p0, p1);
        }
        let h = &self.header;
        if p0 > p1 || p1 > h.positions {
            return Err(Error::input(
                &self.path,
                format!("positions {p0}..{p1} outside the table's {}", h.positions),
            ));
        }
        let per = (h.directions() * h.bins).max(1);
        let cached = self.cache.lock().map(|c| c.clone()).unwrap_or(None);
        let run = match cached {
            Some(c) if c.0 <= p0 && p1 <= c.0 + c.1.len() / per => c,
            _ => {
                let (q0, q1) = self.decode_range(p0, p1, per);
                let run = std::sync::Arc::new((q0, self.decode(q0, q1, per)?));
                if let Ok(mut c) = self.cache.lock() {
                    *c = Some(run.clone());
                }
                run
            }
        };
        let from = (p0 - run.0) * per;
        Ok(std::borrow::Cow::Owned(EnergyMatrix {
            meta: h.meta.clone(),
            positions: h.positions,
            angles_rel_deg: h.angles_rel_deg.clone(),
            headings_deg: h.headings_deg.clone(),
            bins: h.bins,
            first: p0,
            data: run.1[from..from + (p1 - p0) * per].to_vec(),
        }))
    }
}

impl EnergyTable {
    /// The positions to decode for a request of `p0..p1`: the whole row groups it overlaps,
    /// widened to whole positions, unless that is more than [`MAX_AHEAD_ROWS`] beyond it.
    fn decode_range(&self, p0: usize, p1: usize, per: usize) -> (usize, usize) {
        let (r0, r1) = (p0 * per, p1 * per);
        let g = &self.group_starts;
        // the last group start at or before r0, the first at or after r1
        let a = g[g.partition_point(|&s| s <= r0).saturating_sub(1)];
        let b = g[g.partition_point(|&s| s < r1).min(g.len() - 1)];
        let (q0, q1) = (a / per, b.div_ceil(per).min(self.header.positions));
        if (q1 - q0) * per > (p1 - p0) * per + MAX_AHEAD_ROWS || q0 > p0 || q1 < p1 {
            (p0, p1)
        } else {
            (q0, q1)
        }
    }

    /// Decode (and check) the energies of positions `q0..q1`.
    fn decode(&self, q0: usize, q1: usize, per: usize) -> Result<Vec<f64>> {
        let df = table::read_parquet_part(
            &self.path,
            &self.file,
            &self.md,
            (q0 * per, (q1 - q0) * per),
            &["energy"],
        )?;
        let data = table::f64_column_nan(&self.path, &df, "energy")?;
        if data.len() != (q1 - q0) * per {
            return Err(Error::input(
                &self.path,
                format!(
                    "positions {q0}..{q1}: {} energies read, {} expected (file changed?)",
                    data.len(),
                    (q1 - q0) * per
                ),
            ));
        }
        let nb = self.header.bins.max(1);
        let nd = self.header.directions().max(1);
        for (i, &e) in data.iter().enumerate() {
            let row = q0 * per + i;
            let missing = self
                .header
                .meta
                .is_missing(row / (nd * nb), (row / nb) % nd);
            check_energy(&self.path, row, e, missing)?;
        }
        Ok(data)
    }
}

/// A bin energy must be non-negative and at most [`MAX_ENERGY`] (`row` names it); NaN
/// exactly where the metadata lists the profile as `missing`.
fn check_energy(path: &Path, row: usize, e: f64, missing: bool) -> Result<()> {
    if missing {
        if !e.is_nan() {
            return Err(Error::input(
                path,
                format!("column `energy` row {row}: {e:e} in a profile the metadata lists as `missing` (NaN expected)"),
            ));
        }
        return Ok(());
    }
    if e.is_nan() {
        return Err(Error::input(
            path,
            format!("column `energy` row {row}: NaN outside the profiles the metadata lists as `missing`"),
        ));
    }
    if e < 0.0 {
        return Err(Error::input(path, format!("row {row}: negative energy")));
    }
    if e > MAX_ENERGY {
        return Err(Error::input(
            path,
            format!(
                "column `energy` row {row}: {e:e} above {MAX_ENERGY:e} (a unit-amplitude echo gives about 1)"
            ),
        ));
    }
    Ok(())
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
                    "position {} heading {}°, campaign {} has {}° (energy table from another campaign?)",
                    m.label(p),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn kv(tw: &str, enbw: &str, tb: &str) -> Vec<(String, String)> {
        [
            ("schema_version", SCHEMA_VERSION.to_string()),
            ("bin_width_ns", tb.to_string()),
            ("pulses", "1".into()),
            ("n0", "1e-12".into()),
            ("enbw", enbw.to_string()),
            ("tw", tw.to_string()),
            ("array", "ula16".into()),
            ("oversample", "5".into()),
            ("band", "57500000000 63500000000 801".into()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    #[test]
    fn metadata_outside_its_physical_range_is_refused_naming_the_key() {
        let p = Path::new("e.parquet");
        let tb = format!("{:.17e}", 1e9 / 6e9);
        assert!(meta_from(p, kv("1.2", "1.5", &tb)).is_ok());
        assert!(meta_from(p, kv("1", "1", &tb)).is_ok());
        for (k, v) in [
            ("tw", kv("1e300", "1.5", &tb)),
            ("tw", kv("0.5", "1.5", &tb)),
            ("tw", kv("6", "1.5", &tb)),
            ("tw", kv("nan", "1.5", &tb)),
            ("enbw", kv("1.2", "0.5", &tb)),
            ("enbw", kv("1.2", "1e9", &tb)),
            ("bin_width_ns", kv("1.2", "1.5", "0")),
            ("bin_width_ns", kv("1.2", "1.5", "inf")),
            ("bin_width_ns", kv("1.2", "1.5", "0.1667")),
        ] {
            let e = meta_from(p, v).unwrap_err().to_string();
            assert!(
                e.contains("e.parquet") && e.contains(&format!("`{k}`")) && !e.contains('\n'),
                "{k}: {e}"
            );
        }
    }
}
