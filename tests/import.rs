//! `pradar import` (issue 18): a simulated campaign copied to a folder under another naming
//! scheme, with its poses in a CSV, gives a manifest whose energy is byte-identical to the
//! original's (from the Touchstone files, from an index CSV, and through `--to-parquet`);
//! missing, duplicated, extra and mismatched files are each listed, exit 1, nothing written.
//! Issue 32: files named by steering angle (`{angle:+03}`, an `angle_deg` index column),
//! the lab's labels and headers kept, one-line refusals of a pattern that matches nothing,
//! the summary first, and `--allow-missing` through energy and the report.

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

/// `pradar import` of the folder `dir` with the poses CSV `poses`, into `out`: the files of
/// `sweeps` = (glob relative to `dir`, name pattern), or none (then `extra` gives
/// `--index`).
fn import_with(
    dir: &Path,
    poses: &str,
    out: &Path,
    sweeps: Option<(&str, &str)>,
    extra: &[&str],
) -> Output {
    let leak = |p: PathBuf| -> &'static str { s(&p).to_owned().leak() };
    let mut args = vec![
        "import",
        "--poses",
        leak(dir.join(poses)),
        "--directions",
        "-90:90:5",
        "--layout",
        leak(dir.join("sim/layout.geojson")),
        "--base",
        leak(dir.join("base.toml")),
        "--out",
        leak(out.to_path_buf()),
    ];
    if let Some((glob, pattern)) = sweeps {
        args.extend([
            "--sweeps",
            leak(dir.join(glob)),
            "--name-pattern",
            pattern.to_owned().leak(),
        ]);
    }
    args.extend(extra);
    pradar(&args)
}

fn import(dir: &Path, out: &Path, extra: &[&str]) -> Output {
    let sweeps =
        (!extra.contains(&"--index")).then_some(("raw/*.s2p", "pos{position}_dir{direction}.s2p"));
    import_with(dir, "poses.csv", out, sweeps, extra)
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
        "missing: position 10, direction 5 (-65°): no file",
        "duplicated: position 10, direction 6 (-60°):",
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

/// The measured folder of [`measured`] renamed as a lab names it: `lab/P01_az-45.s2p`
/// (labels P01, P02 in pose order, signed degrees), poses under `Pos,X [m],Y [m],Heading
/// [deg]`; returns the labels' original names (`10`, `20`).
fn lab_folder(dir: &Path) {
    let poses = std::fs::read_to_string(dir.join("poses.csv")).unwrap();
    let mut rows: Vec<Vec<String>> = poses
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    rows.sort_by_key(|r| r[0].parse::<i64>().unwrap());
    std::fs::create_dir_all(dir.join("lab")).unwrap();
    let mut csv = String::from("Pos,X [m],Y [m],Heading [deg]\n");
    for (i, r) in rows.iter().enumerate() {
        csv.push_str(&format!("P{:02},{},{},{}\n", i + 1, r[1], r[2], r[3]));
        for d in 0..37 {
            let angle = -90 + 5 * d as i64;
            std::fs::copy(
                dir.join(format!("raw/pos{}_dir{d}.s2p", r[0])),
                dir.join(format!("lab/P{:02}_az{angle:+03}.s2p", i + 1)),
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("lab_poses.csv"), csv).unwrap();
}

fn import_lab(dir: &Path, out: &Path, pattern: &str, extra: &[&str]) -> Output {
    import_with(
        dir,
        "lab_poses.csv",
        out,
        Some(("lab/*.s2p", pattern)),
        extra,
    )
}

#[test]
fn angle_names_lab_labels_and_headers_give_the_same_energy() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    measured(dir);
    lab_folder(dir);
    let original = std::fs::read(dir.join("energy.parquet")).unwrap();
    let m = dir.join("lab_glob/campaign.toml");
    let o = import_lab(dir, &m, "{position}_az{angle:+03}.s2p", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let manifest = std::fs::read_to_string(&m).unwrap();
    assert!(
        manifest.contains(r#"labels = ["P01", "P02"]"#),
        "{manifest}"
    );
    assert_eq!(energy(&m), original, "energy of the angle-named lab folder");
    // an index CSV with the lab's labels and an angle_deg column
    let mut index = String::from("Pos,Angle [deg],Path\n");
    for p in 1..=2 {
        for d in 0..37 {
            let a = -90 + 5 * d;
            index.push_str(&format!("P{p:02},{a},lab/P{p:02}_az{a:+03}.s2p\n"));
        }
    }
    std::fs::write(dir.join("lab_index.csv"), &index).unwrap();
    let m2 = dir.join("lab_index/campaign.toml");
    let idx = dir.join("lab_index.csv");
    let run = || import_with(dir, "lab_poses.csv", &m2, None, &["--index", s(&idx)]);
    let o = run();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(energy(&m2), original, "energy of the angle_deg index");
    // an angle off the grid is refused, naming the file
    std::fs::write(
        &idx,
        index.replace("P02,-85,lab/P02_az-85.s2p", "P02,-87.5,lab/P02_az-85.s2p"),
    )
    .unwrap();
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("P02_az-85.s2p: angle -87.5° is not on the --directions grid (-90:90:5°)"),
        "{err}"
    );
    assert!(
        err.contains("missing: position P02, direction 1 (-85°): no file"),
        "{err}"
    );
}

#[test]
fn name_patterns_that_cannot_be_right_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    measured(dir);
    lab_folder(dir);
    let m = dir.join("x/campaign.toml");
    // an index field over angle names: matches none, one line naming the pattern and a file
    for pattern in [
        "{position}_az{direction}.s2p",
        "{position}_az+{direction}.s2p",
    ] {
        let o = import_lab(dir, &m, pattern, &[]);
        assert_one_line_error(&o, pattern);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("matches none of the 74 file(s)"), "{err}");
        assert!(err.contains("e.g. not `P01_az"), "{err}");
        assert!(err.contains("{angle}"), "the hint names {{angle}}: {err}");
        assert!(!m.exists());
    }
    // `az+05` is never direction index 5, even where an index field could read it
    std::fs::copy(dir.join("lab/P01_az+05.s2p"), dir.join("lab/P01_az05.s2p")).unwrap();
    let o = import_lab(dir, &m, "{position}_az{direction:02}.s2p", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let first = err.lines().next().unwrap();
    assert!(
        first.starts_with("error: import: ") && first.contains("problem(s) before processing"),
        "the summary comes first: {err}"
    );
    assert!(err.contains("P01_az+05.s2p: name does not match"), "{err}");
    // at most 20 problem lines after the summary, then the count of the rest
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 22, "{err}");
    assert!(lines[21].trim().starts_with("… and "), "{err}");
    std::fs::remove_file(dir.join("lab/P01_az05.s2p")).unwrap();
    // a lab header that cannot be read lists the accepted names
    std::fs::write(
        dir.join("lab_poses.csv"),
        std::fs::read_to_string(dir.join("lab_poses.csv"))
            .unwrap()
            .replace("X [m]", "East [m]"),
    )
    .unwrap();
    let o = import_lab(dir, &m, "{position}_az{angle:+03}.s2p", &[]);
    assert_one_line_error(&o, "lab_poses.csv");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("accepted names") && err.contains("x, x_m"),
        "{err}"
    );
}

#[test]
fn allow_missing_goes_on_to_energy_and_the_report() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    measured(dir);
    lab_folder(dir);
    let original = pradar::energy::EnergyMatrix::read(&dir.join("energy.parquet")).unwrap();
    std::fs::remove_file(dir.join("lab/P02_az+10.s2p")).unwrap();
    // a pose without any file between P01 and P02: left out, P02 becomes index 1
    let poses = std::fs::read_to_string(dir.join("lab_poses.csv")).unwrap();
    let mut lines: Vec<String> = poses.lines().map(String::from).collect();
    lines.insert(2, lines[1].replacen("P01", "P1b", 1));
    std::fs::write(dir.join("lab_poses.csv"), lines.join("\n") + "\n").unwrap();
    let m = dir.join("lab_missing/campaign.toml");
    let pattern = "{position}_az{angle:+03}.s2p";
    let o = import_lab(dir, &m, pattern, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    // 37 of P1b and one of P02; the first 20 shown
    assert!(err.contains("(38 missing, 0 duplicated"), "{err}");
    assert!(
        err.contains("missing: position P1b, direction 0 (-90°): no file"),
        "{err}"
    );
    assert!(err.contains("… and 18 more"), "{err}");
    assert!(err.contains("--allow-missing"), "{err}");
    let o = import_lab(dir, &m, pattern, &["--allow-missing"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: left out: position P02, direction 20 (10°): no file"),
        "{err}"
    );
    assert!(
        err.contains("warning: left out: position P1b: no sweep file at all"),
        "{err}"
    );
    let manifest = std::fs::read_to_string(&m).unwrap();
    assert!(
        manifest.contains("dropped_positions = [\"P1b\"]")
            && manifest.contains(r#"labels = ["P01", "P02"]"#),
        "{manifest}"
    );
    assert!(manifest.contains("[[sweeps.missing]]"), "{manifest}");
    // the energy: NaN where the sweep is missing, every other profile as the original's
    let e = m.with_file_name("energy.parquet");
    let o = pradar(&["energy", "--campaign", s(&m), "--out", s(&e)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let em = pradar::energy::EnergyMatrix::read(&e).unwrap();
    assert_eq!(em.meta.missing, vec![(1, 20)]);
    assert!(!em.has(1, 20) && em.has(1, 19) && em.has(0, 20));
    assert!(em.profile(1, 20).iter().all(|v| v.is_nan()));
    for p in 0..2 {
        for d in 0..37 {
            if (p, d) == (1, 20) {
                continue;
            }
            for (a, b) in em.profile(p, d).iter().zip(original.profile(p, d)) {
                // N0 differs (one profile fewer in its estimate); the energies do not
                assert_eq!(a, b, "position {p}, direction {d}");
            }
        }
    }
    // --to-parquet keeps the gap (NaN rows) and the original file list
    let m2 = dir.join("lab_missing_pq/campaign.toml");
    let o = import_lab(dir, &m2, pattern, &["--allow-missing", "--to-parquet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let manifest = std::fs::read_to_string(&m2).unwrap();
    assert!(
        manifest.contains("format = \"parquet\"") && manifest.contains("P01_az-90.s2p"),
        "{manifest}"
    );
    let e2 = m2.with_file_name("energy.parquet");
    let o = pradar(&["energy", "--campaign", s(&m2), "--out", s(&e2)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let em2 = pradar::energy::EnergyMatrix::read(&e2).unwrap();
    assert_eq!(em2.meta.missing, em.meta.missing);
    assert_eq!(em2.meta.n0, em.meta.n0);
    // the whole report runs on it
    let rep = dir.join("report");
    let o = pradar(&[
        "report",
        "--campaign",
        s(&m),
        "--energy",
        s(&e),
        "--out",
        s(&rep),
        "--skip-experiments",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let page = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(page.contains("P02"), "the page names the lab's labels");
    assert!(
        page.contains("position P02, direction 20 (10°)"),
        "the page lists the missing sweep"
    );
    // every stage ran: nothing failed on the page, the maps and the check are there
    assert!(!page.contains(" failed: "), "a stage failed on the page");
    for f in [
        "check/check.csv",
        "maps/og/metrics.json",
        "maps/ekf/metrics.json",
    ] {
        assert!(rep.join(f).is_file(), "{f} missing from the report");
    }
    for f in ["maps/og/metrics.json", "maps/ekf/metrics.json"] {
        let j = std::fs::read_to_string(rep.join(f)).unwrap();
        // (no truth: the three-class scores are null by design)
        let numbers = j.replace("\"three_class\": null", "");
        assert!(!j.contains("NaN") && !numbers.contains("null"), "{f}: {j}");
    }
    // the coupling's mean over the directions of a position skips the missing one
    let t = std::fs::read_to_string(&m)
        .unwrap()
        .replace("coupling = \"gate\"", "coupling = \"mean\"");
    assert!(t.contains("coupling = \"mean\""), "{t}");
    let mc = m.with_file_name("mean.toml");
    std::fs::write(&mc, t).unwrap();
    let em_mean = m.with_file_name("energy_mean.parquet");
    let o = pradar(&["energy", "--campaign", s(&mc), "--out", s(&em_mean)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
