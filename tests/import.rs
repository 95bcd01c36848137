//! `pradar import` (issue 18): a simulated campaign copied to a folder under another naming
//! scheme, with its poses in a CSV, gives a manifest whose energy is byte-identical to the
//! original's (from the Touchstone files, from an index CSV, and through `--to-parquet`);
//! missing, duplicated, extra and mismatched files are each listed, exit 1, nothing written.

use crate::common::*;
use pradar::campaign::manifest::SweepFormat;
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::{path_str as s, pradar_quiet as pradar};

/// A simulated campaign (2 positions, 401 points, 37 directions) in `dir/sim` with its
/// energy in `dir/energy.parquet`; its sweeps copied to `dir/raw/pos{10·(p+1)}_dir{d}.s2p`
/// (labels from 10, no padding), its poses to `dir/poses.csv`, the sections import cannot
/// read from files to `dir/base.toml`.
fn measured(dir: &Path) -> toml::Table {
    let mut t = corridor();
    set(&mut t, "band.points", 401i64);
    set(&mut t, "array.elements", 100i64);
    set(&mut t, "processing.max_delay_ns", 45.0);
    set(&mut t, "processing.noise_from_ns", 50.0);
    let poses = t["poses"].as_array().unwrap()[..2].to_vec();
    t.insert("poses".into(), poses.into());
    let _ = chain(dir, &t, SweepFormat::Touchstone);
    let sim: toml::Table =
        toml::from_str(&std::fs::read_to_string(dir.join("sim/campaign.toml")).unwrap()).unwrap();
    std::fs::create_dir_all(dir.join("raw")).unwrap();
    let mut csv = String::from("position,x,y,heading\n");
    for (p, pose) in sim["poses"].as_array().unwrap().iter().enumerate() {
        // rows out of order: labels, not row order, give the manifest order
        let row = format!(
            "{},{},{},{}\n",
            10 * (p + 1),
            pose["x_m"].as_float().unwrap(),
            pose["y_m"].as_float().unwrap(),
            pose["heading_deg"].as_float().unwrap()
        );
        csv.insert_str(csv.find('\n').unwrap() + 1, &row);
        for d in 0..37 {
            std::fs::copy(
                dir.join(format!("sim/sweeps/p{p:03}_d{d:02}_k00.s2p")),
                dir.join(format!("raw/pos{}_dir{d}.s2p", 10 * (p + 1))),
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("poses.csv"), csv).unwrap();
    let mut base = toml::Table::new();
    for k in ["name", "seed", "array", "noise", "processing"] {
        base.insert(k.into(), sim[k].clone());
    }
    std::fs::write(dir.join("base.toml"), toml::to_string(&base).unwrap()).unwrap();
    sim
}

fn import(dir: &Path, out: &Path, extra: &[&str]) -> Output {
    let glob = dir.join("raw/*.s2p");
    let mut args = vec![
        "import",
        "--poses",
        s(&dir.join("poses.csv")).to_owned().leak(),
        "--directions",
        "-90:90:5",
        "--layout",
        s(&dir.join("sim/layout.geojson")).to_owned().leak(),
        "--base",
        s(&dir.join("base.toml")).to_owned().leak(),
        "--out",
        s(out).to_owned().leak(),
    ];
    if !extra.contains(&"--index") {
        args.extend([
            "--sweeps",
            s(&glob).to_owned().leak(),
            "--name-pattern",
            "pos{position}_dir{direction}.s2p",
        ]);
    }
    args.extend(extra);
    pradar(&args)
}

fn energy(manifest: &Path) -> Vec<u8> {
    let out = manifest.with_file_name("energy.parquet");
    let o = pradar(&["energy", "--campaign", s(manifest), "--out", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(out).unwrap()
}

#[test]
fn imported_campaign_gives_byte_identical_energy() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    measured(dir);
    let original = std::fs::read(dir.join("energy.parquet")).unwrap();
    // glob + naming pattern
    let m = dir.join("glob/campaign.toml");
    let o = import(dir, &m, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        energy(&m),
        original,
        "energy from the imported manifest differs"
    );
    // index CSV (paths relative to it; one path holds a comma, quoted as CSV quotes it)
    std::fs::create_dir_all(dir.join("raw2")).unwrap();
    std::fs::copy(
        dir.join("raw/pos10_dir0.s2p"),
        dir.join("raw2/pos10,dir0.s2p"),
    )
    .unwrap();
    let mut index = String::from("position,direction,path\n");
    for p in [10, 20] {
        for d in 0..37 {
            if (p, d) == (10, 0) {
                index.push_str("10,0, \"raw2/pos10,dir0.s2p\"\n");
            } else {
                index.push_str(&format!("{p},{d},raw/pos{p}_dir{d}.s2p\n"));
            }
        }
    }
    std::fs::write(dir.join("index.csv"), index).unwrap();
    let m2 = dir.join("indexed/campaign.toml");
    let o = import(
        dir,
        &m2,
        &["--index", s(&dir.join("index.csv")).to_owned().leak()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        energy(&m2),
        original,
        "energy from the index-CSV manifest differs"
    );
    // --to-parquet: the Parquet sweep table gives the same energy
    let m3 = dir.join("pq/campaign.toml");
    let o = import(dir, &m3, &["--to-parquet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("pq/sweeps.parquet").is_file());
    assert!(std::fs::read_to_string(&m3)
        .unwrap()
        .contains("format = \"parquet\""));
    assert_eq!(
        energy(&m3),
        original,
        "energy from the Parquet sweep table differs"
    );
    eprintln!(
        "energy tables byte-identical: {} bytes (glob, index CSV, --to-parquet)",
        original.len()
    );
}

#[test]
fn missing_duplicated_extra_and_mismatched_files_are_listed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    measured(dir);
    let raw = |n: &str| -> PathBuf { dir.join("raw").join(n) };
    std::fs::remove_file(raw("pos10_dir5.s2p")).unwrap(); // missing
    std::fs::copy(raw("pos10_dir6.s2p"), raw("pos010_dir6.s2p")).unwrap(); // duplicated
    std::fs::copy(raw("pos10_dir7.s2p"), raw("pos99_dir7.s2p")).unwrap(); // extra: no such pose
    std::fs::write(raw("notes.s2p"), "! not a sweep\n").unwrap(); // extra: name
                                                                  // mismatched: every other point of the sweep (a 200-point grid)
    let text = std::fs::read_to_string(raw("pos20_dir3.s2p")).unwrap();
    let thin: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, l)| l.starts_with(['!', '#']) || i % 2 == 0)
        .map(|(_, l)| l)
        .collect();
    std::fs::write(raw("pos20_dir3.s2p"), thin.join("\n")).unwrap();
    let m = dir.join("bad/campaign.toml");
    let o = import(dir, &m, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"));
    for want in [
        "missing: position 10, direction 5, pulse 0",
        "duplicated: position 10, direction 6, pulse 0:",
        "extra: ",
        "pos99_dir7.s2p: position 99 is not in",
        "notes.s2p: name does not match",
        "grid: ",
        "pos20_dir3.s2p: 200 points",
        "error: import: 5 problem(s) before processing (1 missing, 1 duplicated, 2 extra, 0 unreadable, 1 grid); nothing written",
    ] {
        assert!(err.contains(want), "stderr should list `{want}`:\n{err}");
    }
    assert!(
        !m.exists() && !dir.join("bad").exists(),
        "nothing may be written"
    );
    // one-port data under a two-port name is refused by the reader, listed as unreadable
    std::fs::write(
        raw("pos10_dir5.s2p"),
        "# GHz S RI R 50\n1 0 0\n2 0 0\n3 0 0\n",
    )
    .unwrap();
    let o = import(dir, &m, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("unreadable: ")
            && err.contains("pos10_dir5.s2p: line 3: 3 numbers on a continuation line"),
        "{err}"
    );
}
