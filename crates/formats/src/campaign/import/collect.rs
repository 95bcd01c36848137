//! The collect step of `import`: everything its inputs say before a sweep file is read.
//!
//! Takes the [`ImportParams`]; gives [`Inputs`]: the base fragment (only the sections the
//! files cannot give), the poses ([`super::reader`]), the directions, the `[sweeps]
//! parameter`, and the sweep files, each as the (position label, direction, pulse) its
//! name says ([`super::pattern`], over the files of a glob: `*` and `?` within a path
//! component) or its index row says, plus the files that name no sweep (with the reason).
//! Nothing here decides whether a file fits the campaign: that is the check step.

use super::pattern::{match_name, parse_pattern, DirectionValue, Field, LabelSet, Piece, Said};
use super::reader::{read_index, read_poses, PoseRow};
use super::{ImportParams, SweepFiles};
use crate::campaign::manifest::Directions;
use crate::campaign::touchstone::SParam;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What an import's inputs say, read before any sweep file is opened.
pub(super) struct Inputs {
    /// The base manifest fragment (empty without `--base`).
    pub(super) base: toml::Table,
    /// The poses, in manifest order.
    pub(super) poses: Vec<PoseRow>,
    /// The poses' labels, in manifest order.
    pub(super) labels: Vec<String>,
    /// Whether every label is an integer (then `007` names pose 7).
    pub(super) numeric: bool,
    /// The directions (`--directions`, else the base's).
    pub(super) directions: Directions,
    /// The base's `[sweeps] parameter`.
    pub(super) param: Option<SParam>,
    /// The files naming a sweep.
    pub(super) entries: Vec<SweepEntry>,
    /// The files matching the glob but not the pattern, with the reason.
    pub(super) extra: Vec<(PathBuf, String)>,
}

/// Read the base, the poses, the directions and the list of sweep files.
pub(super) fn collect(p: &ImportParams) -> Result<Inputs> {
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
    let (entries, extra) = match &p.sweeps {
        SweepFiles::Glob { glob, pattern } => cells_from_glob(glob, pattern, &lset)?,
        SweepFiles::Index(i) => (read_index(i)?, Vec::new()),
    };
    Ok(Inputs {
        base,
        poses,
        labels,
        numeric,
        directions,
        param,
        entries,
        extra,
    })
}

/// The sections a base manifest fragment may give.
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

/// The base manifest fragment: only the sections `import` cannot read from the files
/// ([`BASE_KEYS`], and of `[sweeps]` only `parameter`).
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
pub(super) fn glob(pattern: &str) -> Result<Vec<PathBuf>> {
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
pub(crate) struct SweepEntry {
    /// The position's label as written (`P03`, `7`, `007`).
    pub(crate) label: String,
    /// The direction, as an index or an angle.
    pub(crate) direction: DirectionValue,
    /// The pulse (0 when not named).
    pub(crate) pulse: i64,
    /// The file.
    pub(crate) path: PathBuf,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_within_a_component() {
        assert!(wild(b"*.s2p", b"p1_d2.s2p"));
        assert!(wild(b"p?_*", b"p1_d2.s2p"));
        assert!(!wild(b"*.s2p", b"p1_d2.s1p"));
    }
}
