//! `pradar report` (issue 32): the report of a measured campaign (no `[scene]`, no truth),
//! the stages that cannot run saying why on the page, and a failed run leaving nothing
//! behind (a campaign without `[scene]` given to `reproduce`; a sweep missing at the
//! energy stage, with and without an earlier folder).

use crate::common::{assert_one_line_error, corridor, pradar_quiet, set, write_campaign};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The corridor's first 6 poses (401 points, 45 ns) simulated into `dir/sim`, its manifest
/// rewritten as a lab's would be (no `[scene]`, no `[clutter]`: `dir/sim/measured.toml`)
/// and its truth moved out of the manifest's folder (`dir/truth`). Returns the manifest.
fn measured_corridor(dir: &Path) -> PathBuf {
    let mut t = corridor();
    set(&mut t, "band.points", 401i64);
    set(&mut t, "processing.max_delay_ns", 45.0);
    set(&mut t, "processing.noise_from_ns", 50.0);
    set(&mut t, "name", "lab hall 3");
    let poses = t["poses"].as_array().unwrap()[..6].to_vec();
    t.insert("poses".into(), poses.into());
    let m = write_campaign(&dir.join("in"), &t);
    let c = pradar::campaign::Campaign::load(&m).unwrap();
    let sim = pradar::simulate::simulate(
        &c,
        &dir.join("sim"),
        pradar::campaign::manifest::SweepFormat::Touchstone,
        &|_, _| {},
    )
    .unwrap();
    let mut st: toml::Table =
        toml::from_str(&std::fs::read_to_string(&sim.manifest).unwrap()).unwrap();
    assert!(st.remove("scene").is_some(), "simulate keeps [scene]");
    st.remove("clutter");
    let measured = dir.join("sim/measured.toml");
    std::fs::write(&measured, toml::to_string(&st).unwrap()).unwrap();
    std::fs::rename(dir.join("sim/truth"), dir.join("truth")).unwrap();
    measured
}

/// A measured campaign gets its report: Table 1 titled with the campaign's name and
/// without a truth column, the geometry-only table and the truth column not run with the
/// reason, the check and the maps; `reproduce` refuses it before writing anything; a
/// failing truth fit is said on the page; a given energy table is used as given.
#[test]
fn report_of_a_measured_campaign() {
    let tmp = tempfile::tempdir().unwrap();
    let m = measured_corridor(tmp.path());
    let out = tmp.path().join("report");
    let o = pradar_quiet(&[
        "report",
        "--campaign",
        s(&m),
        "--skip-experiments",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("<title>pradar report: lab hall 3</title>")
            || html.contains("pradar report: lab hall 3")
    );
    assert!(html.contains("Table 1 (lab hall 3)"), "Table 1 title");
    assert!(html.contains("not run: the campaign has no [scene] section"));
    assert!(html.contains("No truth column: the campaign has no simulator"));
    assert!(html.contains("Does the fitted model reproduce the channel?"));
    assert!(!html.contains("check failed"), "the check ran");
    assert!(out.join("check/check.csv").is_file());
    assert!(out.join("maps/og/map.pgm").is_file() || out.join("maps/og").is_dir());
    assert!(!out.join("table1_geometry.md").exists());
    assert!(
        !out.join("work/geometry").exists(),
        "no geometry chain without a scene"
    );
    let md = std::fs::read_to_string(out.join("table1.md")).unwrap();
    assert!(
        md.starts_with("# Table 1: lab hall 3 channel parameters"),
        "{md}"
    );
    let header = md.lines().find(|l| l.starts_with("| ")).unwrap();
    assert!(!header.contains("truth"), "{header}");
    for p in 0..6 {
        assert!(out.join(format!("energy_p{p:02}.png")).is_file());
    }

    // reproduce simulates: a campaign without [scene] is refused in one line, nothing made
    let out2 = tmp.path().join("reproduced");
    let o = pradar_quiet(&["reproduce", "--campaign", s(&m), "--out", s(&out2)]);
    assert_one_line_error(&o, "pradar report");
    assert!(!out2.exists(), "a refused reproduce leaves nothing");

    // a truth folder whose fit fails: the page says why there is no truth column; the
    // energy table given is used (not computed again)
    let bad_truth = tmp.path().join("bad_truth");
    std::fs::create_dir_all(&bad_truth).unwrap();
    std::fs::write(bad_truth.join("rays.parquet"), b"not parquet").unwrap();
    let energy = tmp.path().join("energy.parquet");
    std::fs::copy(out.join("work/energy.parquet"), &energy).unwrap();
    let out3 = tmp.path().join("report3");
    let o = pradar_quiet(&[
        "report",
        "--campaign",
        s(&m),
        "--energy",
        s(&energy),
        "--truth",
        s(&bad_truth),
        "--skip-experiments",
        "--out",
        s(&out3),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(out3.join("index.html")).unwrap();
    assert!(
        html.contains("No truth column: the fit of the truth in"),
        "the truth's failure on the page"
    );
    assert!(html.contains("(given)"), "the energy table given");
    assert!(!out3.join("work/energy.parquet").exists());
    assert_eq!(
        std::fs::read(out3.join("table1.md")).unwrap(),
        std::fs::read(out.join("table1.md")).unwrap(),
        "the same energy table, the same Table 1"
    );
    // an input inside --out is refused
    let o = pradar_quiet(&[
        "report",
        "--campaign",
        s(&m),
        "--energy",
        s(&out3.join("work/../fitted_model.toml")),
        "--out",
        s(&out3),
    ]);
    assert_one_line_error(&o, "inside --out");
}

/// A stage that fails (a sweep file missing at the energy stage) leaves nothing behind: no
/// report folder when the run made it; an earlier folder's own files kept and nothing added.
#[test]
fn failed_report_leaves_nothing_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let m = measured_corridor(tmp.path());
    let sweep = std::fs::read_dir(tmp.path().join("sim/sweeps"))
        .or_else(|_| std::fs::read_dir(tmp.path().join("sim")))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|e| e == "s2p" || e == "s1p"))
        .expect("a Touchstone sweep");
    std::fs::remove_file(&sweep).unwrap();
    let out = tmp.path().join("report");
    let args = [
        "report",
        "--campaign",
        s(&m),
        "--skip-experiments",
        "--out",
        s(&out),
    ];
    let o = pradar_quiet(&args);
    let name = sweep.file_name().unwrap().to_str().unwrap();
    assert_one_line_error(&o, name);
    assert!(!out.exists(), "a failed run leaves no report folder");
    // an earlier folder: its files stay, the failed run adds nothing
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let o = pradar_quiet(&args);
    assert!(!o.status.success());
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("notes.txt")]);
}

/// The energy stage's `[noise]` warning (the manifest's floor implying an N0 more than 3 dB
/// from the data's) is printed by `report` as `energy` prints it, one line, and shown on
/// the page beside N0.
#[test]
fn report_prints_and_shows_the_energy_noise_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let m = measured_corridor(tmp.path());
    // the same sweeps, the manifest's floor 10 dB above what they hold
    let mut t: toml::Table = toml::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    let floor = t["noise"]["floor_dbm"].as_float().unwrap();
    set(&mut t, "noise.floor_dbm", floor + 10.0);
    let off = m.with_file_name("floor_off.toml");
    std::fs::write(&off, toml::to_string(&t).unwrap()).unwrap();
    let warnings = |o: &std::process::Output| -> Vec<String> {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (String::from_utf8_lossy(&o.stderr).lines())
            .filter(|l| l.starts_with("warning: "))
            .map(String::from)
            .collect()
    };
    let e = tmp.path().join("energy.parquet");
    let energy = warnings(&pradar_quiet(&[
        "energy",
        "--campaign",
        s(&off),
        "--out",
        s(&e),
    ]));
    assert_eq!(energy.len(), 1, "{energy:?}");
    assert!(
        energy[0].contains("dB from the") && energy[0].contains("[noise] floor_dbm"),
        "{energy:?}"
    );
    let out = tmp.path().join("report");
    let o = pradar_quiet(&[
        "report",
        "--campaign",
        s(&off),
        "--skip-experiments",
        "--out",
        s(&out),
    ]);
    assert_eq!(warnings(&o), energy, "report's warning is energy's");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let row = format!("<tr><th>N0 warning</th><td>{}</td></tr>", energy[0]);
    let n0 = html.find("<th>N0 (estimated)</th>").expect("the N0 row");
    let at = html
        .find(&row)
        .unwrap_or_else(|| panic!("no warning row:\n{html}"));
    assert!(at > n0, "the warning follows N0");
}
