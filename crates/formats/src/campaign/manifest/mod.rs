//! Campaign manifest (`campaign.toml`, DESIGN §3): band, array, poses, directions, layout,
//! noise, seed, pulses, processing options and the `[sweeps]` index.
//!
//! The analysis view [`Manifest`] deliberately has no field for the simulator-only sections
//! `[scene]` and `[clutter]` (the ground truth): serde skips them, so no analysis command can
//! read them. The simulator reads them separately ([`crate::simulate::SceneConfig`]).
//!
//! Every validation error names the manifest file and the dotted field.
//!
//! The sub-sections' `check` methods (`Band`, `ArrayConfig`, `Directions`, `Processing`, …)
//! stay inherent: they validate file contents where the manifest is read, not algorithm
//! parameters, so they are not [`crate::params::ParamGuard`] sets (no `Valid` wrapper).
//!
//! [`Manifest::restrict`] (`restrict`) gives the manifest of some of its positions, every
//! position-indexed field remapped (the held-out check's halves).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use crate::units::C0;

/// Current manifest/energy schema version.
pub const SCHEMA_VERSION: u32 = 1;

/// Bounds on the sizes a manifest implies, checked before anything is allocated: each is
/// well above any campaign of the method and well below what would exhaust a workstation.
pub mod limits {
    /// Frequency points per sweep: 100 001 is the largest sweep of current VNAs.
    pub const MAX_POINTS: usize = 100_001;
    /// IFFT length (points − 1) · oversample: 2^22 complex samples (64 MiB per buffer).
    pub const MAX_NFFT: usize = 1 << 22;
    /// IFFT oversampling: 65 samples per bin resolve a bin's shape far beyond need.
    pub const MAX_OVERSAMPLE: usize = 65;
    /// Directions per position: 3601 is a 0.1° step over a full turn.
    pub const MAX_DIRECTIONS: usize = 3601;
    /// Repeated sweeps per direction.
    pub const MAX_PULSES: usize = 1000;
    /// Poses of a campaign (also the largest position index a table may carry).
    pub const MAX_POSITIONS: usize = 1_000_000;
    /// Sweeps of a campaign (positions × directions × pulses).
    pub const MAX_SWEEPS: usize = 100_000_000;
    /// |x|, |y| of a pose, m (the layout's own bound, [`crate::campaign::layout::MAX_COORD_M`]).
    pub const MAX_COORD_M: f64 = crate::campaign::layout::MAX_COORD_M;
    /// Widest `{name:0W}` of a sweep-name template.
    pub const MAX_PATTERN_WIDTH: usize = 20;
}
use limits::*;

mod restrict;
mod sections;

pub use restrict::check_keep;
pub use sections::*;

/// Sweep file format.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum SweepFormat {
    /// One Touchstone file (v1 `.sNp` or v2) per (position, direction, pulse).
    #[default]
    Touchstone,
    /// One Parquet long table (position, direction, pulse, frequency_hz, re, im).
    Parquet,
}

impl SweepFormat {
    /// Every format, in the order the command line lists them.
    pub const ALL: [SweepFormat; 2] = [SweepFormat::Touchstone, SweepFormat::Parquet];

    /// Name (`touchstone`, `parquet`): the manifest's `[sweeps] format`, the command-line
    /// value, the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            SweepFormat::Touchstone => "touchstone",
            SweepFormat::Parquet => "parquet",
        }
    }
}

impl std::fmt::Display for SweepFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SweepFormat {
    type Err = Error;
    /// Parse a [`SweepFormat::name`].
    fn from_str(s: &str) -> Result<SweepFormat> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "sweeps.format", "sweep format")
    }
}

/// One explicitly listed sweep file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Position index.
    pub position: usize,
    /// Direction index.
    pub direction: usize,
    /// Pulse (repeat) index.
    #[serde(default)]
    pub pulse: usize,
    /// Path relative to the manifest folder.
    pub path: PathBuf,
}

/// `[sweeps]`: where the sweeps are (written by `simulate`, required by `energy`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct SweepsConfig {
    /// File format.
    #[serde(default)]
    pub format: SweepFormat,
    /// Touchstone name template with `{position:03}`, `{direction:02}`, `{pulse:02}`
    /// (the width after the colon is optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern: Option<String>,
    /// Touchstone files listed one by one (instead of `pattern`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<SweepFile>,
    /// The Parquet table (format = "parquet").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// The S-parameter read from Touchstone files (`"S21"`, `"S11"`, any `"Sij"`); absent:
    /// S21, or S11 for a one-port file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parameter: Option<crate::campaign::touchstone::SParam>,
    /// (position, direction) sweeps the campaign does not have (`import --allow-missing`):
    /// the energy stage writes their profiles as NaN and lists them in the table's
    /// metadata; extraction, the maps and the statistics skip them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub missing: Vec<MissingSweep>,
    /// Labels of the positions `import --allow-missing` left out (no complete direction);
    /// they are not among `[[poses]]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dropped_positions: Vec<String>,
}

/// A (position, direction) without a sweep (every pulse of it left out).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(deny_unknown_fields)]
pub struct MissingSweep {
    /// Position index.
    pub position: usize,
    /// Direction index.
    pub direction: usize,
}

/// `[calibration]`: calibration sweeps applied by the energy stage
/// ([`crate::energy::calibration`]); names relative to the manifest, templates with
/// `{direction}` / `{position}` as in `[sweeps] pattern`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// Empty-scene (or absorber) sweep(s), subtracted coherently before the IFFT.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<String>,
    /// System-response sweep(s) (a thru, or cables + arrays alone), divided out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
}

/// The analysis view of `campaign.toml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// Schema version (1).
    pub schema_version: u32,
    /// Campaign name.
    pub name: String,
    /// Layout GeoJSON, relative to the manifest folder.
    pub layout: PathBuf,
    /// Seed of every random draw.
    pub seed: u64,
    /// Repeated sweeps (measured) or independent noise draws (simulated) per direction.
    #[serde(default = "default_pulses")]
    pub pulses: usize,
    /// `[band]`.
    pub band: Band,
    /// `[array]`.
    pub array: ArrayConfig,
    /// `[directions]`.
    pub directions: Directions,
    /// `[noise]`.
    pub noise: NoiseConfig,
    /// `[processing]`.
    #[serde(default)]
    pub processing: Processing,
    /// `[[poses]]`.
    pub poses: Vec<Pose>,
    /// The lab's label of every position (`P01`, `12`, …; one per pose, in pose order),
    /// written by `import`; absent: positions are named by their index.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub labels: Vec<String>,
    /// `[sweeps]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweeps: Option<SweepsConfig>,
    /// `[calibration]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CalibrationConfig>,
}

fn default_pulses() -> usize {
    1
}

/// A loaded, validated campaign: the manifest and where it lives.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// The manifest.
    pub manifest: Manifest,
    /// Path of `campaign.toml`.
    pub path: PathBuf,
}

/// An angle in degrees as messages write it: to 1e-9 of a degree, trailing zeros dropped
/// (`-31.7`, not the `-31.700000000000003` of `-45 + 19·0.7`).
pub fn angle_text(deg: f64) -> String {
    let r = (deg * 1e9).round() / 1e9;
    let r = if r == 0.0 { 0.0 } else { r };
    format!("{r}")
}

/// Turn a (possibly multi-line) TOML error into one line.
pub fn one_line(msg: &str) -> String {
    msg.split('\n')
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('|') && *l != "^")
        .collect::<Vec<_>>()
        .join(" ")
}

impl Manifest {
    /// Validate every field.
    pub fn check(&self) -> Result<()> {
        if self.schema_version != SCHEMA_VERSION {
            return Err(Error::param(
                "schema_version",
                format!(
                    "unsupported {} (expected {SCHEMA_VERSION})",
                    self.schema_version
                ),
            ));
        }
        self.band.check()?;
        self.array.check()?;
        self.directions.check()?;
        self.processing.check_with(&self.band)?;
        if self.processing.coupling == CouplingRemoval::Mean && self.directions.count() < 2 {
            // the mean over one direction is that direction's sweep: echoes and all
            return Err(Error::param(
                "processing.coupling",
                "\"mean\" subtracts the mean sweep over the directions; with one direction \
                 it removes the echoes too (use \"gate\")",
            ));
        }
        if !self.noise.floor_dbm.is_finite() || !self.noise.tx_power_dbm.is_finite() {
            return Err(Error::param("noise.floor_dbm", "must be finite"));
        }
        if self.pulses == 0 {
            return Err(Error::param("pulses", "must be >= 1"));
        }
        if self.pulses > MAX_PULSES {
            return Err(Error::param(
                "pulses",
                format!("{} exceeds {MAX_PULSES} repeats per direction", self.pulses),
            ));
        }
        if self.poses.is_empty() {
            return Err(Error::param(
                "poses",
                "at least one [[poses]] entry is required",
            ));
        }
        if self.poses.len() > MAX_POSITIONS {
            return Err(Error::param(
                "poses",
                format!("{} poses exceeds {MAX_POSITIONS}", self.poses.len()),
            ));
        }
        let sweeps = self.poses.len() * self.directions.count() * self.pulses;
        if sweeps > MAX_SWEEPS {
            return Err(Error::param(
                "pulses",
                format!("poses × directions × pulses = {sweeps} sweeps exceeds {MAX_SWEEPS}"),
            ));
        }
        for (i, p) in self.poses.iter().enumerate() {
            if !(p.x_m.is_finite() && p.y_m.is_finite() && p.heading_deg.is_finite()) {
                return Err(Error::param(
                    format!("poses[{i}]"),
                    "x_m, y_m, heading_deg must be finite",
                ));
            }
            if p.x_m.abs() > MAX_COORD_M || p.y_m.abs() > MAX_COORD_M {
                return Err(Error::param(
                    format!("poses[{i}]"),
                    format!("({}, {}) m beyond ±{MAX_COORD_M} m", p.x_m, p.y_m),
                ));
            }
        }
        if self.layout.as_os_str().is_empty() {
            return Err(Error::param("layout", "missing layout path"));
        }
        self.check_labels()?;
        if let Some(s) = &self.sweeps {
            self.check_missing(&s.missing)?;
            if let Some((i, f)) = s.files.iter().enumerate().find(|(_, f)| {
                s.missing
                    .iter()
                    .any(|m| m.position == f.position && m.direction == f.direction)
            }) {
                return Err(Error::param(
                    format!("sweeps.files[{i}]"),
                    format!(
                        "a file for position {}, direction {}, which [sweeps] missing lists as not swept",
                        f.position, f.direction
                    ),
                ));
            }
            match s.format {
                SweepFormat::Touchstone => {
                    if s.pattern.is_none() && s.files.is_empty() {
                        return Err(Error::param(
                            "sweeps.pattern",
                            "touchstone sweeps need `pattern` or `files`",
                        ));
                    }
                    if let Some(p) = &s.pattern {
                        check_pattern(p, self.poses.len(), self.directions.count(), self.pulses)?;
                    }
                    self.check_files(&s.files)?;
                }
                SweepFormat::Parquet => {
                    if s.path.is_none() {
                        return Err(Error::param("sweeps.path", "parquet sweeps need `path`"));
                    }
                    // the files the table was made from (`import --to-parquet`): provenance
                    self.check_files(&s.files)?;
                }
            }
        }
        Ok(())
    }

    /// Number of positions.
    pub fn positions(&self) -> usize {
        self.poses.len()
    }

    /// The name of position `p` in messages, tables and plots: the lab's label when the
    /// manifest has labels, else the index.
    pub fn label(&self, p: usize) -> String {
        match self.labels.get(p) {
            Some(l) => l.clone(),
            None => p.to_string(),
        }
    }

    /// Direction `d` as messages show it: "index (angle°)".
    pub fn direction_name(&self, d: usize) -> String {
        format!("{d} ({}°)", angle_text(self.directions.angle_deg(d)))
    }

    /// The missing (position, direction) sweeps, sorted.
    pub fn missing(&self) -> Vec<(usize, usize)> {
        let mut v: Vec<(usize, usize)> = self
            .sweeps
            .as_ref()
            .map(|s| {
                s.missing
                    .iter()
                    .map(|m| (m.position, m.direction))
                    .collect()
            })
            .unwrap_or_default();
        v.sort_unstable();
        v
    }

    /// `labels`: none, or one non-empty label per pose, all distinct, without control
    /// characters.
    fn check_labels(&self) -> Result<()> {
        if self.labels.is_empty() {
            return Ok(());
        }
        if self.labels.len() != self.poses.len() {
            return Err(Error::param(
                "labels",
                format!(
                    "{} labels for {} poses (one per pose, in pose order)",
                    self.labels.len(),
                    self.poses.len()
                ),
            ));
        }
        let mut seen = std::collections::HashSet::new();
        for (i, l) in self.labels.iter().enumerate() {
            if l.trim().is_empty() || l.chars().any(char::is_control) || l.len() > 200 {
                return Err(Error::param(
                    format!("labels[{i}]"),
                    "a label is a non-empty line of at most 200 bytes",
                ));
            }
            if !seen.insert(l) {
                return Err(Error::param(
                    format!("labels[{i}]"),
                    format!("`{l}` names two poses"),
                ));
            }
        }
        Ok(())
    }

    /// `[sweeps] missing`: inside the campaign, listed once, and leaving every position at
    /// least one direction.
    fn check_missing(&self, missing: &[MissingSweep]) -> Result<()> {
        let (np, nd) = (self.poses.len(), self.directions.count());
        let mut seen = std::collections::HashSet::new();
        let mut per = vec![0usize; np];
        for (i, m) in missing.iter().enumerate() {
            if m.position >= np || m.direction >= nd {
                return Err(Error::param(
                    format!("sweeps.missing[{i}]"),
                    format!(
                        "(position {}, direction {}) outside the campaign ({np} positions, {nd} directions)",
                        m.position, m.direction
                    ),
                ));
            }
            if !seen.insert((m.position, m.direction)) {
                return Err(Error::param(
                    format!("sweeps.missing[{i}]"),
                    format!(
                        "position {}, direction {} listed twice",
                        m.position, m.direction
                    ),
                ));
            }
            per[m.position] += 1;
            if per[m.position] == nd {
                return Err(Error::param(
                    format!("sweeps.missing[{i}]"),
                    format!(
                        "position {} would have no sweep at all (leave the position out instead)",
                        m.position
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `[sweeps] files`: every index inside the campaign, no (position, direction, pulse)
    /// listed twice and no file given for two sweeps.
    fn check_files(&self, files: &[SweepFile]) -> Result<()> {
        let (np, nd, nk) = (self.poses.len(), self.directions.count(), self.pulses);
        let mut seen = std::collections::HashMap::new();
        let mut paths = std::collections::HashMap::new();
        for (i, f) in files.iter().enumerate() {
            if f.position >= np || f.direction >= nd || f.pulse >= nk {
                return Err(Error::param(
                    format!("sweeps.files[{i}]"),
                    format!("index (position {}, direction {}, pulse {}) outside the campaign ({np} positions, {nd} directions, {nk} pulses)", f.position, f.direction, f.pulse),
                ));
            }
            if let Some(j) = seen.insert((f.position, f.direction, f.pulse), i) {
                return Err(Error::param(
                    format!("sweeps.files[{i}]"),
                    format!(
                        "position {}, direction {}, pulse {} already listed by sweeps.files[{j}]",
                        f.position, f.direction, f.pulse
                    ),
                ));
            }
            if let Some(j) = paths.insert(f.path.clone(), i) {
                return Err(Error::param(
                    format!("sweeps.files[{i}]"),
                    format!(
                        "file {} already listed by sweeps.files[{j}] for another sweep",
                        f.path.display()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A sweep-name template names only `{position}`, `{direction}` and `{pulse}` (widths up
/// to [`limits::MAX_PATTERN_WIDTH`]) and varies with every index that takes more than one
/// value: a template without `{direction}` over 37 directions would read one file 37 times.
pub fn check_pattern(
    pattern: &str,
    positions: usize,
    directions: usize,
    pulses: usize,
) -> Result<()> {
    let field = "sweeps.pattern";
    let mut names = Vec::new();
    let mut rest = pattern;
    while let Some(open) = rest.find('{') {
        let after = &rest[open + 1..];
        let Some(close) = after.find('}') else {
            return Err(Error::param(field, format!("`{pattern}`: unclosed `{{`")));
        };
        let spec = &after[..close];
        let (name, width) = spec.split_once(':').unwrap_or((spec, ""));
        if !matches!(name, "position" | "direction" | "pulse") {
            return Err(Error::param(
                field,
                format!("`{pattern}`: unknown placeholder `{{{spec}}}` (use {{position}}, {{direction}}, {{pulse}})"),
            ));
        }
        if !width.is_empty() {
            match width.parse::<usize>() {
                Ok(w) if w <= MAX_PATTERN_WIDTH => {}
                _ => {
                    return Err(Error::param(
                        field,
                        format!("`{pattern}`: width `{width}` of `{{{name}}}` must be a number up to {MAX_PATTERN_WIDTH}"),
                    ))
                }
            }
        }
        names.push(name);
        rest = &after[close + 1..];
    }
    for (name, n, what) in [
        ("position", positions, "poses"),
        ("direction", directions, "directions"),
        ("pulse", pulses, "pulses"),
    ] {
        if n > 1 && !names.contains(&name) {
            return Err(Error::param(
                field,
                format!("`{pattern}` has no {{{name}}} but the campaign has {n} {what}: every sweep would read the same file"),
            ));
        }
    }
    Ok(())
}

impl Campaign {
    /// Read and validate `campaign.toml`; errors name the file and the field.
    pub fn load(path: &Path) -> Result<Campaign> {
        let text = crate::io::read_text(path)?;
        Self::from_str(&text, path)
    }

    /// Parse manifest text that notionally lives at `path`.
    pub fn from_str(text: &str, path: &Path) -> Result<Campaign> {
        let manifest: Manifest =
            toml::from_str(text).map_err(|e| Error::input(path, one_line(&e.to_string())))?;
        manifest
            .check()
            .map_err(|e| Error::input(path, e.to_string()))?;
        let c = Campaign {
            manifest,
            path: path.to_path_buf(),
        };
        let layout = c.layout_path();
        if !layout.is_file() {
            return Err(Error::input(
                path,
                format!("field `layout`: file {} not found", layout.display()),
            ));
        }
        c.check_poses_inside(&crate::campaign::layout::Layout::load(&layout)?)?;
        Ok(c)
    }

    /// Every pose lies strictly inside the layout's perimeter (refused otherwise: a pose on
    /// or beyond a wall sees the walls from behind, and the energy, the maps and the fit
    /// would all be of another room).
    pub fn check_poses_inside(&self, layout: &crate::campaign::layout::Layout) -> Result<()> {
        for (i, p) in self.manifest.poses.iter().enumerate() {
            let at = geo::Coord { x: p.x_m, y: p.y_m };
            if !layout.inside_perimeter(at) {
                return Err(Error::input(
                    &self.path,
                    format!(
                        "poses[{i}] at ({}, {}) m is not inside the perimeter of {}",
                        p.x_m,
                        p.y_m,
                        self.layout_path().display()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Folder of the manifest (paths inside are relative to it).
    pub fn dir(&self) -> PathBuf {
        self.path
            .parent()
            .map(Path::to_path_buf)
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."))
    }

    /// Resolved layout path.
    pub fn layout_path(&self) -> PathBuf {
        self.dir().join(&self.manifest.layout)
    }

    /// Override `[array] elements` (`--elements N`).
    pub fn set_elements(&mut self, n: usize) -> Result<()> {
        let mut a = self.manifest.array;
        a.elements = n;
        a.check().map_err(|_| {
            Error::param(
                "--elements",
                format!("{n} is not a perfect square (use 16, 100 or 400)"),
            )
        })?;
        self.manifest.array = a;
        Ok(())
    }
}

/// Expand a sweep name template for one (position, direction, pulse).
///
/// ```
/// use pradar_formats::campaign::manifest::expand_pattern;
/// let name = expand_pattern("sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p", 4, 36, 0);
/// assert_eq!(name, "sweeps/p004_d36_k00.s2p");
/// ```
pub fn expand_pattern(pattern: &str, position: usize, direction: usize, pulse: usize) -> String {
    let mut out = String::with_capacity(pattern.len() + 8);
    let mut rest = pattern;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let Some(close) = after.find('}') else {
            out.push_str(&rest[open..]);
            return out;
        };
        let spec = &after[..close];
        let (name, width) = match spec.split_once(':') {
            Some((n, w)) => (
                n,
                w.trim_start_matches('0')
                    .parse::<usize>()
                    .unwrap_or(0)
                    .min(MAX_PATTERN_WIDTH),
            ),
            None => (spec, 0),
        };
        let value = match name {
            "position" => Some(position),
            "direction" => Some(direction),
            "pulse" => Some(pulse),
            _ => None,
        };
        match value {
            Some(v) => out.push_str(&format!("{v:0width$}")),
            None => {
                out.push('{');
                out.push_str(spec);
                out.push('}');
            }
        }
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_expands_with_widths() {
        assert_eq!(
            expand_pattern(
                "sweeps/p{position:03}_d{direction:02}_k{pulse}.s2p",
                3,
                7,
                1
            ),
            "sweeps/p003_d07_k1.s2p"
        );
    }

    #[test]
    fn directions_count_and_angles() {
        let d = Directions {
            start_deg: -90.0,
            stop_deg: 90.0,
            step_deg: 5.0,
        };
        assert_eq!(d.count(), 37);
        assert_eq!(d.angle_deg(36), 90.0);
    }

    #[test]
    fn array_side_and_check() {
        let a = ArrayConfig {
            elements: 100,
            one_bit: false,
            element_q: 1.0,
            steering: Steering::Mechanical,
        };
        assert_eq!(a.side(), 10);
        assert!(a.check().is_ok());
        let bad = ArrayConfig { elements: 50, ..a };
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("array.elements"));
    }

    /// Each format reads back from its name, which is the manifest's (serde) spelling and
    /// the command-line value.
    #[test]
    fn sweep_format_names_round_trip_and_match_the_manifest() {
        let names = SweepFormat::ALL.map(|f| f.to_string());
        assert_eq!(names, ["touchstone", "parquet"]);
        for f in SweepFormat::ALL {
            assert_eq!(f.to_string().parse::<SweepFormat>().unwrap(), f);
            let sweeps = SweepsConfig {
                format: f,
                ..SweepsConfig::default()
            };
            let text = toml::to_string(&sweeps).unwrap();
            assert!(text.contains(&format!("format = \"{f}\"")), "{text}");
            assert_eq!(toml::from_str::<SweepsConfig>(&text).unwrap().format, f);
        }
        let e = "Parquet".parse::<SweepFormat>().unwrap_err().to_string();
        assert!(e.contains("(touchstone|parquet)"), "{e}");
    }

    /// `coupling = "mean"` over a single direction would subtract every echo: refused,
    /// naming the field; over two directions it is accepted.
    #[test]
    fn mean_coupling_needs_two_directions() {
        let text = |stop: f64| {
            format!(
                "schema_version = 1\nname = \"t\"\nlayout = \"l.geojson\"\nseed = 3\n\
                 [band]\nstart_hz = 57.5e9\nstop_hz = 63.5e9\npoints = 801\n\
                 [array]\nelements = 16\n\
                 [directions]\nstart_deg = 0.0\nstop_deg = {stop:?}\nstep_deg = 10.0\n\
                 [noise]\nfloor_dbm = -100.0\n[processing]\ncoupling = \"mean\"\n\
                 [[poses]]\nx_m = 0.5\ny_m = 0.5\nheading_deg = 0.0\n"
            )
        };
        let one: Manifest = toml::from_str(&text(0.0)).unwrap();
        let e = one.check().unwrap_err().to_string();
        assert!(
            e.contains("processing.coupling") && e.contains("one direction"),
            "{e}"
        );
        let two: Manifest = toml::from_str(&text(10.0)).unwrap();
        two.check().unwrap();
    }
}
