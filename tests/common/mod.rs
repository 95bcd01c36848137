//! Shared helpers for the end-to-end tests: build campaigns from the fixtures in `data/`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Run the `pradar` binary with `args` and `--quiet`.
pub fn pradar_quiet(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap()
}

/// A path as a `&str` (test paths are UTF-8).
pub fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Python interpreter of the cross-checks: `$PRADAR_PYTHON` (set by `scripts/test` to
/// its venv, which has numpy, pandas and pyarrow), else `python3` from the `PATH`.
pub fn python() -> std::process::Command {
    let exe = std::env::var_os("PRADAR_PYTHON").unwrap_or_else(|| "python3".into());
    std::process::Command::new(exe)
}

/// Whether the Python cross-checks may pass without running: only when
/// `PRADAR_SKIP_PYTHON=1` is set explicitly (they fail loudly otherwise).
pub fn skip_python() -> bool {
    std::env::var("PRADAR_SKIP_PYTHON").is_ok_and(|v| v == "1")
}

/// Load a fixture manifest as a TOML table.
pub fn fixture(name: &str) -> toml::Table {
    let text = std::fs::read_to_string(root().join("data").join(name)).unwrap();
    toml::from_str(&text).unwrap()
}

/// Set a dotted key (`band.points`) in a TOML table.
pub fn set(t: &mut toml::Table, key: &str, v: impl Into<toml::Value>) {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().unwrap();
    let mut cur = t;
    for p in parts {
        cur = cur
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(Default::default()))
            .as_table_mut()
            .unwrap();
    }
    cur.insert(last.to_string(), v.into());
}

/// Write a manifest (and the layout it names, copied from `data/tests` or `data/corridor`)
/// into `dir`; returns the manifest path.
pub fn write_campaign(dir: &Path, t: &toml::Table) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let layout = t["layout"].as_str().unwrap().to_string();
    for src in ["data/tests", "data/corridor"] {
        let p = root().join(src).join(&layout);
        if p.is_file() {
            std::fs::copy(&p, dir.join(&layout)).unwrap();
            break;
        }
    }
    let path = dir.join("campaign.toml");
    std::fs::write(&path, toml::to_string(t).unwrap()).unwrap();
    path
}

/// The built-in corridor manifest as a table.
pub fn corridor() -> toml::Table {
    fixture("corridor/campaign.toml")
}

/// Write a manifest into `dir/in`, simulate it into `dir/sim` (sweeps in `format`) and
/// compute its energy matrix into `dir/energy.parquet`.
pub fn chain(
    dir: &Path,
    t: &toml::Table,
    format: pradar::campaign::manifest::SweepFormat,
) -> (pradar::campaign::Campaign, pradar::energy::EnergyMatrix) {
    use pradar::campaign::Campaign;
    let m = write_campaign(&dir.join("in"), t);
    let c = Campaign::load(&m).unwrap();
    let sim = pradar::simulate::simulate(&c, &dir.join("sim"), format, &|_, _| {}).unwrap();
    let sc = Campaign::load(&sim.manifest).unwrap();
    let e = dir.join("energy.parquet");
    pradar::energy::run(&sc, &e, &|_, _| {}).unwrap();
    (sc, pradar::energy::EnergyMatrix::read(&e).unwrap())
}

/// `pradar synth` of `model` (saved as `dir/model.toml`) on campaign `cpath` with `seed`
/// into `dir/e.parquet`, its truth in `dir/truth`; the energy table.
pub fn synth(
    dir: &Path,
    cpath: &Path,
    model: &pradar::model::file::ModelConfig,
    seed: u64,
) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let mp = dir.join("model.toml");
    model.save(&mp).unwrap();
    let e = dir.join("e.parquet");
    let seed = seed.to_string();
    let o = pradar_quiet(&[
        "synth",
        "--model",
        path_str(&mp),
        "--campaign",
        path_str(cpath),
        "--out",
        path_str(&e),
        "--truth",
        path_str(&dir.join("truth")),
        "--seed",
        &seed,
    ]);
    assert!(
        o.status.success(),
        "synth: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    e
}

/// A CLI failure: non-zero exit, no panic, exactly one `error: ` line naming `must_name`.
pub fn assert_one_line_error(o: &std::process::Output, must_name: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{}", err.trim());
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "panic: {err}");
    let lines: Vec<&str> = err.trim().lines().collect();
    assert_eq!(lines.len(), 1, "one line expected: {err}");
    assert!(lines[0].starts_with("error: "));
    assert!(
        lines[0].contains(must_name),
        "should name {must_name}: {err}"
    );
}

/// The manifest of the fit tests in a hall (`tests/closed_loop.rs`, `tests/fit_coverage.rs`):
/// layout `hall.geojson` beside it, seed 77, `points` over 57.5–63.5 GHz, 400 elements, a
/// half-plane scan in `step_deg` steps, noise floor −100 dBm, 80 ns of delay behind a 3 ns
/// coupling gate, and `poses` as [x_m, y_m, heading_deg].
pub fn hall_manifest(step_deg: f64, points: usize, poses: &[[f64; 3]]) -> String {
    let mut t = format!(
        r#"schema_version = 1
name = "hall"
layout = "hall.geojson"
seed = 77
[band]
start_hz = 57.5e9
stop_hz = 63.5e9
points = {points}
[array]
elements = 400
[directions]
start_deg = -90.0
stop_deg = 90.0
step_deg = {step_deg:?}
[noise]
floor_dbm = -100.0
[processing]
coupling = "gate"
gate_ns = 3.0
max_delay_ns = 80.0
noise_from_ns = 100.0
"#
    );
    for [x, y, h] in poses {
        t.push_str(&format!(
            "[[poses]]\nx_m = {x:.3}\ny_m = {y:.3}\nheading_deg = {h:.1}\n"
        ));
    }
    t
}

/// The closed-loop model sets of issue 4: Table 1 defaults with λ (1/ns), AoA std (deg) and
/// d_c (m) given, d_p 0.4 m, Γ 15 ns, γ 4 ns and 5 rays per cluster.
pub fn hall_model(lambda: f64, aoa_deg: f64, dc_m: f64) -> pradar::model::file::ModelConfig {
    use pradar::model::file::{ModelConfig, Quantity};
    let mut m = ModelConfig::table1_defaults();
    m.intra_cluster_rate = Quantity::new(lambda, "1/ns", "exponential");
    m.intra_cluster_aoa = Quantity::new(aoa_deg, "deg", "laplacian");
    m.perimeter_offset = Quantity::new(0.4, "m", "exponential");
    m.perimeter_spacing = Quantity::new(dc_m, "m", "exponential");
    m.cluster_decay = Quantity::new(15.0, "ns", "exponential");
    m.ray_decay = Quantity::new(4.0, "ns", "exponential");
    m.rays_per_cluster = Quantity::new(5.0, "count", "poisson");
    m
}

/// The columns of a simulator's truth `rays.parquet` the per-path scorers read.
pub struct TruthRays {
    /// Position index per ray.
    pub pos: Vec<i64>,
    /// Relative angle, degrees.
    pub a: Vec<f64>,
    /// True delay, ns (not folded).
    pub d: Vec<f64>,
    /// Power, dB (NaN when not seen).
    pub pw: Vec<f64>,
    /// Kind (`diffuse`, `specular`, `corner`, `edge`, cluster kinds).
    pub kind: Vec<String>,
    /// Truth cluster id.
    pub truth_cluster: Vec<i64>,
}

/// Read a truth `rays.parquet` ([`TruthRays`]).
pub fn truth_rays(path: &Path) -> TruthRays {
    let df = pradar::table::read_parquet(path, None).unwrap();
    let pos = pradar::table::i64_column(path, &df, "position").unwrap();
    let a = pradar::table::f64_column(path, &df, "angle_rel_deg").unwrap();
    let d = pradar::table::f64_column(path, &df, "delay_ns").unwrap();
    let pw = pradar::table::f64_column_or_nan(path, &df, "power_db")
        .unwrap()
        .unwrap();
    let kind = pradar::table::str_column(path, &df, "kind")
        .unwrap()
        .unwrap();
    let truth_cluster = pradar::table::i64_column(path, &df, "truth_cluster").unwrap();
    TruthRays {
        pos,
        a,
        d,
        pw,
        kind,
        truth_cluster,
    }
}
