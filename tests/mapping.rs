//! Grid mapping I (issue 5): metrics on hand-made maps, map files read back by an independent
//! reader, the side-lobe ghost, the corridor at N = 16 and 100, fusion of two trajectories,
//! determinism across thread counts and bad input. Every figure asserted is printed.

use crate::common;

use common::*;
use pradar::campaign::manifest::{Campaign, SweepFormat};
use pradar::energy;
use pradar::mapping::job::{load_run, LoadedRun, MapRun};
use pradar::mapping::metrics::{evaluate, psi};
use pradar::mapping::og::{fuse, og_map, sigmoid, LogOddsMap, Method, OgParams};
use pradar::mapping::output::{soft_grey, write_map_files};
use pradar::mapping::reference::LayoutRaster;
use pradar::mapping::score::{observable_region, score};
use pradar::params::ParamGuard;
use pradar::simulate::simulate;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

// ---------------------------------------------------------------- helpers

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Simulate (Parquet sweeps) and compute the energy table; returns (manifest, energy).
fn sim_chain(dir: &Path, t: &toml::Table, elements: Option<usize>) -> (PathBuf, PathBuf) {
    let m = write_campaign(&dir.join("in"), t);
    let mut c = Campaign::load(&m).unwrap();
    if let Some(n) = elements {
        c.set_elements(n).unwrap();
    }
    let sim = simulate(&c, &dir.join("sim"), SweepFormat::Parquet, &|_, _| {}).unwrap();
    let sc = Campaign::load(&sim.manifest).unwrap();
    let e = dir.join("energy.parquet");
    energy::run(&sc, &e, &|_, _| {}).unwrap();
    (sim.manifest, e)
}

fn load(c: &Path, e: &Path) -> LoadedRun {
    let run = MapRun {
        campaign: c.to_path_buf(),
        energy: e.to_path_buf(),
    };
    load_run(
        &run,
        None,
        &pradar::mapping::GridParams::default().check().unwrap(),
        &OgParams::default().check().unwrap(),
        None,
    )
    .unwrap()
}

fn map(l: &LoadedRun, method: Method) -> LogOddsMap {
    og_map(
        &l.model,
        &l.energy,
        &OgParams::default().check().unwrap(),
        method,
        &l.detector,
        &|_, _| {},
    )
    .unwrap()
}

pub fn pradar(args: &[&str], threads: Option<&str>) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pradar"));
    c.args(args).arg("--quiet");
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t);
    }
    c.output().unwrap()
}

/// The corridor simulated once per test binary at N = 16 and N = 100:
/// (N, manifest, energy).
fn corridor_runs() -> &'static Vec<(usize, PathBuf, PathBuf)> {
    static RUNS: OnceLock<Vec<(usize, PathBuf, PathBuf)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mapping_corridor");
        [16usize, 100]
            .iter()
            .map(|&n| {
                let (m, e) = sim_chain(&dir.join(format!("n{n}")), &corridor(), Some(n));
                (n, m, e)
            })
            .collect()
    })
}

// ---------------------------------------------------------------- metrics

fn column_map(rows: usize, cols: usize, col: usize) -> Vec<bool> {
    (0..rows * cols).map(|i| i % cols == col).collect()
}

#[test]
fn psi_identical_maps_is_zero() {
    let (rows, cols) = (10, 12);
    let a = column_map(rows, cols, 4);
    let all = vec![true; rows * cols];
    let (p, po, pf) = psi(&a, &a, &all, rows, cols);
    eprintln!("identical: psi {p} (occupied {po}, free {pf})");
    assert_eq!(p, 0.0);
    let m = evaluate(&a, &a, &all, rows, cols);
    eprintln!(
        "identical: F1 {} wrong-cell rate {}",
        m.f1, m.wrong_cell_rate
    );
    assert_eq!(m.f1, 1.0);
    assert_eq!(m.wrong_cell_rate, 0.0);
}

#[test]
fn psi_one_cell_shift_has_the_known_value() {
    // an occupied column at col 4 vs col 5 on a 10 x 10 grid: occupied term 1 + 1; free term:
    // the 10 free cells of A at col 5 are 1 from B's free cells, and vice versa: 2·10/90
    let (rows, cols) = (10, 10);
    let a = column_map(rows, cols, 4);
    let b = column_map(rows, cols, 5);
    let all = vec![true; rows * cols];
    let (p, po, pf) = psi(&a, &b, &all, rows, cols);
    let want = 2.0 + 2.0 * 10.0 / 90.0;
    eprintln!("one-cell shift: psi {p} (occupied {po}, free {pf}), expected {want}");
    assert!((p - want).abs() < 1e-12);
    assert!((po - 2.0).abs() < 1e-12);
    let m = evaluate(&a, &b, &all, rows, cols);
    eprintln!(
        "one-cell shift: exact F1 {}, F1 within one cell {}, wrong-cell rate {}",
        m.f1, m.f1_1, m.wrong_cell_rate
    );
    assert_eq!(m.f1, 0.0);
    assert_eq!(m.f1_1, 1.0);
    assert!((m.wrong_cell_rate - 0.2).abs() < 1e-12);
    // a two-cell diagonal shift of a single cell: Manhattan distance 4 each way
    let mut c = vec![false; rows * cols];
    let mut d = vec![false; rows * cols];
    c[2 * cols + 2] = true;
    d[4 * cols + 4] = true;
    let (_, po, _) = psi(&c, &d, &all, rows, cols);
    eprintln!("single cell moved by (2, 2): occupied term {po} (expected 8)");
    assert_eq!(po, 8.0);
}

#[test]
fn psi_absent_class_counts_the_diameter() {
    let (rows, cols) = (10, 12);
    let all_free = vec![false; rows * cols];
    let b = column_map(rows, cols, 3);
    let all = vec![true; rows * cols];
    let (p, po, pf) = psi(&all_free, &b, &all, rows, cols);
    // free term: B's 10 occupied cells are 1 from a free cell of A... no: A→B: A's cells on
    // column 3 are 1 from B's free cells (10 of 120); B→A: 0
    let want_free = 10.0 / 120.0;
    eprintln!(
        "occupied class absent: psi {p} (occupied term {po}, expected rows + cols = {}; free {pf}, expected {want_free})",
        rows + cols
    );
    assert_eq!(po, (rows + cols) as f64);
    assert!((pf - want_free).abs() < 1e-12);
    // both classes absent in a region-restricted comparison where one map is all occupied
    let all_occ = vec![true; rows * cols];
    let (p2, po2, pf2) = psi(&all_occ, &all_free, &all, rows, cols);
    eprintln!("all-occupied vs all-free: psi {p2} ({po2} + {pf2})");
    assert_eq!(p2, 2.0 * (rows + cols) as f64);
}

#[test]
fn all_free_map_has_f1_zero() {
    let (rows, cols) = (8, 9);
    let reference = column_map(rows, cols, 2);
    let free = vec![false; rows * cols];
    let all = vec![true; rows * cols];
    let m = evaluate(&free, &reference, &all, rows, cols);
    eprintln!(
        "all-free: precision {} recall {} F1 {} F1(1 cell) {} wrong-cell rate {}",
        m.precision, m.recall, m.f1, m.f1_1, m.wrong_cell_rate
    );
    assert_eq!(m.f1, 0.0);
    assert_eq!(m.f1_1, 0.0);
    assert!((m.wrong_cell_rate - 8.0 / 72.0).abs() < 1e-12);
    // on a region that excludes the occupied column the all-free map is perfect but has no
    // occupied class in either map: the occupied term is the diameter
    let region: Vec<bool> = (0..rows * cols).map(|i| i % cols != 2).collect();
    let r = evaluate(&free, &reference, &region, rows, cols);
    eprintln!("all-free on a region without walls: psi {}", r.psi);
    assert_eq!(r.psi, (rows + cols) as f64);
}

// ---------------------------------------------------------------- files

/// Independent binary PGM (P5) reader: (width, height, maxval, pixels).
pub fn read_pgm(path: &Path) -> (usize, usize, usize, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if bytes[i] == b'#' {
            while bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let st = i;
        while !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        fields.push(String::from_utf8(bytes[st..i].to_vec()).unwrap());
    }
    i += 1; // single whitespace after maxval
    assert_eq!(fields[0], "P5");
    let (w, h, mx) = (
        fields[1].parse().unwrap(),
        fields[2].parse().unwrap(),
        fields[3].parse().unwrap(),
    );
    (w, h, mx, bytes[i..].to_vec())
}

fn yaml_field<'a>(text: &'a str, key: &str) -> &'a str {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{key}:")))
        .unwrap_or_else(|| panic!("missing {key}"))
        .trim()
}

#[test]
fn pgm_and_yaml_read_back_match_the_map() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = pradar::mapping::reference::GridSpec {
        x0_m: -1.25,
        y0_m: 2.5,
        cell_m: 0.1,
        cols: 7,
        rows: 5,
    };
    // a map with distinct values per cell, row 0 = lowest y
    let probs: Vec<f64> = (0..35)
        .map(|i| (i as f64 * 0.37).sin() * 0.5 + 0.5)
        .collect();
    let grey: Vec<u8> = probs.iter().map(|&p| soft_grey(p)).collect();
    write_map_files(tmp.path(), "m", &spec, &grey, 0.5, 0.45).unwrap();
    let (w, h, mx, px) = read_pgm(&tmp.path().join("m.pgm"));
    assert_eq!((w, h, mx, px.len()), (7, 5, 255, 35));
    let mut worst = 0.0f64;
    for r in 0..5 {
        for c in 0..7 {
            // image row 0 is the top (highest y) grid row
            let v = px[(4 - r) * 7 + c];
            assert_eq!(v, grey[r * 7 + c], "cell ({r}, {c})");
            let p_ros = (255.0 - v as f64) / 255.0;
            worst = worst.max((p_ros - probs[r * 7 + c]).abs());
        }
    }
    let y = std::fs::read_to_string(tmp.path().join("m.yaml")).unwrap();
    eprintln!("yaml:\n{y}max |p_map_server - p| = {worst:.5}");
    assert!(worst <= 0.5 / 255.0 + 1e-12);
    assert_eq!(yaml_field(&y, "image"), "m.pgm");
    assert_eq!(yaml_field(&y, "resolution").parse::<f64>().unwrap(), 0.1);
    assert_eq!(yaml_field(&y, "negate"), "0");
    assert_eq!(
        yaml_field(&y, "occupied_thresh").parse::<f64>().unwrap(),
        0.5
    );
    assert_eq!(yaml_field(&y, "free_thresh").parse::<f64>().unwrap(), 0.45);
    let origin: Vec<f64> = yaml_field(&y, "origin")
        .trim_matches(|c| c == '[' || c == ']')
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert_eq!(origin, vec![-1.25, 2.5, 0.0]);
    assert!(tmp.path().join("m.png").is_file());
}

// ---------------------------------------------------------------- ghost

#[test]
fn side_lobe_ghost_is_rejected_by_the_side_lobe_aware_map() {
    // nine poses along x heading east, beams -20..20 degrees (4x4 array, main lobe about
    // +-13 degrees): the strong reflector at (1, -3) is 72-108 degrees off the heading, so
    // it is only ever seen through side lobes; two weak targets ahead at 5 m
    let tmp = tempfile::tempdir().unwrap();
    let t = fixture("tests/ghost.toml");
    let (c, e) = sim_chain(tmp.path(), &t, None);
    let l = load(&c, &e);
    let spec = l.model.spec;
    let target = geo::Coord { x: 1.0, y: -3.0 };
    let cm = &l.campaign.manifest;
    // the ghost cells: on the boresight of every (pose, direction), at the reflector's range
    let mut ghosts = Vec::new();
    for pose in &cm.poses {
        let r = (target.x - pose.x_m).hypot(target.y - pose.y_m);
        for a in cm.directions.angles_deg() {
            let th = (pose.heading_deg + a).to_radians();
            let p = geo::Coord {
                x: pose.x_m + r * th.cos(),
                y: pose.y_m + r * th.sin(),
            };
            let (row, col) = spec.cell_of(p).unwrap();
            ghosts.push(row * spec.cols + col);
        }
    }
    ghosts.sort();
    ghosts.dedup();
    let (tr, tc) = spec.cell_of(target).unwrap();
    let mut res = Vec::new();
    for method in [Method::OgBoresight, Method::Og] {
        let m = map(&l, method);
        let pmax = ghosts
            .iter()
            .map(|&i| sigmoid(m.logodds[i]))
            .fold(0.0, f64::max);
        let above = ghosts
            .iter()
            .filter(|&&i| sigmoid(m.logodds[i]) > 0.5)
            .count();
        let ptarget = (tr.saturating_sub(1)..=tr + 1)
            .flat_map(|r| (tc - 1..=tc + 1).map(move |c| (r, c)))
            .map(|(r, c)| sigmoid(m.logodds[r * spec.cols + c]))
            .fold(0.0, f64::max);
        eprintln!(
            "{}: ghost cells {}: max p {pmax:.3}, {above} above 0.5; p at the reflector (3x3 max) {ptarget:.3}",
            method.name(),
            ghosts.len()
        );
        res.push(pmax);
    }
    assert!(res[0] > 0.5, "the boresight map should show the ghost");
    assert!(res[1] < 0.5, "the side-lobe-aware map should reject it");
}

// ---------------------------------------------------------------- corridor

pub fn metrics_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap()
}

pub fn fig(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut c = v;
    for p in path {
        c = &c[*p];
    }
    c.as_f64()
        .unwrap_or_else(|| panic!("{path:?} missing in metrics.json"))
}

#[test]
fn corridor_side_lobe_aware_beats_boresight_and_n100_beats_n16() {
    let tmp = tempfile::tempdir().unwrap();
    let mut psi_og = Vec::new();
    let mut f1_og = Vec::new();
    for (n, c, e) in corridor_runs() {
        let mut figs = Vec::new();
        for method in ["og", "og-boresight"] {
            let out = tmp.path().join(format!("{method}_{n}"));
            let o = pradar(
                &[
                    "map",
                    "--method",
                    method,
                    "--campaign",
                    s(c),
                    "--energy",
                    s(e),
                    "--out",
                    s(&out),
                ],
                None,
            );
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            for f in [
                format!("{method}.png"),
                format!("{method}.pgm"),
                format!("{method}.yaml"),
                format!("{method}_binary.png"),
                format!("{method}_binary.pgm"),
                format!("{method}_binary.yaml"),
                "reference.png".into(),
                "reference.pgm".into(),
                "reference.yaml".into(),
            ] {
                assert!(out.join(&f).is_file(), "{f} missing");
            }
            let j = metrics_json(&out);
            let g = |region: &str, k: &str| fig(&j, &["metrics", region, k]);
            eprintln!(
                "N={n} {method:>12}: observable psi {:.3} F1 {:.3} F1(1 cell) {:.3} wrong {:.3} | all-free psi {:.3} F1 {:.3} wrong {:.3} || whole psi {:.3} F1 {:.3} F1(1) {:.3} wrong {:.4} | all-free psi {:.3} F1 {:.3} wrong {:.4}",
                g("observable", "psi"),
                g("observable", "f1"),
                g("observable", "f1_1"),
                g("observable", "wrong_cell_rate"),
                g("observable_all_free", "psi"),
                g("observable_all_free", "f1"),
                g("observable_all_free", "wrong_cell_rate"),
                g("whole", "psi"),
                g("whole", "f1"),
                g("whole", "f1_1"),
                g("whole", "wrong_cell_rate"),
                g("whole_all_free", "psi"),
                g("whole_all_free", "f1"),
                g("whole_all_free", "wrong_cell_rate"),
            );
            // both maps beat the all-free map
            assert!(g("observable", "psi") < g("observable_all_free", "psi"));
            assert!(g("observable", "f1") > g("observable_all_free", "f1"));
            assert!(g("whole", "psi") < g("whole_all_free", "psi"));
            assert!(g("whole", "f1") > g("whole_all_free", "f1"));
            figs.push((g("observable", "psi"), g("observable", "f1")));
        }
        let ((og_psi, og_f1), (bs_psi, bs_f1)) = (figs[0], figs[1]);
        assert!(
            og_psi < bs_psi,
            "N={n}: og psi {og_psi} vs boresight {bs_psi}"
        );
        assert!(og_f1 > bs_f1, "N={n}: og F1 {og_f1} vs boresight {bs_f1}");
        psi_og.push(og_psi);
        f1_og.push(og_f1);
    }
    eprintln!("og psi: N=16 {:.3}, N=100 {:.3}", psi_og[0], psi_og[1]);
    eprintln!("og F1: N=16 {:.3}, N=100 {:.3}", f1_og[0], f1_og[1]);
    assert!(psi_og[1] < psi_og[0], "N = 100 should beat N = 16 on psi");
    assert!(f1_og[1] > f1_og[0], "N = 100 should beat N = 16 on F1");
}

#[test]
fn same_map_with_one_and_two_threads() {
    let (_, c, e) = &corridor_runs()[1];
    let l = load(c, e);
    let run = |threads: usize, method: Method| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| map(&l, method))
    };
    for method in [Method::Og, Method::OgBoresight] {
        let a = run(1, method);
        let b = run(2, method);
        let same = a
            .logodds
            .iter()
            .zip(&b.logodds)
            .all(|(x, y)| x.to_bits() == y.to_bits());
        eprintln!("{}: 1 vs 2 threads bit-identical: {same}", method.name());
        assert!(same);
    }
}

// ---------------------------------------------------------------- fusion

#[test]
fn two_trajectories_fused_beat_either_alone() {
    // short range (30 ns, 4.5 m): run A walks the west part heading east, run B the T-junction
    // heading north; neither sees the whole corridor
    let tmp = tempfile::tempdir().unwrap();
    let pose = |x: f64, y: f64, h: f64| {
        let mut t = toml::Table::new();
        t.insert("x_m".into(), x.into());
        t.insert("y_m".into(), y.into());
        t.insert("heading_deg".into(), h.into());
        toml::Value::Table(t)
    };
    let trajectories: [Vec<toml::Value>; 2] = [
        (0..5)
            .map(|i| pose(0.0 + 0.5 * i as f64, -0.3, 0.0))
            .collect(),
        (0..5)
            .map(|i| pose(7.8, -3.0 + 0.5 * i as f64, 90.0))
            .collect(),
    ];
    let mut runs = Vec::new();
    for (i, poses) in trajectories.iter().enumerate() {
        let mut t = corridor();
        set(&mut t, "processing.max_delay_ns", 30.0);
        t.insert("poses".into(), toml::Value::Array(poses.clone()));
        runs.push(sim_chain(&tmp.path().join(format!("r{i}")), &t, Some(100)));
    }
    // CLI: fused map with metrics vs number of runs and per run
    let out = tmp.path().join("fused");
    let ra = format!("{}={}", s(&runs[0].0), s(&runs[0].1));
    let rb = format!("{}={}", s(&runs[1].0), s(&runs[1].1));
    let o = pradar(
        &[
            "map",
            "--method",
            "og",
            "--run",
            &ra,
            "--run",
            &rb,
            "--out",
            s(&out),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j = metrics_json(&out);
    let single: Vec<f64> = (0..2)
        .map(|i| fig(&j["runs"][i], &["metrics", "observable", "psi"]))
        .collect();
    let single_f1: Vec<f64> = (0..2)
        .map(|i| fig(&j["runs"][i], &["metrics", "observable", "f1"]))
        .collect();
    let fused = fig(&j, &["metrics", "observable", "psi"]);
    let fused_f1 = fig(&j, &["metrics", "observable", "f1"]);
    let by_n: Vec<f64> = (0..2)
        .map(|i| fig(&j["fusion"][i], &["metrics", "observable", "psi"]))
        .collect();
    eprintln!(
        "fusion (observable = union of both runs' main-lobe coverage, {} cells): run A psi {:.3} F1 {:.3}, run B psi {:.3} F1 {:.3}, fused psi {fused:.3} F1 {fused_f1:.3}; psi vs runs {by_n:?}; all-free psi {:.3}",
        j["observable_cells"],
        single[0],
        single_f1[0],
        single[1],
        single_f1[1],
        fig(&j, &["metrics", "observable_all_free", "psi"])
    );
    assert!(fused < single[0] && fused < single[1]);
    assert_eq!(by_n[1], fused);
    // library: fused log-odds = l0 + sum of each run's evidence, exactly
    let loaded: Vec<LoadedRun> = runs.iter().map(|(c, e)| load(c, e)).collect();
    let maps: Vec<LogOddsMap> = loaded.iter().map(|l| map(l, Method::Og)).collect();
    let f = fuse(&maps).unwrap();
    let mut worst = 0.0f64;
    for i in 0..f.logodds.len() {
        let want =
            maps[0].l0 + (maps[0].logodds[i] - maps[0].l0) + (maps[1].logodds[i] - maps[1].l0);
        assert_eq!(f.logodds[i].to_bits(), want.to_bits(), "cell {i}");
        worst = worst.max((f.logodds[i] - maps[0].logodds[i] - maps[1].logodds[i]).abs());
    }
    eprintln!("fused log-odds == l0 + sum(l_run - l0) on all {} cells (prior 0.5: |fused - l_A - l_B| max {worst:e})", f.logodds.len());
    assert_eq!(worst, 0.0);
    // and the library's scores agree with the CLI's
    let reference = loaded[0].layout.rasterize(0.1, 0.5);
    let region = pradar::mapping::score::Regions {
        observable: observable_region(&[&loaded[0].model, &loaded[1].model], &loaded[0].layout),
        building: pradar::mapping::score::building_region(&loaded[0].layout, &reference),
        objects: None,
        edge_band: Vec::new(),
        detectable: None,
    };
    let sc = score(&f, &reference, &region);
    assert!((sc.observable.psi - fused).abs() < 1e-12);
}

// ---------------------------------------------------------------- bad input

#[test]
fn bad_input_gives_one_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let t = fixture("tests/ghost.toml");
    let (c, e) = sim_chain(&tmp.path().join("g"), &t, None);
    let out = tmp.path().join("out");
    let map_args = |c: &Path, e: &Path| {
        vec![
            "map".to_string(),
            "--campaign".into(),
            s(c).into(),
            "--energy".into(),
            s(e).into(),
            "--out".into(),
            s(&out).into(),
        ]
    };
    let call = |args: Vec<String>| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        pradar(&a, None)
    };
    // energy from another campaign: other poses
    let mut other = t.clone();
    let poses = other["poses"].as_array().unwrap()[..4].to_vec();
    other.insert("poses".into(), poses.into());
    let oc = write_campaign(&tmp.path().join("other_poses"), &other);
    let o = call(map_args(&oc, &e));
    assert_one_line_error(&o, "energy.parquet");
    assert!(String::from_utf8_lossy(&o.stderr).contains("another campaign"));
    // other directions (same count)
    let mut other = t.clone();
    set(&mut other, "directions.start_deg", -30.0);
    set(&mut other, "directions.stop_deg", 10.0);
    let oc = write_campaign(&tmp.path().join("other_dirs"), &other);
    assert_one_line_error(&call(map_args(&oc, &e)), "energy.parquet");
    // element count differs from the energy table's
    let mut a = map_args(&c, &e);
    a.extend(["--elements".into(), "100".into()]);
    assert_one_line_error(&call(a), "elements");
    // empty energy table (right columns and metadata, no rows)
    let empty = tmp.path().join("empty.parquet");
    let meta = pradar::table::parquet_metadata(&e).unwrap();
    let df = pradar::table::frame(
        &empty,
        vec![
            pradar::table::col("position", Vec::<i64>::new()),
            pradar::table::col("direction", Vec::<i64>::new()),
            pradar::table::col("angle_rel_deg", Vec::<f64>::new()),
            pradar::table::col("angle_global_deg", Vec::<f64>::new()),
            pradar::table::col("bin", Vec::<i64>::new()),
            pradar::table::col("delay_ns", Vec::<f64>::new()),
            pradar::table::col("energy", Vec::<f64>::new()),
        ],
    )
    .unwrap();
    pradar::table::write_parquet(&empty, &df, meta).unwrap();
    assert_one_line_error(&call(map_args(&c, &empty)), "empty.parquet");
    // malformed --run
    assert_one_line_error(
        &pradar(&["map", "--run", "nonsense", "--out", s(&out)], None),
        "--run",
    );
    assert!(!out.exists(), "no output on failure");
    // unknown method: a bad value, one line, exit 1, no panic
    let o = pradar(
        &[
            "map",
            "--method",
            "ekf2",
            "--campaign",
            s(&c),
            "--energy",
            s(&e),
            "--out",
            s(&out),
        ],
        None,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{}", err.lines().next().unwrap_or(""));
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: ") && err.contains("ekf2") && err.contains("--method"));
    assert!(!err.contains("panicked"));
    assert!(!out.exists());
}
