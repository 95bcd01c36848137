//! The poses and index CSVs of `import`: a small CSV reader (RFC 4180 quoting within a
//! line, `#` comments, blank lines skipped) and the two tables read from it.
//!
//! Takes a path (a device or FIFO is refused before it is opened; the bytes decoded as the
//! Touchstone reader decodes them) and gives the poses ([`PoseRow`], in manifest order) or
//! the sweep files an index lists ([`SweepEntry`]). Header names are read in any case with
//! a unit in brackets folded in (`X [m]` → `x_m`); a header without a needed column is
//! refused listing the accepted names. Every refusal is one line naming the file, and the
//! line and column at fault: a value that is not a number, not finite, or (x, y) beyond
//! the layout's ±[`MAX_COORD_M`] m, a position label listed twice, a table of more rows
//! than [`MAX_POSES`] or [`MAX_INDEX_ROWS`].

use super::collect::SweepEntry;
use super::pattern::DirectionValue;
use crate::campaign::layout::MAX_COORD_M;
use crate::campaign::touchstone::decode;
use crate::error::{Error, Result};
use std::path::Path;

/// A pose row: label, x_m, y_m, heading_deg.
pub(super) type PoseRow = (String, f64, f64, f64);

/// A small CSV ([`split_csv`] quoting): the header (lower-cased, units folded into the
/// name: `X [m]` → `x_m`), then (line number, cells) per row.
type CsvRows = (Vec<String>, Vec<(usize, Vec<String>)>);

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
pub(super) fn header_name(h: &str) -> String {
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
pub(super) fn split_csv(line: &str) -> std::result::Result<Vec<String>, String> {
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

/// The column named by any of `names`, if the header has one.
fn optional_column(header: &[String], names: &[&str]) -> Option<usize> {
    header.iter().position(|h| names.contains(&h.as_str()))
}

/// Cell `c` of `row` (line `line`) read as a `what`: an error naming the file, the line
/// and the value when it is not one.
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

/// The poses of a poses CSV, as `import --poses` reads them.
pub(super) fn read_poses(path: &Path) -> Result<Vec<PoseRow>> {
    poses_from(path, read_csv(path)?)
}

/// The poses of a poses CSV's text, as `import --poses` reads them (`path` names the file
/// in errors): `(label, x_m, y_m, heading_deg)` in manifest order (see [`order_poses`]).
/// The entry point of the poses target of the fuzz harness (`pradar::fuzz`, feature `fuzz`).
#[cfg(any(test, feature = "fuzz"))]
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
        // the manifest's bound, refused here so the line names this file and the column
        for (c, v) in [(cx, row.1), (cy, row.2)] {
            if v.abs() > MAX_COORD_M {
                return Err(Error::input(
                    path,
                    format!("line {n}: {} = {v:e} m, beyond ±{MAX_COORD_M} m", h[c]),
                ));
            }
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

/// The sweep files an index CSV's text lists, as `import --index` reads them (`path` names
/// the file in errors, and relative paths are taken from its folder): columns `position`
/// (or `pos`, `label`), `direction` (an index) or `angle_deg` (signed degrees), optionally
/// `pulse`, and `path`. The entry point of the index target of the fuzz harness
/// (`pradar::fuzz`, feature `fuzz`); gives the number of files listed.
#[cfg(feature = "fuzz")]
pub fn parse_index(text: &str, path: &Path) -> Result<usize> {
    index_from(path, parse_csv(text, path)?).map(|entries| entries.len())
}

/// The sweep files of an index CSV, as `import --index` reads them.
pub(super) fn read_index(path: &Path) -> Result<Vec<SweepEntry>> {
    index_from(path, read_csv(path)?)
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
    fn a_pose_beyond_the_bound_is_one_short_line_naming_the_csv() {
        let e = |text: &str| {
            parse_poses(text, Path::new("poses.csv"))
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            e("position,x,y,heading\n0,1e308,0,0\n"),
            "poses.csv: line 2: x = 1e308 m, beyond ±10000 m"
        );
        assert_eq!(
            e("Pos,X [m],Y [m],Heading [deg]\nP01,1,-20000.5,0\n"),
            "poses.csv: line 2: y_m = -2.00005e4 m, beyond ±10000 m"
        );
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
}
