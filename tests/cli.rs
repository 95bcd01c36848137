//! End-to-end tests of the `pradar` binary: bad input gives one clear line and a non-zero
//! exit (never a panic, never a partial output), determinism across thread counts, formats.

use crate::common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pradar"))
}

struct Out {
    code: i32,
    stderr: String,
}

fn run(args: &[&str], threads: Option<&str>) -> Out {
    let mut c = bin();
    c.args(args).arg("--quiet");
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t);
    }
    let o = c.output().unwrap();
    Out {
        code: o.status.code().unwrap_or(-1),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A small simulated campaign (2 positions, 401 points) in `dir`; returns the manifest.
fn small_sim(dir: &Path, format: &str, threads: Option<&str>) -> PathBuf {
    let mut t = corridor();
    set(&mut t, "band.points", 401i64);
    set(&mut t, "processing.max_delay_ns", 45.0);
    set(&mut t, "processing.noise_from_ns", 50.0);
    let poses = t["poses"].as_array().unwrap()[..2].to_vec();
    t.insert("poses".into(), poses.into());
    let m = write_campaign(&dir.join("in"), &t);
    let o = run(
        &[
            "simulate",
            "--campaign",
            s(&m),
            "--out",
            s(&dir.join("sim")),
            "--format",
            format,
            "--elements",
            "100",
        ],
        threads,
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    dir.join("sim/campaign.toml")
}

fn assert_clean_error(o: &Out, must_name: &str, out: &Path) {
    assert_ne!(o.code, 0, "expected failure");
    assert!(!o.stderr.contains("panicked"), "panic: {}", o.stderr);
    let lines: Vec<&str> = o.stderr.trim().lines().collect();
    assert_eq!(lines.len(), 1, "one line expected: {}", o.stderr);
    assert!(lines[0].starts_with("error: "), "{}", lines[0]);
    assert!(
        lines[0].contains(must_name),
        "error should name `{must_name}`: {}",
        lines[0]
    );
    assert!(
        !out.exists(),
        "partial output {} left behind",
        out.display()
    );
    let parent = out.parent().unwrap();
    if parent.is_dir() {
        for e in std::fs::read_dir(parent).unwrap() {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            assert!(!n.contains(".tmp"), "temp file {n} left behind");
        }
    }
}

fn first_sweep(dir: &Path) -> PathBuf {
    dir.join("sim/sweeps/p000_d00_k00.s2p")
}

#[test]
fn bad_sweep_files_give_one_clear_line() {
    let tmp = tempfile::tempdir().unwrap();
    let m = small_sim(tmp.path(), "touchstone", None);
    let out = tmp.path().join("out/energy.parquet");
    let f = first_sweep(tmp.path());
    let good = std::fs::read_to_string(&f).unwrap();
    // truncated: cut in the middle of a data row
    std::fs::write(&f, &good[..good.len() / 2]).unwrap();
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, "p000_d00_k00.s2p", &out);
    // NaN in a value
    let lines: Vec<String> = good.lines().map(String::from).collect();
    let mut bad = lines.clone();
    let i = bad
        .iter()
        .position(|l| !l.starts_with('!') && !l.starts_with('#'))
        .unwrap()
        + 3;
    let mut toks: Vec<String> = bad[i].split_whitespace().map(String::from).collect();
    toks[3] = "NaN".into();
    bad[i] = toks.join(" ");
    std::fs::write(&f, bad.join("\n")).unwrap();
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, &format!("line {}", i + 1), &out);
    // garbage number
    toks[3] = "0.1.2".into();
    bad[i] = toks.join(" ");
    std::fs::write(&f, bad.join("\n")).unwrap();
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, "cannot parse", &out);
    // wrong band: shift every frequency by 1 GHz
    let shifted: Vec<String> = lines
        .iter()
        .map(|l| {
            if l.starts_with('!') || l.starts_with('#') {
                return l.clone();
            }
            let mut t: Vec<String> = l.split_whitespace().map(String::from).collect();
            let fr: f64 = t[0].parse().unwrap();
            t[0] = format!("{:.0}", fr + 1e9);
            t.join(" ")
        })
        .collect();
    std::fs::write(&f, shifted.join("\n")).unwrap();
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, "does not match [band]", &out);
    // missing sweep file
    std::fs::remove_file(&f).unwrap();
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, "p000_d00_k00.s2p", &out);
}

#[test]
fn bad_manifests_give_one_clear_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sim");
    // layout file missing
    let mut t = corridor();
    set(&mut t, "layout", "nowhere.geojson");
    let dir = tmp.path().join("a");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("campaign.toml"), toml::to_string(&t).unwrap()).unwrap();
    let o = run(
        &[
            "simulate",
            "--campaign",
            s(&dir.join("campaign.toml")),
            "--out",
            s(&out),
        ],
        None,
    );
    assert_clean_error(&o, "layout", &out);
    // layout key missing altogether
    let mut t = corridor();
    t.remove("layout");
    let m = write_campaign(&tmp.path().join("b"), &{
        let mut t2 = t.clone();
        t2.insert("layout".into(), "layout.geojson".into());
        t2
    });
    std::fs::write(&m, toml::to_string(&t).unwrap()).unwrap();
    let o = run(&["simulate", "--campaign", s(&m), "--out", s(&out)], None);
    assert_clean_error(&o, "layout", &out);
    // bad field values
    for (key, val, name) in [
        ("array.elements", toml::Value::Integer(50), "array.elements"),
        ("band.points", toml::Value::String("many".into()), "points"),
        (
            "processing.oversample",
            toml::Value::Integer(4),
            "processing.oversample",
        ),
        (
            "scene.scatterers_per_cell",
            toml::Value::Float(2.0),
            "scene.scatterers_per_cell",
        ),
        (
            "clutter.ray_decay.unit",
            toml::Value::String("s".into()),
            "ray_decay.unit",
        ),
    ] {
        let mut t = corridor();
        set(&mut t, key, val);
        let m = write_campaign(&tmp.path().join(name.replace('.', "_")), &t);
        let o = run(&["simulate", "--campaign", s(&m), "--out", s(&out)], None);
        assert_ne!(o.code, 0, "{key}");
        assert!(o.stderr.contains("campaign.toml"), "{key}: {}", o.stderr);
        assert_clean_error(&o, name, &out.join("campaign.toml"));
    }
    // --elements not a square
    let m = write_campaign(&tmp.path().join("c"), &corridor());
    let o = run(
        &[
            "simulate",
            "--campaign",
            s(&m),
            "--out",
            s(&out),
            "--elements",
            "50",
        ],
        None,
    );
    assert_clean_error(&o, "--elements", &out.join("campaign.toml"));
    // energy on a manifest without [sweeps]
    let e = tmp.path().join("e.parquet");
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&e)], None);
    assert_clean_error(&o, "[sweeps]", &e);
}

fn tree_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                v.push((
                    p.strip_prefix(dir).unwrap().display().to_string(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    v.sort();
    v
}

#[test]
fn same_seed_same_bytes_with_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let mut trees = Vec::new();
    for (i, th) in ["1", "2"].iter().enumerate() {
        let d = tmp.path().join(format!("t{i}"));
        let m = small_sim(&d, "parquet", Some(th));
        let o = run(
            &[
                "energy",
                "--campaign",
                s(&m),
                "--out",
                s(&d.join("sim/energy.parquet")),
            ],
            Some(th),
        );
        assert_eq!(o.code, 0, "{}", o.stderr);
        let mut t = tree_bytes(&d.join("sim"));
        // the manifest records the source path, which differs between the two runs
        t.retain(|(n, _)| n != "campaign.toml");
        trees.push(t);
    }
    assert_eq!(trees[0].len(), trees[1].len());
    for (a, b) in trees[0].iter().zip(&trees[1]) {
        assert_eq!(a.0, b.0);
        assert!(a.1 == b.1, "{} differs between 1 and 2 threads", a.0);
    }
}

#[test]
fn touchstone_and_parquet_sweeps_give_the_same_energy() {
    let tmp = tempfile::tempdir().unwrap();
    let mut e = Vec::new();
    for f in ["touchstone", "parquet"] {
        let d = tmp.path().join(f);
        let m = small_sim(&d, f, None);
        let out = d.join("energy.parquet");
        let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
        assert_eq!(o.code, 0, "{}", o.stderr);
        e.push(pradar::energy::EnergyMatrix::read(&out).unwrap());
    }
    let peak = e[0].data.iter().cloned().fold(0.0, f64::max);
    let worst = e[0]
        .data
        .iter()
        .zip(&e[1].data)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // Touchstone prints 12 significant digits
    assert!(
        worst <= 1e-9 * peak,
        "max difference {worst:e} vs peak {peak:e}"
    );
    assert_eq!(e[0].meta.bin_width_ns, e[1].meta.bin_width_ns);
}

#[test]
fn energy_parquet_is_read_by_pandas() {
    let tmp = tempfile::tempdir().unwrap();
    let m = small_sim(tmp.path(), "touchstone", None);
    let out = tmp.path().join("energy.parquet");
    let o = run(&["energy", "--campaign", s(&m), "--out", s(&out)], None);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let py = python()
        .arg(root().join("scripts/read_energy.py"))
        .arg(&out)
        .output();
    match py {
        Ok(r) if r.status.success() => {
            let text = String::from_utf8_lossy(&r.stdout);
            eprintln!("{text}");
            assert!(text.starts_with("ok rows="), "{text}");
            assert!(text.contains("positions=2 directions=37"), "{text}");
        }
        Ok(r) if skip_python() => {
            eprintln!("skipped (PRADAR_SKIP_PYTHON=1): {}", String::from_utf8_lossy(&r.stderr));
        }
        Err(e) if skip_python() => eprintln!("skipped (PRADAR_SKIP_PYTHON=1): {e}"),
        Ok(r) => panic!(
            "pandas could not read the energy table (run scripts/test, which makes a venv with numpy pandas pyarrow; or set PRADAR_PYTHON, or PRADAR_SKIP_PYTHON=1): {}{}",
            String::from_utf8_lossy(&r.stdout),
            String::from_utf8_lossy(&r.stderr)
        ),
        Err(e) => panic!("no Python interpreter (PRADAR_PYTHON or python3; run scripts/test): {e}"),
    }
}

/// The point-target room: the fit leaves quantities not estimable and writes their stated
/// values, so the experiments run on the model as it is and Table 1 says which values are
/// stated. The same room with nothing in it: no quantity can be fitted, so the experiments
/// do not run, and the sweeps `reproduce` makes for them beside the fit are removed again.
#[test]
fn reproduce_without_experiments_leaves_no_experiment_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("rep");
    let m = concat!(env!("CARGO_MANIFEST_DIR"), "/data/tests/point_target.toml");
    let o = run(
        &[
            "reproduce",
            "--out",
            s(&out),
            "--campaign",
            m,
            "--seeds",
            "1",
        ],
        None,
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("(stated)"), "Table 1 names the stated values");
    assert!(out.join("experiments").is_dir(), "the experiments run");
    let mut empty = fixture("tests/point_target.toml");
    empty["scene"].as_table_mut().unwrap().remove("targets");
    let m = write_campaign(&tmp.path().join("empty"), &empty);
    let out = tmp.path().join("rep_empty");
    let o = run(&["reproduce", "--out", s(&out), "--campaign", s(&m)], None);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("not run"),
        "the experiments should not run here"
    );
    assert!(!out.join("experiments").exists());
}

#[test]
fn reproduce_writes_the_report() {
    let tmp = tempfile::tempdir().unwrap();
    let mut t = corridor();
    set(&mut t, "band.points", 401i64);
    set(&mut t, "processing.max_delay_ns", 45.0);
    set(&mut t, "processing.noise_from_ns", 50.0);
    let poses = t["poses"].as_array().unwrap()[..6].to_vec();
    t.insert("poses".into(), poses.into());
    let m = write_campaign(&tmp.path().join("in"), &t);
    let out = tmp.path().join("rep");
    let o = run(
        &[
            "reproduce",
            "--out",
            s(&out),
            "--campaign",
            s(&m),
            "--seeds",
            "1",
        ],
        None,
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for p in 0..3 {
        let png = format!("energy_p{p:02}.png");
        assert!(html.contains(&png));
        let bytes = std::fs::read(out.join(&png)).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
    assert!(html.contains("Stage timings") && html.contains("simulate"));
    // the K chosen per position and Table 1 against K_max: the default row, one row per
    // larger cap (2× and 3× the default), the truth row; every position's K at most its
    // row's cap
    assert!(html.contains("K chosen per position"));
    let kmax = std::fs::read_to_string(out.join("table1_kmax.md")).unwrap();
    let rows: Vec<&str> = kmax.lines().filter(|l| l.starts_with("| ")).collect();
    assert_eq!(rows.len(), 5, "{kmax}");
    for (row, cap) in rows[1..4].iter().zip([16usize, 32, 48]) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert!(cells[1].starts_with(&cap.to_string()), "{row}");
        let hi: usize = cells[2].split(['–', ' ']).nth(1).unwrap().parse().unwrap();
        assert!(hi <= cap, "{row}");
        // the positions whose K moved against the default: a count
        let _: usize = cells[3].parse().unwrap();
    }
    assert!(rows[4].contains("simulator truth"));
    // the experiments' sections, each with its panel and table
    for e in ["fig5", "fig6", "prior-sensitivity", "pose-noise"] {
        let png = format!("experiments/{e}/{e}.png");
        assert!(
            html.contains(&png),
            "{e} section missing: {}",
            html.split("failed")
                .nth(1)
                .unwrap_or("")
                .chars()
                .take(300)
                .collect::<String>()
        );
        assert_eq!(&std::fs::read(out.join(&png)).unwrap()[1..4], b"PNG");
        assert!(out.join(format!("experiments/{e}/{e}.md")).is_file());
    }
}

#[test]
fn unknown_command_fails_cleanly() {
    let o = bin().arg("frobnicate").output().unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("panicked"));
}

/// Every out-of-range or unknown flag value: one `error:` line naming the flag, exit status
/// 1, no panic, nothing written, and no work started (the inputs need not exist).
#[test]
fn out_of_range_flags_give_one_clear_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = s(&out);
    let corridor = root().join("data/corridor/campaign.toml");
    let c = s(&corridor);
    let map = ["map", "--campaign", c, "--energy", "e.parquet", "--out", o];
    let extract = [
        "extract",
        "--energy",
        "e.parquet",
        "--campaign",
        c,
        "--out",
        o,
    ];
    let cluster = ["cluster", "--mpcs", "m.parquet", "--out", o];
    let fit = [
        "fit",
        "--clusters",
        "c.parquet",
        "--campaign",
        c,
        "--out",
        o,
        "--table",
        "t.md",
    ];
    let simulate = ["simulate", "--campaign", c, "--out", o];
    let synth = [
        "synth",
        "--model",
        "nowhere.toml",
        "--campaign",
        c,
        "--out",
        o,
    ];
    let reproduce = ["reproduce", "--out", o];
    let experiment = ["experiment", "fig5", "--out", o];
    let calibrate = [
        "calibrate",
        "--energy",
        "e.parquet",
        "--campaign",
        c,
        "--out",
        o,
    ];
    let cases: Vec<(&[&str], &[&str], &str)> = vec![
        (&fit, &["--bootstrap", "0"], "--bootstrap"),
        (&cluster, &["--k-max", "0"], "--k-max"),
        (&cluster, &["--k-max", "-2"], "--k-max"),
        (&cluster, &["--criterion", "best"], "--criterion"),
        (&map, &["--cell-m", "0"], "--cell-m"),
        (&map, &["--cell-m", "20"], "--cell-m"),
        (&map, &["--pfa", "0"], "--pfa"),
        (&map, &["--pfa", "1.5"], "--pfa"),
        (&map, &["--prior", "0"], "--prior"),
        (&map, &["--prior", "1"], "--prior"),
        (&map, &["--mu0", "-1"], "--mu0"),
        (&map, &["--sigma0", "0"], "--sigma0"),
        (&map, &["--pose-noise-m", "-1"], "--pose-noise-m"),
        (&map, &["--pose-noise-deg", "NaN"], "--pose-noise-deg"),
        (&map, &["--ekf", "sparse"], "--ekf"),
        (&map, &["--method", "ogb"], "--method"),
        (&map, &["--og-credit-depth", "-1"], "--og-credit-depth"),
        (&map, &["--og-credit-depth", "nan"], "--og-credit-depth"),
        (&map, &["--og-bound-silent", "maybe"], "--og-bound-silent"),
        (&map, &["--og-credit", "arc"], "--og-credit"),
        (&calibrate, &["--ridge", "lasso"], "--ridge"),
        (
            &calibrate,
            &["--no-walls", "--prior", "p.toml"],
            "--no-walls",
        ),
        (&extract, &["--margin-db", "-1"], "--margin-db"),
        (&extract, &["--margin-db", "inf"], "--margin-db"),
        (&extract, &["--dynamic-range-db", "0"], "--dynamic-range-db"),
        (&extract, &["--method", "music"], "--method"),
        (&simulate, &["--elements", "7"], "--elements"),
        (&simulate, &["--format", "csv"], "--format"),
        (&synth, &["--elements", "7"], "--elements"),
        (&reproduce, &["--seeds", ""], "--seeds"),
        (&experiment, &["--seeds", ""], "--seeds"),
        (&experiment, &["--seeds", "1,1"], "seeds"),
    ];
    for (cmd, flag, name) in cases {
        let args: Vec<&str> = cmd.iter().chain(flag).copied().collect();
        let r = run(&args, None);
        assert_eq!(r.code, 1, "{args:?}: {}", r.stderr);
        assert_clean_error(&r, name, &out);
    }
    // an unknown experiment: named, before any input is resolved
    let r = run(&["experiment", "fig7", "--out", o], None);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert_clean_error(&r, "fig7", &out);
}
