//! The predictive check (issue 29, `pradar check`): the chain's fitted model against the
//! physics scenes it was fitted on and against a second realisation of each (another
//! simulator seed), and the check's power and calibration on synth data of a known model.
//!
//! Each scene goes simulate → energy → extract → cluster → fit → levels
//! (`pipeline::analyse`, what `reproduce` runs), then `check` with 20 draws. The tables
//! are printed (`cargo test --release --test tests check:: -- --nocapture`).
//!
//! The figures (tables per scene, what passes and what misses) are in docs/model.md,
//! "Issue 29". The rule's calibration and power on synth data of known models
//! (`check_calibration_and_power`, ignored: about 1 h on 2 cores) are in README.md's check
//! paragraph.

use crate::common;
use pradar::campaign::manifest::SweepFormat;
use pradar::campaign::Campaign;
use pradar::check::stats::Statistics;
use pradar::check::{check, CheckParams, CheckResult};
use pradar::energy::EnergyMatrix;
use pradar::model::file::ModelConfig;
use pradar::model::EnergySimulator;
use pradar::params::ParamGuard;
use std::path::Path;

/// The scene `t` simulated into `dir`, its energy table and the chain's fitted model.
fn fitted(dir: &Path, t: &toml::Table) -> (Campaign, EnergyMatrix, ModelConfig) {
    let (sc, em) = common::chain(dir, t, SweepFormat::Parquet);
    let a = pradar::pipeline::analyse(&sc, &em, &dir.join("energy.parquet"), dir, false).unwrap();
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
/// realisation (the rule of [`pradar::check`]: max-T p > 0.05 and the noise floors within
/// 1 dB). Under the earlier ratio rule (docs/model.md) the corridor's second realisation
/// and the furnished hall's own table missed on first arrival; not re-run under this rule.
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

/// A zoo scene simulated into `dir` (Parquet sweeps), its energy table and the chain's
/// fitted model (with its levels), as `reproduce` runs them.
fn zoo_fitted(
    dir: &Path,
    scene: &pradar::simulate::zoo::ZooScene,
) -> (Campaign, EnergyMatrix, ModelConfig) {
    let input = dir.join("in");
    pradar::simulate::zoo::write(&input, std::slice::from_ref(scene)).unwrap();
    let c = Campaign::load(&input.join(&scene.name).join("campaign.toml")).unwrap();
    let sim =
        pradar::simulate::simulate(&c, &dir.join("sim"), SweepFormat::Parquet, &|_, _| {}).unwrap();
    let sc = Campaign::load(&sim.manifest).unwrap();
    let e = dir.join("energy.parquet");
    pradar::energy::run(&sc, &e, &|_, _| {}).unwrap();
    let em = EnergyMatrix::read(&e).unwrap();
    let a = pradar::pipeline::analyse(&sc, &em, &e, dir, false).unwrap();
    (sc, em, a.fit.unwrap().model)
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

/// A copy of `em` whose energies are `model`'s draw at `seed` (as `synth` with that seed
/// writes them; its metadata `em`'s, which for a synth table of the same campaign is the
/// one `synth` writes).
fn drawn_table(
    sim: &EnergySimulator,
    em: &EnergyMatrix,
    model: &ModelConfig,
    seed: u64,
) -> EnergyMatrix {
    let mut t = em.clone();
    t.data = sim.energies(model, seed).unwrap();
    t
}

/// `model` with every level 10 dB up: the clusters' and vertices' σ and the diffuse σ′
/// ×10, every |Γ| ×√10.
fn level_up(model: &ModelConfig) -> ModelConfig {
    let mut m = model.clone();
    m.cluster_rrcs.value *= 10.0;
    if let Some(w) = m.walls.as_mut() {
        // |Γ| ≤ 1 (passive): a wall already near it stays at 1
        w.specular_gamma.value = (w.specular_gamma.value * 10f64.sqrt()).min(1.0);
        for q in w.material_gamma.values_mut() {
            q.value = (q.value * 10f64.sqrt()).min(1.0);
        }
        for q in [w.corner_rcs.as_mut(), w.edge_rcs.as_mut()]
            .into_iter()
            .flatten()
        {
            q.value *= 10.0;
        }
    }
    if let Some(d) = m.diffuse.as_mut() {
        d.wall_rcs_per_m.value *= 10.0;
    }
    m
}

/// A noise mismatch: the measured table's metadata records an N0 3 dB above what its
/// bins hold (as an N0 read from aliased echoes did); the check's draws carry the recorded
/// N0, so the floors differ by 3 dB, and the check fails with one line naming both.
#[test]
fn noise_mismatch_fails_with_one_line() {
    let (dir, c, m) = office_model();
    let mut em = synth_table(dir.path(), &c, &m, 5);
    let path = dir.path().join("synth_5.parquet");
    let params = CheckParams {
        draws: pradar::check::MIN_DRAWS,
        ..Default::default()
    }
    .check()
    .unwrap();
    let ok = check(&c, &em, &path, &m, &params, &|_, _| {}).unwrap();
    println!("{}", ok.verdict());
    assert!(ok.noise.agree(), "{}", ok.noise.line());
    assert!(ok.noise.offset_db().abs() < 0.3, "{}", ok.noise.line());
    em.meta.n0 *= 2.0;
    let r = check(&c, &em, &path, &m, &params, &|_, _| {}).unwrap();
    println!("{}", r.verdict());
    assert!(!r.passes());
    assert!(r.misses().contains(&"noise"));
    let off = r.noise.offset_db();
    assert!((off + 3.0).abs() < 0.3, "{off}");
    let v = r.verdict();
    assert!(
        v.starts_with("FAIL: noise: the measured table's floor"),
        "{v}"
    );
    assert_eq!(v.lines().count(), 1);
}

/// One scene's calibration and power: `reps` synth tables of `model` (seeds 1000 + k, in
/// memory) checked against `model` (false rejections), and `power_reps` tables each of
/// the model with levels +10 dB, with 3× the rays per cluster, of `model` with a recorded
/// N0 3 dB above its bins', and (printed, not asserted) with the intra-cluster AoA std
/// ×0.3, checked against `model`. Returns the rejection counts
/// [null, level, rays, noise, aoa] and prints them with the times.
fn calibration_and_power(
    name: &str,
    c: &Campaign,
    em: &EnergyMatrix,
    path: &Path,
    model: &ModelConfig,
    reps: usize,
    power_reps: usize,
) -> [usize; 5] {
    let sim = EnergySimulator::for_table(c, em, path, 1e-3).unwrap();
    let params = CheckParams::default().check().unwrap();
    let run = |table: &EnergyMatrix| check(c, table, path, model, &params, &|_, _| {}).unwrap();
    let mut out = [0usize; 5];
    let t0 = std::time::Instant::now();
    let mut per_stat = [0usize; pradar::check::stats::NAMES.len()];
    let mut noise_db = Vec::new();
    for k in 0..reps {
        let r = run(&drawn_table(&sim, em, model, 1000 + k as u64));
        noise_db.push(r.noise.offset_db());
        if !r.passes() {
            out[0] += 1;
            println!("{name} null rep {k}: {}", r.verdict());
        }
        for (i, s) in r.stats.iter().enumerate() {
            per_stat[i] += (s.p_value() <= 0.05) as usize;
        }
        if (k + 1) % 10 == 0 {
            println!(
                "{name}: {} null reps, {} rejected, {:.0} s",
                k + 1,
                out[0],
                t0.elapsed().as_secs_f64()
            );
        }
    }
    let null_s = t0.elapsed().as_secs_f64();
    noise_db.sort_by(f64::total_cmp);
    println!(
        "{name}: false rejections {}/{reps} ({:.0} %), {:.1} s per check; per statistic p ≤ 0.05: {per_stat:?}; noise floor offsets {:+.2}..{:+.2} dB",
        out[0],
        100.0 * out[0] as f64 / reps as f64,
        null_s / reps.max(1) as f64,
        noise_db.first().unwrap_or(&f64::NAN),
        noise_db.last().unwrap_or(&f64::NAN)
    );
    let mut rays = model.clone();
    rays.rays_per_cluster.value *= 3.0;
    let mut aoa = model.clone();
    aoa.intra_cluster_aoa.value *= 0.3;
    let level = level_up(model);
    for (slot, label, alt) in [
        (1, "level +10 dB", Some(&level)),
        (2, "rays per cluster x3", Some(&rays)),
        (3, "noise: recorded N0 +3 dB", None),
        (4, "AoA std x0.3", Some(&aoa)),
    ] {
        let t0 = std::time::Instant::now();
        let mut misses = std::collections::BTreeMap::<&str, usize>::new();
        for k in 0..power_reps {
            let seed = 2000 + k as u64;
            let table = match alt {
                Some(a) => drawn_table(&sim, em, a, seed),
                None => {
                    let mut t = drawn_table(&sim, em, model, seed);
                    t.meta.n0 *= 2.0;
                    t
                }
            };
            let r = run(&table);
            out[slot] += (!r.passes()) as usize;
            for m in r.misses() {
                *misses.entry(m).or_default() += 1;
            }
        }
        println!(
            "{name}: {label}: rejected {}/{power_reps} ({:.0} %) in {:.0} s; misses {misses:?}",
            out[slot],
            100.0 * out[slot] as f64 / power_reps.max(1) as f64,
            t0.elapsed().as_secs_f64()
        );
    }
    out
}

/// Slow (ignored): the check is calibrated and has power. Per scene — the corridor's
/// fitted model (the chain's) and the office's model file — `REPS` synth tables of the
/// model checked against it are rejected at most 10 % of the time, and synth tables with
/// the level +10 dB, 3× the rays per cluster or a recorded N0 3 dB off are each rejected in
/// at least 90 % of `POWER_REPS`. The AoA std ×0.3 is printed, not asserted. Figures in
/// README.md's check paragraph. `PRADAR_CHECK_REPS` / `PRADAR_CHECK_POWER_REPS` override the
/// counts (defaults 50 and 20), `PRADAR_CHECK_SCENES` the scenes (default `corridor,office`;
/// zoo scenes by name, e.g. `corridor,office,z06-hall,z10-l-hall`: the two of the zoo with
/// the fewest sweeps among the halls, picked for time, run with the chain's fitted model).
#[test]
#[ignore]
fn check_calibration_and_power() {
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let reps = env("PRADAR_CHECK_REPS", 50);
    let power_reps = env("PRADAR_CHECK_POWER_REPS", 20);
    let scenes = std::env::var("PRADAR_CHECK_SCENES").unwrap_or("corridor,office".into());
    let mut failed = Vec::new();
    let mut judge = |name: &str, n: [usize; 5]| {
        if n[0] * 10 > reps {
            failed.push(format!("{name}: false rejections {}/{reps}", n[0]));
        }
        for (i, what) in [(1, "level +10 dB"), (2, "rays x3"), (3, "noise mismatch")] {
            if n[i] * 10 < power_reps * 9 {
                failed.push(format!("{name}: {what} rejected {}/{power_reps}", n[i]));
            }
        }
    };
    if scenes.contains("corridor") {
        let dir = tempfile::tempdir().unwrap();
        let t0 = std::time::Instant::now();
        let (c, em, model) = fitted(&dir.path().join("a"), &common::corridor());
        println!("corridor: fitted in {:.0} s", t0.elapsed().as_secs_f64());
        let path = dir.path().join("a/energy.parquet");
        let n = calibration_and_power("corridor", &c, &em, &path, &model, reps, power_reps);
        judge("corridor", n);
    }
    if scenes.contains("office") {
        let (dir, c, m) = office_model();
        let em = synth_table(dir.path(), &c, &m, 5);
        let path = dir.path().join("synth_5.parquet");
        let n = calibration_and_power("office", &c, &em, &path, &m, reps, power_reps);
        judge("office", n);
    }
    // zoo scenes (`pradar zoo --seed 1`), named in the list: the chain's fitted model of
    // the physics scene, checked against synth tables of itself
    let zoo = pradar::simulate::zoo::generate(1, 20);
    for name in scenes.split(',').filter(|s| s.starts_with('z')) {
        let scene = zoo
            .iter()
            .find(|z| z.name == name)
            .unwrap_or_else(|| panic!("no zoo scene {name}"));
        let dir = tempfile::tempdir().unwrap();
        let t0 = std::time::Instant::now();
        let (c, em, model) = zoo_fitted(dir.path(), scene);
        println!("{name}: fitted in {:.0} s", t0.elapsed().as_secs_f64());
        let path = dir.path().join("energy.parquet");
        let n = calibration_and_power(name, &c, &em, &path, &model, reps, power_reps);
        judge(name, n);
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// `pradar check` end to end: the office model against its own synth table exits 0 and
/// writes the table (CSV/Markdown/HTML) and the CDF panels; with `--fail-below`, the model
/// with three times the rays exits 1 with one line; a `--draws` of 18 (too few for the
/// p-value to reach α) is refused, saying why.
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
        "statistic,unit,measured_median,draws_median,ks,ks_reference,ratio,p_value,p_adjusted,verdict"
    ));
    let mut rays = m.clone();
    rays.rays_per_cluster.value *= 3.0;
    let rays_path = dir.path().join("rays.toml");
    rays.save(&rays_path).unwrap();
    let a = args(&rays_path, &dir.path().join("check_rays"));
    let o = common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>());
    common::assert_one_line_error(&o, "check failed");
    let mut a = args(&model, &dir.path().join("check_one"));
    a.extend(["--draws".into(), "18".into()]);
    let o = common::pradar_quiet(&a.iter().map(String::as_str).collect::<Vec<_>>());
    common::assert_one_line_error(&o, "--draws");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("must be in [19, 1000]") && err.contains("cannot reach α = 0.05"),
        "{err}"
    );
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

/// The held-out check (`check::holdout`, `pradar check --holdout`) on the corridor cut to
/// six poses (halves of three), 19 draws: two ways, fitted on A = positions 0–2 and
/// checked on B = 3–5 and back, each a check of R draws with a p-value in (0, 1]; the
/// command with `--quiet` prints exactly the three verdict lines the library gives (both
/// ways' and the combined one), writes its files, and refuses `--model` beside
/// `--holdout` naming both.
#[test]
fn holdout_fits_each_half_and_checks_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = common::corridor();
    t.get_mut("poses")
        .and_then(|p| p.as_array_mut())
        .unwrap()
        .truncate(6);
    let (c, em) = common::chain(&dir.path().join("a"), &t, SweepFormat::Parquet);
    let path = dir.path().join("a/energy.parquet");
    let params = CheckParams {
        draws: pradar::check::MIN_DRAWS,
        ..Default::default()
    }
    .check()
    .unwrap();
    let t0 = std::time::Instant::now();
    let r = pradar::check::holdout(
        &c,
        &em,
        &path,
        &params,
        &pradar::check::Estimator::Chain,
        &|_, _| {},
    )
    .unwrap();
    println!(
        "{}\n{}\n({:.1} s)",
        r.table().to_markdown(),
        r.lines().join("\n"),
        t0.elapsed().as_secs_f64()
    );
    let labels: Vec<Vec<String>> = r.halves.iter().map(|h| h.labels.clone()).collect();
    assert_eq!(labels, [["0", "1", "2"], ["3", "4", "5"]]);
    assert_eq!(r.halves[1].positions, [3, 4, 5]);
    assert_eq!([r.ways[0].fitted_on, r.ways[1].fitted_on], [0, 1]);
    for w in &r.ways {
        let p = w.result.joint_p;
        assert!(p > 0.0 && p <= 1.0, "{p}");
        assert_eq!(w.result.draws.len(), pradar::check::MIN_DRAWS);
        // checked on the other half: that half's rows of the table
        let other = em.restrict(&r.halves[1 - w.fitted_on].positions).unwrap();
        let ctx = pradar::check::context(&other);
        assert_eq!(ctx.np, 3);
        assert_eq!(w.result.measured, Statistics::of(&ctx, &other.data));
    }
    let lines = r.lines();
    assert_eq!(lines.len(), 3);
    assert!(lines[0]
        .starts_with("held out, fitted on A (positions 0–2) → checked on B (positions 3–5): "));
    assert!(lines[1]
        .starts_with("held out, fitted on B (positions 3–5) → checked on A (positions 0–2): "));
    let want = if r.passes() {
        "held-out check: PASS"
    } else {
        "held-out check: FAIL"
    };
    assert!(lines[2].starts_with(want), "{}", lines[2]);
    // the command: the same verdict lines with --quiet, and its files
    let out = dir.path().join("hc");
    let mut argv = vec![
        "check",
        "--holdout",
        "--campaign",
        common::path_str(&c.path),
        "--energy",
        common::path_str(&path),
        "--draws",
        "19",
    ];
    argv.extend(["--out", common::path_str(&out)]);
    let o = common::pradar_quiet(&argv);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(String::from_utf8_lossy(&o.stdout), lines.join("\n") + "\n");
    for f in pradar::report::check::holdout_files() {
        assert!(out.join(&f).is_file(), "{f}");
    }
    let m = ModelConfig::load(&out.join("fit_A_check_B/model.toml")).unwrap();
    assert_eq!(m, r.ways[0].model);
    // the refined estimator: each way's model is the chain's refined on its own half (the
    // same clusters and levels, then smm: `[calibration]` names it and its distance fell)
    let smm = pradar::smm::SmmParams {
        draws: 4,
        iterations: 10,
        ..Default::default()
    };
    let rs = pradar::check::holdout(
        &c,
        &em,
        &path,
        &params,
        &pradar::check::Estimator::Smm(smm.check().unwrap()),
        &|_, _| {},
    )
    .unwrap();
    println!("smm: {}", rs.lines().join("\n"));
    assert_eq!(rs.estimator, pradar::check::EstimatorKind::Smm);
    assert!(
        rs.verdict().starts_with("held-out check (estimator smm): "),
        "{}",
        rs.verdict()
    );
    for (w, chain) in rs.ways.iter().zip(&r.ways) {
        assert_eq!(w.model.inter_cluster_rate, chain.model.inter_cluster_rate);
        match &w.model.calibration {
            Some(cal) => {
                // "distance D from D0": the refinement lowered the fit half's distance
                let d: Vec<f64> = (cal.method.split(['(', ')', ' ', ',']))
                    .filter_map(|t| t.parse().ok())
                    .collect();
                let (got, from) = (d[d.len() - 2], d[d.len() - 1]);
                assert!(
                    got < from && (got - cal.epsilon).abs() < 1e-4,
                    "{}",
                    cal.method
                );
                assert!(cal.method.starts_with("smm"), "{}", cal.method);
            }
            // nothing beat the chain's model: it is returned unchanged
            None => assert_eq!(w.model, chain.model),
        }
        let p = w.result.joint_p;
        assert!(p > 0.0 && p <= 1.0, "{p}");
    }
    // a name --estimator does not know is refused listing the three; beside --model too
    let mut bad = argv.clone();
    bad.extend(["--estimator", "nope"]);
    let o = common::pradar_quiet(&bad);
    common::assert_one_line_error(&o, "--estimator");
    assert!(String::from_utf8_lossy(&o.stderr).contains("calibrate"));
    argv.extend(["--model", "m.toml"]);
    let o = common::pradar_quiet(&argv);
    common::assert_one_line_error(&o, "--holdout");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--model"));
    let mut argv: Vec<&str> = argv.into_iter().filter(|a| *a != "--holdout").collect();
    argv.extend(["--estimator", "smm"]);
    let o = common::pradar_quiet(&argv);
    common::assert_one_line_error(&o, "--estimator");
}
