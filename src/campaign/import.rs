//! `pradar import`: a campaign manifest built and validated from what a measurement
//! campaign leaves on disk.
//!
//! Takes ([`ImportParams`]): a poses table (CSV with a header `position, x, y, heading` —
//! `x_m, y_m, heading_deg` also accepted — metres and degrees; position labels are any
//! distinct integers, mapped to manifest positions in increasing order), the sweep files —
//! either a glob (`raw/*.s2p`; `*` and `?` within a path component) plus a naming pattern
//! for the file names with `{position}`, `{direction}` and `{pulse}` (`{position:03}` fixes
//! the width; without a width any run of digits), or an index CSV `position, direction,
//! [pulse,] path` (paths relative to the CSV) — the directions (indices 0..n−1 over
//! `start:stop:step` degrees), the layout, and optionally a base manifest fragment giving
//! `name`, `seed`, `[array]`, `[noise]`, `[processing]`, `[calibration]` and `[sweeps]
//! parameter`, which cannot be read from the files.
//!
//! Gives: the band and grid read from the files (start, stop and point count of the first
//! file; every file must have the same grid, uniform to 1e-6 of a step), the pulse count
//! (largest `{pulse}` + 1), and, **before any processing**, the list of problems: missing
//! (position, direction, pulse) cells, duplicated cells (two files naming one cell), extra
//! files (matching the glob but not the pattern, or naming a position not in the poses
//! table, a direction or pulse out of range), unreadable files (the reader's one-line
//! refusal, naming file, line and reason; also a file without the `[sweeps] parameter`) and
//! files whose grid differs from the first's. With any problem nothing is written
//! ([`ImportOutcome::problems`]; the command exits 1). Otherwise the manifest is written
//! atomically with an explicit `[sweeps] files` list (paths relative to the manifest), and
//! with `to_parquet` the sweeps are also converted to the Parquet sweep table
//! `sweeps.parquet` beside it (which the manifest then names; later stages read it faster).
//!
//! `[noise]` from the base, else `floor_dbm = -100`, `tx_power_dbm = 0`: only `simulate` and
//! `synth` read it (a measured campaign's N0 is estimated from its signal-free bins).
//!
//! Refused before any sweep is read: an `--out` (or, with `to_parquet`, its
//! `sweeps.parquet`) that is one of the inputs — the poses CSV, the index CSV, the base,
//! the layout, a sweep file — by path or by inode ([`crate::io::refuse_overwrite`]); a
//! poses CSV of more than [`MAX_POSES`] rows, an index of more than [`MAX_INDEX_ROWS`]; a
//! poses or index CSV that is a device or FIFO. A sweep file that is not a regular file
//! (device, FIFO, dangling link, symlink loop; [`crate::io::regular_input`]) is an
//! `unreadable:` problem, never opened.

use crate::campaign::manifest::{Campaign, Directions};
use crate::campaign::sweeps::{parquet_batch, SweepReader};
use crate::campaign::touchstone::{decode, parse_touchstone, SParam};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where the sweep files are and how they are named.
#[derive(Debug, Clone)]
pub enum SweepFiles {
    /// A glob and a file-name pattern with `{position}`, `{direction}`, `{pulse}`.
    Glob {
        /// e.g. `raw/*.s2p`.
        glob: String,
        /// e.g. `pos{position}_dir{direction:02}.s2p`.
        pattern: String,
    },
    /// An index CSV `position, direction, [pulse,] path`.
    Index(PathBuf),
}

/// Inputs of [`run`].
#[derive(Debug, Clone)]
pub struct ImportParams {
    /// Poses CSV.
    pub poses: PathBuf,
    /// The sweep files.
    pub sweeps: SweepFiles,
    /// Directions (else from the base).
    pub directions: Option<Directions>,
    /// Layout GeoJSON (else from the base).
    pub layout: Option<PathBuf>,
    /// Base manifest fragment (TOML).
    pub base: Option<PathBuf>,
    /// Campaign name (else the base's, else the output folder's name).
    pub name: Option<String>,
    /// `[array] elements` (else the base's).
    pub elements: Option<usize>,
    /// Output manifest.
    pub out: PathBuf,
    /// Also write the Parquet sweep table.
    pub to_parquet: bool,
}

/// What [`run`] found and wrote.
#[derive(Debug, Clone, Default)]
pub struct ImportOutcome {
    /// Problems found before processing (nothing written when not empty), one line each.
    pub problems: Vec<String>,
    /// Positions, directions, pulses.
    pub shape: (usize, usize, usize),
    /// Sweep files matched.
    pub files: usize,
    /// Band (start, stop, points) read from the files.
    pub band: Option<(f64, f64, usize)>,
    /// Reader notes (e.g. noise blocks skipped), with a count of files each.
    pub notes: Vec<String>,
    /// The manifest written.
    pub manifest: Option<PathBuf>,
    /// The Parquet sweep table written.
    pub parquet: Option<PathBuf>,
}

impl std::fmt::Display for ImportOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (np, nd, nk) = self.shape;
        write!(
            f,
            "{} sweep files: {np} positions x {nd} directions x {nk} pulses",
            self.files
        )?;
        if let Some((a, b, n)) = self.band {
            write!(f, ", {:.6}..{:.6} GHz, {n} points", a / 1e9, b / 1e9)?;
        }
        for n in &self.notes {
            write!(f, "\nnote: {n}")?;
        }
        if let Some(m) = &self.manifest {
            write!(f, "\nwrote {}", m.display())?;
        }
        if let Some(p) = &self.parquet {
            write!(f, "\nwrote {}", p.display())?;
        }
        Ok(())
    }
}

/// A pose row: label, x_m, y_m, heading_deg.
type PoseRow = (i64, f64, f64, f64);

/// A small CSV ([`split_csv`] quoting): the lower-cased header, then (line number, cells)
/// per row.
type CsvRows = (Vec<String>, Vec<(usize, Vec<String>)>);

/// One sweep file as `import` reads it: its grid and reader notes, or the refusal.
type FileRead = std::result::Result<(Vec<f64>, Vec<String>), String>;

fn read_csv(path: &Path) -> Result<CsvRows> {
    // a device or FIFO would never end (or block): refused before it is opened
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        crate::io::regular_input(path, "table")?;
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_csv(&decode(&bytes), path)
}

/// The header and rows of a CSV's text (`path` names it in errors).
fn parse_csv(text: &str, path: &Path) -> Result<CsvRows> {
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (_, head) = rows
        .next()
        .ok_or_else(|| Error::input(path, "empty table (a header line is needed)"))?;
    let header: Vec<String> = split_csv(head)
        .map_err(|e| Error::input(path, format!("header line: {e}")))?
        .into_iter()
        .map(|h| h.to_ascii_lowercase())
        .collect();
    let mut body = Vec::new();
    for (n, l) in rows {
        let cells = split_csv(l).map_err(|e| Error::input(path, format!("line {n}: {e}")))?;
        if cells.len() > header.len() {
            return Err(Error::input(
                path,
                format!(
                    "line {n}: {} cells for the header's {} columns (a cell holding a comma must be quoted: \"a,b.s2p\")",
                    cells.len(),
                    header.len()
                ),
            ));
        }
        body.push((n, cells));
    }
    Ok((header, body))
}

/// The cells of one CSV line (RFC 4180 quoting within a line): separated by commas,
/// unquoted cells trimmed; a cell opening with `"` (after spaces) runs to its closing
/// quote, `""` inside it is one `"`, and it is kept as written. Refused: a quote left open
/// (a quoted cell may not span lines), text after a closing quote, a `"` inside an
/// unquoted cell.
fn split_csv(line: &str) -> std::result::Result<Vec<String>, String> {
    let mut cells = Vec::new();
    let mut rest = line;
    loop {
        let t = rest.trim_start();
        if let Some(q) = t.strip_prefix('"') {
            let mut cell = String::new();
            let mut chars = q.char_indices();
            let after = loop {
                match chars.next() {
                    None => {
                        return Err(format!(
                            "cell {} opens a quote that the line does not close",
                            cells.len() + 1
                        ))
                    }
                    Some((i, '"')) => {
                        if q[i + 1..].starts_with('"') {
                            cell.push('"');
                            chars.next();
                        } else {
                            break &q[i + 1..];
                        }
                    }
                    Some((_, c)) => cell.push(c),
                }
            };
            cells.push(cell);
            let after = after.trim_start();
            match after.strip_prefix(',') {
                Some(r) => rest = r,
                None if after.is_empty() => return Ok(cells),
                None => {
                    return Err(format!(
                        "text after the closing quote of cell {}",
                        cells.len()
                    ))
                }
            }
        } else {
            let (cell, next) = match t.find(',') {
                Some(i) => (&t[..i], Some(&t[i + 1..])),
                None => (t, None),
            };
            if cell.contains('"') {
                return Err(format!(
                    "a `\"` inside unquoted cell {} (quote the whole cell, a quote in it doubled)",
                    cells.len() + 1
                ));
            }
            cells.push(cell.trim().to_string());
            match next {
                Some(r) => rest = r,
                None => return Ok(cells),
            }
        }
    }
}

/// The column named by any of `names`: an error naming the file when absent.
fn column(path: &Path, header: &[String], names: &[&str]) -> Result<usize> {
    optional_column(header, names)
        .ok_or_else(|| Error::input(path, format!("no column `{}` in the header", names[0])))
}

fn optional_column(header: &[String], names: &[&str]) -> Option<usize> {
    header.iter().position(|h| names.contains(&h.as_str()))
}

fn cell<T: std::str::FromStr>(
    path: &Path,
    line: usize,
    row: &[String],
    c: usize,
    what: &str,
) -> Result<T> {
    let v = row.get(c).map(String::as_str).unwrap_or("");
    v.parse()
        .map_err(|_| Error::input(path, format!("line {line}: `{v}` is not a valid {what}")))
}

/// Poses a poses CSV may hold (a campaign of more positions is not a measurement; the
/// bound keeps a runaway table from being parsed row by row).
pub const MAX_POSES: usize = 100_000;

/// Rows an index CSV may hold (one per sweep file).
pub const MAX_INDEX_ROWS: usize = 10_000_000;

/// Refuse a table of more than `max` rows, naming the bound.
fn bound_rows(path: &Path, rows: usize, max: usize, what: &str) -> Result<()> {
    if rows > max {
        return Err(Error::input(
            path,
            format!("{rows} rows: more than {max} {what}"),
        ));
    }
    Ok(())
}

fn read_poses(path: &Path) -> Result<Vec<PoseRow>> {
    poses_from(path, read_csv(path)?)
}

/// The poses of a poses CSV's text, as `import --poses` reads them (`path` names the file
/// in errors): `(label, x_m, y_m, heading_deg)` sorted by label. The entry point of the
/// poses target of [`crate::fuzz`].
pub fn parse_poses(text: &str, path: &Path) -> Result<Vec<(i64, f64, f64, f64)>> {
    poses_from(path, parse_csv(text, path)?)
}

fn poses_from(path: &Path, (h, rows): CsvRows) -> Result<Vec<PoseRow>> {
    bound_rows(path, rows.len(), MAX_POSES, "poses")?;
    let cp = column(path, &h, &["position"])?;
    let cx = column(path, &h, &["x", "x_m"])?;
    let cy = column(path, &h, &["y", "y_m"])?;
    let ch = column(path, &h, &["heading", "heading_deg"])?;
    let mut out: Vec<PoseRow> = Vec::with_capacity(rows.len());
    let mut labels = std::collections::HashSet::with_capacity(rows.len());
    for (n, r) in &rows {
        let row = (
            cell(path, *n, r, cp, "position (integer)")?,
            cell::<f64>(path, *n, r, cx, "x (m)")?,
            cell::<f64>(path, *n, r, cy, "y (m)")?,
            cell::<f64>(path, *n, r, ch, "heading (degrees)")?,
        );
        if !(row.1.is_finite() && row.2.is_finite() && row.3.is_finite()) {
            return Err(Error::input(
                path,
                format!("line {n}: x, y, heading must be finite"),
            ));
        }
        if !labels.insert(row.0) {
            return Err(Error::input(
                path,
                format!("line {n}: position {} listed twice", row.0),
            ));
        }
        out.push(row);
    }
    if out.is_empty() {
        return Err(Error::input(path, "no poses"));
    }
    out.sort_by_key(|p| p.0);
    Ok(out)
}

/// A piece of a naming pattern.
#[derive(Debug, Clone, PartialEq)]
enum Piece {
    Lit(String),
    Field(usize, Option<usize>),
}

const FIELDS: [&str; 3] = ["position", "direction", "pulse"];

fn parse_pattern(p: &str) -> Result<Vec<Piece>> {
    let mut out = Vec::new();
    let mut rest = p;
    while let Some(open) = rest.find('{') {
        if open > 0 {
            out.push(Piece::Lit(rest[..open].to_string()));
        }
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| Error::param("--name-pattern", format!("`{p}`: `{{` without `}}`")))?
            + open;
        let spec = &rest[open + 1..close];
        let (name, width) = match spec.split_once(':') {
            Some((n, w)) => (
                n,
                Some(w.parse::<usize>().map_err(|_| {
                    Error::param(
                        "--name-pattern",
                        format!("`{{{spec}}}`: the width must be a number"),
                    )
                })?),
            ),
            None => (spec, None),
        };
        let f = FIELDS.iter().position(|&x| x == name).ok_or_else(|| {
            Error::param(
                "--name-pattern",
                format!("unknown field `{{{name}}}` (use {{position}}, {{direction}}, {{pulse}})"),
            )
        })?;
        out.push(Piece::Field(f, width));
        rest = &rest[close + 1..];
    }
    if !rest.is_empty() {
        out.push(Piece::Lit(rest.to_string()));
    }
    for (f, name) in FIELDS.iter().enumerate().take(2) {
        if !out
            .iter()
            .any(|q| matches!(q, Piece::Field(g, _) if *g == f))
        {
            return Err(Error::param(
                "--name-pattern",
                format!("`{p}` has no {{{name}}}"),
            ));
        }
    }
    Ok(out)
}

/// Match a name against the pattern: the values of (position, direction, pulse).
fn match_name(pieces: &[Piece], s: &str, vals: &mut [Option<i64>; 3]) -> bool {
    let Some((first, rest)) = pieces.split_first() else {
        return s.is_empty();
    };
    match first {
        Piece::Lit(l) => s
            .strip_prefix(l.as_str())
            .is_some_and(|t| match_name(rest, t, vals)),
        Piece::Field(f, width) => {
            let digits = s.bytes().take_while(u8::is_ascii_digit).count();
            let lens: Vec<usize> = match width {
                Some(w) if *w <= digits => vec![*w],
                Some(_) => vec![],
                None => (1..=digits).rev().collect(),
            };
            for n in lens {
                let v: i64 = match s[..n].parse() {
                    Ok(v) => v,
                    Err(_) => continue,
                };
                if vals[*f].is_some_and(|old| old != v) {
                    continue;
                }
                let saved = vals[*f];
                vals[*f] = Some(v);
                if match_name(rest, &s[n..], vals) {
                    return true;
                }
                vals[*f] = saved;
            }
            false
        }
    }
}

/// `*` and `?` within one path component.
fn wild(p: &[u8], s: &[u8]) -> bool {
    match (p.first(), s.first()) {
        (None, None) => true,
        (Some(b'*'), _) => wild(&p[1..], s) || (!s.is_empty() && wild(p, &s[1..])),
        (Some(b'?'), Some(_)) => wild(&p[1..], &s[1..]),
        (Some(a), Some(b)) if a == b => wild(&p[1..], &s[1..]),
        _ => false,
    }
}

/// Files matching a glob, sorted.
pub fn glob(pattern: &str) -> Result<Vec<PathBuf>> {
    let path = Path::new(pattern);
    let mut base = PathBuf::new();
    let mut parts: Vec<String> = Vec::new();
    for c in path.components() {
        let s = c.as_os_str().to_string_lossy();
        if parts.is_empty() && !s.contains(['*', '?']) {
            base.push(c);
        } else {
            parts.push(s.into_owned());
        }
    }
    if parts.is_empty() {
        return Ok(if base.is_file() { vec![base] } else { vec![] });
    }
    let start = if base.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        base
    };
    let mut found = Vec::new();
    walk(&start, &parts, &mut found)?;
    found.sort();
    Ok(found)
}

fn walk(dir: &Path, parts: &[String], found: &mut Vec<PathBuf>) -> Result<()> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    for entry in rd {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !wild(parts[0].as_bytes(), name.as_bytes()) {
            continue;
        }
        let p = entry.path();
        if parts.len() == 1 {
            // a matching name that is not a regular file (a dangling link, a loop, a
            // device) is kept: the read refuses it, naming it, instead of it being missed
            if !p.is_dir() {
                found.push(p);
            }
        } else if p.is_dir() {
            walk(&p, &parts[1..], found)?;
        }
    }
    Ok(())
}

/// (position label, direction, pulse) → files naming that cell; and files naming none.
type Cells = (
    BTreeMap<(i64, i64, i64), Vec<PathBuf>>,
    Vec<(PathBuf, String)>,
);

fn cells_from_glob(glob_pat: &str, pattern: &str) -> Result<Cells> {
    let pieces = parse_pattern(pattern)?;
    let mut cells: BTreeMap<(i64, i64, i64), Vec<PathBuf>> = BTreeMap::new();
    let mut extra = Vec::new();
    let files = glob(glob_pat)?;
    if files.is_empty() {
        return Err(Error::param(
            "--sweeps",
            format!("`{glob_pat}` matches no file"),
        ));
    }
    for f in files {
        let name = f
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mut v = [None; 3];
        if match_name(&pieces, &name, &mut v) {
            cells
                .entry((v[0].unwrap_or(0), v[1].unwrap_or(0), v[2].unwrap_or(0)))
                .or_default()
                .push(f);
        } else {
            extra.push((f, format!("name does not match `{pattern}`")));
        }
    }
    Ok((cells, extra))
}

fn cells_from_index(path: &Path) -> Result<Cells> {
    index_from(path, read_csv(path)?)
}

/// The sweep files an index CSV's text lists, as `import --index` reads them (`path` names
/// the file in errors, and relative paths are taken from its folder): per (position,
/// direction, pulse) the files naming it. The entry point of the index target of
/// [`crate::fuzz`].
pub fn parse_index(text: &str, path: &Path) -> Result<BTreeMap<(i64, i64, i64), Vec<PathBuf>>> {
    Ok(index_from(path, parse_csv(text, path)?)?.0)
}

fn index_from(path: &Path, (h, rows): CsvRows) -> Result<Cells> {
    bound_rows(path, rows.len(), MAX_INDEX_ROWS, "sweep files")?;
    let cp = column(path, &h, &["position"])?;
    let cd = column(path, &h, &["direction"])?;
    let ck = optional_column(&h, &["pulse"]);
    let cf = column(path, &h, &["path"])?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut cells: BTreeMap<(i64, i64, i64), Vec<PathBuf>> = BTreeMap::new();
    for (n, r) in &rows {
        let key = (
            cell(path, *n, r, cp, "position (integer)")?,
            cell(path, *n, r, cd, "direction (integer)")?,
            match ck {
                Some(c) => cell(path, *n, r, c, "pulse (integer)")?,
                None => 0,
            },
        );
        let f = r
            .get(cf)
            .filter(|s| !s.is_empty())
            .ok_or_else(|| Error::input(path, format!("line {n}: empty path")))?;
        cells.entry(key).or_default().push(dir.join(f));
    }
    Ok((cells, Vec::new()))
}

/// `path` relative to `dir` when inside it, else absolute.
fn relative_to(path: &Path, dir: &Path) -> PathBuf {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, d) = (abs(path), abs(dir));
    p.strip_prefix(&d).map(Path::to_path_buf).unwrap_or(p)
}

const BASE_KEYS: [&str; 10] = [
    "schema_version",
    "name",
    "seed",
    "array",
    "noise",
    "processing",
    "calibration",
    "directions",
    "layout",
    "sweeps",
];

fn read_base(path: &Path) -> Result<toml::Table> {
    let text = crate::io::read_text(path)?;
    let t: toml::Table = toml::from_str(&text)
        .map_err(|e| Error::input(path, crate::campaign::manifest::one_line(&e.to_string())))?;
    for k in t.keys() {
        if !BASE_KEYS.contains(&k.as_str()) {
            return Err(Error::input(
                path,
                format!("field `{k}` cannot be given to import (band, poses, pulses and sweep files come from the files; allowed: {})", BASE_KEYS.join(", ")),
            ));
        }
    }
    if let Some(s) = t.get("sweeps").and_then(|s| s.as_table()) {
        if let Some(k) = s.keys().find(|k| *k != "parameter") {
            return Err(Error::input(
                path,
                format!("field `sweeps.{k}`: only `sweeps.parameter` may be given to import"),
            ));
        }
    }
    Ok(t)
}

/// The folder of the output manifest (`.` for a bare name).
fn out_dir(p: &ImportParams) -> &Path {
    p.out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Refuse an import whose `--out` (or, with `--to-parquet`, its `sweeps.parquet`) is one
/// of its inputs: the poses CSV, the index CSV, the base, the layout (`--layout` or the
/// base's, relative to the output folder), or a sweep file (matched or listed).
fn refuse_inputs(
    p: &ImportParams,
    base: &toml::Table,
    cells: &BTreeMap<(i64, i64, i64), Vec<PathBuf>>,
    extra: &[(PathBuf, String)],
) -> Result<()> {
    let dir = out_dir(p);
    let pq = dir.join("sweeps.parquet");
    let mut outputs: Vec<(&Path, &str)> = vec![(&p.out, "--out")];
    if p.to_parquet {
        outputs.push((&pq, "--to-parquet (sweeps.parquet beside --out)"));
    }
    let mut inputs: Vec<(&Path, &str)> = vec![(&p.poses, "--poses")];
    if let SweepFiles::Index(i) = &p.sweeps {
        inputs.push((i, "--index"));
    }
    if let Some(b) = &p.base {
        inputs.push((b, "--base"));
    }
    let base_layout = base
        .get("layout")
        .and_then(|v| v.as_str())
        .map(|l| dir.join(l));
    match (&p.layout, &base_layout) {
        (Some(l), _) => inputs.push((l, "--layout")),
        (None, Some(l)) => inputs.push((l, "layout (of --base)")),
        (None, None) => {}
    }
    let what = match p.sweeps {
        SweepFiles::Index(_) => "sweep file (of --index)",
        SweepFiles::Glob { .. } => "sweep file (of --sweeps)",
    };
    inputs.extend(cells.values().flatten().map(|f| (f.as_path(), what)));
    inputs.extend(extra.iter().map(|(f, _)| (f.as_path(), what)));
    crate::io::refuse_overwrite(&outputs, &inputs)
}

/// Build and validate the manifest; with problems, write nothing and return them.
pub fn run(p: &ImportParams, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<ImportOutcome> {
    let base = p
        .base
        .as_deref()
        .map(read_base)
        .transpose()?
        .unwrap_or_default();
    let poses = read_poses(&p.poses)?;
    let directions = match p.directions {
        Some(d) => d,
        None => {
            let d = base.get("directions").ok_or_else(|| {
                Error::param(
                    "--directions",
                    "needed (START:STOP:STEP degrees) unless the base gives [directions]",
                )
            })?;
            d.clone().try_into().map_err(|e: toml::de::Error| {
                Error::input(
                    p.base.as_deref().unwrap_or(Path::new("base")),
                    format!(
                        "[directions]: {}",
                        crate::campaign::manifest::one_line(&e.to_string())
                    ),
                )
            })?
        }
    };
    directions.check()?;
    let param: Option<SParam> = match base.get("sweeps").and_then(|s| s.get("parameter")) {
        Some(v) => Some(v.as_str().unwrap_or("").parse().map_err(|e: String| {
            Error::input(
                p.base.as_deref().unwrap_or(Path::new("base")),
                format!("sweeps.parameter: {e}"),
            )
        })?),
        None => None,
    };
    let (cells, extra_names) = match &p.sweeps {
        SweepFiles::Glob { glob, pattern } => cells_from_glob(glob, pattern)?,
        SweepFiles::Index(i) => cells_from_index(i)?,
    };
    let nd = directions.count();
    let np = poses.len();
    let labels: BTreeMap<i64, usize> = poses.iter().enumerate().map(|(i, q)| (q.0, i)).collect();
    let nk = cells.keys().map(|k| k.2).max().unwrap_or(0).max(0) as usize + 1;
    let mut problems = Vec::new();
    for (f, why) in &extra_names {
        problems.push(format!("extra: {}: {why}", f.display()));
    }
    // cell → file, in manifest order
    let mut table: Vec<Option<PathBuf>> = vec![None; np * nd * nk];
    for ((pl, d, k), files) in &cells {
        let why = if !labels.contains_key(pl) {
            Some(format!("position {pl} is not in {}", p.poses.display()))
        } else if *d < 0 || *d as usize >= nd {
            Some(format!(
                "direction {d} outside 0..{} ({nd} directions)",
                nd - 1
            ))
        } else if *k < 0 {
            Some(format!("pulse {k} is negative"))
        } else {
            None
        };
        if let Some(why) = why {
            for f in files {
                problems.push(format!("extra: {}: {why}", f.display()));
            }
            continue;
        }
        if files.len() > 1 {
            let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            problems.push(format!(
                "duplicated: position {pl}, direction {d}, pulse {k}: {}",
                names.join(", ")
            ));
        }
        table[(labels[pl] * nd + *d as usize) * nk + *k as usize] = Some(files[0].clone());
    }
    for (i, f) in table.iter().enumerate() {
        if f.is_none() {
            let (pi, d, k) = (i / (nd * nk), (i / nk) % nd, i % nk);
            problems.push(format!(
                "missing: position {}, direction {d}, pulse {k}: no file",
                poses[pi].0
            ));
        }
    }
    // no output may be an input (checked before any file is read)
    let present: Vec<&PathBuf> = table.iter().flatten().collect();
    refuse_inputs(p, &base, &cells, &extra_names)?;
    // read every file (in parallel): grid, parameter, reader refusals
    let done = std::sync::atomic::AtomicUsize::new(0);
    let reads: Vec<FileRead> = present
        .par_iter()
        .map(|path| {
            let r = (|| -> Result<(Vec<f64>, Vec<String>)> {
                crate::io::regular_input(path, "sweep file")?;
                let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
                let net = parse_touchstone(&decode(&bytes), path)?;
                net.check_param(param.unwrap_or(SParam::default_for(net.ports)), path)?;
                Ok((net.freq_hz, net.notes))
            })()
            .map_err(|e| e.to_string());
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, present.len());
            r
        })
        .collect();
    let mut grid: Option<(&PathBuf, Vec<f64>)> = None;
    let mut notes: BTreeMap<String, usize> = BTreeMap::new();
    for (path, r) in present.iter().zip(reads) {
        match r {
            Err(e) => problems.push(format!("unreadable: {e}")),
            Ok((f, ns)) => {
                for n in ns {
                    // the line number differs from file to file: keep the sentence's kind
                    let kind = n.split(" from line").next().unwrap_or(&n).to_string();
                    *notes.entry(kind).or_default() += 1;
                }
                match &grid {
                    None => grid = Some((path, f)),
                    Some((first, g)) => {
                        let step = (g[g.len() - 1] - g[0]) / (g.len().max(2) - 1) as f64;
                        let tol = (1e-6 * step).max(1.0);
                        if f.len() != g.len() || f.iter().zip(g).any(|(a, b)| (a - b).abs() > tol) {
                            problems.push(format!(
                                "grid: {}: {} points {:.6}..{:.6} GHz, but {} has {} points {:.6}..{:.6} GHz",
                                path.display(), f.len(), f[0] / 1e9, f[f.len() - 1] / 1e9,
                                first.display(), g.len(), g[0] / 1e9, g[g.len() - 1] / 1e9
                            ));
                        }
                    }
                }
            }
        }
    }
    let mut outcome = ImportOutcome {
        shape: (np, nd, nk),
        files: present.len() + extra_names.len(),
        notes: notes
            .into_iter()
            .map(|(n, c)| format!("{n} in {c} file(s)"))
            .collect(),
        ..Default::default()
    };
    let band = match &grid {
        Some((first, g)) => {
            let n = g.len();
            let step = (g[n - 1] - g[0]) / (n.max(2) - 1) as f64;
            if n < 2
                || g.iter()
                    .enumerate()
                    .any(|(k, f)| (f - (g[0] + k as f64 * step)).abs() > (1e-6 * step).max(1.0))
            {
                problems.push(format!("grid: {}: frequencies not uniformly spaced (the energy stage needs a uniform grid)", first.display()));
            }
            outcome.band = Some((g[0], g[n - 1], n));
            (g[0], g[n - 1], n)
        }
        None => (0.0, 0.0, 0),
    };
    if !problems.is_empty() || grid.is_none() {
        if grid.is_none() && problems.is_empty() {
            problems.push("no readable sweep file".into());
        }
        outcome.problems = problems;
        return Ok(outcome);
    }

    // the manifest
    let out_dir = out_dir(p);
    let mut t = toml::Table::new();
    t.insert("schema_version".into(), toml::Value::Integer(1));
    let name = p
        .name
        .clone()
        .or_else(|| base.get("name").and_then(|v| v.as_str()).map(String::from))
        .unwrap_or_else(|| {
            std::path::absolute(out_dir)
                .ok()
                .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
                .unwrap_or_else(|| "campaign".into())
        });
    t.insert("name".into(), name.into());
    let layout = match (&p.layout, base.get("layout").and_then(|v| v.as_str())) {
        (Some(l), _) => relative_to(l, out_dir),
        (None, Some(l)) => PathBuf::from(l),
        (None, None) => {
            return Err(Error::param(
                "--layout",
                "needed unless the base gives `layout`",
            ))
        }
    };
    t.insert(
        "layout".into(),
        layout.to_string_lossy().into_owned().into(),
    );
    t.insert(
        "seed".into(),
        base.get("seed").cloned().unwrap_or(toml::Value::Integer(1)),
    );
    t.insert("pulses".into(), toml::Value::Integer(nk as i64));
    let mut b = toml::Table::new();
    b.insert("start_hz".into(), band.0.into());
    b.insert("stop_hz".into(), band.1.into());
    b.insert("points".into(), toml::Value::Integer(band.2 as i64));
    t.insert("band".into(), b.into());
    let mut array = base
        .get("array")
        .and_then(|a| a.as_table())
        .cloned()
        .unwrap_or_default();
    if let Some(n) = p.elements {
        array.insert("elements".into(), toml::Value::Integer(n as i64));
    }
    if !array.contains_key("elements") {
        return Err(Error::param(
            "--elements",
            "needed unless the base gives [array] elements",
        ));
    }
    t.insert("array".into(), array.into());
    t.insert(
        "directions".into(),
        toml::Value::try_from(directions).map_err(|e| Error::param("directions", e.to_string()))?,
    );
    let noise = base.get("noise").cloned().unwrap_or_else(|| {
        let mut n = toml::Table::new();
        n.insert("floor_dbm".into(), (-100.0).into());
        n.insert("tx_power_dbm".into(), 0.0.into());
        n.into()
    });
    t.insert("noise".into(), noise);
    for k in ["processing", "calibration"] {
        if let Some(v) = base.get(k) {
            t.insert(k.into(), v.clone());
        }
    }
    let poses_toml: Vec<toml::Value> = poses
        .iter()
        .map(|q| {
            let mut m = toml::Table::new();
            m.insert("x_m".into(), q.1.into());
            m.insert("y_m".into(), q.2.into());
            m.insert("heading_deg".into(), q.3.into());
            m.into()
        })
        .collect();
    t.insert("poses".into(), poses_toml.into());
    let mut sweeps = toml::Table::new();
    sweeps.insert("format".into(), "touchstone".into());
    if let Some(par) = param {
        sweeps.insert("parameter".into(), par.to_string().into());
    }
    let files: Vec<toml::Value> = table
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut m = toml::Table::new();
            m.insert(
                "position".into(),
                toml::Value::Integer((i / (nd * nk)) as i64),
            );
            m.insert(
                "direction".into(),
                toml::Value::Integer(((i / nk) % nd) as i64),
            );
            m.insert("pulse".into(), toml::Value::Integer((i % nk) as i64));
            let rel = relative_to(f.as_ref().expect("no missing cells"), out_dir);
            m.insert("path".into(), rel.to_string_lossy().into_owned().into());
            m.into()
        })
        .collect();
    sweeps.insert("files".into(), files.into());
    t.insert("sweeps".into(), sweeps.clone().into());
    let text = toml::to_string(&t).map_err(|e| Error::input(&p.out, e.to_string()))?;
    // validate as `energy` will read it (layout present, every field in range)
    let c = Campaign::from_str(&text, &p.out)?;
    if p.to_parquet {
        let pq = out_dir.join("sweeps.parquet");
        let reader = SweepReader::open(&c)?;
        let mut stream = crate::table::ParquetStream::create(&pq)?;
        for pos in 0..np {
            let sw = reader.read_position(pos)?;
            stream.write(&parquet_batch(&pq, &c.manifest.band, &sw)?)?;
        }
        stream.finish(None)?;
        let mut s = toml::Table::new();
        s.insert("format".into(), "parquet".into());
        s.insert("path".into(), "sweeps.parquet".into());
        t.insert("sweeps".into(), s.into());
        outcome.parquet = Some(pq);
    }
    let text = toml::to_string(&t).map_err(|e| Error::input(&p.out, e.to_string()))?;
    Campaign::from_str(&text, &p.out)?;
    crate::io::write_bytes(&p.out, text.as_bytes())?;
    outcome.manifest = Some(p.out.clone());
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_cells_quoted_and_unquoted() {
        let c = split_csv;
        assert_eq!(c(" 1, 2 ,x").unwrap(), ["1", "2", "x"]);
        assert_eq!(c("1,,").unwrap(), ["1", "", ""]);
        assert_eq!(
            c(r#"0,1, "raw/a,b.s2p" ,"say ""hi""""#).unwrap(),
            ["0", "1", "raw/a,b.s2p", r#"say "hi""#]
        );
        assert_eq!(c(r#""a""#).unwrap(), ["a"]);
        assert!(c(r#"0,"raw/a,b.s2p"#)
            .unwrap_err()
            .contains("cell 2 opens a quote"));
        assert!(c(r#"0,"a"b"#)
            .unwrap_err()
            .contains("after the closing quote of cell 2"));
        assert!(c(r#"0,a"b"#)
            .unwrap_err()
            .contains("inside unquoted cell 2"));
    }

    #[test]
    fn naming_patterns_match_with_and_without_widths() {
        let pcs = parse_pattern("pos{position}_dir{direction:02}_k{pulse}.s2p").unwrap();
        let mut v = [None; 3];
        assert!(match_name(&pcs, "pos12_dir07_k1.s2p", &mut v));
        assert_eq!(v, [Some(12), Some(7), Some(1)]);
        let mut v = [None; 3];
        assert!(!match_name(&pcs, "pos12_dir7_k1.s2p", &mut v));
        let pcs = parse_pattern("{position}{direction:02}.s1p").unwrap();
        let mut v = [None; 3];
        assert!(match_name(&pcs, "10312.s1p", &mut v));
        assert_eq!(v, [Some(103), Some(12), None]);
        assert!(parse_pattern("p{position}.s2p").is_err());
        assert!(parse_pattern("p{position}_{angle}.s2p").is_err());
    }

    #[test]
    fn wildcards_within_a_component() {
        assert!(wild(b"*.s2p", b"p1_d2.s2p"));
        assert!(wild(b"p?_*", b"p1_d2.s2p"));
        assert!(!wild(b"*.s2p", b"p1_d2.s1p"));
    }
}
