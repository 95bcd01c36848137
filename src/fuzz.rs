//! In-process fuzzing of the parsers on stable Rust: a harness per file kind a user gives
//! pradar, a seeded mutator over committed seed inputs, and the run loop shared by
//! `examples/fuzz.rs` (`scripts/fuzz N`: N executions per parser) and the bounded run of
//! the test suite (`tests/fuzz.rs`). Built only with the cargo feature `fuzz`
//! (`scripts/fuzz` and `scripts/test` turn it on).
//!
//! Targets ([`Target`]): Touchstone (`parse_touchstone`, under each of the extensions
//! `.s2p`, `.s1p`, `.s3p`, `.s4p`, `.ts` until one accepts: v1 takes its port count from
//! the extension), manifest (`Campaign::from_str`,
//! with a layout beside it), layout (`Layout::from_geojson`), model file
//! (`ModelConfig::from_str`), and the energy, MPC and clustered-MPC Parquet readers
//! (`EnergyMatrix::read` and `EnergyTable::open` + `load`, `read_mpcs` + `read_sector_deg`, `read_clustered`; the bytes are
//! written to a scratch file first, as the readers take paths), the import's poses and
//! index CSV readers (`campaign::import::parse_poses`, `parse_index`, on the text decoded as
//! `import` decodes it), and the calibration step (`Calibration::from_sweeps` + `apply` on
//! measured, background and reference sweeps decoded from the bytes as f64 pairs, see
//! `calibration_step`; an accepted calibration leaving a non-finite value is a failure). An execution passes when
//! the parser returns, `Ok` or `Err`; a panic is a failure, caught with `catch_unwind`
//! and reported with its message (the process's panic hook is silenced while fuzzing).
//!
//! Mutations ([`Mutator`]): bit flips, interesting bytes (0, 0xff, 0x7f, 0x80), random
//! insertions, deletions, duplicated ranges, truncation, splices with another seed and,
//! for the text formats, a number replaced by an extreme one (`1e308`, `-1`, `nan`,
//! `70000`, `1e-7`, …) — the values that found the panics and unbounded allocations
//! (docs/reliability.md). One to four mutations are stacked per input. Everything is drawn from a
//! ChaCha8 stream of the run's seed: a run is reproducible, and a failing input is
//! written to the crash folder under its hash; committed to `fuzz/regressions/<target>/`
//! it is replayed by every test run.
//!
//! A Parquet input can also make polars *abort* (an allocation of billions of bytes sized
//! from a corrupt footer, which no `catch_unwind` catches). The driver therefore runs each
//! target in a child process and, when the child dies, saves the input it was running
//! (the scratch file), counts an abort and resumes the same stream after it ([`Drive`]).
//!
//! No coverage feedback (that needs a nightly compiler or an external engine): the
//! mutations are structure-aware enough to reach the checks of each format from its
//! seeds, and the run counts executions, `Ok`s and `Err`s so a harness that only ever hits
//! the first check shows up as 0 `Ok`s.

use crate::error::Result;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

/// A parser under fuzz.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Touchstone v1/v2 files.
    Touchstone,
    /// `campaign.toml`.
    Manifest,
    /// Layout GeoJSON.
    Layout,
    /// Model file (`fitted_model.toml`).
    Model,
    /// Energy Parquet table.
    Energy,
    /// MPC Parquet table.
    Mpc,
    /// Clustered MPC Parquet table.
    Cluster,
    /// `import --poses` CSV.
    Poses,
    /// `import --index` CSV.
    Index,
    /// The calibration step: a reference and a background sweep built from the input's
    /// bytes, checked and applied to sweeps built from them too.
    Calibration,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 10] = [
        Target::Touchstone,
        Target::Manifest,
        Target::Layout,
        Target::Model,
        Target::Energy,
        Target::Mpc,
        Target::Cluster,
        Target::Poses,
        Target::Index,
        Target::Calibration,
    ];

    /// Name (seed and regression folder name, command-line name).
    pub fn name(self) -> &'static str {
        match self {
            Target::Touchstone => "touchstone",
            Target::Manifest => "manifest",
            Target::Layout => "layout",
            Target::Model => "model",
            Target::Energy => "energy",
            Target::Mpc => "mpc",
            Target::Cluster => "cluster",
            Target::Poses => "poses",
            Target::Index => "index",
            Target::Calibration => "calibration",
        }
    }

    /// The target called `name`.
    pub fn parse(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Whether the format is text (number-token mutations apply).
    pub fn is_text(self) -> bool {
        matches!(
            self,
            Target::Touchstone
                | Target::Manifest
                | Target::Layout
                | Target::Model
                | Target::Poses
                | Target::Index
        )
    }

    /// The folders of committed seed inputs, relative to the repository root.
    pub fn seed_dirs(self) -> Vec<&'static str> {
        match self {
            Target::Touchstone => vec!["data/touchstone", "data/touchstone/zoo"],
            Target::Manifest => vec!["fuzz/seeds/manifest"],
            Target::Layout => vec!["data/corridor", "data/tests"],
            Target::Model => vec!["fuzz/seeds/model"],
            Target::Energy => vec!["fuzz/seeds/energy"],
            Target::Mpc => vec!["fuzz/seeds/mpc"],
            Target::Cluster => vec!["fuzz/seeds/cluster"],
            Target::Poses => vec!["fuzz/seeds/poses"],
            Target::Index => vec!["fuzz/seeds/index"],
            Target::Calibration => vec!["fuzz/seeds/calibration"],
        }
    }

    /// File extensions of its seeds.
    fn extensions(self) -> &'static [&'static str] {
        match self {
            Target::Touchstone => &["s1p", "s2p", "s3p", "s4p", "ts"],
            Target::Manifest | Target::Model => &["toml"],
            Target::Layout => &["geojson"],
            Target::Energy | Target::Mpc | Target::Cluster => &["parquet"],
            Target::Poses | Target::Index => &["csv"],
            Target::Calibration => &["bin"],
        }
    }
}

/// Read every seed of `target` under the repository `root` (and, when present, its
/// regression inputs in `fuzz/regressions/<target>/`), sorted by path.
pub fn load_seeds(root: &Path, target: Target) -> Vec<(PathBuf, Vec<u8>)> {
    let regressions = regression_dir(root, target);
    let mut dirs: Vec<PathBuf> = target.seed_dirs().iter().map(|d| root.join(d)).collect();
    dirs.push(regressions.clone());
    let mut out = Vec::new();
    for d in dirs {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_file())
            .filter(|p| {
                *d == regressions
                    || p.extension()
                        .and_then(|e| e.to_str())
                        .is_some_and(|e| target.extensions().contains(&e))
            })
            .collect();
        paths.sort();
        for p in paths {
            if let Ok(b) = std::fs::read(&p) {
                out.push((p, b));
            }
        }
    }
    out
}

/// Where the failing inputs of `target` are kept as regression fixtures.
pub fn regression_dir(root: &Path, target: Target) -> PathBuf {
    root.join("fuzz/regressions").join(target.name())
}

/// A scratch folder for one harness: the layout the manifest target needs, and the file
/// the Parquet targets write their input to.
pub struct Scratch {
    dir: PathBuf,
}

impl Scratch {
    /// Prepare `dir` (created; a corridor-like rectangle `layout.geojson` is written).
    pub fn new(dir: &Path) -> Result<Scratch> {
        std::fs::create_dir_all(dir).map_err(|e| crate::error::Error::io(dir, e))?;
        let layout = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
            "properties": {"role": "perimeter"}, "geometry": {"type": "Polygon",
            "coordinates": [[[-1, -4], [11, -4], [11, 2], [-1, 2], [-1, -4]]]}}]}"#;
        crate::io::write_bytes(&dir.join("layout.geojson"), layout.as_bytes())?;
        Ok(Scratch {
            dir: dir.to_path_buf(),
        })
    }
}

/// The outcome of one execution.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The parser accepted the input.
    Ok,
    /// The parser refused it with an error (the message).
    Err(String),
    /// The parser panicked (the message).
    Panic(String),
}

/// Run the parser of `target` on `bytes` (text formats decoded as the CLI decodes them).
pub fn execute(target: Target, bytes: &[u8], scratch: &Scratch) -> Outcome {
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        parse(target, bytes, scratch)
    }));
    match r {
        Ok(Ok(())) => Outcome::Ok,
        Ok(Err(e)) => Outcome::Err(e.to_string()),
        Err(p) => Outcome::Panic(
            p.downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "non-string panic".into()),
        ),
    }
}

fn parse(target: Target, bytes: &[u8], scratch: &Scratch) -> Result<()> {
    let text = || String::from_utf8_lossy(bytes).into_owned();
    match target {
        Target::Touchstone => {
            // a v1 file's port count comes from its extension: every one is tried
            let decoded = crate::campaign::touchstone::decode(bytes);
            let mut last = Ok(());
            for ext in ["s2p", "s1p", "s3p", "s4p", "ts"] {
                let p = scratch.dir.join(format!("fuzz.{ext}"));
                last = crate::campaign::touchstone::parse_touchstone(&decoded, &p).map(|_| ());
                if last.is_ok() {
                    break;
                }
            }
            last
        }
        Target::Manifest => {
            let p = scratch.dir.join("campaign.toml");
            crate::campaign::Campaign::from_str(&text(), &p).map(|_| ())
        }
        Target::Layout => {
            let p = scratch.dir.join("fuzz.geojson");
            crate::campaign::layout::Layout::from_geojson(&text(), &p).map(|_| ())
        }
        Target::Model => {
            let p = scratch.dir.join("model.toml");
            crate::model::file::ModelConfig::from_str(&text(), &p).map(|_| ())
        }
        Target::Poses => {
            let p = scratch.dir.join("poses.csv");
            let text = crate::campaign::touchstone::decode(bytes);
            crate::campaign::import::parse_poses(&text, &p).map(|_| ())
        }
        Target::Index => {
            let p = scratch.dir.join("index.csv");
            let text = crate::campaign::touchstone::decode(bytes);
            crate::campaign::import::parse_index(&text, &p).map(|_| ())
        }
        Target::Calibration => calibration_step(bytes, &scratch.dir),
        Target::Energy | Target::Mpc | Target::Cluster => {
            let p = parquet_input(&scratch.dir, target);
            std::fs::write(&p, bytes).map_err(|e| crate::error::Error::io(&p, e))?;
            match target {
                Target::Energy => {
                    // both readers: the whole table, and the streaming one over every
                    // position (what `extract` and `map` use)
                    let whole = crate::energy::EnergyMatrix::read(&p).map(|_| ());
                    let streamed = crate::energy::EnergyTable::open(&p).and_then(|t| {
                        use crate::energy::EnergySource;
                        let np = t.header().positions;
                        t.load(0, np)?;
                        t.load(0, 1.min(np))?;
                        t.load(np.saturating_sub(1), np).map(|_| ())
                    });
                    whole.and(streamed)
                }
                Target::Mpc => {
                    crate::mpc::read_sector_deg(&p)?;
                    crate::mpc::read_mpcs(&p).map(|_| ())
                }
                _ => crate::fit::channel::read_clustered(&p).map(|_| ()),
            }
        }
    }
}

/// The calibration step on sweeps decoded from `bytes`: byte 0 says which calibration
/// sweeps there are (bit 0 background, bit 1 reference), the directions (1–3, bits 2–3)
/// and pulses (1–2, bit 4); byte 1 the points (8–64); the rest are little-endian f64
/// pairs (re, im): the measured sweeps, then the background, then the reference. Too few
/// values is a refusal. `Calibration::from_sweeps` checks
/// the reference, `apply` computes (S − B)/R; when both accept, every value must be finite
/// (a non-finite one accepted would be a NaN energy): a panic otherwise.
fn calibration_step(bytes: &[u8], dir: &Path) -> Result<()> {
    use crate::campaign::manifest::Band;
    use crate::campaign::sweeps::PositionSweeps;
    use crate::energy::calibration::Calibration;
    use num_complex::Complex64;
    let input = dir.join("calibration.bin");
    let (flags, points) = match bytes {
        [f, p, ..] => (*f, 8 + usize::from(*p) % 57),
        _ => return Err(crate::error::Error::input(&input, "shorter than 2 bytes")),
    };
    let (has_b, has_r) = (flags & 1 == 1, flags & 2 == 2);
    let directions = 1 + usize::from((flags >> 2) & 3) % 3;
    let pulses = 1 + usize::from((flags >> 4) & 1);
    let sweeps = directions * pulses + usize::from(has_b) + usize::from(has_r);
    let mut vals = bytes[2..].chunks_exact(16).map(|c| {
        let f = |b: &[u8]| f64::from_le_bytes(b.try_into().expect("8 bytes"));
        Complex64::new(f(&c[..8]), f(&c[8..]))
    });
    let mut take = |n: usize| -> Result<Vec<Complex64>> {
        let v: Vec<Complex64> = vals.by_ref().take(n).collect();
        if v.len() < n {
            return Err(crate::error::Error::input(
                &input,
                format!("{sweeps} sweeps of {points} points need more values"),
            ));
        }
        Ok(v)
    };
    let s21 = take(directions * pulses * points)?;
    let background = if has_b {
        Some((dir.join("background.s2p"), take(points)?))
    } else {
        None
    };
    let reference = if has_r {
        Some((dir.join("reference.s2p"), take(points)?))
    } else {
        None
    };
    let band = Band {
        start_hz: 57.5e9,
        stop_hz: 63.5e9,
        points,
    };
    let cal = Calibration::from_sweeps(&band, background, reference)?;
    let mut sw = PositionSweeps {
        position: 0,
        directions,
        pulses,
        points,
        s21,
        missing: vec![],
    };
    let measured_finite = sw.s21.iter().all(|v| v.re.is_finite() && v.im.is_finite());
    cal.apply(&mut sw)?;
    // a measured value that is not finite is the sweep reader's to refuse; once they all
    // are, an accepted calibration must leave finite values
    if measured_finite {
        if let Some(j) = sw
            .s21
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            panic!(
                "calibration accepted a non-finite value at {j}: {}",
                sw.s21[j]
            );
        }
    }
    Ok(())
}

/// Extreme numbers the text mutations put in place of a number.
const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "1",
    "1e308",
    "-1e308",
    "1e-7",
    "nan",
    "inf",
    "-0",
    "70000",
    "2e8",
    "999999999",
    "1e12",
    "18446744073709551615",
    "4294967297",
    "0.5",
];

/// The seeded mutator.
pub struct Mutator {
    rng: ChaCha8Rng,
}

impl Mutator {
    /// A mutator drawing from `seed`.
    pub fn new(seed: u64) -> Mutator {
        Mutator {
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// A new input: one to four mutations of a seed drawn from `seeds`.
    pub fn next(&mut self, seeds: &[Vec<u8>], text: bool) -> Vec<u8> {
        let mut b = seeds[self.rng.gen_range(0..seeds.len())].clone();
        let n = self.rng.gen_range(1..=4);
        for _ in 0..n {
            self.mutate(&mut b, seeds, text);
        }
        b
    }

    fn mutate(&mut self, b: &mut Vec<u8>, seeds: &[Vec<u8>], text: bool) {
        let r = &mut self.rng;
        if b.is_empty() {
            b.push(r.gen());
            return;
        }
        let ops = if text { 9 } else { 8 };
        let len = b.len();
        match r.gen_range(0..ops) {
            0 => {
                let i = r.gen_range(0..len);
                b[i] ^= 1 << r.gen_range(0..8);
            }
            1 => {
                let i = r.gen_range(0..len);
                b[i] = [0u8, 0xff, 0x7f, 0x80, b'0', b'9', b'-', b'.'][r.gen_range(0..8)];
            }
            2 => {
                let i = r.gen_range(0..=len);
                let k = r.gen_range(1..=8);
                let ins: Vec<u8> = (0..k).map(|_| r.gen()).collect();
                b.splice(i..i, ins);
            }
            3 => {
                let i = r.gen_range(0..len);
                let k = r.gen_range(1..=(len - i).min(64));
                b.drain(i..i + k);
            }
            4 => {
                let i = r.gen_range(0..len);
                let k = r.gen_range(1..=(len - i).min(64));
                let dup: Vec<u8> = b[i..i + k].to_vec();
                let at = r.gen_range(0..=len);
                b.splice(at..at, dup);
            }
            5 => {
                let at = r.gen_range(0..len);
                b.truncate(at.max(1));
            }
            6 => {
                let other = &seeds[r.gen_range(0..seeds.len())];
                if !other.is_empty() {
                    let i = r.gen_range(0..len);
                    let j = r.gen_range(0..other.len());
                    let k = r.gen_range(1..=(other.len() - j).min(256));
                    let end = (i + k).min(len);
                    b.splice(i..end, other[j..j + k].iter().copied());
                }
            }
            7 => {
                // a 4- or 8-byte little-endian integer field overwritten (Parquet lengths)
                let w = if r.gen() { 4 } else { 8 };
                if len >= w {
                    let i = r.gen_range(0..=len - w);
                    let v: u64 =
                        [0, 1, u32::MAX as u64, u64::MAX, 1 << 31, r.gen()][r.gen_range(0..6)];
                    b[i..i + w].copy_from_slice(&v.to_le_bytes()[..w]);
                }
            }
            _ => {
                // a number token replaced by an extreme value
                let starts: Vec<usize> = (0..len)
                    .filter(|&i| {
                        b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_alphanumeric())
                    })
                    .collect();
                if starts.is_empty() {
                    return;
                }
                let i = starts[r.gen_range(0..starts.len())];
                let mut j = i;
                while j < len && (b[j].is_ascii_digit() || b"._eE+-".contains(&b[j])) {
                    j += 1;
                }
                let v = EXTREMES[r.gen_range(0..EXTREMES.len())];
                b.splice(i..j, v.bytes());
            }
        }
    }
}

/// Counts of a fuzz run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Executions.
    pub executions: u64,
    /// Inputs accepted.
    pub ok: u64,
    /// Inputs refused with an error.
    pub errors: u64,
    /// Panics (each input saved to the crash folder).
    pub panics: u64,
    /// The first panic messages (at most 5).
    pub panic_messages: Vec<String>,
}

/// Silence the panic hook (the harness reports panics itself); returns the previous hook.
pub fn silence_panics() {
    std::panic::set_hook(Box::new(|_| {}));
}

/// How a fuzz run is driven: skip the first `skip` executions (their inputs are drawn
/// but not run: a run resumed after an abort continues the same stream), `mark` called
/// with each execution's index before it runs, `progress` every 1000 executions.
pub struct Drive<'a> {
    /// Executions to skip.
    pub skip: u64,
    /// Called with the index of each execution before it runs.
    pub mark: &'a dyn Fn(u64),
    /// Called every 1000 executions with the counts so far.
    pub progress: &'a dyn Fn(&Stats),
}

/// Run `target` on every seed as is, then on `iterations` mutated inputs drawn with
/// `seed`; a panicking input is written to `crashes` (when given) as `<hash>.bin`.
pub fn run(
    target: Target,
    seeds: &[Vec<u8>],
    iterations: u64,
    seed: u64,
    scratch: &Scratch,
    crashes: Option<&Path>,
    drive: &Drive,
) -> Stats {
    let mut stats = Stats::default();
    let mut m = Mutator::new(seed ^ (target as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let mut index = 0u64;
    let mut exec = |stats: &mut Stats, input: &[u8]| {
        let i = index;
        index += 1;
        if i < drive.skip {
            return;
        }
        (drive.mark)(i);
        let o = execute(target, input, scratch);
        stats.executions += 1;
        match o {
            Outcome::Ok => stats.ok += 1,
            Outcome::Err(_) => stats.errors += 1,
            Outcome::Panic(msg) => {
                stats.panics += 1;
                if stats.panic_messages.len() < 5 {
                    stats.panic_messages.push(msg);
                }
                if let Some(dir) = crashes {
                    save_crash(dir, input);
                }
            }
        }
        if stats.executions.is_multiple_of(1000) {
            (drive.progress)(stats);
        }
    };
    for s in seeds {
        exec(&mut stats, s);
    }
    if seeds.is_empty() {
        return stats;
    }
    for _ in 0..iterations {
        let input = m.next(seeds, target.is_text());
        exec(&mut stats, &input);
    }
    stats
}

/// Save a failing input to `dir` as `<hash>.bin`; returns its path.
pub fn save_crash(dir: &Path, input: &[u8]) -> PathBuf {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    input.hash(&mut h);
    let _ = std::fs::create_dir_all(dir);
    let p = dir.join(format!("{:016x}.bin", h.finish()));
    let _ = std::fs::write(&p, input);
    p
}

/// The scratch file a Parquet target's current input is written to (after an abort it
/// holds the input that caused it).
pub fn parquet_input(scratch_dir: &Path, target: Target) -> PathBuf {
    scratch_dir.join(format!("fuzz_{}.parquet", target.name()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutator_is_deterministic_and_changes_its_input() {
        let seeds = vec![b"[band]\npoints = 801\n".to_vec()];
        let a: Vec<Vec<u8>> = {
            let mut m = Mutator::new(3);
            (0..50).map(|_| m.next(&seeds, true)).collect()
        };
        let mut m = Mutator::new(3);
        let b: Vec<Vec<u8>> = (0..50).map(|_| m.next(&seeds, true)).collect();
        assert_eq!(a, b);
        let changed = a.iter().filter(|x| **x != seeds[0]).count();
        assert!(changed >= 45, "{changed} of 50 mutated");
        // the number mutation reaches the extreme values
        let hits = (0..500)
            .map(|_| String::from_utf8_lossy(&m.next(&seeds, true)).into_owned())
            .filter(|s| {
                EXTREMES
                    .iter()
                    .any(|e| s.contains(&format!("points = {e}\n")))
            })
            .count();
        assert!(hits >= 10, "{hits} of 500 with an extreme value");
    }
}
