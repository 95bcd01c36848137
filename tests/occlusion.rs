//! Maps that look like the building (issue 17): both mappers with the occlusion model of
//! `mapping::grid::visibility` on the corridor at N = 16 and N = 100 and on a second layout
//! (`data/tests/office.*`), scored on the building, the observable region and the whole map
//! with the all-free map's figures beside them; a multi-bounce ghost behind a wall; the
//! scalable EKF against the dense one. Every figure asserted is printed.

use crate::common;

use common::*;
use pradar::campaign::layout::Layout;
use pradar::campaign::manifest::SweepFormat;
use pradar::mapping::reference::{CellClass, LayoutRaster};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Simulate `t` at `n` elements (Parquet sweeps) and its energy into `dir`:
/// (manifest, energy).
fn simulated(dir: &Path, t: &toml::Table, n: usize) -> (PathBuf, PathBuf) {
    let mut t = t.clone();
    set(&mut t, "array.elements", n as i64);
    let (c, _) = chain(dir, &t, SweepFormat::Parquet);
    (c.path.clone(), dir.join("energy.parquet"))
}

/// The scenes of the must-show, simulated once per test binary: (name, N, manifest, energy).
fn scenes() -> &'static Vec<(String, usize, PathBuf, PathBuf)> {
    static RUNS: OnceLock<Vec<(String, usize, PathBuf, PathBuf)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("occlusion");
        let mut out = Vec::new();
        for (name, t) in [
            ("corridor", corridor()),
            ("office", fixture("tests/office.toml")),
        ] {
            for n in [16usize, 100] {
                let (c, e) = simulated(&root.join(format!("{name}_n{n}")), &t, n);
                out.push((name.to_string(), n, c, e));
            }
        }
        out
    })
}

/// `pradar map --method METHOD` on one run (the mapping tests' runner); its metrics.json.
fn map(method: &str, c: &Path, e: &Path, out: &Path) -> Value {
    map_with(method, &[], c, e, out)
}

/// [`map`] with extra flags.
fn map_with(method: &str, extra: &[&str], c: &Path, e: &Path, out: &Path) -> Value {
    let mut args = vec![
        "map",
        "--method",
        method,
        "--campaign",
        s(c),
        "--energy",
        s(e),
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    let o = crate::mapping::pradar(&args, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    crate::mapping::metrics_json(out)
}

use crate::mapping::fig as f;

fn wrong(v: &Value, region: &str) -> f64 {
    f(v, &["metrics", region, "wrong_cell_rate"]) * f(v, &["metrics", region, "cells"])
}

type Figures = Vec<(
    String,
    usize,
    std::collections::HashMap<&'static str, Value>,
)>;

/// Every scene mapped by `og`, `og-boresight` and `ekf` once per test binary, and by the
/// EKF without the arc explanation (`ekf-unexplained`: `--ekf-arc-explain 0`) (figures
/// printed): (scene, N, metrics.json per method).
fn figures() -> &'static Figures {
    static FIGS: OnceLock<Figures> = OnceLock::new();
    FIGS.get_or_init(|| {
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("occlusion_maps");
        let mut all = Vec::new();
        for (name, n, c, e) in scenes() {
            let mut figs = std::collections::HashMap::new();
            for method in ["og", "og-boresight", "ekf", "ekf-unexplained"] {
                let out = root.join(format!("{name}_{n}_{method}"));
                let j = match method {
                    "ekf-unexplained" => {
                        map_with("ekf", &["--ekf-arc-explain", "0"], c, e, &out)
                    }
                    m => map(m, c, e, &out),
                };
                let t = |r: &str, k: &str| f(&j, &["metrics", "three_class", r, k]);
                eprintln!(
                    "{name} N={n} {method:>12}: three-class building wrong {:.0} (all-free {:.0}) walls found {:.3} precision(1) {:.3} F1(1) {:.3} free marked occupied {:.4} objects found {:.0} of {:.0} | whole wrong {:.0} (all-free {:.0}) beyond the walls marked occupied {:.4}",
                    t("building", "wrong"),
                    t("building_all_free", "wrong"),
                    t("building", "walls_found_1"),
                    t("building", "precision_1"),
                    t("building", "f1_1"),
                    t("building", "free_marked_occupied"),
                    t("whole", "objects_found"),
                    t("whole", "objects"),
                    t("whole", "wrong"),
                    t("whole_all_free", "wrong"),
                    t("whole", "beyond_marked_occupied"),
                );
                let g = |p: &[&str]| f(&j, p);
                eprintln!(
                    "{name} N={n} {method:>12}: building wrong {:.0} (all-free {:.0}) psi {:.2} (all-free {:.2}) | whole wrong {:.0} (all-free {:.0}) psi {:.2} | observable wrong {:.0} (all-free {:.0}) psi {:.2} (all-free {:.2}) | walls found (1 cell) {:.3} of {:.0} | free marked occupied {:.4} of {:.0} | outside marked occupied {:.4} of {:.0}",
                    wrong(&j, "building"),
                    wrong(&j, "building_all_free"),
                    g(&["metrics", "building", "psi"]),
                    g(&["metrics", "building_all_free", "psi"]),
                    wrong(&j, "whole"),
                    wrong(&j, "whole_all_free"),
                    g(&["metrics", "whole", "psi"]),
                    wrong(&j, "observable"),
                    wrong(&j, "observable_all_free"),
                    g(&["metrics", "observable", "psi"]),
                    g(&["metrics", "observable_all_free", "psi"]),
                    g(&["metrics", "classes", "walls_found_1"]),
                    g(&["metrics", "classes", "observable_wall_cells"]),
                    g(&["metrics", "classes", "free_marked_occupied"]),
                    g(&["metrics", "classes", "free_cells"]),
                    g(&["metrics", "classes", "outside_marked_occupied"]),
                    g(&["metrics", "classes", "outside_cells"]),
                );
                figs.insert(method, j);
            }
            all.push((name.clone(), *n, figs));
        }
        all
    })
}

/// Issue 31, item 2 (range rings), the arc explanation measured alone: the default EKF
/// (a cell is occupied only if on some detected echo's range ring its share c̃·x̂² is at
/// least γ = −26.5 dB of the ring's largest) against the same filter with the step off
/// (`--ekf-arc-explain 0`). In each of the four scenes: fewer wrong cells over the
/// building, at most 5 % of the room's free cells and of the cells beyond the walls
/// marked occupied, a higher F1 within one cell, and walls found within 0.05 of the map
/// without the step. Off → on (building wrong, room free marked occupied, beyond marked
/// occupied, walls found, F1(1)): corridor N = 16 461 → 376, 8.5 → 4.1 %, 2.3 → 1.5 %,
/// 0.508 → 0.486, 0.523 → 0.588; N = 100 401 → 337, 6.6 → 3.4 %, 1.6 → 1.2 %,
/// 0.538 → 0.533, 0.598 → 0.653; office N = 16 343 → 312, 6.0 → 4.4 %, 8.5 → 4.3 %,
/// 0.710 → 0.672, 0.709 → 0.718; N = 100 332 → 275, 6.8 → 4.0 %, 5.7 → 3.9 %,
/// 0.751 → 0.717, 0.739 → 0.768 (all-free 364 / 364 / 293 / 293: below it at N = 100).
/// (Figures measured before the boundary band of 5 Dec 2026, which lowers every map's
/// three-class wrong cells and room cells marked occupied: docs/mapping.md.)
#[test]
fn ekf_arc_explanation_clears_room_cells_that_explain_no_echo() {
    for (name, n, figs) in figures() {
        let t = |m: &str, r: &str, k: &str| f(&figs[m], &["metrics", "three_class", r, k]);
        let (off, on) = (
            t("ekf-unexplained", "building", "wrong"),
            t("ekf", "building", "wrong"),
        );
        assert!(
            on < off,
            "{name} N={n}: building wrong {on} vs {off} without"
        );
        let room = t("ekf", "building", "free_marked_occupied");
        assert!(
            room <= 0.05,
            "{name} N={n}: room free marked occupied {room}"
        );
        let beyond = t("ekf", "whole", "beyond_marked_occupied");
        assert!(
            beyond <= 0.05,
            "{name} N={n}: beyond marked occupied {beyond}"
        );
        let (f_off, f_on) = (
            t("ekf-unexplained", "building", "f1_1"),
            t("ekf", "building", "f1_1"),
        );
        assert!(
            f_on > f_off,
            "{name} N={n}: F1(1) {f_on} vs {f_off} without"
        );
        let (w_off, w_on) = (
            t("ekf-unexplained", "building", "walls_found_1"),
            t("ekf", "building", "walls_found_1"),
        );
        assert!(
            w_on > w_off - 0.05,
            "{name} N={n}: walls found {w_on} vs {w_off} without"
        );
    }
}

/// What the occlusion model achieves today (issue 17's must-show is the ignored test
/// below): on all four scenes the side-lobe-aware OG has fewer wrong cells on the building
/// than the all-free map and than the boresight baseline, and on the corridor it marks at
/// most 5 % of the cells beyond the walls occupied (54 % at N = 100 before the occlusion
/// model, `docs/mapping.md`). Wrong cells on the three-class reference (DESIGN §2, issue 31:
/// the truth's objects are not counted as wrong; until 5 Dec 2026 this test counted them,
/// and the OG default of that day, `--og-bound-silent nearer --og-credit-depth 0.05`,
/// marks more of the office's objects: layout-only 301 / 311 of the all-free 293, three-class
/// 164 / 170).
#[test]
fn og_beats_all_free_and_boresight_on_the_building_and_keeps_the_corridor_outside_free() {
    let mut failures = Vec::new();
    for (name, n, figs) in figures() {
        let (og, bs) = (&figs["og"], &figs["og-boresight"]);
        let t = |v: &Value, region: &str| f(v, &["metrics", "three_class", region, "wrong"]);
        let (wo, wa, wb) = (
            t(og, "building"),
            t(og, "building_all_free"),
            t(bs, "building"),
        );
        if wo >= wa || wo >= wb {
            failures.push(format!(
                "{name} N={n}: og building wrong {wo:.0} not below all-free {wa:.0} and boresight {wb:.0}"
            ));
        }
        let oo = f(og, &["metrics", "classes", "outside_marked_occupied"]);
        if name == "corridor" && oo > 0.05 {
            failures.push(format!("{name} N={n} og: outside marked occupied {oo:.4}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Issue 17's must-show for both mappers on the corridor at N = 16 and 100 and the office
/// at N = 16 and 100: fewer wrong cells than the all-free map on the building and on the
/// whole map, >= 85 % of the observable wall cells found within one cell, <= 5 % of the
/// room's free cells and <= 5 % of the cells beyond the walls marked occupied, and the OG
/// better than the boresight baseline on ψ and wrong cells. Unmet (figures printed by
/// `figures()`; the list of misses in the failure message): the whole map, where the
/// cells just beyond the walls a range ring still reaches outnumber the hits, and the EKF,
/// whose means rise over the whole main-lobe arc of an echo. Run with `--ignored`.
#[test]
#[ignore = "unmet (layout-only: the simulator's objects count as wrong): whole-map wrong cells above all-free for both mappers; building wrong above all-free for the EKF (404/376/337/301 vs 364/364/293/293) and, since the OG default of 5 Dec 2026, the OG in the office (301/311 vs 293; three-class 164/170); walls found 0.823/0.833 (OG), 0.812/0.809 (EKF) at N = 16; free/outside cells marked occupied above 5 % in some scenes (OG 5.4-7.2 %, EKF office N = 16 5.1 %)"]
fn both_mappers_map_the_building_and_leave_the_outside_free() {
    let mut failures = Vec::new();
    for (name, n, figs) in figures() {
        for method in ["og", "ekf"] {
            let j = &figs[method];
            let mut check = |ok: bool, what: String| {
                if !ok {
                    failures.push(format!("{name} N={n} {method}: {what}"));
                }
            };
            check(
                wrong(j, "building") < wrong(j, "building_all_free"),
                "building: not fewer wrong cells than all-free".into(),
            );
            check(
                wrong(j, "whole") < wrong(j, "whole_all_free"),
                "whole map: not fewer wrong cells than all-free".into(),
            );
            let found = f(j, &["metrics", "classes", "walls_found_1"]);
            check(
                found >= 0.85,
                format!("walls found within one cell {found:.3} < 0.85"),
            );
            let fo = f(j, &["metrics", "classes", "free_marked_occupied"]);
            check(
                fo <= 0.05,
                format!("free cells marked occupied {fo:.4} > 0.05"),
            );
            let oo = f(j, &["metrics", "classes", "outside_marked_occupied"]);
            check(
                oo <= 0.05,
                format!("outside cells marked occupied {oo:.4} > 0.05"),
            );
        }
        let (og, bs) = (&figs["og"], &figs["og-boresight"]);
        for region in ["building", "whole"] {
            let (po, pb) = (
                f(og, &["metrics", region, "psi"]),
                f(bs, &["metrics", region, "psi"]),
            );
            let (wo, wb) = (wrong(og, region), wrong(bs, region));
            if po >= pb || wo >= wb {
                failures.push(format!(
                    "{name} N={n}: og on the {region}: psi {po:.3} / wrong {wo:.0} vs boresight {pb:.3} / {wb:.0}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "NOT MET:\n{}", failures.join("\n"));
}

/// Issue 31's (Maps II) must-show for both mappers with their defaults on the corridor and
/// the office at N = 16 and 100, scored against the three-class reference (structure, the
/// simulator's objects, free; the band of cells a wall on a grid line touches from the
/// other side ignored, `mapping::metrics`): over the building fewer wrong cells than the
/// all-free map; observable walls found within one cell ≥ 0.85; ≤ 5 % of the room's free
/// cells (building) and ≤ 5 % of the cells beyond the walls (whole map) marked occupied; F1
/// within one cell (building) above the boresight baseline's, and ψ (three-class, building:
/// the object zones left out, DESIGN §2) below it. Prints the grid (✓ met, ✗ unmet) and
/// lists the misses. Measured (defaults): 40 of 48 — the OG misses observable walls 0.823 /
/// 0.833 (corridor and office N = 16) and ψ on the corridor at N = 16 (8.26 vs 7.79; at N =
/// 100 7.46 vs 7.48 is met); the EKF misses observable walls 0.812 / 0.809 (N = 16), F1(1)
/// on the corridor N = 16 (0.588 vs 0.599) and ψ on the corridor (9.63 / 8.21 vs 7.79 /
/// 7.48). Both are below the all-free map over the building in every scene (OG 253 / 248 /
/// 164 / 170, EKF 311 / 283 / 226 / 197 vs 364 / 364 / 293 / 293). With the OG's rules
/// before 5 Dec 2026 (`--og-bound-silent off --og-credit-depth guard`) 37 of 48: the OG
/// also missed the office N = 100's beyond the walls (7.0 %) and ψ in the office at N = 16;
/// with the layout-only ψ (objects counted as wrong, before 5 Dec 2026) 39 of 48. The ghost
/// and fig6 are their own tests. Issue 48's decisions: ψ is judged on the observable region
/// (a) and 0.80 of the observable walls is accepted at N = 16 (d): 46 of 48 (the OG all 24;
/// the EKF misses the corridor at N = 16 on F1(1), 0.599 against 0.599, and on ψ, 3.92
/// against 3.43).
#[test]
#[ignore = "unmet: 46 of 48 with issue 48's decisions (EKF corridor N = 16: F1(1) 0.599 vs boresight 0.599, psi on the observable region 3.92 vs 3.43); the OG meets all 24"]
fn maps_ii_must_show_on_the_three_class_reference() {
    let mut failures = Vec::new();
    let mut met = 0;
    let mut total = 0;
    for (name, n, figs) in figures() {
        let bs = &figs["og-boresight"];
        let t = |j: &Value, region: &str, k: &str| f(j, &["metrics", "three_class", region, k]);
        // issue 48 (d): 0.81–0.83 of the observable walls at N = 16 is what 25° beams see
        let walls_bound = if *n == 16 { 0.80 } else { 0.85 };
        for method in ["og", "ekf"] {
            let j = &figs[method];
            let checks = [
                (
                    "below all-free",
                    t(j, "building", "wrong"),
                    t(j, "building_all_free", "wrong"),
                    t(j, "building", "wrong") < t(j, "building_all_free", "wrong"),
                ),
                (
                    "observable walls",
                    t(j, "observable", "walls_found_1"),
                    walls_bound,
                    t(j, "observable", "walls_found_1") >= walls_bound,
                ),
                (
                    "room",
                    t(j, "building", "free_marked_occupied"),
                    0.05,
                    t(j, "building", "free_marked_occupied") <= 0.05,
                ),
                (
                    "beyond",
                    t(j, "whole", "beyond_marked_occupied"),
                    0.05,
                    t(j, "whole", "beyond_marked_occupied") <= 0.05,
                ),
                (
                    "F1(1) vs boresight",
                    t(j, "building", "f1_1"),
                    t(bs, "building", "f1_1"),
                    t(j, "building", "f1_1") > t(bs, "building", "f1_1"),
                ),
                (
                    "psi vs boresight (observable)",
                    t(j, "observable", "psi"),
                    t(bs, "observable", "psi"),
                    t(j, "observable", "psi") < t(bs, "observable", "psi"),
                ),
            ];
            eprintln!(
                "psi {name} N={n} {method}: three-class building {:.2} (boresight {:.2}), observable {:.2} ({:.2}); layout-only building {:.2} ({:.2})",
                t(j, "building", "psi"),
                t(bs, "building", "psi"),
                t(j, "observable", "psi"),
                t(bs, "observable", "psi"),
                f(j, &["metrics", "building", "psi"]),
                f(bs, &["metrics", "building", "psi"]),
            );
            let grid: Vec<String> = checks
                .iter()
                .map(|(what, v, bound, ok)| {
                    format!("{what} {v:.3} ({bound:.3}) {}", if *ok { "✓" } else { "✗" })
                })
                .collect();
            eprintln!("MUST-SHOW {name} N={n} {method}: {}", grid.join(" | "));
            for (what, v, bound, ok) in checks {
                total += 1;
                if ok {
                    met += 1;
                } else {
                    failures.push(format!(
                        "{name} N={n} {method}: {what} {v:.3} vs {bound:.3}"
                    ));
                }
            }
        }
    }
    eprintln!("MUST-SHOW met {met} of {total}");
    assert!(
        failures.is_empty(),
        "NOT MET ({met} of {total} met):\n{}",
        failures.join("\n")
    );
}

/// fig6's statement as decided in issue 48 (b), judged on physics: on the sweeps simulated
/// at both N (the corridor and the office, three campaign seeds each: the fixture's seed and
/// the next two), N = 16 has more wrong cells than N = 100 over the building for both
/// mappers (three-class reference, objects from `truth/scatterers.csv`). On model data
/// fig6 reports the comparison (`experiment::fig6_*`) and asserts nothing about it. Figures
/// in `docs/mapping.md` ("Issue 48"). About 3 min on 2 shared cores (eight simulations
/// beside the four of [`scenes`]); run with `--ignored`.
#[test]
#[ignore = "unmet: 8 of 12 (OG office seed 1 164 vs 170, office seed 2 184 vs 184; EKF corridor seed 2 274 vs 292, office all met; about 3 min)"]
fn fig6_n16_has_more_wrong_cells_than_n100_on_physics_sweeps() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("occlusion_fig6");
    let mut failures = Vec::new();
    for (name, t) in [
        ("corridor", corridor()),
        ("office", fixture("tests/office.toml")),
    ] {
        let seed0 = t["seed"].as_integer().unwrap();
        for k in 0..3i64 {
            let mut wrong_by_n = std::collections::HashMap::new();
            for n in [16usize, 100] {
                let (c, e) = if k == 0 {
                    let r = scenes().iter().find(|r| r.0 == name && r.1 == n).unwrap();
                    (r.2.clone(), r.3.clone())
                } else {
                    let mut t = t.clone();
                    set(&mut t, "seed", seed0 + k);
                    simulated(&root.join(format!("{name}_s{k}_n{n}")), &t, n)
                };
                for method in ["og", "ekf"] {
                    let j = map(
                        method,
                        &c,
                        &e,
                        &root.join(format!("{name}_s{k}_n{n}_{method}")),
                    );
                    let w = f(&j, &["metrics", "three_class", "building", "wrong"]);
                    wrong_by_n.insert((n, method), w);
                }
            }
            for method in ["og", "ekf"] {
                let (a, b) = (wrong_by_n[&(16, method)], wrong_by_n[&(100, method)]);
                eprintln!(
                    "fig6 on sweeps, {name} seed {} {method}: three-class building wrong N = 16 {a:.0}, N = 100 {b:.0}",
                    seed0 + k
                );
                if a <= b {
                    failures.push(format!(
                        "{name} seed {} {method}: {a:.0} vs {b:.0}",
                        seed0 + k
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "NOT MET:\n{}", failures.join("\n"));
}

/// The ghost scene: the office with a strong reflector seen only through the north wall
/// (the image of a reflector through the wall, path seen via the wall), no clutter.
fn ghost_scene() -> (toml::Table, [f64; 2]) {
    let mut t = fixture("tests/office.toml");
    t.remove("clutter");
    // a reflector 0.8 m in front of the north wall (y = 4.5) seen through it: its image
    let image = [3.0, 5.3];
    let mut target = toml::Table::new();
    target.insert("x_m".into(), image[0].into());
    target.insert("y_m".into(), image[1].into());
    target.insert("rrcs_m".into(), 0.3.into());
    target.insert(
        "via_m".into(),
        toml::Value::Array(vec![3.0.into(), 4.5.into()]),
    );
    let scene = t.get_mut("scene").unwrap().as_table_mut().unwrap();
    scene.insert(
        "targets".into(),
        toml::Value::Array(vec![toml::Value::Table(target)]),
    );
    (t, image)
}

/// A multi-bounce ghost behind a wall: both mappers with their defaults leave at most 5 of
/// the 90 cells around the image occupied (the boresight map shows it). The ghost rules
/// measured on this scene and not kept are in docs/cli.md ("Options measured and not
/// kept"). Run with `--ignored`.
#[test]
#[ignore = "unmet: OG 15, EKF 5 of 90 ghost cells occupied (boresight 35)"]
fn a_multi_bounce_ghost_leaves_no_occupied_cell_beyond_the_wall() {
    let (t, image) = ghost_scene();
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("occlusion_ghost");
    let (c, e) = simulated(&root, &t, 100);
    let campaign = pradar::campaign::Campaign::load(&c).unwrap();
    let layout = Layout::load(&campaign.layout_path()).unwrap();
    let reference = layout.rasterize(0.1, 0.5);
    let spec = reference.spec;
    // the cells beyond the wall within 0.6 m of the image and at least 2 cells behind the
    // wall (the wall's own cells and their neighbours are not the ghost's)
    let ghost_cells: Vec<usize> = (0..spec.len())
        .filter(|&i| {
            let p = spec.center(i / spec.cols, i % spec.cols);
            reference.cells[i] == CellClass::Outside
                && (p.x - image[0]).hypot(p.y - image[1]) <= 0.6
                && p.y >= 4.5 + 0.25
        })
        .collect();
    assert!(ghost_cells.len() > 50, "the image must lie inside the grid");
    let mut res = std::collections::HashMap::new();
    let runs: [(&str, &str, &[&str]); 3] = [
        ("og-boresight", "og-boresight", &[]),
        ("og", "og", &[]),
        ("ekf", "ekf", &[]),
    ];
    for (tag, method, flags) in runs {
        let out = root.join(format!("map_{tag}"));
        let j = map_with(method, flags, &c, &e, &out);
        let bin = read_binary_pgm(&out.join(format!("{method}_binary.pgm")));
        let occ = ghost_cells.iter().filter(|&&i| bin[i]).count();
        let outside = (0..spec.len())
            .filter(|&i| reference.cells[i] == CellClass::Outside && bin[i])
            .count();
        let walls = f(&j, &["metrics", "three_class", "building", "walls_found_1"]);
        eprintln!(
            "{tag:>12}: {occ} of {} cells within 0.6 m of the ghost (beyond the wall) occupied; {outside} outside cells occupied in all; walls found (building) {walls:.3}",
            ghost_cells.len()
        );
        res.insert(tag, (occ, walls));
    }
    assert!(
        res["og-boresight"].0 > 0,
        "the boresight map should show the ghost"
    );
    for method in ["og", "ekf"] {
        assert!(
            res[method].0 <= 5,
            "{method}: {} ghost cells occupied",
            res[method].0
        );
    }
}

/// A binary PGM map read back by the mapping tests' independent reader (row 0 of the file
/// is the northern row): true = occupied, row-major from the lowest y.
fn read_binary_pgm(path: &Path) -> Vec<bool> {
    let (w, h, _, px) = crate::mapping::read_pgm(path);
    let mut out = vec![false; w * h];
    for r in 0..h {
        for c in 0..w {
            out[(h - 1 - r) * w + c] = px[r * w + c] < 128;
        }
    }
    out
}

/// The walls the echoes can show at all: the ceiling of "walls found within one cell" for a
/// mapper that places occupancy on detected echoes in line of sight (issue 31's must-show
/// asks ≥ 0.85). A wall cell is *shown* when a cell of its 8-neighbourhood (the walls-found
/// tolerance) lies in line of sight of some pose (through the layout's walls, as the
/// observable region), inside the two-way −3 dB main lobe of some direction of that pose,
/// within a bin where the run's own detector (`pradar map`'s P_fa, peak and
/// range-side-lobe tests) fires. Reads the layout and the energy table (no truth); printed
/// beside the mappers' walls found (building and observable).
///
/// Asserts that on the observable walls the ceiling is ≥ 0.9 in every scene (measured
/// 0.930 / 0.978 / 1.000 / 1.000): there the must-show is within the data's reach and a
/// shortfall is the mapper's. On the building the ceiling is 0.555 / 0.607 / 0.812 /
/// 0.805 (corridor N = 16, 100, office N = 16, 100): the building's wall cells no pose
/// sees in its main lobe (178 / 180 of 364 in the corridor, 78 / 86 of 293 in the office)
/// put 0.85 out of reach of any mapper that respects line of sight (the boresight
/// baseline, which credits echoes beyond the walls, finds 0.604 / 0.673 / 0.894 / 0.908).
#[test]
fn walls_the_echoes_can_show() {
    use pradar::mapping::score::score_binary;
    let figs = figures();
    let mut failures = Vec::new();
    for (name, n, c, e) in scenes() {
        let (runs, reference, regions) = loaded_og_run(c, e);
        let evidenced = main_lobe_evidence(&runs[0]);
        // the evidence scored as a map by the maps' own scorer: its walls found is the ceiling
        let shown = score_binary(&evidenced, &reference, &regions)
            .three_class
            .expect("the scenes have a truth");
        let ceiling = |m: &pradar::mapping::metrics::ThreeClassMetrics| {
            let n = m.structure_cells;
            ((m.walls_found_1 * n as f64).round() as usize, n)
        };
        let (sb, nb) = ceiling(&shown.building);
        let (so, no) = ceiling(&shown.observable);
        let scene = &figs.iter().find(|(s, k, _)| s == name && k == n).unwrap().2;
        let found = |method: &str, region: &str| {
            f(
                &scene[method],
                &["metrics", "three_class", region, "walls_found_1"],
            )
        };
        eprintln!(
            "{name} N={n}: wall cells shown by a main-lobe detection (within one cell): building {sb} of {nb} = {:.3} (og {:.3}, ekf {:.3}, og-boresight {:.3}), observable {so} of {no} = {:.3} (og {:.3}, ekf {:.3}, og-boresight {:.3})",
            sb as f64 / nb as f64,
            found("og", "building"),
            found("ekf", "building"),
            found("og-boresight", "building"),
            so as f64 / no as f64,
            found("og", "observable"),
            found("ekf", "observable"),
            found("og-boresight", "observable"),
        );
        if (so as f64) < 0.9 * no as f64 {
            failures.push(format!(
                "{name} N={n}: observable walls shown {:.3} < 0.9",
                so as f64 / no as f64
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// One run loaded as `pradar map --method og` loads it (defaults): the runs, the reference
/// and the scoring regions.
fn loaded_og_run(
    c: &Path,
    e: &Path,
) -> (
    Vec<pradar::mapping::job::LoadedRun>,
    pradar::mapping::reference::ReferenceMap,
    pradar::mapping::score::Regions,
) {
    use pradar::mapping::job::{load_runs, runs_regions, MapOptions, MapRun};
    use pradar::mapping::{EkfParams, GridParams, Method, OgParams};
    use pradar::params::ParamGuard;
    let opts = MapOptions {
        method: Method::Og,
        runs: vec![MapRun {
            campaign: c.to_path_buf(),
            energy: e.to_path_buf(),
        }],
        out: PathBuf::from("unused"),
        elements: None,
        grid: GridParams::default(),
        og: OgParams::default(),
        ekf: EkfParams::default(),
        pose_noise: Default::default(),
        poses_from: Default::default(),
        odometry: Default::default(),
    }
    .check()
    .unwrap();
    let (runs, reference) = load_runs(&opts).unwrap();
    let regions = runs_regions(&runs, &reference).unwrap();
    (runs, reference, regions)
}

/// The cells a main-lobe detection of `run` shows: for every detection (the OG's own
/// detector) of every (pose, direction), the cells of its bin inside the direction's −3 dB
/// main lobe and in line of sight of the pose.
fn main_lobe_evidence(run: &pradar::mapping::job::LoadedRun) -> Vec<bool> {
    use pradar::energy::EnergySource;
    let m = &run.model;
    let spec = m.spec;
    let main = m.params.main_weight() as f32;
    let tol = spec.cell_m * std::f64::consts::FRAC_1_SQRT_2;
    let mut evidenced = vec![false; spec.len()];
    let np = m.poses.len();
    for p in 0..np {
        let part = run.energy.load(p, p + 1).unwrap();
        let det = run.detector.detect_pose(&part, p);
        let g = m.pose_geometry(p);
        let pose = m.poses[p];
        let at = geo::Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        for (d, det) in det.iter().enumerate() {
            let beam = m.beam(&g, d);
            let bins = det.len().min(beam.ptr.len() - 1);
            for b in (0..bins).filter(|&b| det[b]) {
                for j in beam.bin_range(b) {
                    let cell = beam.cell[j] as usize;
                    if beam.weight[j] < main || evidenced[cell] {
                        continue;
                    }
                    let centre = spec.center(cell / spec.cols, cell % spec.cols);
                    if !run.layout.occluded(at, centre, tol) {
                        evidenced[cell] = true;
                    }
                }
            }
        }
    }
    evidenced
}

/// Issue 55, item 1: the detectable reference (`mapping::detectable`, from the simulator's
/// paths) holds the walls the data show: of the wall cells with a main-lobe detection
/// within one cell (the OG's own detector on the simulated sweeps, as
/// [`walls_the_echoes_can_show`]), at least 90 % are within one cell of a detectable wall
/// cell — a detectable reference at the wrong energy scale (the threshold against |S21|²
/// off by the kernel's K(0), or the pattern's gain) or without the main-lobe rule would
/// not hold them. The detectable share of the observable walls is between 0.5 and 1 (a
/// reference of every observable wall, the old ceiling, reads 1), and each mapper's
/// detectable walls found is printed beside its observable walls found. Each map's false
/// cells by cause (issue 55, item 2) add up to the free cells it marks (printed).
#[test]
fn the_detectable_walls_hold_the_walls_the_echoes_show() {
    let figs = figures();
    let mut failures = Vec::new();
    for (name, n, c, e) in scenes() {
        let (runs, reference, regions) = loaded_og_run(c, e);
        let det = regions
            .detectable
            .as_ref()
            .expect("simulate's truth has paths");
        let evidenced = main_lobe_evidence(&runs[0]);
        let spec = reference.spec;
        let near = |v: &[bool], i: usize| {
            let (r, c) = ((i / spec.cols) as isize, (i % spec.cols) as isize);
            (-1..=1).any(|dr| {
                (-1..=1).any(|dc| {
                    let (rr, cc) = (r + dr, c + dc);
                    rr >= 0
                        && cc >= 0
                        && (rr as usize) < spec.rows
                        && (cc as usize) < spec.cols
                        && v[rr as usize * spec.cols + cc as usize]
                })
            })
        };
        let (mut shown, mut held) = (0usize, 0usize);
        for i in 0..spec.len() {
            if reference.cells[i] == CellClass::Occupied && near(&evidenced, i) {
                shown += 1;
                held += near(&det.walls, i) as usize;
            }
        }
        let scene = &figs.iter().find(|(s, k, _)| s == name && k == n).unwrap().2;
        let g = |method: &str, p: &[&str]| f(&scene[method], p);
        let share = g(
            "og",
            &[
                "metrics",
                "three_class",
                "detectable",
                "detectable_share_of_observable",
            ],
        );
        let cells = det.walls.iter().filter(|&&w| w).count();
        eprintln!(
            "{name} N={n}: detectable wall cells {cells}, {:.3} of the observable walls; wall cells a main-lobe detection shows {shown}, {held} of them ({:.3}) within one cell of a detectable one; detectable walls found og {:.3} ekf {:.3} (observable walls found og {:.3} ekf {:.3}); detectable objects found og {:.0} ekf {:.0} of {:.0}",
            share,
            held as f64 / shown.max(1) as f64,
            g("og", &["metrics", "three_class", "detectable", "walls_found_1"]),
            g("ekf", &["metrics", "three_class", "detectable", "walls_found_1"]),
            g("og", &["metrics", "three_class", "observable", "walls_found_1"]),
            g("ekf", &["metrics", "three_class", "observable", "walls_found_1"]),
            g("og", &["metrics", "three_class", "detectable", "objects_found"]),
            g("ekf", &["metrics", "three_class", "detectable", "objects_found"]),
            g("og", &["metrics", "three_class", "detectable", "objects"]),
        );
        for method in ["og", "ekf"] {
            // false cells by cause: they add up to the free cells the three-class figures
            // count as marked (room and beyond the walls, whole grid)
            let fc = |k: &str| g(method, &["metrics", "three_class", "false_cells", k]);
            let w = |k: &str| g(method, &["metrics", "three_class", "whole", k]);
            let marked = (w("free_marked_occupied") * w("free_cells")
                + w("beyond_marked_occupied") * w("beyond_cells"))
            .round();
            let parts = ["main_lobe_arc", "side_lobe", "folded", "image", "noise"];
            eprintln!(
                "{name} N={n} {method}: false cells {:.0} = arc {:.0} + side lobe {:.0} + folded {:.0} + image {:.0} + noise {:.0}",
                fc("total"),
                fc(parts[0]),
                fc(parts[1]),
                fc(parts[2]),
                fc(parts[3]),
                fc(parts[4])
            );
            if fc("total") != marked || parts.iter().map(|k| fc(k)).sum::<f64>() != fc("total") {
                failures.push(format!(
                    "{name} N={n} {method}: false cells {} do not add up (marked free cells {marked})",
                    fc("total")
                ));
            }
        }
        if (held as f64) < 0.9 * shown as f64 {
            failures.push(format!(
                "{name} N={n}: {held} of {shown} shown wall cells near a detectable one (< 0.9)"
            ));
        }
        if !(0.5..=1.0).contains(&share) || share == 1.0 {
            failures.push(format!(
                "{name} N={n}: detectable share of the observable walls {share:.3} not in [0.5, 1)"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Issue 31, "Maps II": the OG's dominant miss of the walls the echoes show is the free
/// evidence of beams without an occluder (a smooth wall at oblique incidence returns no
/// echo to them, `docs/mapping.md`). Against the OG with `--og-bound-silent off
/// --og-credit-depth guard` (`off`): with such a direction bounding the visibility
/// polygon at its first detection instead (`--og-bound-silent leak`, alias `true`) the OG
/// finds ≥ 0.85 of the office N = 16's observable walls (measured 0.865) with fewer
/// building wrong cells than the all-free map in every scene. Bounding it at the nearer of
/// that detection and the range interpolated from its neighbours' occluders
/// (`--og-bound-silent nearer`) keeps both and never marks more cells beyond the walls
/// occupied than `leak`, fewer in the office at N = 16 (measured 8.7 → 8.3 %; corridor
/// 3.3 / 3.2 %, office N = 100 11.1 % both). With the occupancy credit limited to cells at
/// most half a cell behind the polygon as well (`--og-credit-depth 0.05`, the default since
/// 5 Dec 2026) the rim of credited cells beyond the walls goes: the cells beyond the walls
/// marked occupied fall to ≤ 5 % in three scenes (1.9 / 2.2 / 4.3 %) and below `off`'s in
/// the office at N = 100 (9.9 → 7.2 %), the room's to ≤ 5 % (three-class building), the
/// three-class building wrong cells stay below the all-free map, and the observable walls
/// found stay within 0.01 of `off`'s (0.823 / 0.875 / 0.833 / 0.923; ≥ 0.8 asserted in the
/// office at N = 16). Figures printed; the default's are the shared scenes' `og` maps.
#[test]
fn og_without_the_free_evidence_of_beams_without_an_occluder_finds_more_walls() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("og_free_without_occluder");
    // the shared scenes' `og` maps are the "nearer-credit" case: the defaults must be it
    let d = pradar::mapping::OgParams::default();
    assert_eq!(d.bound_silent, pradar::mapping::grid::SilentBound::Nearer);
    assert_eq!(d.credit_depth_m, Some(0.05));
    let mut failures = Vec::new();
    for (name, n, c, e) in scenes() {
        const OFF: [&str; 4] = ["--og-bound-silent", "off", "--og-credit-depth", "guard"];
        let base = &map_with("og", &OFF, c, e, &root.join(format!("{name}_{n}_off")));
        let default = &figures()
            .iter()
            .find(|(s, k, _)| s == name && k == n)
            .unwrap()
            .2["og"];
        let w = |v: &Value| {
            f(
                v,
                &["metrics", "three_class", "observable", "walls_found_1"],
            )
        };
        let o = |v: &Value| f(v, &["metrics", "classes", "outside_marked_occupied"]);
        let w0 = w(base);
        let mut leak_outside = f64::NAN;
        let runs: [(&str, &[&str]); 3] = [
            (
                "bound",
                &["--og-bound-silent", "true", "--og-credit-depth", "guard"],
            ),
            (
                "nearer",
                &["--og-bound-silent", "nearer", "--og-credit-depth", "guard"],
            ),
            ("nearer-credit", &[]),
        ];
        for (label, flags) in runs {
            let j = if label == "nearer-credit" {
                default.clone()
            } else {
                map_with("og", flags, c, e, &root.join(format!("{name}_{n}_{label}")))
            };
            let w1 = w(&j);
            eprintln!(
                "{name} N={n} {label}: observable walls found {w0:.3} -> {w1:.3}; outside marked occupied {:.4} -> {:.4}; building wrong {:.0} -> {:.0} (all-free {:.0})",
                o(base),
                o(&j),
                wrong(base, "building"),
                wrong(&j, "building"),
                wrong(&j, "building_all_free"),
            );
            let office16 = name == "office" && *n == 16;
            let need = match (label, office16) {
                ("bound" | "nearer", true) => 0.85,
                ("nearer-credit", true) => 0.8,
                ("nearer-credit", false) => w0 - 0.01,
                _ => w0,
            };
            if w1 < need {
                failures.push(format!("{name} N={n} {label}: {w1:.3} < {need:.3}"));
            }
            // (nearer-credit: layout-only building wrong above the all-free map in the
            // office, 301 / 311 vs 293; its three-class figure is asserted below)
            if matches!(label, "bound" | "nearer")
                && wrong(&j, "building") >= wrong(&j, "building_all_free")
            {
                failures.push(format!(
                    "{name} N={n} {label}: building wrong not below all-free"
                ));
            }
            match label {
                "bound" => leak_outside = o(&j),
                "nearer" => {
                    let ok = if office16 {
                        o(&j) < leak_outside
                    } else {
                        o(&j) <= leak_outside
                    };
                    if !ok {
                        failures.push(format!(
                            "{name} N={n} nearer: outside marked occupied {:.4} vs leak {leak_outside:.4}",
                            o(&j)
                        ));
                    }
                }
                "nearer-credit" => {
                    // the must-show's figures this combination keeps (three-class building)
                    let t = |k: &str| f(&j, &["metrics", "three_class", "building", k]);
                    let all_free = f(
                        &j,
                        &["metrics", "three_class", "building_all_free", "wrong"],
                    );
                    let room = t("free_marked_occupied");
                    let outside_cap = if name == "office" && *n == 100 {
                        o(base) // 9.9 % with the rules before: asserted lower, not <= 5 %
                    } else {
                        0.05
                    };
                    if t("wrong") >= all_free || room > 0.05 || o(&j) >= outside_cap {
                        failures.push(format!(
                            "{name} N={n} nearer-credit: building wrong {:.0} (all-free {all_free:.0}), room {room:.4}, outside {:.4} (cap {outside_cap:.4})",
                            t("wrong"),
                            o(&j)
                        ));
                    }
                }
                _ => {}
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `--og-credit echo` (issue 55 item 2): each detection credits only the bearing of the
/// echo its direction resolved. On the four scenes the false cells (three-class room and
/// beyond the walls, by cause) fall to at most 0.7 of the default ring credit's on each and
/// 0.55 over the four (measured 64 → 35, 75 → 23, 62 → 41, 100 → 29), the side lobe's to at
/// most half over the four (162 → 58), and the detectable walls found stay ≥ 0.75 (0.897,
/// 0.809, 0.781, 0.874 against 0.915, 0.869, 0.869, 0.922: the recall it costs).
#[test]
fn og_echo_credit_halves_the_false_cells() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("og_echo_credit");
    let (mut ring_all, mut echo_all, mut ring_side, mut echo_side) = (0.0, 0.0, 0.0, 0.0);
    let mut failures = Vec::new();
    for (name, n, c, e) in scenes() {
        let ring = &figures()
            .iter()
            .find(|(s, k, _)| s == name && k == n)
            .unwrap()
            .2["og"];
        let echo = map_with(
            "og",
            &["--og-credit", "echo"],
            c,
            e,
            &root.join(format!("{name}_{n}")),
        );
        let fc = |v: &Value, k: &str| f(v, &["metrics", "three_class", "false_cells", k]);
        let det = |v: &Value| {
            f(
                v,
                &["metrics", "three_class", "detectable", "walls_found_1"],
            )
        };
        let bw = |v: &Value| f(v, &["metrics", "three_class", "building", "wrong"]);
        eprintln!(
            "{name} N={n}: false cells {:.0} -> {:.0} (side lobe {:.0} -> {:.0}, arc {:.0} -> {:.0}); detectable walls found {:.3} -> {:.3}; building wrong {:.0} -> {:.0}",
            fc(ring, "total"),
            fc(&echo, "total"),
            fc(ring, "side_lobe"),
            fc(&echo, "side_lobe"),
            fc(ring, "main_lobe_arc"),
            fc(&echo, "main_lobe_arc"),
            det(ring),
            det(&echo),
            bw(ring),
            bw(&echo),
        );
        ring_all += fc(ring, "total");
        echo_all += fc(&echo, "total");
        ring_side += fc(ring, "side_lobe");
        echo_side += fc(&echo, "side_lobe");
        if fc(&echo, "total") > 0.7 * fc(ring, "total") {
            failures.push(format!(
                "{name} N={n}: false cells not below 0.7 of the ring's"
            ));
        }
        if det(&echo) < 0.75 {
            failures.push(format!(
                "{name} N={n}: detectable walls found {:.3}",
                det(&echo)
            ));
        }
    }
    eprintln!("four scenes: false cells {ring_all:.0} -> {echo_all:.0}, side lobe {ring_side:.0} -> {echo_side:.0}");
    assert!(echo_all <= 0.55 * ring_all, "{echo_all} vs {ring_all}");
    assert!(echo_side <= 0.5 * ring_side, "{echo_side} vs {ring_side}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
