//! The bad-input corpus: inputs a user can produce by mistake, each run through
//! the `pradar` binary in a fresh copy of one small campaign (the corridor, 3 poses, 16
//! elements, simulated once). Every case must exit with status 1 and print exactly one
//! `error: ` line naming the file and the field at fault, never panic, leave every file of
//! the folder byte-identical (hash before and after) and add no file (no partial output,
//! no temp file).
//!
//! It covers the import, calibration and calibrate surfaces too: outputs that are inputs
//! (also by hard link, and files inputs name: index rows, `[calibration]` files, the base,
//! the layout, `--to-parquet`'s table), outputs that are folders, sockets or a full
//! device, sweep files that are FIFOs, devices, folders, dangling links or loops, bounded
//! sizes (poses, population, simulations), overflowing values and calibrations that leave
//! NaN or no noise, a v2 two-port without its data order, energy metadata outside its
//! physical range, Touchstone rows swapped or reversed, commas in index paths, and clap's
//! usage errors. The snapshot records every entry by kind (a
//! FIFO or device is never read), so the harness checks those too. The FIFO and
//! character-device outputs that must be written into, not replaced, are
//! [`device_and_fifo_outputs_are_written_into_not_replaced`].

use crate::common::{corridor, set};
use polars::prelude::*;
use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The base folder: `in/` (the scene manifest), `sim/` (simulated, Touchstone), `e.parquet`,
/// `m.parquet`, `c.parquet` (+ summary), `model.toml`, `t.md`; for `import`, `poses.csv`
/// (the 3 poses), `index.csv` (every sweep file of `sim/`) and `base.toml` (name, seed,
/// array, noise, processing of `sim/campaign.toml`).
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
            closed_loop: 0,
        })
        .unwrap();
        import_inputs(d);
        dir
    })
    .path()
}

/// `poses.csv`, `index.csv` and `base.toml` of the simulated campaign (see [`base`]).
fn import_inputs(d: &Path) {
    let sim: toml::Table =
        toml::from_str(&std::fs::read_to_string(d.join("sim/campaign.toml")).unwrap()).unwrap();
    let mut poses = String::from("position,x,y,heading\n");
    for (p, q) in sim["poses"].as_array().unwrap().iter().enumerate() {
        let f = |k: &str| q[k].as_float().unwrap();
        poses += &format!("{p},{},{},{}\n", f("x_m"), f("y_m"), f("heading_deg"));
    }
    std::fs::write(d.join("poses.csv"), poses).unwrap();
    let mut index = String::from("position,direction,pulse,path\n");
    let mut names: Vec<String> = std::fs::read_dir(d.join("sim/sweeps"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    for n in names {
        // p000_d00_k00.s2p
        let (p, dd, k) = (&n[1..4], &n[6..8], &n[10..12]);
        let num = |x: &str| x.parse::<usize>().unwrap();
        index += &format!("{},{},{},sim/sweeps/{n}\n", num(p), num(dd), num(k));
    }
    std::fs::write(d.join("index.csv"), index).unwrap();
    let mut base = toml::Table::new();
    for k in ["name", "seed", "array", "noise", "processing"] {
        if let Some(v) = sim.get(k) {
            base.insert(k.into(), v.clone());
        }
    }
    std::fs::write(d.join("base.toml"), toml::to_string(&base).unwrap()).unwrap();
}

pub(crate) fn copy_tree(from: &Path, to: &Path) {
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

/// Every entry under `dir` (relative path → hash of what it is): a regular file by its
/// bytes, a symbolic link by its target, a FIFO, socket or device by its kind and inode
/// (never opened: reading a FIFO would block), a folder by its kind (and its entries).
pub(crate) fn snapshot(dir: &Path) -> BTreeMap<PathBuf, u64> {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, u64>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let m = std::fs::symlink_metadata(&p).unwrap();
            let t = m.file_type();
            let mut h = std::collections::hash_map::DefaultHasher::new();
            if t.is_dir() {
                "dir".hash(&mut h);
                walk(root, &p, out);
            } else if t.is_file() {
                std::fs::read(&p).unwrap().hash(&mut h);
            } else if t.is_symlink() {
                ("link", std::fs::read_link(&p).unwrap()).hash(&mut h);
            } else {
                let kind = (
                    t.is_fifo(),
                    t.is_socket(),
                    t.is_char_device(),
                    t.is_block_device(),
                );
                ("special", kind, m.ino(), m.rdev()).hash(&mut h);
            }
            out.insert(p.strip_prefix(root).unwrap().to_path_buf(), h.finish());
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
    /// Lines before the `error:` line: import lists its problems one a line first.
    problems: usize,
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
        problems: 0,
    }
}

/// A case of `import` that lists `problems` lines before its `error:` line.
fn import_case(
    name: &'static str,
    problems: usize,
    args: &'static [&'static str],
    want: &'static [&'static str],
    setup: impl Fn(&Path) + 'static,
) -> Case {
    Case {
        problems,
        ..case(name, args, want, setup)
    }
}

/// Replace `file` of the case folder (a sweep file) by what `make` puts at its path.
fn replace_with(dir: &Path, file: &str, make: impl FnOnce(&Path)) {
    let p = dir.join(file);
    std::fs::remove_file(&p).unwrap();
    make(&p);
}

/// Make a FIFO at `p` (with the `mkfifo` command: no extra crate).
pub(crate) fn mkfifo(p: &Path) {
    let ok = std::process::Command::new("mkfifo")
        .arg(p)
        .status()
        .unwrap()
        .success();
    assert!(ok, "mkfifo {}", p.display());
}

/// Rewrite the data lines of a Touchstone file of the case folder: every number after the
/// frequency becomes `value` (on every data line, or only the first when `first_only`),
/// written to `to` (the same file when equal).
fn touchstone_values(dir: &Path, from: &str, to: &str, value: &str, first_only: bool) {
    let text = std::fs::read_to_string(dir.join(from)).unwrap();
    let mut done = false;
    let mut out = String::new();
    for l in text.lines() {
        let t = l.trim();
        if t.is_empty() || t.starts_with('!') || t.starts_with('#') || (first_only && done) {
            out += l;
        } else {
            let mut toks = t.split_whitespace();
            let f = toks.next().unwrap().to_string();
            let rest: Vec<&str> = toks.map(|_| value).collect();
            out += &format!("{f} {}", rest.join(" "));
            done = true;
        }
        out.push('\n');
    }
    std::fs::write(dir.join(to), out).unwrap();
}

/// Set one key of the energy table's metadata (`e.parquet`), its rows unchanged.
fn energy_meta(dir: &Path, key: &str, value: &str) {
    let p = dir.join("e.parquet");
    let mut meta = pradar::table::parquet_metadata(&p).unwrap();
    match meta.iter_mut().find(|(k, _)| k == key) {
        Some(hit) => hit.1 = value.into(),
        None => meta.push((key.into(), value.into())),
    }
    let df = pradar::table::read_parquet(&p, None).unwrap();
    pradar::table::write_parquet(&p, &df, meta).unwrap();
}

/// Rewrite a Touchstone file of the case folder: `f` gets its header lines (comments and
/// the option line) and its data lines, and returns the new text.
fn touchstone_rows(dir: &Path, file: &str, f: impl FnOnce(Vec<&str>, Vec<&str>) -> String) {
    let p = dir.join(file);
    let text = std::fs::read_to_string(&p).unwrap();
    let (head, rows): (Vec<&str>, Vec<&str>) = text
        .lines()
        .partition(|l| l.starts_with('!') || l.starts_with('#'));
    std::fs::write(&p, f(head, rows)).unwrap();
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

/// `calibrate` with the prior `prior.toml` (see [`prior_interval`]).
const CALIBRATE_PRIOR: &[&str] = &[
    "calibrate",
    "--energy",
    "e.parquet",
    "--campaign",
    "sim/campaign.toml",
    "--out",
    "cal.toml",
    "--prior",
    "prior.toml",
];

/// `prior.toml`: the fitted model with `quantity`'s interval [lo, hi].
fn prior_interval(dir: &Path, quantity: &str, lo: f64, hi: f64) {
    std::fs::copy(dir.join("model.toml"), dir.join("prior.toml")).unwrap();
    let v = toml::Value::Array(vec![lo.into(), hi.into()]);
    toml_set(dir, "prior.toml", &format!("{quantity}.interval"), v);
}

const IMPORT: &[&str] = &[
    "import",
    "--poses",
    "poses.csv",
    "--index",
    "index.csv",
    "--directions",
    "-90:90:5",
    "--layout",
    "sim/layout.geojson",
    "--base",
    "base.toml",
    "--out",
    "imp/campaign.toml",
];

/// `import` of [`IMPORT`] with another `--out`.
macro_rules! import_out {
    ($out:expr) => {
        &[
            "import",
            "--poses",
            "poses.csv",
            "--index",
            "index.csv",
            "--directions",
            "-90:90:5",
            "--layout",
            "sim/layout.geojson",
            "--base",
            "base.toml",
            "--out",
            $out,
        ]
    };
}

fn nothing(_: &Path) {}

/// The campaign manifest every case runs on (in the copied base folder).
const M: &str = "sim/campaign.toml";
/// The sweep pattern of [`M`].
const PAT: &str = "sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p";

/// Every bad-input case, in order: the groups below, each a table of cases (a command
/// line, what its one-line error must name, and the setup that breaks the input).
fn cases() -> Vec<Case> {
    [
        output_names_input_cases(),
        manifest_and_size_cases(),
        layout_model_and_flag_cases(),
        file_cases(),
        output_is_input_cases(),
        not_regular_file_cases(),
        bound_and_overflow_cases(),
        format_and_label_cases(),
        order_and_path_cases(),
        usage_cases(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// Bad-input cases: the outputs that name an input of the same run.
fn output_names_input_cases() -> Vec<Case> {
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
    ]
}

/// Bad-input cases: the manifest against the files, and sizes bounded before allocation.
fn manifest_and_size_cases() -> Vec<Case> {
    vec![
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
    ]
}

/// Bad-input cases: layout geometry, model files and flags.
fn layout_model_and_flag_cases() -> Vec<Case> {
    vec![
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
    ]
}

/// Bad-input cases: corrupt Parquet, messages naming the user's file, and outputs that are
/// not regular files.
fn file_cases() -> Vec<Case> {
    vec![
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
        // ---- outputs that are not regular files
        case(
            "energy --out is a folder",
            &["energy", "--campaign", M, "--out", "sim/sweeps"],
            &["sim/sweeps", "is a directory", "refusing"],
            nothing,
        ),
        case(
            "energy --out is a socket",
            &["energy", "--campaign", M, "--out", "sock"],
            &["sock", "is a socket", "refusing"],
            |d| {
                // the socket file stays after the listener is dropped
                drop(std::os::unix::net::UnixListener::bind(d.join("sock")).unwrap());
            },
        ),
        case(
            "energy --out a full device",
            &["energy", "--campaign", M, "--out", "/dev/full"],
            &["/dev/full", "No space left on device"],
            nothing,
        ),
        case(
            "import --out a full device",
            import_out!("/dev/full"),
            &["/dev/full", "No space left on device"],
            nothing,
        ),
    ]
}

/// Bad-input cases: an output that is an input, also one an input names.
fn output_is_input_cases() -> Vec<Case> {
    vec![
        // ---- an output that is an input, also one an input names
        case(
            "energy --out = a hard link of its manifest",
            &["energy", "--campaign", M, "--out", "link.toml"],
            &["link.toml", "input --campaign", M],
            |d| std::fs::hard_link(d.join(M), d.join("link.toml")).unwrap(),
        ),
        case(
            "energy --out = its calibration reference",
            &["energy", "--campaign", M, "--out", "sim/ref.s2p"],
            &["sim/ref.s2p", "input calibration.reference", "--out"],
            |d| {
                std::fs::copy(d.join("sim/sweeps/p000_d00_k00.s2p"), d.join("sim/ref.s2p"))
                    .unwrap();
                toml_set(d, M, "calibration.reference", "ref.s2p");
            },
        ),
        case(
            "energy --out = its calibration background",
            &["energy", "--campaign", M, "--out", "sim/bg.s2p"],
            &["sim/bg.s2p", "input calibration.background"],
            |d| {
                std::fs::copy(d.join("sim/sweeps/p000_d00_k00.s2p"), d.join("sim/bg.s2p")).unwrap();
                toml_set(d, M, "calibration.background", "bg.s2p");
            },
        ),
        case(
            "import --out = its poses",
            import_out!("poses.csv"),
            &["poses.csv", "input --poses", "--out"],
            nothing,
        ),
        case(
            "import --out = its index",
            import_out!("index.csv"),
            &["index.csv", "input --index"],
            nothing,
        ),
        case(
            "import --out = its base",
            import_out!("./base.toml"),
            &["base.toml", "input --base"],
            nothing,
        ),
        case(
            "import --out = its layout",
            import_out!("sim/layout.geojson"),
            &["sim/layout.geojson", "input --layout"],
            nothing,
        ),
        case(
            "import --out = a sweep file of its index",
            import_out!("sim/sweeps/p002_d36_k00.s2p"),
            &["p002_d36_k00.s2p", "sweep file (of --index)"],
            nothing,
        ),
        case(
            "import --to-parquet over an input named sweeps.parquet",
            &[
                "import",
                "--poses",
                "imp/sweeps.parquet",
                "--index",
                "index.csv",
                "--directions",
                "-90:90:5",
                "--layout",
                "sim/layout.geojson",
                "--base",
                "base.toml",
                "--out",
                "imp/campaign.toml",
                "--to-parquet",
            ],
            &["imp/sweeps.parquet", "--to-parquet", "input --poses"],
            |d| {
                std::fs::create_dir(d.join("imp")).unwrap();
                std::fs::copy(d.join("poses.csv"), d.join("imp/sweeps.parquet")).unwrap();
            },
        ),
    ]
}

/// Bad-input cases: sweep files and index entries that are not regular files.
fn not_regular_file_cases() -> Vec<Case> {
    vec![
        // ---- sweep files and index entries that are not regular files
        case(
            "sweep file is a FIFO",
            ENERGY,
            &["p001_d03_k00.s2p", "is a FIFO"],
            |d| replace_with(d, "sim/sweeps/p001_d03_k00.s2p", mkfifo),
        ),
        case(
            "sweep file is a folder",
            ENERGY,
            &["p001_d03_k00.s2p", "is a directory"],
            |d| {
                replace_with(d, "sim/sweeps/p001_d03_k00.s2p", |p| {
                    std::fs::create_dir(p).unwrap()
                })
            },
        ),
        case(
            "sweep file is a link to /dev/zero",
            ENERGY,
            &["p001_d03_k00.s2p", "is a device"],
            |d| {
                replace_with(d, "sim/sweeps/p001_d03_k00.s2p", |p| {
                    std::os::unix::fs::symlink("/dev/zero", p).unwrap()
                })
            },
        ),
        case(
            "sweep file is a dangling link",
            ENERGY,
            &["p001_d03_k00.s2p", "dangling symbolic link"],
            |d| {
                replace_with(d, "sim/sweeps/p001_d03_k00.s2p", |p| {
                    std::os::unix::fs::symlink("gone.s2p", p).unwrap()
                })
            },
        ),
        case(
            "sweep file is a symlink loop",
            ENERGY,
            &["p001_d03_k00.s2p", "symlink loop"],
            |d| {
                replace_with(d, "sim/sweeps/p001_d03_k00.s2p", |p| {
                    std::os::unix::fs::symlink(p.file_name().unwrap(), p).unwrap()
                })
            },
        ),
        case(
            "calibration reference is a FIFO",
            ENERGY,
            &["sim/ref.s2p", "calibration.reference", "is a FIFO"],
            |d| {
                mkfifo(&d.join("sim/ref.s2p"));
                toml_set(d, M, "calibration.reference", "ref.s2p");
            },
        ),
        import_case(
            "index row naming /dev/zero",
            1,
            IMPORT,
            &["unreadable: /dev/zero", "is a device", "1 unreadable"],
            |d| edit(d, "index.csv", "sim/sweeps/p000_d00_k00.s2p", "/dev/zero"),
        ),
        import_case(
            "index row naming a FIFO",
            1,
            IMPORT,
            &["unreadable: fifo", "is a FIFO", "1 unreadable"],
            |d| {
                mkfifo(&d.join("fifo"));
                edit(d, "index.csv", "sim/sweeps/p000_d00_k00.s2p", "fifo");
            },
        ),
        import_case(
            "index row with pulse 10^11",
            2,
            IMPORT,
            &[
                "extra: sim/sweeps/p000_d00_k00.s2p: pulse 100000000000 beyond the 1000 repeats",
                "missing: position 0, direction 0 (-90°): no file",
            ],
            |d| {
                edit(
                    d,
                    "index.csv",
                    "0,0,0,sim/sweeps/p000_d00_k00.s2p",
                    "0,0,100000000000,sim/sweeps/p000_d00_k00.s2p",
                )
            },
        ),
        import_case(
            "index with a NaN angle_deg",
            0,
            IMPORT,
            &["index.csv", "line 2", "angle must be finite"],
            |d| {
                edit(
                    d,
                    "index.csv",
                    "position,direction,pulse,path",
                    "position,angle_deg,pulse,path",
                );
                edit(d, "index.csv", "0,0,0,sim", "0,NaN,0,sim");
            },
        ),
    ]
}

/// Bad-input cases: sizes bounded, values that overflow and calibrations that leave nothing.
fn bound_and_overflow_cases() -> Vec<Case> {
    vec![
        // ---- sizes bounded
        case(
            "poses CSV of 10^6 rows",
            IMPORT,
            &["poses.csv", "1000000 rows", "more than 100000 poses"],
            |d| {
                let mut s = String::from("position,x,y,heading\n");
                for i in 0..1_000_000 {
                    s += &format!("{i},1.0,0.0,0.0\n");
                }
                std::fs::write(d.join("poses.csv"), s).unwrap();
            },
        ),
        case(
            "poses CSV with x = 1e308",
            IMPORT,
            &["error: poses.csv: line 2: x = 1e308 m, beyond ±10000 m"],
            |d| {
                let p = d.join("poses.csv");
                let text = std::fs::read_to_string(&p).unwrap();
                let mut lines: Vec<String> = text.lines().map(String::from).collect();
                let mut cells: Vec<String> = lines[1].split(',').map(String::from).collect();
                cells[1] = "1e308".into();
                lines[1] = cells.join(",");
                std::fs::write(&p, lines.join("\n") + "\n").unwrap();
            },
        ),
        case(
            "calibrate --population 10001",
            &[
                "calibrate",
                "--energy",
                "e.parquet",
                "--campaign",
                M,
                "--out",
                "cal.toml",
                "--population",
                "10001",
            ],
            &["--population", "[20, 10000]"],
            nothing,
        ),
        case(
            "calibrate --simulations 100001",
            &[
                "calibrate",
                "--energy",
                "e.parquet",
                "--campaign",
                M,
                "--out",
                "cal.toml",
                "--simulations",
                "100001",
            ],
            &["--simulations", "[20, 100000]"],
            nothing,
        ),
        // ---- values that overflow, calibrations that leave nothing
        case(
            "Touchstone value 1e308",
            ENERGY,
            &["p000_d00_k00.s2p", "line", "overflows"],
            |d| {
                let f = "sim/sweeps/p000_d00_k00.s2p";
                touchstone_values(d, f, f, "1e308", true)
            },
        ),
        case(
            "calibration reference of 1e-200",
            ENERGY,
            &["not finite", "calibration.reference"],
            |d| {
                touchstone_values(
                    d,
                    "sim/sweeps/p000_d00_k00.s2p",
                    "sim/ref.s2p",
                    "1e-200",
                    false,
                );
                toml_set(d, M, "calibration.reference", "ref.s2p");
            },
        ),
        case(
            "calibration background = the measurement",
            ENERGY,
            &[M, "N0 = 0", "calibration.background", "measurement itself"],
            |d| {
                toml_set(
                    d,
                    M,
                    "calibration.background",
                    "sweeps/p{position:03}_d{direction:02}_k00.s2p",
                )
            },
        ),
        case(
            "prior interval of three bounds",
            &[
                "calibrate",
                "--energy",
                "e.parquet",
                "--campaign",
                M,
                "--out",
                "cal.toml",
                "--prior",
                "prior.toml",
            ],
            &["prior.toml", "3 bounds given, exactly 2"],
            |d| {
                std::fs::copy(d.join("model.toml"), d.join("prior.toml")).unwrap();
                let v = toml::Value::Array(vec![1.0.into(), 2.0.into(), 3.0.into()]);
                toml_set(d, "prior.toml", "ray_decay.interval", v);
            },
        ),
        case(
            "prior interval beyond the model's range",
            CALIBRATE_PRIOR,
            &["prior.toml", "cluster_decay.interval [1, 20000]", "outside"],
            |d| prior_interval(d, "cluster_decay", 1.0, 2e4),
        ),
        case(
            "prior bound 1e300",
            CALIBRATE_PRIOR,
            &[
                "prior.toml",
                "cluster_decay.interval [1, 1e300]",
                "1e300 ns outside",
            ],
            |d| prior_interval(d, "cluster_decay", 1.0, 1e300),
        ),
        case(
            "energy table whose position column is Int8",
            EXTRACT,
            &["e.parquet", "column `position` is Int8", "expected Int32"],
            |d| {
                // written by pyarrow (data/tests/energy_int8_position.parquet: 16 rows of the
                // corridor's table, `position` cast to int8): polars keeps the Int8 from
                // the Arrow schema pyarrow stores
                let fixture = crate::common::root().join("data/tests/energy_int8_position.parquet");
                std::fs::copy(fixture, d.join("e.parquet")).unwrap();
            },
        ),
    ]
}

/// Bad-input cases: a v2 two-port without its data order, energy metadata out of range,
/// labels, missing sweeps and NaN energies.
fn format_and_label_cases() -> Vec<Case> {
    vec![
        // ---- a v2 two-port without its data order, energy metadata out of range
        case(
            "Touchstone v2 two-port without [Two-Port Data Order]",
            ENERGY,
            &["p000_d00_k00.s2p", "line", "[Two-Port Data Order] missing"],
            |d| {
                touchstone_rows(d, "sim/sweeps/p000_d00_k00.s2p", |head, rows| {
                    let mut t = String::from("[Version] 2.0\n");
                    for l in head {
                        t += &format!("{l}\n");
                    }
                    t += "[Number of Ports] 2\n[Network Data]\n";
                    for l in rows {
                        t += &format!("{l}\n");
                    }
                    t + "[End]\n"
                })
            },
        ),
        case(
            "energy table with an absurd tw",
            EXTRACT,
            &["e.parquet", "metadata `tw` = 1e300", "physical range"],
            |d| energy_meta(d, "tw", "1e300"),
        ),
        case(
            "energy table with tw below 1",
            EXTRACT,
            &["e.parquet", "metadata `tw`", "[1, 5]"],
            |d| energy_meta(d, "tw", "1e-9"),
        ),
        case(
            "energy table with an enbw of 50 bins",
            EXTRACT,
            &["e.parquet", "metadata `enbw` = 50", "[1, 3]"],
            |d| energy_meta(d, "enbw", "50"),
        ),
        case(
            "energy table whose bin width is not 1e9/B",
            EXTRACT,
            &["e.parquet", "metadata `bin_width_ns` = 1", "1e9/B"],
            |d| energy_meta(d, "bin_width_ns", "1"),
        ),
        case(
            "energy table with a negative bin width",
            EXTRACT,
            &["e.parquet", "metadata `bin_width_ns` = -0.5", "> 0"],
            |d| energy_meta(d, "bin_width_ns", "-0.5"),
        ),
        // ---- labels, missing sweeps, NaN energies
        case(
            "manifest labels fewer than the poses",
            ENERGY,
            &[M, "labels", "3 poses"],
            |d| toml_set(d, M, "labels", toml::Value::Array(vec!["P01".into()])),
        ),
        case(
            "manifest labels naming one pose twice",
            ENERGY,
            &[M, "labels[2]", "names two poses"],
            |d| {
                let v = ["P01", "P02", "P01"].map(toml::Value::from).to_vec();
                toml_set(d, M, "labels", toml::Value::Array(v))
            },
        ),
        case(
            "sweeps.missing outside the campaign",
            ENERGY,
            &[M, "sweeps.missing[0]", "outside the campaign"],
            |d| {
                let mut m = toml::Table::new();
                m.insert("position".into(), 7i64.into());
                m.insert("direction".into(), 0i64.into());
                toml_set(d, M, "sweeps.missing", toml::Value::Array(vec![m.into()]))
            },
        ),
        case(
            "NaN energy outside a missing profile",
            EXTRACT,
            &["e.parquet", "column `energy` row 7", "NaN outside"],
            |d| parquet_edit(d, "e.parquet", |df| set_cell(df, "energy", 7, f64::NAN)),
        ),
        case(
            "energy metadata `missing` that is not position:direction",
            EXTRACT,
            &["e.parquet", "metadata `missing`", "not position:direction"],
            |d| energy_meta(d, "missing", "0-3"),
        ),
        case(
            "energy metadata `missing` outside the table",
            EXTRACT,
            &["e.parquet", "metadata `missing`", "outside the table"],
            |d| energy_meta(d, "missing", "0:99"),
        ),
        case(
            "energy metadata `missing` on a profile that holds energies",
            EXTRACT,
            &["e.parquet", "lists as `missing`", "NaN expected"],
            |d| energy_meta(d, "missing", "0:0"),
        ),
    ]
}

/// Bad-input cases: rows out of order and commas in index paths.
fn order_and_path_cases() -> Vec<Case> {
    vec![
        // ---- rows out of order, commas in index paths
        case(
            "Touchstone frequency rows swapped",
            ENERGY,
            &[
                "p000_d00_k00.s2p",
                "not increasing (below",
                "of line",
                "swapped or reversed",
            ],
            |d| {
                touchstone_rows(d, "sim/sweeps/p000_d00_k00.s2p", |head, mut rows| {
                    rows.swap(10, 11);
                    head.into_iter()
                        .chain(rows)
                        .map(|l| format!("{l}\n"))
                        .collect()
                })
            },
        ),
        case(
            "Touchstone frequency rows reversed",
            ENERGY,
            &[
                "p000_d00_k00.s2p",
                "not increasing (below",
                "swapped or reversed",
            ],
            |d| {
                touchstone_rows(d, "sim/sweeps/p000_d00_k00.s2p", |head, rows| {
                    let rows = rows.into_iter().rev();
                    head.into_iter()
                        .chain(rows)
                        .map(|l| format!("{l}\n"))
                        .collect()
                })
            },
        ),
        case(
            "index path with an unquoted comma",
            IMPORT,
            &[
                "index.csv",
                "line 2: 5 cells for the header's 4 columns",
                "quoted",
            ],
            |d| {
                edit(
                    d,
                    "index.csv",
                    "sim/sweeps/p000_d00_k00.s2p",
                    "sim/sweeps/p000,d00_k00.s2p",
                )
            },
        ),
        case(
            "index path with an unclosed quote",
            IMPORT,
            &["index.csv", "line 2: cell 4 opens a quote"],
            |d| {
                edit(
                    d,
                    "index.csv",
                    "sim/sweeps/p000_d00_k00.s2p",
                    "\"sim/sweeps/p000,d00_k00.s2p",
                )
            },
        ),
        import_case(
            "index path with a quoted comma naming no file",
            1,
            IMPORT,
            &["unreadable: sim/sweeps/p000,d00_k00.s2p", "not found"],
            |d| {
                edit(
                    d,
                    "index.csv",
                    "sim/sweeps/p000_d00_k00.s2p",
                    "\"sim/sweeps/p000,d00_k00.s2p\"",
                )
            },
        ),
    ]
}

/// Bad-input cases: clap's usage errors, one line each.
fn usage_cases() -> Vec<Case> {
    vec![
        // ---- clap's usage errors, one line
        case(
            "import with --index and --sweeps",
            &[
                "import",
                "--poses",
                "poses.csv",
                "--index",
                "index.csv",
                "--sweeps",
                "sim/sweeps/*.s2p",
                "--name-pattern",
                "p{position:03}_d{direction:02}_k{pulse:02}.s2p",
                "--out",
                "imp/campaign.toml",
            ],
            &["--sweeps", "cannot be used with", "--index"],
            nothing,
        ),
        case(
            "import with neither --index nor --sweeps",
            &[
                "import",
                "--poses",
                "poses.csv",
                "--out",
                "imp/campaign.toml",
            ],
            &["required", "--sweeps"],
            nothing,
        ),
        case(
            "import --sweeps without --name-pattern",
            &[
                "import",
                "--poses",
                "poses.csv",
                "--sweeps",
                "sim/sweeps/*.s2p",
                "--out",
                "imp/campaign.toml",
            ],
            &["required", "--name-pattern"],
            nothing,
        ),
        case(
            "negative --seed",
            &[
                "cluster",
                "--mpcs",
                "m.parquet",
                "--out",
                "c2.parquet",
                "--seed",
                "-1",
            ],
            &["'-1'", "--seed"],
            nothing,
        ),
        case(
            "unknown flag",
            &[
                "energy",
                "--campaign",
                M,
                "--out",
                "e2.parquet",
                "--outt",
                "x",
            ],
            &["--outt"],
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
        // the `error:` line first; an import's problem lines after it
        if lines.len() != 1 + c.problems || !lines[0].starts_with("error: ") {
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

/// Run `pradar args` in `dir`, killed after 120 s (a FIFO nobody reads would block it):
/// the exit code and stderr.
fn run_bounded(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_pradar"))
        .args(args)
        .arg("--quiet")
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > std::time::Duration::from_secs(120) {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("pradar {args:?} still running after 120 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    (status.code(), err)
}

/// An output that is a FIFO or a character device is written into (exit 0) and
/// is still a FIFO or a character device afterwards, never a regular file renamed over it;
/// `--out /dev/null` discards. The character device is made with `mknod X c 1 3` (the
/// node of /dev/null) where that is permitted, else that part is skipped with the reason
/// printed. The inputs are unchanged (the harness's snapshot) and no temp file is left.
#[test]
fn device_and_fifo_outputs_are_written_into_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    copy_tree(base(), d);
    let kind = |p: &Path| std::fs::symlink_metadata(p).unwrap().file_type();
    // a FIFO, read by `cat` into a file (spawned first: opening a FIFO for writing waits
    // for a reader; the child is killed at the end whatever happened)
    let fifo = d.join("out.fifo");
    mkfifo(&fifo);
    let before = snapshot(d);
    let got_dir = tempfile::tempdir().unwrap();
    let got = got_dir.path().join("fifo-bytes");
    let mut cat = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("cat '{}' > '{}'", fifo.display(), got.display()))
        .spawn()
        .unwrap();
    let (code, err) = run_bounded(
        d,
        &[
            "energy",
            "--campaign",
            "sim/campaign.toml",
            "--out",
            "out.fifo",
        ],
    );
    let cat_done = (0..200).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(50));
        cat.try_wait().unwrap().is_some()
    });
    if !cat_done {
        cat.kill().unwrap();
    }
    cat.wait().unwrap();
    assert_eq!(code, Some(0), "energy --out FIFO: {err}");
    assert!(kind(&fifo).is_fifo(), "the FIFO was replaced");
    let bytes = std::fs::read(&got).unwrap();
    assert!(
        bytes.starts_with(b"PAR1") && bytes.ends_with(b"PAR1"),
        "the FIFO's reader got {} bytes, not a Parquet file",
        bytes.len()
    );
    assert_eq!(snapshot(d), before, "inputs changed or files added");

    // /dev/null itself, and the import's manifest into it
    let (code, err) = run_bounded(
        d,
        &[
            "energy",
            "--campaign",
            "sim/campaign.toml",
            "--out",
            "/dev/null",
        ],
    );
    assert_eq!(code, Some(0), "energy --out /dev/null: {err}");
    assert!(kind(Path::new("/dev/null")).is_char_device());
    assert_eq!(snapshot(d), before, "inputs changed or files added");

    // a character device made here
    let node = d.join("null.node");
    let made = std::process::Command::new("mknod")
        .arg(&node)
        .args(["c", "1", "3"])
        .output()
        .unwrap();
    if !made.status.success() {
        eprintln!(
            "skipped the mknod part: mknod not permitted here ({})",
            String::from_utf8_lossy(&made.stderr).trim()
        );
        return;
    }
    let before = snapshot(d);
    for args in [
        &[
            "energy",
            "--campaign",
            "sim/campaign.toml",
            "--out",
            "null.node",
        ][..],
        &[
            "import",
            "--poses",
            "poses.csv",
            "--index",
            "index.csv",
            "--directions",
            "-90:90:5",
            "--layout",
            "sim/layout.geojson",
            "--base",
            "base.toml",
            "--out",
            "null.node",
        ],
    ] {
        let (code, err) = run_bounded(d, args);
        assert_eq!(code, Some(0), "{} --out a character device: {err}", args[0]);
        assert!(
            kind(&node).is_char_device(),
            "{}: the node was replaced",
            args[0]
        );
        assert_eq!(
            snapshot(d),
            before,
            "{}: inputs changed or files added",
            args[0]
        );
    }
}
