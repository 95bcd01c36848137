//! Shared helpers for the end-to-end tests: build campaigns from the fixtures in `data/`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
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
    let sim =
        pradar::campaign::simulate::simulate(&c, &dir.join("sim"), format, &|_, _| {}).unwrap();
    let sc = Campaign::load(&sim.manifest).unwrap();
    let e = dir.join("energy.parquet");
    pradar::energy::run(&sc, &e, &|_, _| {}).unwrap();
    (sc, pradar::energy::EnergyMatrix::read(&e).unwrap())
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
