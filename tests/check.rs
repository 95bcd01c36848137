//! The predictive check (issue 29, `pradar check`): the chain's fitted model against the
//! physics scenes it was fitted on and against a second realisation of each (another
//! simulator seed), and the check's power and calibration on synth data of a known model.
//!
//! Each scene goes simulate → energy → extract → cluster → fit → levels
//! (`pipeline::analyse`, what `reproduce` runs), then `check` with 20 draws. The tables
//! are printed (`cargo test --release --test tests check:: -- --nocapture`).
//!
//! The figures (tables per scene, what passes and what misses) are in docs/model.md,
//! "Issue 29".

use crate::common;
use pradar::campaign::manifest::SweepFormat;
use pradar::campaign::Campaign;
use pradar::check::{check, CheckParams, CheckResult};
use pradar::energy::EnergyMatrix;
use pradar::model::file::ModelConfig;
use pradar::params::ParamGuard;
use std::path::Path;

/// The scene `t` simulated into `dir`, its energy table and the chain's fitted model.
fn fitted(dir: &Path, t: &toml::Table) -> (Campaign, EnergyMatrix, ModelConfig) {
    let (sc, em) = common::chain(dir, t, SweepFormat::Parquet);
    let a = pradar::pipeline::analyse(&sc, &em, dir, false).unwrap();
    (sc, em, a.fit.unwrap().model)
}

/// `check` of `model` against `em` (of `c`, read from `path`), 20 draws, its table printed.
fn checked(
    label: &str,
    c: &Campaign,
    em: &EnergyMatrix,
    path: &Path,
    model: &ModelConfig,
) -> CheckResult {
    let r = check(
        c,
        em,
        path,
        model,
        &CheckParams::default().check().unwrap(),
        &|_, _| {},
    )
    .unwrap();
    println!(
        "\n### {label}\n\n{}\n{}\n",
        r.table().to_markdown(),
        r.verdict()
    );
    r
}

/// The scene `t` fitted in `dir/a`, checked against its own table (printed); with
/// `second`, also a second realisation of it (simulator seed + 1, in `dir/b`) against the
/// same model. Returns (own, second).
fn scene(name: &str, t: &toml::Table, second: bool) -> (CheckResult, Option<CheckResult>) {
    let dir = tempfile::tempdir().unwrap();
    let (c, em, model) = fitted(&dir.path().join("a"), t);
    let own = checked(
        &format!("{name}: fitted model vs its scene"),
        &c,
        &em,
        &dir.path().join("a/energy.parquet"),
        &model,
    );
    let other = second.then(|| {
        let mut t2 = t.clone();
        let seed = t2["seed"].as_integer().unwrap();
        common::set(&mut t2, "seed", seed + 1);
        let (c2, em2) = common::chain(&dir.path().join("b"), &t2, SweepFormat::Parquet);
        checked(
            &format!("{name}: fitted model vs a second realisation"),
            &c2,
            &em2,
            &dir.path().join("b/energy.parquet"),
            &model,
        )
    });
    (own, other)
}

/// The corridor's fitted model passes the check against the corridor (about 15 s).
#[test]
fn corridor_fitted_model_passes_check() {
    let (own, _) = scene("corridor", &common::corridor(), false);
    assert!(own.passes(), "corridor: {}", own.verdict());
}

/// Slow (about 4 min on 2 cores): the must-show over the three physics scenes —
/// each scene's fitted model passes against its own table and against a second
/// realisation. Measured at this commit (docs/model.md): the corridor's second
/// realisation misses on first arrival (1.57) and the furnished hall's own table on first
/// arrival (1.60), so this test fails today; it states the target.
#[test]
#[ignore]
fn three_scenes_pass_and_generalise() {
    let mut failed = Vec::new();
    for (name, t) in [
        ("corridor", common::corridor()),
        ("office", common::fixture("tests/office.toml")),
        (
            "furnished hall",
            common::fixture("tests/furnished_hall.toml"),
        ),
    ] {
        let (own, other) = scene(name, &t, true);
        if !own.passes() {
            failed.push(format!("{name}: {}", own.verdict()));
        }
        let other = other.expect("asked for");
        if !other.passes() {
            failed.push(format!("{name} (second realisation): {}", other.verdict()));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The office's fitted model (`data/tests/office_model.toml`: the chain's model of the
/// office, walls and vertices included) and the office campaign.
fn office_model() -> (tempfile::TempDir, Campaign, ModelConfig) {
    let dir = tempfile::tempdir().unwrap();
    let m = common::write_campaign(
        &dir.path().join("in"),
        &common::fixture("tests/office.toml"),
    );
    let c = Campaign::load(&m).unwrap();
    let model = ModelConfig::load(&common::root().join("data/tests/office_model.toml")).unwrap();
    (dir, c, model)
}

/// synth of `model` over `c` at `seed`, read back.
fn synth_table(dir: &Path, c: &Campaign, model: &ModelConfig, seed: u64) -> EnergyMatrix {
    let out = dir.join(format!("synth_{seed}.parquet"));
    let p = pradar::model::SynthParams::default()
        .seed(seed)
        .check()
        .unwrap();
    pradar::model::synth(c, model, &out, &p, &|_, _| {}).unwrap();
    EnergyMatrix::read(&out).unwrap()
}

/// The check has power: against synth data of the office model, the model itself passes
/// and the model with its levels 10 dB up (every level quantity ×10, |Γ| ×√10) or three
/// times the rays per cluster fails. AoA ×0.3 is printed, not asserted: the check's
/// statistics do not resolve the intra-cluster AoA behind the geometry's returns
/// (docs/model.md, "What the check cannot see").
#[test]
fn check_has_power() {
    let (dir, c, m) = office_model();
    let em = synth_table(dir.path(), &c, &m, 5);
    let path = dir.path().join("synth_5.parquet");
    assert!(checked("office model vs its synth", &c, &em, &path, &m).passes());
    let mut level = m.clone();
    level.cluster_rrcs.value *= 10.0;
    let w = level.walls.as_mut().unwrap();
    w.specular_gamma.value *= 10f64.sqrt();
    for q in [w.corner_rcs.as_mut(), w.edge_rcs.as_mut()]
        .into_iter()
        .flatten()
    {
        q.value *= 10.0;
    }
    level.diffuse.as_mut().unwrap().wall_rcs_per_m.value *= 10.0;
    let r = checked("level +10 dB", &c, &em, &path, &level);
    assert!(!r.passes(), "{}", r.verdict());
    let mut rays = m.clone();
    rays.rays_per_cluster.value *= 3.0;
    let r = checked("rays per cluster x3", &c, &em, &path, &rays);
    assert!(!r.passes(), "{}", r.verdict());
    let mut aoa = m.clone();
    aoa.intra_cluster_aoa.value *= 0.3;
    let r = checked("AoA std x0.3 (not asserted)", &c, &em, &path, &aoa);
    println!("AoA x0.3: {}", r.verdict());
}

/// Slow (about 1–2 min): the check is calibrated — the office model against 20 synth
/// tables of itself (seeds 101–120) passes in at least 90 % of them, and each statistic's
/// p-value is below 0.05 in at most 15 % of them.
#[test]
#[ignore]
fn check_is_calibrated() {
    let (dir, c, m) = office_model();
    let reps = 20;
    let mut passes = 0;
    let mut low = [0usize; pradar::check::stats::NAMES.len()];
    for seed in 101..101 + reps as u64 {
        let em = synth_table(dir.path(), &c, &m, seed);
        let path = dir.path().join(format!("synth_{seed}.parquet"));
        let r = check(
            &c,
            &em,
            &path,
            &m,
            &CheckParams::default().check().unwrap(),
            &|_, _| {},
        )
        .unwrap();
        println!("seed {seed}: {}", r.verdict());
        passes += r.passes() as usize;
        for (k, s) in r.stats.iter().enumerate() {
            low[k] += (s.p_value() < 0.05) as usize;
        }
    }
    println!("passes {passes}/{reps}; p < 0.05 per statistic: {low:?}");
    assert!(passes * 10 >= reps * 9, "passes {passes}/{reps}");
    for (k, n) in low.iter().enumerate() {
        assert!(
            n * 100 <= reps * 15,
            "{}: p < 0.05 in {n}/{reps}",
            pradar::check::stats::NAMES[k].0
        );
    }
}

/// `pradar check` end to end: the office model against its own synth table exits 0 and
/// writes the table (CSV/Markdown/HTML) and the CDF panels; with `--fail-below`, the model
/// with three times the rays exits 1 with one line; a `--draws` of 1 is refused.
#[test]
fn check_command() {
    let (dir, c, m) = office_model();
    synth_table(dir.path(), &c, &m, 5);
    let energy = dir.path().join("synth_5.parquet");
    let model = common::root().join("data/tests/office_model.toml");
    let out = dir.path().join("check");
    let args = |model: &Path, out: &Path| -> Vec<String> {
        [
            "check",
            "--model",
            common::path_str(model),
            "--campaign",
            common::path_str(&c.path),
            "--energy",
            common::path_str(&energy),
            "--out",
            common::path_str(out),
            "--fail-below",
            "0.05",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let a = args(&model, &out);
    let o = common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["check.csv", "check.md", "check_cdfs.png", "index.html"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("check.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + pradar::check::stats::NAMES.len());
    assert!(csv.starts_with(
        "statistic,unit,measured_median,draws_median,ks,ks_reference,ratio,p_value,verdict"
    ));
    let mut rays = m.clone();
    rays.rays_per_cluster.value *= 3.0;
    let rays_path = dir.path().join("rays.toml");
    rays.save(&rays_path).unwrap();
    let a = args(&rays_path, &dir.path().join("check_rays"));
    let o = common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>());
    common::assert_one_line_error(&o, "check failed");
    let mut a = args(&model, &dir.path().join("check_one"));
    a.extend(["--draws".into(), "1".into()]);
    let o = common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>());
    common::assert_one_line_error(&o, "--draws");
    // --posterior: each draw's rays per cluster from a particle; a good sample around the
    // model's value passes as the model does, a bad file or a quantity the model file
    // lacks is one line naming it
    let r = m.rays_per_cluster.value;
    let post = dir.path().join("cal_posterior.csv");
    let with_post = |text: &str, out: &str| {
        std::fs::write(&post, text).unwrap();
        let mut a = args(&model, &dir.path().join(out));
        a.extend(["--posterior".into(), common::path_str(&post).to_string()]);
        common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let good = format!(
        "weight,distance,rays_per_cluster,rays_per_cluster_raw\n1,0.1,{},{}\n1,0.2,{},{}\n",
        0.9 * r,
        0.9 * r,
        1.1 * r,
        1.1 * r
    );
    let o = with_post(&good, "check_post");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.path().join("check_post/check.csv").is_file());
    let o = with_post(
        "weight,distance,rays_per_cluster,rays_per_cluster_raw\n1,0.1,2\n",
        "p1",
    );
    common::assert_one_line_error(&o, "cal_posterior.csv");
    let o = with_post(
        "weight,distance,no_such_quantity,no_such_quantity_raw\n1,0.1,2,2\n",
        "p2",
    );
    common::assert_one_line_error(&o, "no_such_quantity");
}
