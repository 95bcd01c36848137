//! Sweep storage: one Touchstone file per (position, direction, pulse), or one Parquet long
//! table `position, direction, pulse, frequency_hz, re, im` (rows sorted by position,
//! direction, pulse, frequency; one row group per position as `simulate` writes it).
//!
//! Reading is per position ([`SweepReader::read_position`]) so the energy stage streams: at
//! most one position's sweeps are in memory. Every file is checked against the manifest's
//! band (same number of points, frequencies within 1e-6 of a step): a wrong band, a missing
//! file, NaN, a value above [`crate::campaign::touchstone::MAX_VALUE`] or a truncated row is
//! an error naming the file (and line or row). Every Touchstone file (or the Parquet table)
//! must be a regular file ([`crate::io::regular_input`]), checked before any is opened.
//!
//! From a Touchstone file of any port count the reader keeps one S-parameter, `[sweeps]
//! parameter` (S21 by default, S11 for a one-port file when the manifest names none); a file
//! without it is an error naming the file and its port count.

use crate::campaign::manifest::{expand_pattern, Band, Campaign, SweepFormat};
use crate::campaign::touchstone::{decode, parse_touchstone, write_s2p, SParam, TsFormat};
use crate::error::{Error, Result};
use crate::table;
use num_complex::Complex64;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// All sweeps of one position: `s21[(direction·pulses + pulse)·points + k]`.
#[derive(Debug, Clone)]
pub struct PositionSweeps {
    /// Position index.
    pub position: usize,
    /// Directions.
    pub directions: usize,
    /// Pulses per direction.
    pub pulses: usize,
    /// Frequency points.
    pub points: usize,
    /// The swept parameter (`[sweeps] parameter`, S21 by default); NaN for a missing sweep.
    pub s21: Vec<Complex64>,
    /// Per direction: the campaign has no sweep there (`[sweeps] missing`); empty when
    /// none is missing.
    pub missing: Vec<bool>,
}

impl PositionSweeps {
    /// Whether direction `d` was swept (not listed in `[sweeps] missing`).
    pub fn has(&self, d: usize) -> bool {
        !self.missing.get(d).copied().unwrap_or(false)
    }
    /// The sweep of one (direction, pulse).
    pub fn sweep(&self, direction: usize, pulse: usize) -> &[Complex64] {
        let i = (direction * self.pulses + pulse) * self.points;
        &self.s21[i..i + self.points]
    }
}

enum Source {
    Touchstone(Vec<PathBuf>, Option<SParam>),
    Parquet(PathBuf),
}

/// Reads a campaign's sweeps position by position.
pub struct SweepReader {
    band: Band,
    positions: usize,
    directions: usize,
    pulses: usize,
    /// Per (position, direction): listed in `[sweeps] missing`.
    missing: Vec<bool>,
    source: Source,
}

/// The files a sweep-name template names just past the campaign's last direction (and
/// pulse) must not exist: files recorded for more directions than `[directions]` gives
/// mean the manifest's step or span is not the one measured (a 10° step over files of a
/// 5° scan would label the first half of the scan as all of it).
fn check_no_more_files(c: &Campaign, pattern: &str, nd: usize, nk: usize) -> Result<()> {
    let dir = c.dir();
    let d = &c.manifest.directions;
    let base = dir.join(expand_pattern(pattern, 0, 0, 0));
    let cases = [
        (
            dir.join(expand_pattern(pattern, 0, nd, 0)),
            format!(
                "[directions] gives {nd} directions ({}°..{}° step {}°)",
                d.start_deg, d.stop_deg, d.step_deg
            ),
        ),
        (
            dir.join(expand_pattern(pattern, 0, 0, nk)),
            format!("pulses = {nk}"),
        ),
    ];
    for (path, said) in cases {
        // a template without the placeholder names the first file again
        if path != base && path.is_file() {
            return Err(Error::input(
                &c.path,
                format!(
                    "{said} but {} exists: the files hold more sweeps than the manifest says",
                    path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Check a frequency grid against the band.
pub fn check_grid(path: &Path, freq_hz: &[f64], band: &Band) -> Result<()> {
    let tol = 1e-6 * band.step_hz();
    let ok = freq_hz.len() == band.points
        && freq_hz
            .iter()
            .enumerate()
            .all(|(k, f)| (f - band.freq(k)).abs() <= tol.max(1.0));
    if ok {
        Ok(())
    } else {
        Err(Error::input(
            path,
            format!(
                "frequency grid ({} points, {:.6}..{:.6} GHz) does not match [band] ({} points, {:.6}..{:.6} GHz)",
                freq_hz.len(),
                freq_hz.first().copied().unwrap_or(f64::NAN) / 1e9,
                freq_hz.last().copied().unwrap_or(f64::NAN) / 1e9,
                band.points,
                band.start_hz / 1e9,
                band.stop_hz / 1e9
            ),
        ))
    }
}

/// Read one Touchstone sweep's parameter `param` (None: [`SParam::default_for`] its port
/// count) into `out`, checking its grid against `band`.
pub fn read_sweep(
    path: &Path,
    param: Option<SParam>,
    band: &Band,
    out: &mut [Complex64],
) -> Result<()> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let net = parse_touchstone(&decode(&bytes), path)?;
    check_grid(path, &net.freq_hz, band)?;
    let p = param.unwrap_or(SParam::default_for(net.ports));
    net.param_into(p, path, out)
}

impl SweepReader {
    /// Open the sweeps listed by the manifest's `[sweeps]`; every Touchstone file must exist.
    pub fn open(c: &Campaign) -> Result<SweepReader> {
        let m = &c.manifest;
        let cfg = m.sweeps.as_ref().ok_or_else(|| {
            Error::input(
                &c.path,
                "no [sweeps] section (run `pradar simulate` or list the files)",
            )
        })?;
        let (np, nd, nk) = (m.positions(), m.directions.count(), m.pulses);
        let dir = c.dir();
        let mut missing = vec![false; np * nd];
        for (p, d) in m.missing() {
            missing[p * nd + d] = true;
        }
        let source = match cfg.format {
            SweepFormat::Touchstone => {
                let mut paths = vec![PathBuf::new(); np * nd * nk];
                if let Some(pat) = &cfg.pattern {
                    for p in 0..np {
                        for d in 0..nd {
                            for k in 0..nk {
                                paths[(p * nd + d) * nk + k] =
                                    dir.join(expand_pattern(pat, p, d, k));
                            }
                        }
                    }
                    check_no_more_files(c, pat, nd, nk)?;
                } else {
                    for (i, f) in cfg.files.iter().enumerate() {
                        if f.position >= np || f.direction >= nd || f.pulse >= nk {
                            return Err(Error::input(
                                &c.path,
                                format!("sweeps.files[{i}]: index (position {}, direction {}, pulse {}) outside the campaign ({np} positions, {nd} directions, {nk} pulses)", f.position, f.direction, f.pulse),
                            ));
                        }
                        paths[(f.position * nd + f.direction) * nk + f.pulse] = dir.join(&f.path);
                    }
                    if let Some(i) = paths
                        .iter()
                        .enumerate()
                        .position(|(i, p)| p.as_os_str().is_empty() && !missing[i / nk])
                    {
                        let (p, d, k) = (i / (nd * nk), (i / nk) % nd, i % nk);
                        return Err(Error::input(
                            &c.path,
                            format!(
                                "sweeps.files: no file for position {} (index {p}), direction {}, pulse {k} (a sweep the campaign lacks is listed in [sweeps] missing: `import --allow-missing`)",
                                m.label(p),
                                m.direction_name(d)
                            ),
                        ));
                    }
                }
                // a missing sweep names no file, whatever a template would give
                for (i, p) in paths.iter_mut().enumerate() {
                    if missing[i / nk] {
                        *p = PathBuf::new();
                    }
                }
                // every file a regular one, before any is opened (a FIFO would block, a
                // device never end)
                let what = format!("sweep file listed in {}", c.path.display());
                for p in paths.iter().filter(|p| !p.as_os_str().is_empty()) {
                    crate::io::regular_input(p, &what)?;
                }
                // the band is checked on the first file now, before anything is computed
                // from [band] (a wrong `points` would otherwise surface as a processing
                // range problem)
                let mut first = vec![Complex64::new(0.0, 0.0); m.band.points];
                let first_path = paths
                    .iter()
                    .find(|p| !p.as_os_str().is_empty())
                    .ok_or_else(|| Error::input(&c.path, "sweeps: no sweep file"))?;
                read_sweep(first_path, cfg.parameter, &m.band, &mut first)?;
                Source::Touchstone(paths, cfg.parameter)
            }
            SweepFormat::Parquet => {
                let p = dir.join(cfg.path.as_ref().expect("checked"));
                crate::io::regular_input(
                    &p,
                    &format!("sweep table listed in {}", c.path.display()),
                )?;
                let rows = table::parquet_rows(&p)?;
                let want = np * nd * nk * m.band.points;
                if rows != want {
                    return Err(Error::input(
                        &p,
                        format!("{rows} rows, expected {want} ({np} positions x {nd} directions x {nk} pulses x {} points)", m.band.points),
                    ));
                }
                Source::Parquet(p)
            }
        };
        Ok(SweepReader {
            band: m.band,
            positions: np,
            directions: nd,
            pulses: nk,
            missing,
            source,
        })
    }

    /// Number of positions.
    pub fn positions(&self) -> usize {
        self.positions
    }

    /// Every sweep file read (the Touchstone files, or the one Parquet table).
    pub fn files(&self) -> Vec<&Path> {
        match &self.source {
            // a missing sweep has no file
            Source::Touchstone(paths, _) => paths
                .iter()
                .filter(|p| !p.as_os_str().is_empty())
                .map(PathBuf::as_path)
                .collect(),
            Source::Parquet(p) => vec![p.as_path()],
        }
    }

    /// Positions read together by [`Self::read_positions`]: one for Touchstone (files are
    /// read in parallel within a position), about 2^20 rows for Parquet so a read decodes
    /// whole row groups instead of slicing one repeatedly. Memory stays bounded by this
    /// chunk, whatever the campaign size.
    pub fn chunk_positions(&self) -> usize {
        match self.source {
            Source::Touchstone(..) => 1,
            Source::Parquet(_) => {
                let rows = self.directions * self.pulses * self.band.points;
                ((1usize << 20) / rows.max(1)).clamp(1, self.positions.max(1))
            }
        }
    }

    /// Read every sweep of position `p`.
    pub fn read_position(&self, p: usize) -> Result<PositionSweeps> {
        Ok(self.read_positions(p, 1)?.remove(0))
    }

    /// Read positions `p0 .. p0 + count` (Touchstone files in parallel).
    pub fn read_positions(&self, p0: usize, count: usize) -> Result<Vec<PositionSweeps>> {
        let (nd, nk, nf) = (self.directions, self.pulses, self.band.points);
        let count = count.min(self.positions - p0);
        let n = nd * nk * nf;
        let mut out = Vec::with_capacity(count);
        match &self.source {
            Source::Touchstone(paths, param) => {
                for p in p0..p0 + count {
                    let mut s21 = vec![Complex64::new(0.0, 0.0); n];
                    let base = p * nd * nk;
                    s21.par_chunks_mut(nf)
                        .enumerate()
                        .try_for_each(|(i, out)| -> Result<()> {
                            if self.missing[p * nd + i / nk] {
                                out.fill(Complex64::new(f64::NAN, f64::NAN));
                                return Ok(());
                            }
                            let path = &paths[base + i];
                            read_sweep(path, *param, &self.band, out)
                        })?;
                    out.push(PositionSweeps {
                        position: p,
                        directions: nd,
                        pulses: nk,
                        points: nf,
                        s21,
                        missing: self.missing[p * nd..(p + 1) * nd].to_vec(),
                    });
                }
            }
            Source::Parquet(path) => {
                let df = table::read_parquet(path, Some((p0 * n, count * n)))?;
                let pos = table::i64_column(path, &df, "position")?;
                let dirs = table::i64_column(path, &df, "direction")?;
                let pulse = match df.column("pulse") {
                    Ok(_) => table::i64_column(path, &df, "pulse")?,
                    Err(_) => vec![0; n * count],
                };
                let f = table::f64_column(path, &df, "frequency_hz")?;
                // NaN only in the sweeps `[sweeps] missing` lists (checked per row below)
                let re = table::f64_column_nan(path, &df, "re")?;
                let im = table::f64_column_nan(path, &df, "im")?;
                let tol = (1e-6 * self.band.step_hz()).max(1.0);
                for c in 0..count {
                    let p = p0 + c;
                    let mut s21 = vec![Complex64::new(0.0, 0.0); n];
                    for (i, v) in s21.iter_mut().enumerate() {
                        let r = c * n + i;
                        let (d, k, j) = (i / (nk * nf), (i / nf) % nk, i % nf);
                        if pos[r] != p as i64 || dirs[r] != d as i64 || pulse[r] != k as i64 {
                            return Err(Error::input(
                                path,
                                format!("row {}: expected position {p}, direction {d}, pulse {k} (rows must be sorted by position, direction, pulse, frequency)", p0 * n + r),
                            ));
                        }
                        if (f[r] - self.band.freq(j)).abs() > tol {
                            return Err(Error::input(
                                path,
                                format!("row {}: frequency {} Hz does not match [band] point {j} ({} Hz)", p0 * n + r, f[r], self.band.freq(j)),
                            ));
                        }
                        let bound = crate::campaign::touchstone::MAX_VALUE;
                        if self.missing[p * nd + d] {
                            // a missing sweep is NaN in the table (`import --allow-missing`)
                            if !(re[r].is_nan() && im[r].is_nan()) {
                                return Err(Error::input(
                                    path,
                                    format!("row {}: position {p}, direction {d} is listed in [sweeps] missing but holds a value (NaN expected)", p0 * n + r),
                                ));
                            }
                            *v = Complex64::new(f64::NAN, f64::NAN);
                            continue;
                        }
                        if !(re[r].abs() <= bound && im[r].abs() <= bound) {
                            return Err(Error::input(
                                path,
                                format!("row {}: re = {}, im = {}: not finite or above {bound:e} (its energy would overflow)", p0 * n + r, re[r], im[r]),
                            ));
                        }
                        *v = Complex64::new(re[r], im[r]);
                    }
                    out.push(PositionSweeps {
                        position: p,
                        directions: nd,
                        pulses: nk,
                        points: nf,
                        s21,
                        missing: self.missing[p * nd..(p + 1) * nd].to_vec(),
                    });
                }
            }
        }
        Ok(out)
    }
}

/// Write one position's sweeps as Touchstone files (RI, Hz, 12 digits), S12 = S21
/// (reciprocal), S11 = S22 = 0 (not simulated).
pub fn write_touchstone_position(
    dir: &Path,
    pattern: &str,
    band: &Band,
    sweeps: &PositionSweeps,
    comment: &str,
) -> Result<()> {
    let freq: Vec<f64> = (0..band.points).map(|k| band.freq(k)).collect();
    let z = Complex64::new(0.0, 0.0);
    (0..sweeps.directions * sweeps.pulses)
        .into_par_iter()
        .try_for_each(|i| {
            let (d, k) = (i / sweeps.pulses, i % sweeps.pulses);
            let path = dir.join(expand_pattern(pattern, sweeps.position, d, k));
            let s: Vec<[Complex64; 4]> = sweeps.sweep(d, k).iter().map(|&v| [z, v, v, z]).collect();
            crate::io::write_atomic(&path, |w| {
                write_s2p(w, &freq, &s, TsFormat::Ri, 12, comment).map_err(|e| Error::io(&path, e))
            })
        })
}

/// Columns of one position's sweeps for the Parquet sweep table.
pub fn parquet_batch(
    path: &Path,
    band: &Band,
    sweeps: &PositionSweeps,
) -> Result<polars::prelude::DataFrame> {
    let n = sweeps.s21.len();
    let nf = sweeps.points;
    let mut pos = Vec::with_capacity(n);
    let mut dir = Vec::with_capacity(n);
    let mut pulse = Vec::with_capacity(n);
    let mut f = Vec::with_capacity(n);
    for i in 0..n {
        pos.push(sweeps.position as i32);
        dir.push((i / (sweeps.pulses * nf)) as i32);
        pulse.push(((i / nf) % sweeps.pulses) as i32);
        f.push(band.freq(i % nf));
    }
    table::frame(
        path,
        vec![
            table::col("position", pos),
            table::col("direction", dir),
            table::col("pulse", pulse),
            table::col("frequency_hz", f),
            table::col("re", sweeps.s21.iter().map(|c| c.re).collect::<Vec<f64>>()),
            table::col("im", sweeps.s21.iter().map(|c| c.im).collect::<Vec<f64>>()),
        ],
    )
}
