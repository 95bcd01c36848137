//! The check step of `import`: whether the collected sweep files make the campaign, before
//! anything is processed or written.
//!
//! Takes the [`Inputs`] of the collect step; gives the campaign's cells ([`Plan`]: the
//! file of each (position, direction, pulse), the positions and sweeps `allow_missing`
//! leaves out) and the [`ImportOutcome`] with every problem found, one line each: files
//! naming a position, direction, angle or pulse the campaign does not have (`extra:`),
//! two files naming one cell (`duplicated:`), cells without a file (`missing:`), files the
//! Touchstone reader refuses (`unreadable:`) and files whose grid differs from the first's
//! (`grid:`). Refused at once: more sweeps than a campaign may have, and an output that is
//! one of the inputs (before any sweep file is read). The sweep files are read in
//! parallel, each only for its grid, its parameter and the reader's notes.

use super::collect::{Inputs, SweepEntry};
use super::pattern::DirectionValue;
use super::{out_dir, ImportOutcome, ImportParams, SweepFiles};
use crate::campaign::manifest::limits::{MAX_PULSES, MAX_SWEEPS};
use crate::campaign::manifest::Directions;
use crate::campaign::touchstone::{decode, parse_touchstone, SParam};
use crate::error::{Error, Result};
use crate::progress::StepProgress;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The campaign's cells and the file of each.
pub(super) struct Plan {
    /// Directions.
    pub(super) nd: usize,
    /// Pulses: the largest accepted `pulse` + 1.
    pub(super) nk: usize,
    /// The file of cell (position `pi`, direction `d`, pulse `k`) at `(pi * nd + d) * nk + k`.
    pub(super) table: Vec<Option<PathBuf>>,
    /// Positions left out (`allow_missing`: no direction with every pulse).
    pub(super) dropped: Vec<bool>,
    /// (position, direction) sweeps recorded as missing, at `pi * nd + d`.
    pub(super) missing_pd: Vec<bool>,
}

impl Plan {
    /// Whether the file of cell `i` goes into the manifest (its position kept, its sweep
    /// not missing).
    pub(super) fn used(&self, i: usize) -> bool {
        let (nd, nk) = (self.nd, self.nk);
        let (pi, d) = (i / (nd * nk), (i / nk) % nd);
        !self.dropped[pi] && !self.missing_pd[pi * nd + d]
    }

    /// The positions kept, in manifest order.
    pub(super) fn kept(&self) -> Vec<usize> {
        (0..self.dropped.len())
            .filter(|&pi| !self.dropped[pi])
            .collect()
    }
}

/// The first readable file and its frequency grid, Hz.
type FirstGrid<'a> = Option<(&'a PathBuf, Vec<f64>)>;

/// One sweep file as `import` reads it: its grid and reader notes, or the refusal.
type FileRead = std::result::Result<(Vec<f64>, Vec<String>), String>;

/// Check the collected files: the cells, what is missing, the outputs against the inputs,
/// then every used file read for its grid. The outcome's problems are empty exactly when
/// the manifest can be written (its band is then set).
pub(super) fn check(
    p: &ImportParams,
    inputs: &Inputs,
    progress: StepProgress,
) -> Result<(Plan, ImportOutcome)> {
    let mut problems: Vec<String> = inputs
        .extra
        .iter()
        .map(|(f, why)| format!("extra: {}: {why}", f.display()))
        .collect();
    let cells = place(p, inputs, &mut problems);
    let mut plan = fill(p, inputs, &cells, &mut problems)?;
    let warnings = find_missing(p, inputs, &mut plan, &mut problems);
    let present: Vec<&PathBuf> = plan
        .table
        .iter()
        .enumerate()
        .filter(|(i, _)| plan.used(*i))
        .filter_map(|(_, f)| f.as_ref())
        .collect();
    // no output may be an input (checked before any file is read)
    refuse_inputs(p, &inputs.base, &inputs.entries, &inputs.extra)?;
    let reads = read_sweeps(&present, inputs.param, progress);
    let (grid, notes) = compare_grids(&present, reads, &mut problems);
    let mut outcome = ImportOutcome {
        shape: (plan.kept().len(), plan.nd, plan.nk),
        files: present.len() + inputs.extra.len(),
        warnings,
        notes: notes
            .into_iter()
            .map(|(n, c)| format!("{n} in {c} file(s)"))
            .collect(),
        ..Default::default()
    };
    match &grid {
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
        }
        None if problems.is_empty() => problems.push("no readable sweep file".into()),
        None => {}
    }
    outcome.problems = problems;
    Ok((plan, outcome))
}

/// Direction `d` as the problem lines name it: its index and its angle.
fn direction_name(directions: &Directions, d: usize) -> String {
    format!(
        "{d} ({}°)",
        crate::campaign::manifest::angle_text(directions.angle_deg(d))
    )
}

/// A cell as the problem lines name it (the pulse only when there are several).
fn cell_name(inputs: &Inputs, nk: usize, pi: usize, d: usize, k: usize) -> String {
    let mut s = format!(
        "position {}, direction {}",
        inputs.labels[pi],
        direction_name(&inputs.directions, d)
    );
    if nk > 1 {
        s.push_str(&format!(", pulse {k}"));
    }
    s
}

/// Each sweep file under its cell (position, direction, pulse), in manifest order; a file
/// naming a position, direction, angle or pulse the campaign does not have is an `extra:`
/// problem.
fn place(
    p: &ImportParams,
    inputs: &Inputs,
    problems: &mut Vec<String>,
) -> BTreeMap<(usize, usize, usize), Vec<PathBuf>> {
    let (labels, numeric, directions) = (&inputs.labels, inputs.numeric, &inputs.directions);
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
    let grid = format!(
        "{}:{}:{}",
        directions.start_deg, directions.stop_deg, directions.step_deg
    );
    let mut cells: BTreeMap<(usize, usize, usize), Vec<PathBuf>> = BTreeMap::new();
    for e in &inputs.entries {
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
            (Some(_), Ok(_)) if e.pulse as u64 >= MAX_PULSES as u64 => Err(format!(
                "pulse {} beyond the {MAX_PULSES} repeats a campaign may have",
                e.pulse
            )),
            (Some(pi), Ok(d)) => Ok((pi, d, e.pulse as usize)),
        };
        match why {
            Ok(key) => cells.entry(key).or_default().push(e.path.clone()),
            Err(why) => problems.push(format!("extra: {}: {why}", e.path.display())),
        }
    }
    cells
}

/// The table of cells, each with its first file; a cell named by two files is a
/// `duplicated:` problem. Refused: more sweeps than a campaign may have.
fn fill(
    p: &ImportParams,
    inputs: &Inputs,
    cells: &BTreeMap<(usize, usize, usize), Vec<PathBuf>>,
    problems: &mut Vec<String>,
) -> Result<Plan> {
    let nd = inputs.directions.count();
    let np = inputs.poses.len();
    // pulses: the largest accepted + 1 (a refused file's number does not count)
    let nk = cells.keys().map(|k| k.2).max().unwrap_or(0) + 1;
    let cells_total = np.saturating_mul(nd).saturating_mul(nk);
    if cells_total > MAX_SWEEPS {
        return Err(Error::input(
            &p.poses,
            format!("{np} poses x {nd} directions x {nk} pulses = {cells_total} sweeps: more than {MAX_SWEEPS}"),
        ));
    }
    let mut table: Vec<Option<PathBuf>> = vec![None; cells_total];
    for (&(pi, d, k), files) in cells {
        if files.len() > 1 {
            let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            problems.push(format!(
                "duplicated: {}: {}",
                cell_name(inputs, nk, pi, d, k),
                names.join(", ")
            ));
        }
        table[(pi * nd + d) * nk + k] = Some(files[0].clone());
    }
    Ok(Plan {
        nd,
        nk,
        table,
        dropped: vec![false; np],
        missing_pd: vec![false; np * nd],
    })
}

/// What is missing: whole positions, or (position, direction) sweeps. Without
/// `allow_missing` each cell without a file is a `missing:` problem; with it the position
/// or sweep is left out, one warning each (returned).
fn find_missing(
    p: &ImportParams,
    inputs: &Inputs,
    plan: &mut Plan,
    problems: &mut Vec<String>,
) -> Vec<String> {
    let (nd, nk) = (plan.nd, plan.nk);
    let labels = &inputs.labels;
    let mut warnings = Vec::new();
    for pi in 0..labels.len() {
        let table = &plan.table;
        let cell_missing = |d: usize| (0..nk).any(|k| table[(pi * nd + d) * nk + k].is_none());
        // a position without one complete direction is left out whole
        if p.allow_missing && (0..nd).all(cell_missing) {
            plan.dropped[pi] = true;
            let none_at_all = (0..nd * nk).all(|i| plan.table[pi * nd * nk + i].is_none());
            warnings.push(format!(
                "left out: position {}: {} (not in the manifest)",
                labels[pi],
                if none_at_all {
                    "no sweep file at all"
                } else {
                    "no direction with every pulse"
                }
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
                plan.missing_pd[pi * nd + d] = true;
                let what = if nk > 1 {
                    format!(" (pulse(s) {absent:?} missing; the others are not used)")
                } else {
                    String::new()
                };
                warnings.push(format!(
                    "left out: position {}, direction {}: no file{what}",
                    labels[pi],
                    direction_name(&inputs.directions, d)
                ));
            } else {
                for k in absent {
                    problems.push(format!(
                        "missing: {}: no file",
                        cell_name(inputs, nk, pi, d, k)
                    ));
                }
            }
        }
    }
    if p.allow_missing && plan.dropped.iter().all(|&x| x) {
        problems.push("missing: no position has a sweep file".into());
    }
    warnings
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

/// Read every file (in parallel) for its grid, its parameter and the reader's refusal.
fn read_sweeps(
    present: &[&PathBuf],
    param: Option<SParam>,
    progress: StepProgress,
) -> Vec<FileRead> {
    let done = std::sync::atomic::AtomicUsize::new(0);
    present
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
        .collect()
}

/// The grid of the first readable file, and the reader's notes by kind with a count of
/// files each; a refused file is an `unreadable:` problem, a file whose grid differs from
/// the first's a `grid:` problem.
fn compare_grids<'a>(
    present: &[&'a PathBuf],
    reads: Vec<FileRead>,
    problems: &mut Vec<String>,
) -> (FirstGrid<'a>, BTreeMap<String, usize>) {
    let mut grid: FirstGrid<'a> = None;
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
    (grid, notes)
}
