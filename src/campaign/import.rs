//! `pradar import`: a campaign manifest built and validated from what a measurement
//! campaign leaves on disk.
//!
//! Takes ([`ImportParams`]):
//! * a poses table: CSV with a position label, x, y and heading (metres, degrees). Header
//!   names are read in any case with a unit in brackets folded in (`X [m]` → `x_m`):
//!   position `position | pos | label | position_label | pose`, `x | x_m`, `y | y_m`,
//!   `heading | heading_deg | theta_deg`; a header without one of them is refused listing
//!   the accepted names. Labels are any text (`P01`, `7`); the manifest keeps them
//!   (`labels`, beside the indices) and every later message, table and plot names them.
//!   Order: by number when every label is an integer (`7` and `07` are then one label),
//!   else as the file lists them;
//! * the sweep files: a glob (`raw/*.s2p`; `*` and `?` within a path component) plus a
//!   naming pattern with `{position}` (a label of the poses: a run of digits when they are
//!   numbers, `{position:03}` exactly three), the direction as `{direction}` (index
//!   0..n−1, `{direction:02}` exactly two digits) or `{angle}` (signed degrees, formatted
//!   as Rust and Python format numbers: `{angle:+03}` reads `+05`, `-45`, `+00`;
//!   `{angle:.1}` reads `-2.5`; the name must be the angle exactly as that format writes
//!   it), and optionally `{pulse}`; or an index CSV `position, direction | angle_deg,
//!   [pulse,] path` (paths relative to the CSV). An angle maps onto `--directions`
//!   exactly (within 1e-6 of a step); one off the grid is a problem naming the file. An
//!   index field never reads digits after a `+`: `az+05` is a signed number (an angle),
//!   never direction 5;
//! * the directions (`start:stop:step` degrees), the layout, and optionally a base
//!   manifest fragment giving `name`, `seed`, `[array]`, `[noise]`, `[processing]`,
//!   `[calibration]` and `[sweeps] parameter`, which cannot be read from the files.
//!
//! Gives: the band and grid read from the files (start, stop and point count of the first
//! file; every file must have the same grid, uniform to 1e-6 of a step), the pulse count
//! (largest `{pulse}` + 1), and, **before any processing**, the list of problems: missing
//! (position, direction, pulse) cells, duplicated cells (two files naming one cell), extra
//! files (matching the glob but not the pattern, or naming a position not in the poses
//! table, a direction, angle or pulse out of range), unreadable files (the reader's
//! one-line refusal, naming file, line and reason; also a file without the `[sweeps]
//! parameter`) and files whose grid differs from the first's. With any problem nothing is
//! written; the command prints the summary first, then at most
//! [`SHOWN_PROBLEMS`] problems and the count of the rest
//! ([`ImportOutcome::problem_report`]), exit 1. A pattern that matches none of the files is
//! refused at once in one line naming the pattern and one file.
//!
//! With `allow_missing` the missing cells are not problems: a position without any file is
//! left out of the manifest (`[sweeps] dropped_positions` keeps its label), a (position,
//! direction) without a file for some pulse is listed in `[sweeps] missing` (its other
//! pulses are not used); one warning each. The energy stage then writes those profiles as
//! NaN and lists them in the table's metadata, and extraction, the maps and the statistics
//! skip them.
//!
//! Otherwise the manifest is written atomically with the labels, every `[processing]`
//! setting written out (the base's over the defaults: window Hann, oversample 5, coupling
//! gate 3 ns, max_delay_ns 100, noise_from_ns 80), and an explicit `[sweeps] files` list
//! (paths relative to the manifest); with `to_parquet` the sweeps are also converted to the
//! Parquet sweep table `sweeps.parquet` beside it, which the manifest then names, keeping
//! the file list as the table's provenance.
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
    /// Go on without what is missing: a position without any sweep file is left out, a
    /// (position, direction) without a file (for any pulse) is listed in `[sweeps]
    /// missing`; one warning per item ([`ImportOutcome::warnings`]).
    pub allow_missing: bool,
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
    /// What `allow_missing` left out, one line each (for stderr).
    pub warnings: Vec<String>,
    /// (position, direction) sweeps recorded as missing.
    pub missing: usize,
    /// Positions left out.
    pub dropped: usize,
}

/// Problem lines shown after the summary; the rest are counted.
pub const SHOWN_PROBLEMS: usize = 20;

impl ImportOutcome {
    /// The refusal of an import with problems, as the command prints it: the summary line
    /// first (counts per kind), then at most [`SHOWN_PROBLEMS`] problems, then "… and N
    /// more". `None` when there is no problem.
    pub fn problem_report(&self) -> Option<(String, Vec<String>)> {
        if self.problems.is_empty() {
            return None;
        }
        let count = |k: &str| self.problems.iter().filter(|p| p.starts_with(k)).count();
        let summary = format!(
            "import: {} problem(s) before processing ({} missing, {} duplicated, {} extra, {} unreadable, {} grid); nothing written{}",
            self.problems.len(),
            count("missing"),
            count("duplicated"),
            count("extra"),
            count("unreadable"),
            count("grid"),
            if count("missing") > 0 {
                " (--allow-missing goes on without the missing sweeps)"
            } else {
                ""
            }
        );
        let mut lines: Vec<String> = self.problems.iter().take(SHOWN_PROBLEMS).cloned().collect();
        if self.problems.len() > SHOWN_PROBLEMS {
            lines.push(format!(
                "… and {} more",
                self.problems.len() - SHOWN_PROBLEMS
            ));
        }
        Some((summary, lines))
    }
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
        if self.missing + self.dropped > 0 {
            write!(
                f,
                "; left out: {} position(s), {} (position, direction) sweep(s) (recorded in the manifest)",
                self.dropped, self.missing
            )?;
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
type PoseRow = (String, f64, f64, f64);

/// A small CSV ([`split_csv`] quoting): the header (lower-cased, units folded into the
/// name: `X [m]` → `x_m`), then (line number, cells) per row.
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
        .map(|h| header_name(&h))
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

/// A header cell as the column lookups see it: lower case, a unit in brackets or
/// parentheses folded in with `_` (`X [m]` → `x_m`, `Heading (deg)` → `heading_deg`,
/// `angle [°]` → `angle_deg`), inner spaces as `_`.
fn header_name(h: &str) -> String {
    let h = h.trim().to_lowercase();
    let (name, unit) = match h.find(['[', '(']) {
        Some(i) => {
            let close = if h[i..].starts_with('[') { ']' } else { ')' };
            let unit = h[i + 1..].trim_end().trim_end_matches(close).trim();
            (h[..i].trim().to_string(), Some(unit.to_string()))
        }
        None => (h.clone(), None),
    };
    let name = name.split_whitespace().collect::<Vec<_>>().join("_");
    match unit {
        Some(u) if !u.is_empty() => {
            let u = match u.as_str() {
                "°" | "degree" | "degrees" => "deg",
                "meter" | "meters" | "metre" | "metres" => "m",
                other => other,
            };
            format!("{name}_{u}")
        }
        _ => name,
    }
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

/// The column named by any of `names`: an error naming the file, the column and the
/// accepted names (and the header read) when absent.
fn column(path: &Path, header: &[String], names: &[&str]) -> Result<usize> {
    optional_column(header, names).ok_or_else(|| {
        Error::input(
            path,
            format!(
                "no {} column in the header `{}` (accepted names, any case, units in brackets folded in: {})",
                names[0],
                header.join(","),
                names.join(", ")
            ),
        )
    })
}

/// The accepted names of the poses and index columns (after [`header_name`]).
const POSITION_NAMES: [&str; 5] = ["position", "pos", "label", "position_label", "pose"];
const X_NAMES: [&str; 2] = ["x", "x_m"];
const Y_NAMES: [&str; 2] = ["y", "y_m"];
const HEADING_NAMES: [&str; 3] = ["heading", "heading_deg", "theta_deg"];
const ANGLE_NAMES: [&str; 4] = ["angle_deg", "angle", "steering_deg", "azimuth_deg"];

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
/// in errors): `(label, x_m, y_m, heading_deg)` in manifest order (see [`order_poses`]).
/// The entry point of the poses target of [`crate::fuzz`].
pub fn parse_poses(text: &str, path: &Path) -> Result<Vec<(String, f64, f64, f64)>> {
    poses_from(path, parse_csv(text, path)?)
}

/// Manifest order of the poses: by number when every label is an integer (`1, 2, 10`),
/// else as the file lists them (`P01, P02, …`, or any names).
fn order_poses(rows: &mut [PoseRow]) {
    if rows.iter().all(|r| r.0.parse::<i64>().is_ok()) {
        rows.sort_by_key(|r| r.0.parse::<i64>().unwrap_or(0));
    }
}

/// Largest length of a position label, bytes.
const MAX_LABEL: usize = 200;

fn poses_from(path: &Path, (h, rows): CsvRows) -> Result<Vec<PoseRow>> {
    bound_rows(path, rows.len(), MAX_POSES, "poses")?;
    let cp = column(path, &h, &POSITION_NAMES)?;
    let cx = column(path, &h, &X_NAMES)?;
    let cy = column(path, &h, &Y_NAMES)?;
    let ch = column(path, &h, &HEADING_NAMES)?;
    let mut out: Vec<PoseRow> = Vec::with_capacity(rows.len());
    let mut labels = std::collections::HashMap::with_capacity(rows.len());
    for (n, r) in &rows {
        let label = r.get(cp).map(|v| v.trim()).unwrap_or("");
        if label.is_empty() || label.len() > MAX_LABEL || label.chars().any(char::is_control) {
            return Err(Error::input(
                path,
                format!("line {n}: the position label must be a non-empty text of at most {MAX_LABEL} bytes"),
            ));
        }
        let row = (
            label.to_string(),
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
        // `7` and `07` name one position when labels are numbers
        let key = label
            .parse::<i64>()
            .map(|v| v.to_string())
            .unwrap_or_else(|_| label.to_string());
        if let Some(first) = labels.insert(key, *n) {
            return Err(Error::input(
                path,
                format!("line {n}: position {label} already listed on line {first}"),
            ));
        }
        out.push(row);
    }
    if out.is_empty() {
        return Err(Error::input(path, "no poses"));
    }
    order_poses(&mut out);
    Ok(out)
}

/// A field of a naming pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Field {
    Position,
    Direction,
    Pulse,
    Angle,
}

/// The format of a field: `{name:SPEC}` with SPEC = `[+][0][width][.precision]` as Rust
/// and Python format numbers (`+` always signed, `0` zero-padded to `width` characters
/// sign included, `.p` exactly p decimals). For the index fields only a width is taken:
/// exactly that many digits (`{direction:02}` reads `07`, not `7`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Spec {
    plus: bool,
    zero: bool,
    width: Option<usize>,
    precision: Option<usize>,
}

/// A piece of a naming pattern.
#[derive(Debug, Clone, PartialEq)]
enum Piece {
    Lit(String),
    Field(Field, Spec),
}

const FIELDS: [(&str, Field); 4] = [
    ("position", Field::Position),
    ("direction", Field::Direction),
    ("pulse", Field::Pulse),
    ("angle", Field::Angle),
];

fn parse_spec(p: &str, name: &str, spec: &str, field: Field) -> Result<Spec> {
    let bad = |why: &str| {
        Error::param(
            "--name-pattern",
            format!("`{p}`: `{{{name}:{spec}}}`: {why}"),
        )
    };
    let mut s = Spec::default();
    let mut rest = spec;
    if field == Field::Angle {
        if let Some(r) = rest.strip_prefix('+') {
            s.plus = true;
            rest = r;
        }
        if let Some(r) = rest.strip_prefix('0') {
            s.zero = true;
            rest = r;
        }
        if let Some((w, prec)) = rest.split_once('.') {
            s.precision = Some(
                prec.parse::<usize>()
                    .ok()
                    .filter(|&v| v <= 9)
                    .ok_or_else(|| bad("the precision after `.` must be a number up to 9"))?,
            );
            rest = w;
        }
    }
    if !rest.is_empty() {
        s.width = Some(
            rest.parse::<usize>()
                .ok()
                .filter(|&w| {
                    (1..=crate::campaign::manifest::limits::MAX_PATTERN_WIDTH).contains(&w)
                })
                .ok_or_else(|| {
                    bad(if field == Field::Angle {
                        "the format is [+][0][width][.precision], e.g. +03 or .1"
                    } else {
                        "the width must be a number (digits in the name)"
                    })
                })?,
        );
    }
    Ok(s)
}

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
        let inner = &rest[open + 1..close];
        let (name, spec) = inner.split_once(':').unwrap_or((inner, ""));
        let field = FIELDS
            .iter()
            .find(|f| f.0 == name)
            .map(|f| f.1)
            .ok_or_else(|| {
                Error::param(
                    "--name-pattern",
                    format!("`{p}`: unknown field `{{{name}}}` (use {{position}}, {{direction}} or {{angle}}, {{pulse}})"),
                )
            })?;
        out.push(Piece::Field(field, parse_spec(p, name, spec, field)?));
        rest = &rest[close + 1..];
    }
    if !rest.is_empty() {
        out.push(Piece::Lit(rest.to_string()));
    }
    let has = |f: Field| {
        out.iter()
            .any(|q| matches!(q, Piece::Field(g, _) if *g == f))
    };
    if !has(Field::Position) {
        return Err(Error::param(
            "--name-pattern",
            format!("`{p}` has no {{position}}"),
        ));
    }
    match (has(Field::Direction), has(Field::Angle)) {
        (false, false) => Err(Error::param(
            "--name-pattern",
            format!("`{p}` has no {{direction}} (index 0..n−1) or {{angle}} (signed degrees)"),
        )),
        (true, true) => Err(Error::param(
            "--name-pattern",
            format!("`{p}` has both {{direction}} and {{angle}}: name the direction once"),
        )),
        _ => Ok(out),
    }
}

/// An angle written as a field of format `s` writes it (see [`Spec`]).
fn format_angle(v: f64, s: &Spec) -> String {
    let digits = match s.precision {
        Some(p) => format!("{:.p$}", v.abs()),
        None => format!("{}", v.abs()),
    };
    let sign = if v.is_sign_negative() && digits.bytes().any(|b| b.is_ascii_digit() && b != b'0') {
        "-"
    } else if s.plus {
        "+"
    } else {
        ""
    };
    let len = sign.len() + digits.len();
    match s.width {
        Some(w) if w > len && s.zero => format!("{sign}{}{digits}", "0".repeat(w - len)),
        Some(w) if w > len => format!("{}{sign}{digits}", " ".repeat(w - len)),
        _ => format!("{sign}{digits}"),
    }
}

/// The value of a direction in a name: its index, or its angle in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DirectionValue {
    /// `{direction}` or an index column `direction`.
    Index(i64),
    /// `{angle}` or an index column `angle_deg`.
    Angle(f64),
}

/// What a name says, field by field (a field named twice must say the same both times).
#[derive(Debug, Clone, Default, PartialEq)]
struct Said {
    position: Option<String>,
    direction: Option<DirectionValue>,
    pulse: Option<i64>,
}

/// How `{position}` reads: the poses' labels (a run naming one of them is preferred) and
/// whether they are all numbers (then `{position}` is a run of digits, `{position:03}`
/// exactly three).
struct LabelSet<'a> {
    labels: &'a [String],
    numeric: bool,
}

/// Match the name `s` from byte `at` against `pieces`, filling `said`.
fn match_name(
    pieces: &[Piece],
    s: &str,
    at: usize,
    labels: &LabelSet<'_>,
    said: &mut Said,
) -> bool {
    let Some((first, rest)) = pieces.split_first() else {
        return at == s.len();
    };
    let t = &s[at..];
    match first {
        Piece::Lit(l) => {
            t.starts_with(l.as_str()) && match_name(rest, s, at + l.len(), labels, said)
        }
        Piece::Field(f, spec) => {
            let digits = t.bytes().take_while(u8::is_ascii_digit).count();
            let exact = |n: usize| -> Vec<usize> {
                match spec.width {
                    Some(w) if w <= n => vec![w],
                    Some(_) => vec![],
                    None => (1..=n).rev().collect(),
                }
            };
            let lens: Vec<usize> = match f {
                Field::Position if labels.numeric => exact(digits),
                Field::Position => {
                    // a label the poses name first (longest first), then any other run
                    let mut v: Vec<usize> = labels
                        .labels
                        .iter()
                        .filter(|l| t.starts_with(l.as_str()))
                        .map(String::len)
                        .collect();
                    v.sort_unstable_by(|a, b| b.cmp(a));
                    for n in (1..=t.len()).rev().filter(|&n| t.is_char_boundary(n)) {
                        if !v.contains(&n) {
                            v.push(n);
                        }
                    }
                    v
                }
                // an index is unsigned: digits after a `+` are a signed number (an
                // angle), never read as an index (`az+05` is not direction 5)
                Field::Direction | Field::Pulse if s[..at].ends_with('+') => vec![],
                Field::Direction | Field::Pulse => exact(digits),
                Field::Angle => {
                    // (spaces first: a width without `0` pads with them)
                    let lead = t.bytes().take_while(|&b| b == b' ').count();
                    let u = &t[lead..];
                    let sg = usize::from(u.starts_with(['+', '-']));
                    let int = u[sg..].bytes().take_while(u8::is_ascii_digit).count();
                    let mut ends = Vec::new();
                    if int > 0 {
                        let frac = u[sg + int..]
                            .strip_prefix('.')
                            .map(|r| r.bytes().take_while(u8::is_ascii_digit).count())
                            .unwrap_or(0);
                        if frac > 0 {
                            ends.push(lead + sg + int + 1 + frac);
                        }
                        ends.extend((1..=int).rev().map(|i| lead + sg + i));
                    }
                    ends
                }
            };
            for n in lens {
                let text = &t[..n];
                let value = match f {
                    Field::Position => Some(text.to_string()),
                    _ => None,
                };
                let saved = said.clone();
                let ok = match f {
                    Field::Position => {
                        let v = value.expect("position");
                        if said.position.as_ref().is_some_and(|old| *old != v) {
                            false
                        } else {
                            said.position = Some(v);
                            true
                        }
                    }
                    Field::Direction | Field::Pulse => match text.parse::<i64>() {
                        Ok(v) if *f == Field::Pulse => {
                            if said.pulse.is_some_and(|old| old != v) {
                                false
                            } else {
                                said.pulse = Some(v);
                                true
                            }
                        }
                        Ok(v) => {
                            let v = DirectionValue::Index(v);
                            if said.direction.is_some_and(|old| old != v) {
                                false
                            } else {
                                said.direction = Some(v);
                                true
                            }
                        }
                        Err(_) => false,
                    },
                    Field::Angle => match text.trim_start().parse::<f64>() {
                        // the name must be the angle as the format writes it
                        Ok(v) if v.is_finite() && format_angle(v, spec) == text => {
                            let v = DirectionValue::Angle(v);
                            if said.direction.is_some_and(|old| old != v) {
                                false
                            } else {
                                said.direction = Some(v);
                                true
                            }
                        }
                        _ => false,
                    },
                };
                if ok && match_name(rest, s, at + n, labels, said) {
                    return true;
                }
                *said = saved;
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

/// One sweep file as a name or an index row gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepEntry {
    /// The position's label as written (`P03`, `7`, `007`).
    pub label: String,
    /// The direction, as an index or an angle.
    pub direction: DirectionValue,
    /// The pulse (0 when not named).
    pub pulse: i64,
    /// The file.
    pub path: PathBuf,
}

/// The files naming a sweep, and the files naming none (with the reason).
type Cells = (Vec<SweepEntry>, Vec<(PathBuf, String)>);

/// Whether a file name holds a signed number (`az+05`, `_-45`): the hint that a pattern's
/// `{direction}` should be `{angle}`.
fn signed_number(name: &str) -> bool {
    let b = name.as_bytes();
    b.windows(2)
        .any(|w| (w[0] == b'+' || w[0] == b'-') && w[1].is_ascii_digit())
}

fn cells_from_glob(glob_pat: &str, pattern: &str, labels: &LabelSet<'_>) -> Result<Cells> {
    let pieces = parse_pattern(pattern)?;
    let mut entries = Vec::new();
    let mut extra = Vec::new();
    let files = glob(glob_pat)?;
    if files.is_empty() {
        return Err(Error::param(
            "--sweeps",
            format!("`{glob_pat}` matches no file"),
        ));
    }
    let n_files = files.len();
    for f in files {
        let name = f
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mut said = Said::default();
        if match_name(&pieces, &name, 0, labels, &mut said) {
            entries.push(SweepEntry {
                label: said.position.unwrap_or_default(),
                direction: said.direction.unwrap_or(DirectionValue::Index(0)),
                pulse: said.pulse.unwrap_or(0),
                path: f,
            });
        } else {
            extra.push((f, format!("name does not match `{pattern}`")));
        }
    }
    if entries.is_empty() {
        // one line, not one per file: the pattern is wrong, not the files
        let (f, _) = &extra[0];
        let name = f.file_name().unwrap_or_default().to_string_lossy();
        let uses_index = pieces
            .iter()
            .any(|q| matches!(q, Piece::Field(Field::Direction, _)));
        let hint = if uses_index && signed_number(&name) {
            " (the names hold signed numbers: if they are steering angles in degrees, name them with {angle}, e.g. `az{angle:+03}`)"
        } else {
            ""
        };
        return Err(Error::param(
            "--name-pattern",
            format!(
                "`{pattern}` matches none of the {n_files} file(s) of `{glob_pat}`, e.g. not `{name}`{hint}"
            ),
        ));
    }
    Ok((entries, extra))
}

fn cells_from_index(path: &Path) -> Result<Cells> {
    Ok((index_from(path, read_csv(path)?)?, Vec::new()))
}

/// The sweep files an index CSV's text lists, as `import --index` reads them (`path` names
/// the file in errors, and relative paths are taken from its folder): columns `position`
/// (or `pos`, `label`), `direction` (an index) or `angle_deg` (signed degrees), optionally
/// `pulse`, and `path`. The entry point of the index target of [`crate::fuzz`].
pub fn parse_index(text: &str, path: &Path) -> Result<Vec<SweepEntry>> {
    index_from(path, parse_csv(text, path)?)
}

fn index_from(path: &Path, (h, rows): CsvRows) -> Result<Vec<SweepEntry>> {
    bound_rows(path, rows.len(), MAX_INDEX_ROWS, "sweep files")?;
    let cp = column(path, &h, &POSITION_NAMES)?;
    let cd = match (
        optional_column(&h, &["direction"]),
        optional_column(&h, &ANGLE_NAMES),
    ) {
        (Some(c), None) => Ok(c),
        (None, Some(c)) => Err(c),
        (Some(_), Some(_)) => {
            return Err(Error::input(
                path,
                "both a `direction` and an `angle_deg` column: give the direction once",
            ))
        }
        (None, None) => {
            return Err(Error::input(
                path,
                format!(
                    "no direction column in the header `{}` (accepted: direction — an index 0..n−1 — or {} — signed degrees)",
                    h.join(","),
                    ANGLE_NAMES.join(", ")
                ),
            ))
        }
    };
    let ck = optional_column(&h, &["pulse"]);
    let cf = column(path, &h, &["path", "file", "filename"])?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::with_capacity(rows.len());
    for (n, r) in &rows {
        let label = r.get(cp).map(|v| v.trim()).unwrap_or("");
        if label.is_empty() {
            return Err(Error::input(path, format!("line {n}: empty position")));
        }
        let direction = match cd {
            Ok(c) => DirectionValue::Index(cell(path, *n, r, c, "direction (integer)")?),
            Err(c) => {
                let a: f64 = cell(path, *n, r, c, "angle (degrees)")?;
                if !a.is_finite() {
                    return Err(Error::input(
                        path,
                        format!("line {n}: the angle must be finite"),
                    ));
                }
                DirectionValue::Angle(a)
            }
        };
        let pulse = match ck {
            Some(c) => cell(path, *n, r, c, "pulse (integer)")?,
            None => 0,
        };
        let f = r
            .get(cf)
            .filter(|s| !s.is_empty())
            .ok_or_else(|| Error::input(path, format!("line {n}: empty path")))?;
        out.push(SweepEntry {
            label: label.to_string(),
            direction,
            pulse,
            path: dir.join(f),
        });
    }
    Ok(out)
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
    entries: &[SweepEntry],
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
    inputs.extend(entries.iter().map(|e| (e.path.as_path(), what)));
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
    let labels: Vec<String> = poses.iter().map(|q| q.0.clone()).collect();
    let numeric = labels.iter().all(|l| l.parse::<i64>().is_ok());
    let lset = LabelSet {
        labels: &labels,
        numeric,
    };
    let (entries, extra_names) = match &p.sweeps {
        SweepFiles::Glob { glob, pattern } => cells_from_glob(glob, pattern, &lset)?,
        SweepFiles::Index(i) => cells_from_index(i)?,
    };
    // a label names a pose exactly, or by number when the poses are numbered (`007` = 7)
    let by_label: std::collections::HashMap<String, usize> = labels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let key = if numeric {
                l.parse::<i64>()
                    .map(|v| v.to_string())
                    .unwrap_or_else(|_| l.clone())
            } else {
                l.clone()
            };
            (key, i)
        })
        .collect();
    let resolve = |l: &str| -> Option<usize> {
        let key = if numeric {
            l.parse::<i64>().map(|v| v.to_string()).ok()?
        } else {
            l.to_string()
        };
        by_label.get(&key).copied()
    };
    let nd = directions.count();
    let np = poses.len();
    let grid = format!(
        "{}:{}:{}",
        directions.start_deg, directions.stop_deg, directions.step_deg
    );
    let dname = |d: usize| format!("{d} ({}°)", directions.angle_deg(d));
    let nk = entries.iter().map(|e| e.pulse).max().unwrap_or(0).max(0) as usize + 1;
    let cell_name = |pi: usize, d: usize, k: usize| {
        let mut s = format!("position {}, direction {}", labels[pi], dname(d));
        if nk > 1 {
            s.push_str(&format!(", pulse {k}"));
        }
        s
    };
    let mut problems = Vec::new();
    for (f, why) in &extra_names {
        problems.push(format!("extra: {}: {why}", f.display()));
    }
    // cell → files, in manifest order
    let mut cells: BTreeMap<(usize, usize, usize), Vec<PathBuf>> = BTreeMap::new();
    for e in &entries {
        let d = match e.direction {
            DirectionValue::Index(d) if d >= 0 && (d as usize) < nd => Ok(d as usize),
            DirectionValue::Index(d) => Err(format!(
                "direction {d} outside 0..{} ({nd} directions over {grid}°)",
                nd - 1
            )),
            DirectionValue::Angle(a) => directions
                .index_of(a)
                .ok_or_else(|| format!("angle {a}° is not on the --directions grid ({grid}°)")),
        };
        let why = match (resolve(&e.label), d) {
            (None, _) => Err(format!(
                "position {} is not in {}",
                e.label,
                p.poses.display()
            )),
            (_, Err(w)) => Err(w),
            (Some(_), Ok(_)) if e.pulse < 0 => Err(format!("pulse {} is negative", e.pulse)),
            (Some(pi), Ok(d)) => Ok((pi, d, e.pulse as usize)),
        };
        match why {
            Ok(key) => cells.entry(key).or_default().push(e.path.clone()),
            Err(why) => problems.push(format!("extra: {}: {why}", e.path.display())),
        }
    }
    let mut table: Vec<Option<PathBuf>> = vec![None; np * nd * nk];
    for (&(pi, d, k), files) in &cells {
        if files.len() > 1 {
            let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            problems.push(format!(
                "duplicated: {}: {}",
                cell_name(pi, d, k),
                names.join(", ")
            ));
        }
        table[(pi * nd + d) * nk + k] = Some(files[0].clone());
    }
    // what is missing: whole positions, or (position, direction) sweeps
    let mut warnings = Vec::new();
    let mut dropped = vec![false; np];
    let mut missing_pd = vec![false; np * nd];
    for pi in 0..np {
        let cell_missing = |d: usize| (0..nk).any(|k| table[(pi * nd + d) * nk + k].is_none());
        let none_at_all = (0..nd * nk).all(|i| table[pi * nd * nk + i].is_none());
        if p.allow_missing && none_at_all {
            dropped[pi] = true;
            warnings.push(format!(
                "dropped position {}: no sweep file at all (left out of the manifest)",
                labels[pi]
            ));
            continue;
        }
        for d in 0..nd {
            if !cell_missing(d) {
                continue;
            }
            let absent: Vec<usize> = (0..nk)
                .filter(|&k| table[(pi * nd + d) * nk + k].is_none())
                .collect();
            if p.allow_missing {
                missing_pd[pi * nd + d] = true;
                let what = if nk > 1 {
                    format!(" (pulse(s) {absent:?} missing; the others are not used)")
                } else {
                    String::new()
                };
                warnings.push(format!(
                    "dropped position {}, direction {}: no file{what}",
                    labels[pi],
                    dname(d)
                ));
            } else {
                for k in absent {
                    problems.push(format!("missing: {}: no file", cell_name(pi, d, k)));
                }
            }
        }
    }
    if p.allow_missing && dropped.iter().all(|&x| x) {
        problems.push("missing: no position has a sweep file".into());
    }
    // no output may be an input (checked before any file is read)
    let used = |i: usize| {
        let (pi, d) = (i / (nd * nk), (i / nk) % nd);
        !dropped[pi] && !missing_pd[pi * nd + d]
    };
    let present: Vec<&PathBuf> = table
        .iter()
        .enumerate()
        .filter(|(i, _)| used(*i))
        .filter_map(|(_, f)| f.as_ref())
        .collect();
    refuse_inputs(p, &base, &entries, &extra_names)?;
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
    let kept: Vec<usize> = (0..np).filter(|&pi| !dropped[pi]).collect();
    let mut outcome = ImportOutcome {
        shape: (kept.len(), nd, nk),
        files: present.len() + extra_names.len(),
        warnings,
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
    // every processing setting written out, the base's over the defaults, so the manifest
    // states what the energy stage will do (a default nobody wrote is still visible)
    let mut processing =
        match toml::Value::try_from(crate::campaign::manifest::Processing::default()) {
            Ok(toml::Value::Table(t)) => t,
            _ => toml::Table::new(),
        };
    if let Some(b) = base.get("processing").and_then(|v| v.as_table()) {
        for (k, v) in b {
            processing.insert(k.clone(), v.clone());
        }
    }
    t.insert("processing".into(), processing.into());
    if let Some(v) = base.get("calibration") {
        t.insert("calibration".into(), v.clone());
    }
    let poses_toml: Vec<toml::Value> = kept
        .iter()
        .map(|&pi| &poses[pi])
        .map(|q| {
            let mut m = toml::Table::new();
            m.insert("x_m".into(), q.1.into());
            m.insert("y_m".into(), q.2.into());
            m.insert("heading_deg".into(), q.3.into());
            m.into()
        })
        .collect();
    t.insert("poses".into(), poses_toml.into());
    // the lab's labels beside the indices: every later message, table and plot names them
    let kept_labels: Vec<toml::Value> = kept.iter().map(|&pi| labels[pi].clone().into()).collect();
    t.insert("labels".into(), kept_labels.into());
    let mut sweeps = toml::Table::new();
    sweeps.insert("format".into(), "touchstone".into());
    if let Some(par) = param {
        sweeps.insert("parameter".into(), par.to_string().into());
    }
    // manifest index of each kept position
    let new_index: Vec<Option<usize>> = {
        let mut v = vec![None; np];
        for (j, &pi) in kept.iter().enumerate() {
            v[pi] = Some(j);
        }
        v
    };
    let files: Vec<toml::Value> = table
        .iter()
        .enumerate()
        .filter(|(i, _)| used(*i))
        .map(|(i, f)| {
            let mut m = toml::Table::new();
            let pi = new_index[i / (nd * nk)].expect("a used sweep's position is kept");
            m.insert("position".into(), toml::Value::Integer(pi as i64));
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
    let missing: Vec<toml::Value> = (0..np * nd)
        .filter(|&i| missing_pd[i] && !dropped[i / nd])
        .map(|i| {
            let mut m = toml::Table::new();
            let pi = new_index[i / nd].expect("kept");
            m.insert("position".into(), toml::Value::Integer(pi as i64));
            m.insert("direction".into(), toml::Value::Integer((i % nd) as i64));
            m.into()
        })
        .collect();
    outcome.missing = missing.len();
    outcome.dropped = dropped.iter().filter(|&&x| x).count();
    if !missing.is_empty() {
        sweeps.insert("missing".into(), missing.into());
    }
    let dropped_labels: Vec<toml::Value> = (0..np)
        .filter(|&pi| dropped[pi])
        .map(|pi| labels[pi].clone().into())
        .collect();
    if !dropped_labels.is_empty() {
        sweeps.insert("dropped_positions".into(), dropped_labels.into());
    }
    t.insert("sweeps".into(), sweeps.clone().into());
    let text = toml::to_string(&t).map_err(|e| Error::input(&p.out, e.to_string()))?;
    // validate as `energy` will read it (layout present, every field in range)
    let c = Campaign::from_str(&text, &p.out)?;
    if p.to_parquet {
        let pq = out_dir.join("sweeps.parquet");
        let reader = SweepReader::open(&c)?;
        let mut stream = crate::table::ParquetStream::create(&pq)?;
        for pos in 0..kept.len() {
            let sw = reader.read_position(pos)?;
            stream.write(&parquet_batch(&pq, &c.manifest.band, &sw)?)?;
        }
        stream.finish(None)?;
        // the Parquet table, with the files it was made from kept as its provenance
        sweeps.insert("format".into(), "parquet".into());
        sweeps.insert("path".into(), "sweeps.parquet".into());
        t.insert("sweeps".into(), sweeps.into());
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

    fn said(pattern: &str, labels: &[&str], name: &str) -> Option<Said> {
        let pcs = parse_pattern(pattern).unwrap();
        let labels: Vec<String> = labels.iter().map(|l| l.to_string()).collect();
        let set = LabelSet {
            numeric: labels.iter().all(|l| l.parse::<i64>().is_ok()),
            labels: &labels,
        };
        let mut v = Said::default();
        match_name(&pcs, name, 0, &set, &mut v).then_some(v)
    }

    #[test]
    fn naming_patterns_match_with_and_without_widths() {
        let v = said(
            "pos{position}_dir{direction:02}_k{pulse}.s2p",
            &["12"],
            "pos12_dir07_k1.s2p",
        )
        .unwrap();
        assert_eq!(v.position.as_deref(), Some("12"));
        assert_eq!(v.direction, Some(DirectionValue::Index(7)));
        assert_eq!(v.pulse, Some(1));
        assert!(said(
            "pos{position}_dir{direction:02}_k{pulse}.s2p",
            &["12"],
            "pos12_dir7_k1.s2p"
        )
        .is_none());
        let v = said("{position}{direction:02}.s1p", &["103"], "10312.s1p").unwrap();
        assert_eq!(v.position.as_deref(), Some("103"));
        assert_eq!(v.direction, Some(DirectionValue::Index(12)));
        assert!(parse_pattern("p{position}.s2p").is_err());
        assert!(parse_pattern("p{position}_{azimuth}.s2p").is_err());
        assert!(parse_pattern("p{position}_{direction}_{angle}.s2p").is_err());
    }

    #[test]
    fn angles_and_labels_in_names() {
        let pat = "{position}_az{angle:+03}.s2p";
        let labels = ["P01", "P02", "P10"];
        for (name, label, angle) in [
            ("P01_az+05.s2p", "P01", 5.0),
            ("P10_az-45.s2p", "P10", -45.0),
            ("P02_az+00.s2p", "P02", 0.0),
            ("P02_az+90.s2p", "P02", 90.0),
            ("P02_az-90.s2p", "P02", -90.0),
        ] {
            let v = said(pat, &labels, name).unwrap_or_else(|| panic!("{name}"));
            assert_eq!(v.position.as_deref(), Some(label), "{name}");
            assert_eq!(v.direction, Some(DirectionValue::Angle(angle)), "{name}");
        }
        // not as the format writes it: no sign, no padding, a decimal point
        for name in [
            "P01_az5.s2p",
            "P01_az+5.s2p",
            "P01_az05.s2p",
            "P01_az+05.0.s2p",
        ] {
            assert!(said(pat, &labels, name).is_none(), "{name}");
        }
        // an unknown label is read (and refused later, naming the file)
        let v = said(pat, &labels, "P13_az+05.s2p").unwrap();
        assert_eq!(v.position.as_deref(), Some("P13"));
        // precision and plain forms
        let v = said("p{position}_{angle:.1}.s2p", &["1"], "p1_-2.5.s2p").unwrap();
        assert_eq!(v.direction, Some(DirectionValue::Angle(-2.5)));
        assert!(said("p{position}_{angle:.1}.s2p", &["1"], "p1_-2.50.s2p").is_none());
        let v = said("p{position}_{angle}.s2p", &["1"], "p1_-45.s2p").unwrap();
        assert_eq!(v.direction, Some(DirectionValue::Angle(-45.0)));
        // `az+05` is a signed number, never direction index 5
        assert!(said("P{position:02}_az+{direction}.s2p", &["3"], "P03_az+05.s2p").is_none());
        assert!(said("P{position:02}_az{direction}.s2p", &["3"], "P03_az+05.s2p").is_none());
        assert_eq!(
            said(
                "P{position:02}_az{direction:02}.s2p",
                &["3"],
                "P03_az05.s2p"
            )
            .unwrap()
            .direction,
            Some(DirectionValue::Index(5))
        );
    }

    #[test]
    fn angle_formats_as_rust_and_python_do() {
        let sp = |s: &str| parse_spec("p", "angle", s, Field::Angle).unwrap();
        assert_eq!(format_angle(5.0, &sp("+03")), format!("{:+03}", 5.0));
        assert_eq!(format_angle(-45.0, &sp("+03")), format!("{:+03}", -45.0));
        assert_eq!(format_angle(0.0, &sp("+03")), "+00");
        assert_eq!(format_angle(-2.5, &sp(".1")), format!("{:.1}", -2.5));
        assert_eq!(format_angle(7.5, &sp("05.1")), format!("{:05.1}", 7.5));
        assert_eq!(format_angle(-90.0, &sp("")), "-90");
        assert!(parse_spec("p", "angle", "x3", Field::Angle).is_err());
    }

    #[test]
    fn lab_headers_are_folded() {
        assert_eq!(header_name("X [m]"), "x_m");
        assert_eq!(header_name("Heading [deg]"), "heading_deg");
        assert_eq!(header_name("heading (°)"), "heading_deg");
        assert_eq!(header_name(" Pos "), "pos");
        assert_eq!(header_name("Angle [deg]"), "angle_deg");
        let rows = parse_poses(
            "Pos,X [m],Y [m],Heading [deg]\nP02,1,2,0\nP01,0.5,1.2,90\n",
            Path::new("poses.csv"),
        )
        .unwrap();
        // file order for text labels
        assert_eq!(rows[0].0, "P02");
        let e = parse_poses(
            "Pos,X [mm],Y [m],Heading [deg]\nP01,1,2,0\n",
            Path::new("poses.csv"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("x, x_m"), "{e}");
        let rows = parse_poses(
            "position,x,y,heading\n10,1,2,0\n2,0.5,1.2,90\n",
            Path::new("p.csv"),
        )
        .unwrap();
        assert_eq!(rows[0].0, "2");
        assert!(parse_poses(
            "position,x,y,heading\n7,1,2,0\n07,0.5,1.2,90\n",
            Path::new("p.csv")
        )
        .is_err());
    }

    #[test]
    fn wildcards_within_a_component() {
        assert!(wild(b"*.s2p", b"p1_d2.s2p"));
        assert!(wild(b"p?_*", b"p1_d2.s2p"));
        assert!(!wild(b"*.s2p", b"p1_d2.s1p"));
    }
}
