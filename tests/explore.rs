//! `pradar explore`: the design-space grid end to end — same bytes with 1 and 2 threads,
//! bad inputs as one line, and (ignored, slow) the must-shows: F1 and walls found
//! rise with N on the corridor and the office for both mappers in every seed, pulses at a
//! low transmit power rise and saturate, and the default grid's benchmark.

use crate::common;

use common::{assert_one_line_error, path_str as s, root};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn explore(out: &Path, threads: usize, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pradar"))
        .arg("explore")
        .args(["--out", s(out)])
        .args(args)
        .arg("--quiet")
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .unwrap()
}

fn corridor() -> PathBuf {
    root().join("data/corridor/campaign.toml")
}

fn office() -> PathBuf {
    root().join("data/tests/office.toml")
}

/// `explore.csv` as (header → column index, rows of fields).
fn rows(dir: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(dir.join("explore.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (head, rows)
}

/// The value of column `name` in row `r` as a number.
fn num(head: &[String], r: &[String], name: &str) -> f64 {
    let i = head.iter().position(|h| h == name).unwrap();
    r[i].parse().unwrap()
}

/// The rows' (elements, pulses, mapper, seed) → (F1, walls found) at tx power `tx`.
fn scores(dir: &Path) -> Vec<(usize, usize, String, u64, f64, f64, f64)> {
    let (h, rs) = rows(dir);
    let mi = h.iter().position(|x| x == "mapper").unwrap();
    rs.iter()
        .map(|r| {
            (
                num(&h, r, "elements") as usize,
                num(&h, r, "pulses") as usize,
                r[mi].clone(),
                num(&h, r, "seed") as u64,
                num(&h, r, "f1_1"),
                num(&h, r, "walls_found_1"),
                num(&h, r, "step_deg"),
            )
        })
        .collect()
}

#[test]
fn same_bytes_with_one_and_two_threads() {
    // N = 16 at 10° plus the paper's setting (added), one seed: two jobs
    let tmp = tempfile::tempdir().unwrap();
    let c = corridor();
    let args = [
        "--campaign",
        s(&c),
        "--elements",
        "16",
        "--pulses",
        "1",
        "--step-deg",
        "10",
        "--seeds",
        "1",
    ];
    let (a, b) = (tmp.path().join("t1"), tmp.path().join("t2"));
    for (dir, t) in [(&a, 1), (&b, 2)] {
        let o = explore(dir, t, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for f in [
        "explore.csv",
        "explore.md",
        "summary.csv",
        "index.html",
        "pareto_og.png",
        "heatmap_og.png",
    ] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs between 1 and 2 threads");
    }
    let (h, rs) = rows(&a);
    assert_eq!(rs.len(), 2, "N = 16 at 10° and the paper's 400 at 5°");
    // the energy model: 19 directions of one 50 µs pulse (+1 µs switching) for N = 16
    let scan = num(&h, &rs[0], "scan_time_s");
    assert!((scan - 19.0 * 51e-6).abs() < 1e-12, "{scan}");
    assert_eq!(num(&h, &rs[1], "elements"), 400.0);
    let index = std::fs::read_to_string(a.join("index.html")).unwrap();
    assert!(index.contains("cheapest within 5 %"), "{index}");
    assert!(
        !a.join("work").join("n16_p1_s10_b6_t0_seed1").exists(),
        "job folder removed"
    );
}

#[test]
fn bad_inputs_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let c = corridor();
    let o = explore(&out, 1, &["--campaign", s(&c), "--elements", "20"]);
    assert_one_line_error(&o, "--elements");
    let o = explore(&out, 1, &["--campaign", s(&c), "--step-deg", "7"]);
    assert_one_line_error(&o, "--step-deg");
    let o = explore(&out, 1, &["--campaign", s(&c), "--pulses", "0"]);
    assert_one_line_error(&o, "--pulses");
    let o = explore(&out, 1, &["--data", "model"]);
    assert_one_line_error(&o, "--model");
    // the default grid against a tiny budget: refused after the probe, with its estimate
    let o = explore(&out, 1, &["--campaign", s(&c), "--max-minutes", "0.01"]);
    assert_one_line_error(&o, "--max-minutes");
    assert!(String::from_utf8_lossy(&o.stderr).contains("estimated at"));
    assert!(!out.join("explore.csv").exists());
}

/// In every seed and for both mappers, F1 and walls found at N = 16 below N = 100.
fn rises_with_n(campaign: &Path) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let o = explore(
        &out,
        2,
        &[
            "--campaign",
            s(campaign),
            "--elements",
            "16,100",
            "--pulses",
            "1",
            "--step-deg",
            "5",
            "--mapper",
            "og,ekf",
            "--seeds",
            "1,2,3",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sc = scores(&out);
    let mut failed = Vec::new();
    for m in ["og", "ekf"] {
        for seed in [1, 2, 3] {
            let at = |n: usize| {
                sc.iter()
                    .find(|r| r.0 == n && r.2 == m && r.3 == seed && r.6 == 5.0)
                    .unwrap()
                    .clone()
            };
            let (a, b) = (at(16), at(100));
            eprintln!(
                "{m} seed {seed}: F1 {:.3} -> {:.3}, walls {:.3} -> {:.3}",
                a.4, b.4, a.5, b.5
            );
            if !(a.4 < b.4 && a.5 < b.5) {
                failed.push(format!("{m} seed {seed}"));
            }
        }
    }
    assert!(failed.is_empty(), "N = 16 not below N = 100 in: {failed:?}");
}

// ~5 min on 2 busy cores (12 maps and 6 simulations)
#[test]
#[ignore]
fn corridor_f1_and_walls_rise_with_n() {
    rises_with_n(&corridor());
}

// ~5 min on 2 busy cores
#[test]
#[ignore]
fn office_f1_and_walls_rise_with_n() {
    rises_with_n(&office());
}

/// At N = 100 and a low transmit power (SNR-limited), the mean F1 over seeds rises from 1
/// to 8 pulses and saturates: the last doubling gains less than the first.
fn pulses_saturate(campaign: &Path, tx_dbm: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let o = explore(
        &out,
        2,
        &[
            "--campaign",
            s(campaign),
            "--elements",
            "100",
            "--pulses",
            "1,2,4,8",
            "--step-deg",
            "5",
            "--tx-power-dbm",
            tx_dbm,
            "--seeds",
            "1,2,3",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sc = scores(&out);
    let mean = |p: usize, walls: bool| {
        let v: Vec<f64> = (sc.iter())
            .filter(|r| r.0 == 100 && r.1 == p)
            .map(|r| if walls { r.5 } else { r.4 })
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    for walls in [false, true] {
        let m: Vec<f64> = [1, 2, 4, 8].iter().map(|&p| mean(p, walls)).collect();
        eprintln!(
            "{} over pulses 1, 2, 4, 8: {m:?}",
            if walls { "walls" } else { "F1" }
        );
        assert!(m[3] > m[0], "no rise: {m:?}");
        assert!(m[3] - m[2] < m[1] - m[0], "no saturation: {m:?}");
    }
}

// ~6 min on 2 busy cores
#[test]
#[ignore]
fn corridor_pulses_rise_and_saturate_at_low_power() {
    pulses_saturate(&corridor(), "-50");
}

// ~6 min on 2 busy cores
#[test]
#[ignore]
fn office_pulses_rise_and_saturate_at_low_power() {
    pulses_saturate(&office(), "-50");
}

// the benchmark: the default grid (6 N × 4 pulses × 3 steps, 3 seeds, OG) on the corridor;
// ≤ 15 min on 2 cores (figure in the README and docs/explore.md)
#[test]
#[ignore]
fn default_grid_on_the_corridor_within_15_minutes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let c = corridor();
    let t = std::time::Instant::now();
    let o = explore(&out, 2, &["--campaign", s(&c)]);
    let secs = t.elapsed().as_secs_f64();
    eprintln!(
        "default grid: {secs:.0} s; {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(rows(&out).1.len(), 6 * 4 * 3 * 3);
    assert!(secs <= 900.0, "{secs:.0} s");
}
