//! Kill safety (issue 20): `energy` and `reproduce --skip-experiments` are killed with
//! SIGKILL at seeded random moments of their run and then rerun to completion. After the
//! rerun no temp file (`.NAME.tmpPID`) is left anywhere in the output folder, and every
//! output is byte-identical to that of an uninterrupted run — except the wall-clock
//! timings the report records (stage times in `index.html`, `*seconds` in the maps'
//! `metrics.json`), compared with the timings removed.

use crate::common::{corridor, set, write_campaign};
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Every file under `dir`: relative path → bytes (timings stripped from HTML pages).
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let mut b = std::fs::read(&p).unwrap();
                if p.extension().is_some_and(|e| e == "html") {
                    b = strip_timings(&String::from_utf8_lossy(&b)).into_bytes();
                }
                if p.extension().is_some_and(|e| e == "json") {
                    let text = String::from_utf8_lossy(&b);
                    let kept: Vec<&str> =
                        text.lines().filter(|l| !l.contains("seconds\":")).collect();
                    b = kept.join("\n").into_bytes();
                }
                out.insert(p.strip_prefix(root).unwrap().to_path_buf(), b);
            }
        }
    }
    let mut out = BTreeMap::new();
    if dir.exists() {
        walk(dir, dir, &mut out);
    }
    out
}

/// An HTML page with every number followed by ` s` (a wall time) replaced by `T`.
fn strip_timings(html: &str) -> String {
    let mut out = String::with_capacity(html.len());
    let b = html.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
                j += 1;
            }
            let rest = &html[j..];
            if rest.starts_with(" s") && !rest[2..].starts_with(|c: char| c.is_alphanumeric()) {
                out.push('T');
            } else {
                out.push_str(&html[i..j]);
            }
            i = j;
        } else {
            let c = html[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

fn temp_files(dir: &Path) -> Vec<PathBuf> {
    contents(dir)
        .into_keys()
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with('.') && n.contains(".tmp"))
        })
        .collect()
}

fn command(args: &[&str]) -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"));
    c.args(args).arg("--quiet");
    c
}

/// Run `args` to completion; its wall time.
fn complete(args: &[&str]) -> Duration {
    let t = Instant::now();
    let o = command(args).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    t.elapsed()
}

/// Kill `args` after each of `kills` seeded delays in (0, `span`), rerunning to completion
/// after each kill; the output folder `out` must then hold no temp file and `reference`.
fn kill_and_rerun(
    args: &[&str],
    out: &Path,
    reference: &BTreeMap<PathBuf, Vec<u8>>,
    span: Duration,
    kills: usize,
    seed: u64,
) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for k in 0..kills {
        let delay = span.mul_f64(rng.gen_range(0.05..0.95));
        let mut child = command(args).spawn().unwrap();
        std::thread::sleep(delay);
        // SIGKILL (std's kill on unix); a run that ended first is fine
        let _ = child.kill();
        let _ = child.wait();
        complete(args);
        let temps = temp_files(out);
        assert!(temps.is_empty(), "kill {k} after {delay:?}: {temps:?} left");
        let now = contents(out);
        let differ: Vec<_> = (now.keys().chain(reference.keys()))
            .filter(|p| now.get(*p) != reference.get(*p))
            .collect();
        assert!(
            differ.is_empty(),
            "kill {k} after {delay:?}: {differ:?} differ"
        );
    }
}

/// A corridor of 4 poses and 16 elements, simulated (Touchstone) into `dir/sim`.
fn small_campaign(dir: &Path) -> PathBuf {
    let mut t = corridor();
    set(&mut t, "array.elements", 16);
    let poses = t["poses"].as_array().unwrap()[..4].to_vec();
    t.insert("poses".into(), toml::Value::Array(poses));
    write_campaign(&dir.join("in"), &t)
}

#[test]
fn energy_killed_at_random_moments_then_rerun_is_byte_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let man = small_campaign(tmp.path());
    let sim = tmp.path().join("sim");
    let m = man.to_str().unwrap();
    complete(&["simulate", "--campaign", m, "--out", sim.to_str().unwrap()]);
    let out = tmp.path().join("out");
    let e = out.join("energy.parquet");
    let sim_m = sim.join("campaign.toml");
    let args = [
        "energy",
        "--campaign",
        sim_m.to_str().unwrap(),
        "--out",
        e.to_str().unwrap(),
    ];
    let span = complete(&args);
    let reference = contents(&out);
    std::fs::remove_dir_all(&out).unwrap();
    kill_and_rerun(&args, &out, &reference, span, 4, 11);
    // a temp left by a killed run of an earlier process is removed by the next run
    let stale = out.join(".energy.parquet.tmp4194305");
    std::fs::write(&stale, b"partial").unwrap();
    complete(&args);
    assert!(!stale.exists());
    assert_eq!(contents(&out), reference);
}

#[test]
#[ignore = "about 1-2 min: 6 kills of reproduce on a 4-pose campaign; the test suite runs the 2-kill variant"]
fn reproduce_killed_six_times_then_rerun_is_byte_identical() {
    reproduce_kills(6, 5);
}

#[test]
fn reproduce_killed_twice_then_rerun_is_byte_identical() {
    reproduce_kills(2, 3);
}

fn reproduce_kills(kills: usize, seed: u64) {
    let tmp = tempfile::tempdir().unwrap();
    let man = small_campaign(tmp.path());
    let out = tmp.path().join("report");
    let args = [
        "reproduce",
        "--campaign",
        man.to_str().unwrap(),
        "--skip-experiments",
        "--out",
        out.to_str().unwrap(),
    ];
    let span = complete(&args);
    let reference = contents(&out);
    std::fs::remove_dir_all(&out).unwrap();
    kill_and_rerun(&args, &out, &reference, span, kills, seed);
}
