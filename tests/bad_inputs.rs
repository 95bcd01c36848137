//! The bad-input corpus (issue 20): inputs a user can produce by mistake, each run through
//! the `pradar` binary in a fresh copy of one small campaign (the corridor, 3 poses, 16
//! elements, simulated once). Every case must exit with status 1 and print exactly one
//! `error: ` line naming the file and the field at fault, never panic, leave every file of
//! the folder byte-identical (hash before and after) and add no file (no partial output,
//! no temp file).

use crate::common::{corridor, set};
use polars::prelude::*;
use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The base folder: `in/` (the scene manifest), `sim/` (simulated, Touchstone), `e.parquet`,
/// `m.parquet`, `c.parquet` (+ summary), `model.toml`, `t.md`.
fn base() -> &'static Path {
    static BASE: OnceLock<tempfile::TempDir> = OnceLock::new();
    BASE.get_or_init(|| {
        use pradar::pipeline::commands;
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mut t = corridor();
        set(&mut t, "array.elements", 16);
        let poses = t["poses"].as_array().unwrap()[..3].to_vec();
        t.insert("poses".into(), toml::Value::Array(poses));
        let man = crate::common::write_campaign(&d.join("in"), &t);
        let none = |_: usize, _: usize| {};
        commands::simulate(
            &commands::Simulate {
                campaign: man,
                out: d.join("sim"),
                elements: None,
                format: pradar::campaign::manifest::SweepFormat::Touchstone,
            },
            &none,
        )
        .unwrap();
        let sim = d.join("sim/campaign.toml");
        commands::energy(
            &commands::Energy {
                campaign: sim.clone(),
                out: d.join("e.parquet"),
            },
            &none,
        )
        .unwrap();
        commands::extract(&commands::Extract {
            energy: d.join("e.parquet"),
            campaign: sim.clone(),
            out: d.join("m.parquet"),
            params: Default::default(),
        })
        .unwrap();
        commands::cluster(&commands::Cluster {
            mpcs: d.join("m.parquet"),
            out: d.join("c.parquet"),
            params: Default::default(),
        })
        .unwrap();
        commands::fit(&commands::Fit {
            clusters: d.join("c.parquet"),
            campaign: sim,
            out: d.join("model.toml"),
            table: d.join("t.md"),
            truth: None,
            energy: None,
            params: pradar::fit::channel::FitParams {
                bootstrap: 40,
                seed: 1,
            },
        })
        .unwrap();
        dir
    })
    .path()
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Every file under `dir` (relative path → hash of its bytes).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, u64> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, u64>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let mut h = std::collections::hash_map::DefaultHasher::new();
                std::fs::read(&p).unwrap().hash(&mut h);
                out.insert(p.strip_prefix(root).unwrap().to_path_buf(), h.finish());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Replace `from` by `to` in a text file of the case folder (which must contain it).
fn edit(dir: &Path, file: &str, from: &str, to: &str) {
    let p = dir.join(file);
    let s = std::fs::read_to_string(&p).unwrap();
    assert!(s.contains(from), "{file} lacks {from:?}");
    std::fs::write(&p, s.replacen(from, to, 1)).unwrap();
}

/// Set a dotted TOML key of a file of the case folder.
fn toml_set(dir: &Path, file: &str, key: &str, v: impl Into<toml::Value>) {
    let p = dir.join(file);
    let mut t: toml::Table = toml::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    set(&mut t, key, v);
    std::fs::write(&p, toml::to_string(&t).unwrap()).unwrap();
}

/// A layout of one perimeter with the given `coordinates` JSON.
fn layout(dir: &Path, coordinates: &str) {
    let text = format!(
        r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature",
        "properties": {{"role": "perimeter"}},
        "geometry": {{"type": "Polygon", "coordinates": {coordinates}}}}}]}}"#
    );
    std::fs::write(dir.join("sim/layout.geojson"), text).unwrap();
}

/// Rewrite a Parquet file of the case folder through `f`.
fn parquet_edit(dir: &Path, file: &str, f: impl FnOnce(&mut DataFrame)) {
    let p = dir.join(file);
    let meta = pradar::table::parquet_metadata(&p).unwrap();
    let mut df = pradar::table::read_parquet(&p, None).unwrap();
    f(&mut df);
    pradar::table::write_parquet(&p, &df, meta).unwrap();
}

/// Set one cell of a numeric column.
fn set_cell(df: &mut DataFrame, name: &str, row: usize, v: f64) {
    let c = df.column(name).unwrap().cast(&DataType::Float64).unwrap();
    let mut vals: Vec<f64> = c.f64().unwrap().into_no_null_iter().collect();
    vals[row] = v;
    let dtype = df.column(name).unwrap().dtype().clone();
    let col = Column::new(name.into(), vals).cast(&dtype).unwrap();
    df.with_column(col).unwrap();
}

/// Overwrite bytes of a file at `offset` (negative: from the end), or truncate it.
fn corrupt(dir: &Path, file: &str, offset: i64, bytes: Option<&[u8]>) {
    let p = dir.join(file);
    let mut b = std::fs::read(&p).unwrap();
    let at = if offset < 0 {
        (b.len() as i64 + offset) as usize
    } else {
        offset as usize
    };
    match bytes {
        Some(x) => b[at..at + x.len()].copy_from_slice(x),
        None => b.truncate(at),
    }
    std::fs::write(&p, b).unwrap();
}

type Setup = Box<dyn Fn(&Path)>;

struct Case {
    name: &'static str,
    setup: Setup,
    args: &'static [&'static str],
    want: &'static [&'static str],
}

fn case(
    name: &'static str,
    args: &'static [&'static str],
    want: &'static [&'static str],
    setup: impl Fn(&Path) + 'static,
) -> Case {
    Case {
        name,
        setup: Box::new(setup),
        args,
        want,
    }
}

const ENERGY: &[&str] = &[
    "energy",
    "--campaign",
    "sim/campaign.toml",
    "--out",
    "e2.parquet",
];
const EXTRACT: &[&str] = &[
    "extract",
    "--energy",
    "e.parquet",
    "--campaign",
    "sim/campaign.toml",
    "--out",
    "m2.parquet",
];
const CLUSTER: &[&str] = &["cluster", "--mpcs", "m.parquet", "--out", "c2.parquet"];
const FIT: &[&str] = &[
    "fit",
    "--clusters",
    "c.parquet",
    "--campaign",
    "sim/campaign.toml",
    "--out",
    "model2.toml",
    "--table",
    "t2.md",
    "--bootstrap",
    "40",
];
const SYNTH: &[&str] = &[
    "synth",
    "--model",
    "model.toml",
    "--campaign",
    "sim/campaign.toml",
    "--out",
    "s.parquet",
];

fn nothing(_: &Path) {}

fn cases() -> Vec<Case> {
    const M: &str = "sim/campaign.toml";
    const PAT: &str = "sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p";
    vec![
        // ---- an output naming an input of the same run
        case(
            "energy --out = its manifest",
            &["energy", "--campaign", M, "--out", M],
            &[M, "input --campaign", "--out"],
            nothing,
        ),
        case(
            "energy --out = a sweep file",
            &[
                "energy",
                "--campaign",
                M,
                "--out",
                "sim/sweeps/p000_d00_k00.s2p",
            ],
            &["p000_d00_k00.s2p", "sweep file"],
            nothing,
        ),
        case(
            "energy --out = its layout",
            &["energy", "--campaign", M, "--out", "sim/layout.geojson"],
            &["sim/layout.geojson", "layout"],
            nothing,
        ),
        case(
            "extract --out = its energy",
            &[
                "extract",
                "--energy",
                "e.parquet",
                "--campaign",
                M,
                "--out",
                "sim/../e.parquet",
            ],
            &["e.parquet", "input --energy"],
            nothing,
        ),
        case(
            "cluster --out = its MPCs",
            &["cluster", "--mpcs", "m.parquet", "--out", "./m.parquet"],
            &["m.parquet", "input --mpcs"],
            nothing,
        ),
        case(
            "cluster summary = its MPCs",
            &[
                "cluster",
                "--mpcs",
                "c_summary.parquet",
                "--out",
                "c.parquet",
            ],
            &["c_summary.parquet", "--out (its summary)"],
            nothing,
        ),
        case(
            "fit --out = its clusters",
            &[
                "fit",
                "--clusters",
                "c.parquet",
                "--campaign",
                M,
                "--out",
                "c.parquet",
                "--table",
                "t2.md",
            ],
            &["c.parquet", "input --clusters"],
            nothing,
        ),
        case(
            "fit --out = --table",
            &[
                "fit",
                "--clusters",
                "c.parquet",
                "--campaign",
                M,
                "--out",
                "x.md",
                "--table",
                "x.md",
            ],
            &["x.md", "both as --table and as --out"],
            nothing,
        ),
        case(
            "fit --table = its manifest",
            &[
                "fit",
                "--clusters",
                "c.parquet",
                "--campaign",
                M,
                "--out",
                "y.toml",
                "--table",
                M,
            ],
            &[M, "input --campaign"],
            nothing,
        ),
        case(
            "simulate into its own folder",
            &["simulate", "--campaign", "in/campaign.toml", "--out", "in"],
            &["in/campaign.toml", "input --campaign"],
            nothing,
        ),
        case(
            "synth --out = its model",
            &[
                "synth",
                "--model",
                "model.toml",
                "--campaign",
                M,
                "--out",
                "model.toml",
            ],
            &["model.toml", "input --model"],
            nothing,
        ),
        case(
            "synth --truth holds its model",
            &[
                "synth",
                "--model",
                "model.toml",
                "--campaign",
                M,
                "--out",
                "s.parquet",
                "--truth",
                ".",
            ],
            &["model.toml", "input --model", "--truth"],
            nothing,
        ),
        // ---- the manifest against the files
        case(
            "step 10° over 5° files",
            ENERGY,
            &[M, "[directions] gives 19 directions", "p000_d19_k00.s2p"],
            |d| toml_set(d, M, "directions.step_deg", 10.0),
        ),
        case(
            "step not dividing the span",
            ENERGY,
            &[M, "directions.step_deg", "92"],
            |d| toml_set(d, M, "directions.step_deg", 7.0),
        ),
        case(
            "pattern without placeholders",
            ENERGY,
            &[M, "sweeps.pattern", "{position}"],
            |d| edit(d, M, PAT, "sweeps/p000_d00_k00.s2p"),
        ),
        case(
            "pattern without {direction}",
            ENERGY,
            &[M, "sweeps.pattern", "{direction}"],
            |d| edit(d, M, PAT, "sweeps/p{position:03}_d00_k{pulse:02}.s2p"),
        ),
        case(
            "pattern width 70000",
            ENERGY,
            &[M, "sweeps.pattern", "70000"],
            |d| edit(d, M, "{position:03}", "{position:70000}"),
        ),
        case(
            "pattern unknown placeholder",
            ENERGY,
            &[M, "sweeps.pattern", "{pos}"],
            |d| edit(d, M, "{position:03}", "{pos}"),
        ),
        case(
            "duplicate files entries",
            ENERGY,
            &[M, "sweeps.files[1]", "sweeps.files[0]"],
            |d| {
                edit(d, M, &format!("pattern = \"{PAT}\""), "files = [{ position = 0, direction = 0, path = \"sweeps/p000_d00_k00.s2p\" }, { position = 0, direction = 0, path = \"sweeps/p000_d01_k00.s2p\" }]")
            },
        ),
        case(
            "one file for two sweeps",
            ENERGY,
            &[M, "sweeps.files[1]", "already listed"],
            |d| {
                edit(d, M, &format!("pattern = \"{PAT}\""), "files = [{ position = 0, direction = 0, path = \"sweeps/p000_d00_k00.s2p\" }, { position = 0, direction = 1, path = \"sweeps/p000_d00_k00.s2p\" }]")
            },
        ),
        case(
            "max_delay_ns 1e308",
            ENERGY,
            &[M, "processing.max_delay_ns"],
            |d| toml_set(d, M, "processing.max_delay_ns", 1e308),
        ),
        case(
            "band.points 401 over 801-point files",
            ENERGY,
            &[M, "band.points = 401"],
            |d| toml_set(d, M, "band.points", 401),
        ),
        case(
            "band.points 1601 over 801-point files",
            ENERGY,
            &["p000_d00_k00.s2p", "801 points", "[band] (1601 points"],
            |d| toml_set(d, M, "band.points", 1601),
        ),
        case(
            "band.stop_hz off the files' grid",
            ENERGY,
            &["p000_d00_k00.s2p", "[band]"],
            |d| toml_set(d, M, "band.stop_hz", 64.0e9),
        ),
        case(
            "pose outside the perimeter",
            ENERGY,
            &[M, "poses[1]", "not inside the perimeter"],
            |d| edit(d, M, "x_m = 0.905", "x_m = 20.0"),
        ),
        // ---- sizes bounded before allocation
        case(
            "band.points 2e8",
            ENERGY,
            &[M, "band.points", "100001"],
            |d| toml_set(d, M, "band.points", 200_000_000),
        ),
        case(
            "step_deg 1e-7",
            ENERGY,
            &[M, "directions.step_deg", "3601"],
            |d| toml_set(d, M, "directions.step_deg", 1e-7),
        ),
        case("pulses 1e12", ENERGY, &[M, "pulses", "1000"], |d| {
            toml_set(d, M, "pulses", 1_000_000_000_000i64)
        }),
        case(
            "oversample 999999999",
            ENERGY,
            &[M, "processing.oversample", "65"],
            |d| toml_set(d, M, "processing.oversample", 999_999_999),
        ),
        case("pose at 1e7 m", ENERGY, &[M, "poses[0]", "10000"], |d| {
            edit(d, M, "x_m = 0.5", "x_m = 1e7")
        }),
        case(
            "k-max 100000",
            &[
                "cluster",
                "--mpcs",
                "m.parquet",
                "--out",
                "c2.parquet",
                "--k-max",
                "100000",
            ],
            &["--k-max", "[1, 64]"],
            nothing,
        ),
        case(
            "MPC position 1e9",
            CLUSTER,
            &["m.parquet", "column `position`", "1000000000"],
            |d| parquet_edit(d, "m.parquet", |df| set_cell(df, "position", 0, 1e9)),
        ),
        case(
            "energy index 1e9",
            EXTRACT,
            &["e.parquet", "rows but"],
            |d| parquet_edit(d, "e.parquet", |df| set_cell(df, "bin", 5, 1e9)),
        ),
        case(
            "one 1e300 energy bin",
            EXTRACT,
            &["e.parquet", "column `energy`", "1e300"],
            |d| parquet_edit(d, "e.parquet", |df| set_cell(df, "energy", 7, 1e300)),
        ),
        // ---- layout geometry
        case(
            "self-intersecting perimeter",
            ENERGY,
            &["sim/layout.geojson", "features[0]", "not a simple polygon"],
            |d| layout(d, "[[[-1,-1],[10,1],[10,-1],[-1,1],[-1,-1]]]"),
        ),
        case(
            "zero-area perimeter",
            ENERGY,
            &["sim/layout.geojson", "features[0]"],
            |d| layout(d, "[[[-1,-1],[4,-1],[10,-1],[-1,-1]]]"),
        ),
        case(
            "perimeter with a hole",
            ENERGY,
            &["sim/layout.geojson", "features[0]", "hole"],
            |d| {
                layout(
                    d,
                    "[[[-2,-2],[11,-2],[11,2],[-2,2],[-2,-2]],[[4,0],[5,0],[5,0.5],[4,0.5],[4,0]]]",
                )
            },
        ),
        case(
            "one-coordinate position",
            ENERGY,
            &["sim/layout.geojson", "coordinates[0][1]", "2 numbers"],
            |d| layout(d, "[[[-2,-2],[11],[11,2],[-2,2],[-2,-2]]]"),
        ),
        case(
            "vertex at 1e7 m",
            ENERGY,
            &["sim/layout.geojson", "features[0]", "beyond"],
            |d| layout(d, "[[[-2,-2],[1e7,-2],[1e7,2],[-2,2],[-2,-2]]]"),
        ),
        case(
            "layout not GeoJSON",
            ENERGY,
            &["sim/layout.geojson", "not valid GeoJSON"],
            |d| std::fs::write(d.join("sim/layout.geojson"), "{ nope").unwrap(),
        ),
        // ---- model files
        case(
            "misspelt family",
            SYNTH,
            &["model.toml", "family", "weibul"],
            |d| {
                edit(
                    d,
                    "model.toml",
                    "family = \"poisson\"",
                    "family = \"weibul\"",
                )
            },
        ),
        case(
            "cluster_rrcs 1e308",
            SYNTH,
            &["model.toml", "cluster_rrcs.value"],
            |d| toml_set(d, "model.toml", "cluster_rrcs.value", 1e308),
        ),
        case(
            "rays_per_cluster 1e9",
            SYNTH,
            &["model.toml", "rays_per_cluster.value"],
            |d| toml_set(d, "model.toml", "rays_per_cluster.value", 1e9),
        ),
        case(
            "rays_per_cluster 1e308",
            SYNTH,
            &["model.toml", "rays_per_cluster.value"],
            |d| toml_set(d, "model.toml", "rays_per_cluster.value", 1e308),
        ),
        case(
            "perimeter_spacing 1e-9 m",
            SYNTH,
            &["model.toml", "perimeter_spacing.value"],
            |d| toml_set(d, "model.toml", "perimeter_spacing.value", 1e-9),
        ),
        case(
            "NaN value",
            SYNTH,
            &["model.toml", "ray_decay.value"],
            |d| toml_set(d, "model.toml", "ray_decay.value", f64::NAN),
        ),
        case("ks_p 2", SYNTH, &["model.toml", "ray_decay.ks_p"], |d| {
            toml_set(d, "model.toml", "ray_decay.ks_p", 2.0)
        }),
        case("model not TOML", SYNTH, &["model.toml"], |d| {
            std::fs::write(d.join("model.toml"), "value = [").unwrap()
        }),
        // ---- flags
        case(
            "bootstrap 0",
            &[
                "fit",
                "--clusters",
                "c.parquet",
                "--campaign",
                M,
                "--out",
                "o.toml",
                "--table",
                "o.md",
                "--bootstrap",
                "0",
            ],
            &["--bootstrap", "[40, 100000]"],
            nothing,
        ),
        case(
            "bootstrap 1",
            &[
                "fit",
                "--clusters",
                "c.parquet",
                "--campaign",
                M,
                "--out",
                "o.toml",
                "--table",
                "o.md",
                "--bootstrap",
                "1",
            ],
            &["--bootstrap", "[40, 100000]"],
            nothing,
        ),
        // ---- corrupt Parquet
        case("truncated energy table", EXTRACT, &["e.parquet"], |d| {
            corrupt(d, "e.parquet", -100, None)
        }),
        case("energy footer zeroed", EXTRACT, &["e.parquet"], |d| {
            corrupt(d, "e.parquet", -12, Some(&[0; 8]))
        }),
        case("MPC table magic broken", CLUSTER, &["m.parquet"], |d| {
            corrupt(d, "m.parquet", -4, Some(b"XXXX"))
        }),
        case("clusters table truncated", FIT, &["c.parquet"], |d| {
            corrupt(d, "c.parquet", 4000, None)
        }),
        case("MPC table empty file", CLUSTER, &["m.parquet"], |d| {
            std::fs::write(d.join("m.parquet"), b"").unwrap()
        }),
        case(
            "energy table is a TOML file",
            &[
                "extract",
                "--energy",
                M,
                "--campaign",
                M,
                "--out",
                "m2.parquet",
            ],
            &[M],
            nothing,
        ),
        // ---- messages naming the user's file
        case(
            "energy of another campaign",
            EXTRACT,
            &["e.parquet", "campaign sim/campaign.toml has"],
            |d| edit(d, M, "heading_deg = 0.0", "heading_deg = 10.0"),
        ),
        case(
            "energy table without a noise level",
            EXTRACT,
            &["e.parquet", "metadata `n0`"],
            |d| {
                let p = d.join("e.parquet");
                let mut meta = pradar::table::parquet_metadata(&p).unwrap();
                meta.iter_mut()
                    .filter(|(k, _)| k == "n0")
                    .for_each(|(_, v)| *v = "0".into());
                let df = pradar::table::read_parquet(&p, None).unwrap();
                pradar::table::write_parquet(&p, &df, meta).unwrap();
            },
        ),
        case(
            "output folder missing",
            &[
                "extract",
                "--energy",
                "e.parquet",
                "--campaign",
                M,
                "--out",
                "/proc/none/m.parquet",
            ],
            &["/proc/none"],
            nothing,
        ),
        case(
            "missing manifest",
            &[
                "energy",
                "--campaign",
                "nowhere.toml",
                "--out",
                "e2.parquet",
            ],
            &["nowhere.toml"],
            nothing,
        ),
    ]
}

#[test]
fn every_bad_input_is_one_line_exit_1_inputs_unchanged_nothing_written() {
    let base = base();
    let mut failures = Vec::new();
    let cases = cases();
    for c in &cases {
        let dir = tempfile::tempdir().unwrap();
        copy_tree(base, dir.path());
        (c.setup)(dir.path());
        let before = snapshot(dir.path());
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
            .args(c.args)
            .arg("--quiet")
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        let lines: Vec<&str> = err.trim().lines().collect();
        let mut why = Vec::new();
        if o.status.code() != Some(1) {
            why.push(format!("exit {:?}", o.status.code()));
        }
        if err.contains("panicked") {
            why.push("panic".into());
        }
        if lines.len() != 1 || !lines[0].starts_with("error: ") {
            why.push(format!("{} lines", lines.len()));
        }
        for w in c.want {
            if !err.contains(w) {
                why.push(format!("does not name {w:?}"));
            }
        }
        if err.contains(".tmp") {
            why.push("names a temp file".into());
        }
        let after = snapshot(dir.path());
        if after != before {
            let changed: Vec<_> = (after.keys().chain(before.keys()))
                .filter(|k| after.get(*k) != before.get(*k))
                .collect();
            why.push(format!("files changed or added: {changed:?}"));
        }
        if !why.is_empty() {
            failures.push(format!("{}: {} — {}", c.name, why.join("; "), err.trim()));
        }
    }
    eprintln!("{} bad inputs run", cases.len());
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
