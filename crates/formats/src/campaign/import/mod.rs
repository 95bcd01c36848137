//! Import (`pradar import`): a campaign manifest built and validated from what a measurement
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
//! `unreadable:` problem, never opened. A pose whose x or y is beyond the layout's bound is
//! refused in one line naming the poses CSV, its line and column, the value in short form.
//!
//! [`import`] reads as its three steps: collect (the base, the poses, the directions and
//! the sweep files with what each name or index row says: `collect`, over `reader` for
//! the CSVs and `pattern` for the names), check (every file under its cell, what is
//! missing, duplicated or extra, outputs against inputs, every used file read for its grid:
//! `check`), then write (the manifest, validated, and the Parquet table: `write`).

mod check;
mod collect;
mod pattern;
mod reader;
mod write;

#[cfg(feature = "fuzz")]
pub use reader::{parse_index, parse_poses};
pub use reader::{MAX_INDEX_ROWS, MAX_POSES};

use crate::campaign::manifest::Directions;
use crate::error::Result;
use crate::progress::StepProgress;
use std::path::{Path, PathBuf};

/// Where the sweep files are and how they are named.
#[derive(Debug, Clone)]
pub enum SweepFiles {
    /// A glob and a file-name pattern with `{position}`, `{direction}` or `{angle}`, and
    /// optionally `{pulse}` (module docs).
    Glob {
        /// e.g. `raw/*.s2p`.
        glob: String,
        /// e.g. `pos{position}_dir{direction:02}.s2p` or `{position}_az{angle:+03}.s2p`.
        pattern: String,
    },
    /// An index CSV `position, direction | angle_deg, [pulse,] path`.
    Index(PathBuf),
}

/// Inputs of [`import`].
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

/// What [`import`] found and wrote.
#[derive(Debug, Clone, Default)]
pub struct ImportOutcome {
    /// Problems found before processing (nothing written when not empty), one line each.
    pub problems: Vec<String>,
    /// Positions, directions, pulses.
    pub shape: (usize, usize, usize),
    /// Sweep files used (named by the manifest), plus those that matched the glob but
    /// not the pattern.
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
            if count("missing: position") > 0 {
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

/// Run `pradar import`: build and validate the manifest (and optionally the Parquet sweep
/// table) from a poses CSV and sweep files. The outcome's `Display` is what the command
/// prints; an outcome with problems wrote nothing ([`ImportOutcome::problem_report`]).
pub fn import(p: &ImportParams, progress: StepProgress) -> Result<ImportOutcome> {
    let inputs = collect::collect(p)?;
    let (plan, outcome) = check::check(p, &inputs, progress)?;
    match outcome.band {
        Some(band) if outcome.problems.is_empty() => write::write(p, &inputs, &plan, band, outcome),
        _ => Ok(outcome),
    }
}

/// The folder of the output manifest (`.` for a bare name).
fn out_dir(p: &ImportParams) -> &Path {
    p.out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}
