//! The predictive check (issue 29, `pradar check`): the chain's fitted model against the
//! physics scenes it was fitted on and against a second realisation of each (another
//! simulator seed), and the check's power and calibration on synth data of a known model.
//!
//! Each scene goes simulate → energy → extract → cluster → fit → levels
//! (`pipeline::analyse`, what `reproduce` runs), then `check` with 20 draws. The tables
//! are printed (`cargo test --release --test tests check:: -- --nocapture`).
//!
//! Measured (2 cores, this suite's seeds): corridor pass (largest ratio 1.34), its second
//! realisation pass; office and furnished hall in the ignored test (about 3 min):
//! docs/model.md has the tables.

use crate::common;
use pradar::campaign::manifest::SweepFormat;
use pradar::campaign::modelfile::ModelConfig;
use pradar::campaign::Campaign;
use pradar::check::{check, CheckParams, CheckResult};
use pradar::energy::EnergyMatrix;
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

/// A scene passes its check, and a second realisation of it (simulator seed + 1) passes
/// against the model fitted on the first.
fn scene_passes(name: &str, t: toml::Table) {
    let dir = tempfile::tempdir().unwrap();
    let (c, em, model) = fitted(&dir.path().join("a"), &t);
    let own = checked(
        &format!("{name}: fitted model vs its scene"),
        &c,
        &em,
        &dir.path().join("a/energy.parquet"),
        &model,
    );
    let mut t2 = t.clone();
    let seed = t2["seed"].as_integer().unwrap();
    common::set(&mut t2, "seed", seed + 1);
    let (c2, em2) = common::chain(&dir.path().join("b"), &t2, SweepFormat::Parquet);
    let other = checked(
        &format!("{name}: fitted model vs a second realisation"),
        &c2,
        &em2,
        &dir.path().join("b/energy.parquet"),
        &model,
    );
    assert!(own.passes(), "{name}: {}", own.verdict());
    assert!(other.passes(), "{name} (other seed): {}", other.verdict());
}

#[test]
fn corridor_fitted_model_passes_check() {
    scene_passes("corridor", common::corridor());
}

/// Slow (about 3 min on 2 cores): the office and the 48-pose furnished hall.
#[test]
#[ignore]
fn office_and_furnished_hall_pass_check() {
    scene_passes("office", common::fixture("tests/office.toml"));
    scene_passes(
        "furnished hall",
        common::fixture("tests/furnished_hall.toml"),
    );
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
