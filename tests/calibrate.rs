//! `pradar calibrate` (issue 19): closed loops `synth` → `calibrate` (the CLI, as a user
//! runs it), scored against the model `synth` drew from. The calibration reads only the
//! energy table and the campaign (never synth's truth folder, nor the corridor's
//! `[clutter]`). Figures are in `docs/calibrate.md`.

use crate::common;

use pradar::model::file::ModelConfig;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

type Pick = fn(&ModelConfig) -> f64;

/// The quantities scored: name in the model file, and how to read it.
const QUANTITIES: [(&str, Pick); 8] = [
    ("intra_cluster_rate", |m| m.intra_cluster_rate.value),
    ("intra_cluster_aoa", |m| m.intra_cluster_aoa.value),
    ("perimeter_spacing", |m| m.perimeter_spacing.value),
    ("perimeter_offset", |m| m.perimeter_offset.value),
    ("cluster_decay", |m| m.cluster_decay.value),
    ("ray_decay", |m| m.ray_decay.value),
    ("cluster_rrcs", |m| m.cluster_rrcs.value),
    ("rays_per_cluster", |m| m.rays_per_cluster.value),
];

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn run(args: &[String], threads: Option<usize>) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pradar"));
    c.args(args).arg("--quiet");
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t.to_string());
    }
    let o = c.output().unwrap();
    assert!(
        o.status.success(),
        "pradar {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    // the sampler's trace (`PRADAR_ABC_TRACE=1`, inherited by the child) passed through
    if std::env::var("PRADAR_ABC_TRACE").is_ok_and(|v| v == "1") {
        for l in String::from_utf8_lossy(&o.stderr).lines() {
            if l.starts_with("abc:") {
                eprintln!("{l}");
            }
        }
    }
}

use common::synth;

/// `calibrate --no-walls` of `energy` (budget `sims`, population `pop`, seed `seed`,
/// `--distance distance` unless None: the default) into `out`. `--no-walls`: the tables
/// these closed loops calibrate are `synth` draws of models without `[diffuse]` and
/// `[walls]`, so the matching prior frees the eight cluster quantities only (the default
/// prior also frees the layout's parts, which such a table has none of).
#[allow(clippy::too_many_arguments)]
fn calibrate(
    energy: &Path,
    cpath: &Path,
    out: &Path,
    sims: usize,
    pop: usize,
    seed: u64,
    threads: Option<usize>,
    distance: Option<&str>,
) -> ModelConfig {
    let mut args: Vec<String> = [
        "calibrate",
        "--energy",
        &s(energy),
        "--campaign",
        &s(cpath),
        "--out",
        &s(out),
        "--simulations",
        &sims.to_string(),
        "--population",
        &pop.to_string(),
        "--seed",
        &seed.to_string(),
        "--no-walls",
    ]
    .map(String::from)
    .into();
    if let Some(d) = distance {
        args.extend(["--distance".to_string(), d.to_string()]);
    }
    // measurements of the ridge choice: `PRADAR_TEST_RIDGE=cv|fixed` adds `--ridge`
    if let Ok(r) = std::env::var("PRADAR_TEST_RIDGE") {
        args.extend(["--ridge".to_string(), r]);
    }
    run(&args, threads);
    ModelConfig::load(out).unwrap()
}

/// `pradar check` (its default draws and seed) of `model` against `energy`, plug-in (every
/// draw the model file's): whether it passes, and its max-T p-value.
fn check(model: &Path, cpath: &Path, energy: &Path) -> (bool, f64) {
    let (pass, p, _) = check_verdict(model, cpath, energy);
    (pass, p)
}

/// [`check`], with its verdict line.
fn check_verdict(model: &Path, cpath: &Path, energy: &Path) -> (bool, f64, String) {
    check_verdict_with(model, cpath, energy, &[])
}

/// [`check_verdict`] with extra flags (`--posterior FILE`): pass, max-T p, the verdict line.
fn check_verdict_with(
    model: &Path,
    cpath: &Path,
    energy: &Path,
    extra: &[&str],
) -> (bool, f64, String) {
    // not --quiet: the verdict line is the progress output's last line
    let o = Command::new(env!("CARGO_BIN_EXE_pradar"))
        .args([
            "check",
            "--model",
            common::path_str(model),
            "--campaign",
            common::path_str(cpath),
            "--energy",
            common::path_str(energy),
        ])
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("PASS:") || l.starts_with("FAIL:"))
        .unwrap_or_else(|| panic!("no verdict in {text}"));
    let p: f64 = line
        .split("max-T p = ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|r| r.parse().ok())
        .unwrap_or_else(|| panic!("no max-T p in {line}"));
    (line.starts_with("PASS:"), p, line.to_string())
}

/// The posterior predictive check (`pradar check --posterior <stem>_posterior.csv`, its
/// default draws and seed) of the calibrated model `cal` against `energy`: what "a
/// calibrated model passes the check" means. Pass, max-T p, the verdict line.
fn predictive(cal: &Path, cpath: &Path, energy: &Path) -> (bool, f64, String) {
    let post = pradar::pipeline::commands::posterior_csv(cal);
    check_verdict_with(
        cal,
        cpath,
        energy,
        &["--posterior", common::path_str(&post)],
    )
}

/// Print each quantity (posterior median, interval, truth, error); return those of the
/// first six (λ, AoA, d_c, d_p, Γ, γ) outside `tol` of the truth, and per quantity
/// whether the interval covers the truth.
fn score(name: &str, got: &ModelConfig, truth: &ModelConfig, tol: f64) -> (Vec<String>, Vec<bool>) {
    let mut failures = Vec::new();
    let mut covered = Vec::new();
    eprintln!("== {name}: quantity | median | 95 % interval | truth | error");
    for (i, (q, pick)) in QUANTITIES.iter().enumerate() {
        let (v, t) = (pick(got), pick(truth));
        let [lo, hi] = got
            .quantity(q)
            .and_then(|x| x.interval)
            .unwrap_or([f64::NAN; 2]);
        let rel = (v - t) / t;
        let cov = lo <= t && t <= hi;
        covered.push(cov);
        eprintln!(
            "{q:20} | {v:9.4} | [{lo:9.4}, {hi:9.4}] | {t:9.4} | {:+6.1} %{}{}",
            100.0 * rel,
            if rel.abs() <= tol { "" } else { "  OUTSIDE" },
            if cov { "" } else { "  (not covered)" }
        );
        if i < 6 && rel.abs() > tol {
            failures.push(format!(
                "{name} {q}: {v:.4} vs {t:.4} ({:+.1} %)",
                100.0 * rel
            ));
        }
    }
    (failures, covered)
}

/// The corridor campaign (`data/corridor`, its `[scene]`/`[clutter]` untouched: calibrate
/// must ignore them) copied into `dir`.
fn corridor(dir: &Path) -> PathBuf {
    common::write_campaign(dir, &common::corridor())
}

/// The prior's hi/lo per quantity of [`QUANTITIES`] (the default prior's ranges).
const PRIOR_HILO: [f64; 8] = [60.0, 30.0, 20.0 / 0.3, 30.0, 30.0, 40.0, 1e4, 20.0];

/// A measurement switch: the environment variable `k` as a count, `d` when unset; a value
/// that is not a count stops the test (a mistyped budget must not run at the default).
fn env_usize(k: &str, d: usize) -> usize {
    match std::env::var(k) {
        Ok(v) => v
            .parse()
            .unwrap_or_else(|_| panic!("{k}={v:?} is not a count")),
        Err(_) => d,
    }
}

/// Whether `PRADAR_COVERAGE_NO_CHECK=1` asks [`coverage`] to skip `pradar check`.
fn no_check() -> bool {
    std::env::var("PRADAR_COVERAGE_NO_CHECK").is_ok_and(|v| v == "1")
}

/// One environment calibrated and scored against the model it was drawn from.
struct Scored {
    /// Per quantity: the 95 % interval covers the truth.
    covered: Vec<bool>,
    /// Per quantity: |median − truth| / truth.
    err: Vec<f64>,
    /// Per quantity: the interval's hi/lo.
    hilo: Vec<f64>,
    /// The calibrated model's posterior predictive check (`check --posterior`) against the
    /// environment: pass, max-T p.
    check: (bool, f64),
}

/// `synth` of `truth` on `cpath` at `synth_seed` into `dir`, calibrated (`sims`, `pop`,
/// `seed`, `distance`), scored and checked (posterior predictive).
#[allow(clippy::too_many_arguments)]
fn environment(
    dir: &Path,
    cpath: &Path,
    truth: &ModelConfig,
    synth_seed: u64,
    sims: usize,
    pop: usize,
    seed: u64,
    distance: Option<&str>,
) -> Scored {
    let e = synth(dir, cpath, truth, synth_seed);
    let out = dir.join("cal.toml");
    let got = calibrate(&e, cpath, &out, sims, pop, seed, None, distance);
    let (_, covered) = score(
        &format!("synth seed {synth_seed}, {}", distance.unwrap_or("default")),
        &got,
        truth,
        0.15,
    );
    let mut err = Vec::new();
    let mut hilo = Vec::new();
    for (q, pick) in QUANTITIES {
        err.push(((pick(&got) - pick(truth)) / pick(truth)).abs());
        let [lo, hi] = got.quantity(q).and_then(|x| x.interval).unwrap();
        hilo.push(hi / lo);
    }
    // `PRADAR_COVERAGE_NO_CHECK=1` (measurements of widths only): no `pradar check`
    let check = if no_check() {
        (false, f64::NAN)
    } else {
        let (pass, p, _) = predictive(&out, cpath, &e);
        (pass, p)
    };
    Scored {
        covered,
        err,
        hilo,
        check,
    }
}

/// The built-in corridor, Table 1 model (`table1_defaults`: λ 0.43/ns, AoA 16.9°, d_c
/// 1.505 m, d_p 0.3 m, Γ 12 ns, γ 3 ns, 6 rays, σ 0.01 m²), three environments (synth
/// seeds 21, 22, 23, never tuned: the thresholds below come from the 20 environments of
/// `corridor_coverage`, seeds 1000–1019), each calibrated with the default distance
/// (`summaries-quantiles` since issue 30's second session) and ridge (`cv` since 5 Dec
/// 2026) at 600 simulations (population 200, seed = the synth seed), `--no-walls` (the
/// model has no `[diffuse]`/`[walls]`: the matching prior, [`calibrate`]).
///
/// Asserted, properties that hold over environments rather than medians at chosen seeds
/// (issue 30 item 5; the bounds hold in every one of `corridor_coverage`'s 20
/// environments, seeds 1000–1019, with the margins given):
/// * coverage: in every environment at least 6 of the 8 95 % intervals cover the model
///   value, and at least 20 of the 24 over the three (20 environments with the
///   cross-validated ridge: 16 at 8/8, 4 at 7/8, 156 of 160; with the fixed ridge
///   before: 10 at 8/8, 4 at 7/8, 6 at 6/8, 144 of 160, where three environments total
///   ≤ 19 with probability ≈ 8 %; with `--distance summaries` 157 of 160, where the bound
///   was 21);
/// * determinism: 1 and 2 threads give the same model file and posterior bytes, for both
///   distances (a small budget).
///
/// Printed as reference, not a target: the intervals' width as a share of the prior's in
/// ln units, c = mean over λ, d_c and Γ of ln(hi/lo) / ln(prior hi/lo) (1 = the prior,
/// 0 = a point; 20 environments: 0.37–0.65, mean 0.49). Issue 45 item 6 withdrew issue
/// 30's "sharper" and "contraction" targets (12–24-pose campaigns do not carry that
/// information, docs/calibrate.md), so the bounds c ≤ 0.75 and mean ≤ 0.65 this test
/// asserted until then are no longer asserted. Also printed, not asserted: the calibrated
/// model's posterior predictive check (`check --posterior`, max-T p).
///
/// Measured (cross-validated ridge, 5 Dec 2026): 8/8, 7/8, 8/8 covered (σ at seed 22);
/// hi/lo λ 13.9/27.7/10.0, d_c 4.6/7.1/3.7, Γ 6.6/9.8/6.4; c 0.521/0.650/0.472; the
/// whole `calibrate::` group 49 s on idle cores. With the fixed ridge: 7/8, 7/8, 7/8
/// covered (Γ at seed 21, σ at 22 and 23); hi/lo λ 10.0/6.6/3.6, d_c 5.3/4.8/5.0, Γ
/// 3.6/8.5/2.7; c 0.444/0.487/0.331. With `--no-walls` (issue 45, 6 Dec 2026, after the
/// draws at the measured N0): the same covered counts, hi/lo and c as the cross-validated
/// figures above; the posterior predictive check passes 3 of 3 (max-T p 1.0, 0.575,
/// 0.9); the three calibrations 176 s at load 3–8.
///
/// Runtime (release): the three calibrations 195 s with load average 6–7 on the 2 shared
/// cores (beside a 20-environment run); 128 s and 147 s for the whole test with
/// `summaries` at load 5–6; on idle cores about half (not measured).
#[test]
fn corridor_closed_loop() {
    let tmp = tempfile::tempdir().unwrap();
    let cpath = corridor(&tmp.path().join("in"));
    let truth = ModelConfig::table1_defaults();
    let t = Instant::now();
    let mut total_covered = 0;
    for seed in [21u64, 22, 23] {
        let dir = tmp.path().join(format!("s{seed}"));
        let r = environment(&dir, &cpath, &truth, seed, 600, 200, seed, None);
        let k = r.covered.iter().filter(|c| **c).count();
        total_covered += k;
        let c = [0, 2, 4]
            .iter()
            .map(|&i| r.hilo[i].ln() / PRIOR_HILO[i].ln())
            .sum::<f64>()
            / 3.0;
        eprintln!(
            "synth seed {seed}: {k}/8 covered, hi/lo λ {:.1} d_c {:.1} Γ {:.1}, width share {c:.3} (reference, not a target), posterior predictive check {:?}",
            r.hilo[0], r.hilo[2], r.hilo[4], r.check
        );
        assert!(
            k >= 6,
            "synth seed {seed}: {k}/8 intervals cover the model value"
        );
        assert!(dir.join("cal_posterior.csv").is_file());
    }
    assert!(total_covered >= 20, "{total_covered}/24 intervals cover");
    eprintln!("three environments: {:.1} s", t.elapsed().as_secs_f64());
    // determinism over threads, at a small budget, both distances
    let e = tmp.path().join("s21").join("e.parquet");
    for d in ["summaries-quantiles", "summaries", "mmd"] {
        let a = tmp.path().join(format!("a_{d}.toml"));
        let b = tmp.path().join(format!("b_{d}.toml"));
        let m = calibrate(&e, &cpath, &a, 60, 30, 9, Some(1), Some(d));
        calibrate(&e, &cpath, &b, 60, 30, 9, Some(2), Some(d));
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{d}"
        );
        assert_eq!(
            std::fs::read(tmp.path().join(format!("a_{d}_posterior.csv"))).unwrap(),
            std::fs::read(tmp.path().join(format!("b_{d}_posterior.csv"))).unwrap(),
            "{d}"
        );
        let method = &m.calibration.as_ref().unwrap().method;
        assert!(method.starts_with("abc-smc"), "{method}");
        assert_eq!(method.contains("MMD"), d == "mmd", "{method}");
        assert_eq!(
            method.contains("quantiles"),
            d == "summaries-quantiles",
            "{method}"
        );
    }
}

/// `calibrate --report --chain`: the page has the marginals and the predictive check
/// (`pradar check`'s table and CDF panels) of the calibrated model and of the chain's
/// model beside it (issue 30 item 3); a chain model the check cannot draw is reported as
/// not checked, not a failed run. A small budget (60 simulations); about 10 s.
#[test]
fn report_has_the_check() {
    let tmp = tempfile::tempdir().unwrap();
    let cpath = corridor(&tmp.path().join("in"));
    let truth = ModelConfig::table1_defaults();
    let e = synth(&tmp.path().join("synth"), &cpath, &truth, 11);
    let chain = tmp.path().join("synth").join("model.toml");
    let rep = tmp.path().join("rep");
    let out = tmp.path().join("cal.toml");
    let mut args: Vec<String> = [
        "calibrate",
        "--energy",
        &s(&e),
        "--campaign",
        &s(&cpath),
        "--out",
        &s(&out),
        "--simulations",
        "60",
        "--population",
        "30",
        "--seed",
        "3",
        "--report",
        &s(&rep),
        "--chain",
        &s(&chain),
    ]
    .map(String::from)
    .into();
    run(&args, None);
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    for want in [
        "Does the calibrated model reproduce the channel?",
        "Does the cluster chain",
        "KS measured↔draws",
        "check_calibrated.png",
        "check_chain.png",
        "(posterior predictive)",
        "check_posterior.png",
        "Westfall–Young",
        "width / prior",
    ] {
        assert!(html.contains(want), "{want} missing from the page");
    }
    assert!(html.matches("<table").count() >= 4);
    assert!(rep.join("check_calibrated.png").is_file());
    assert!(rep.join("check_posterior.png").is_file());
    assert!(rep.join("check_chain.png").is_file());
    // a chain model with a quantity marked not estimable: not checked, the run succeeds
    let mut bad = truth.clone();
    bad.ray_decay = pradar::model::file::Quantity::not_estimable(
        &bad.ray_decay.unit,
        &bad.ray_decay.family,
        "too few rays",
    );
    bad.save(&chain).unwrap();
    std::fs::remove_dir_all(&rep).unwrap();
    args.push("--distance".into());
    args.push("mmd".into());
    run(&args, None);
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(html.contains("Not checked"), "{html}");
    assert!(!rep.join("check_chain.png").exists());
}

/// Bad input: a prior interval that is no range, a table of another campaign; one line
/// naming the file and field, exit 1, no panic, nothing written.
#[test]
fn bad_inputs_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let cpath = corridor(&tmp.path().join("in"));
    let mut prior = ModelConfig::table1_defaults();
    prior.ray_decay.interval = Some([0.0, 5.0]);
    let pp = tmp.path().join("prior.toml");
    prior.save(&pp).unwrap();
    let out = tmp.path().join("cal.toml");
    let o = common::pradar_quiet(&[
        "calibrate",
        "--energy",
        common::path_str(&tmp.path().join("missing.parquet")),
        "--campaign",
        common::path_str(&cpath),
        "--out",
        common::path_str(&out),
        "--prior",
        common::path_str(&pp),
    ]);
    common::assert_one_line_error(&o, "ray_decay.interval");
    assert!(!out.exists());
    let o = common::pradar_quiet(&[
        "calibrate",
        "--energy",
        common::path_str(&tmp.path().join("missing.parquet")),
        "--campaign",
        common::path_str(&cpath),
        "--out",
        common::path_str(&out),
    ]);
    common::assert_one_line_error(&o, "missing.parquet");
    let o = common::pradar_quiet(&[
        "calibrate",
        "--energy",
        "x.parquet",
        "--campaign",
        common::path_str(&cpath),
        "--out",
        common::path_str(&out),
        "--simulations",
        "5",
    ]);
    common::assert_one_line_error(&o, "--simulations");
}

/// A hall `2·hx` m × 12 m with `n` random poses at least 2.5 m from the walls (seeded),
/// 3° steps (61 directions), as `tests/closed_loop.rs`'s hall but shorter.
fn hall(dir: &Path, hx: f64, n: usize) -> PathBuf {
    use rand::{Rng, SeedableRng};
    std::fs::create_dir_all(dir).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let poses: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                rng.gen_range(-(hx - 2.5)..(hx - 2.5)),
                rng.gen_range(-3.5..3.5),
                rng.gen_range(-180.0..180.0),
            ]
        })
        .collect();
    std::fs::write(
        dir.join("hall.geojson"),
        format!(
            r#"{{"type":"FeatureCollection","features":[{{"type":"Feature","properties":{{"role":"perimeter","name":"hall","material":"concrete"}},"geometry":{{"type":"Polygon","coordinates":[[[{m},-6.0],[{hx},-6.0],[{hx},6.0],[{m},6.0],[{m},-6.0]]]}}}}]}}"#,
            m = -hx
        ),
    )
    .unwrap();
    let path = dir.join("campaign.toml");
    std::fs::write(&path, common::hall_manifest(3.0, 801, &poses)).unwrap();
    path
}

/// The closed-loop sets of `tests/closed_loop.rs` (sets 1–3 and the Table 1 set without its
/// `[diffuse]`), as [`hall_sets`] describes them.
fn hall_set_models() -> [(&'static str, ModelConfig); 4] {
    [
        (
            "set 1 (λ 1.0/ns, AoA 8°, d_c 6 m)",
            common::hall_model(1.0, 8.0, 6.0),
        ),
        (
            "set 2 (λ 0.43/ns, AoA 16.9°, d_c 8 m)",
            common::hall_model(0.43, 16.9, 8.0),
        ),
        (
            "set 3 (λ 0.2/ns, AoA 30°, d_c 10 m; interleaved)",
            common::hall_model(0.2, 30.0, 10.0),
        ),
        (
            "Table 1 (table1_defaults, no [diffuse])",
            ModelConfig::table1_defaults(),
        ),
    ]
}

/// Priority 2: the closed-loop sets of `tests/closed_loop.rs` (sets 1–3: λ 1.0/0.43/0.2 per
/// ns, AoA 8/16.9/30°, d_c 6/8/10 m, d_p 0.4 m, Γ 15 ns, γ 4 ns, 5 rays; the Table 1 set
/// `table1_defaults` without its `[diffuse]`, whose 40 wall points per metre would make
/// each simulation ~10× slower) in a 160 m × 12 m hall with 32 random poses, 61
/// directions; synth seed 11, calibrate 1200 simulations (population 300) seed 5, default
/// prior. Prints every set; asserts nothing beyond the run completing.
///
/// Measured (posterior median vs model; 1720 s with other jobs on the cores): within 15 %
/// set 1 λ +10.0 %, d_p +7.0 %; set 2 AoA +9.0 %, Γ +2.4 %; set 3 (interleaved) λ −14.5 %,
/// Γ +5.7 %; Table 1 set Γ −7.8 %. NOT met: set 1 AoA −36 %, d_c +23 %, Γ +17 %, γ +101 %;
/// set 2 λ −15.1 %, d_c +80 %, d_p −59 %, γ +30 %; set 3 AoA +38 %, d_c +52 %, d_p −26 %,
/// γ −15.6 %; Table 1 set λ −33 %, AoA −20 %, d_c −29 %, d_p +52 %, γ +153 %. The 95 %
/// intervals cover the model value for 31 of 32 quantities (set 2's d_c [8.4, 20] m misses
/// 8 m: the default prior ends at 20 m). `cargo test --release --test tests
/// calibrate::hall_sets -- --ignored --nocapture`.
#[test]
#[ignore = "about 30 min on 2 shared cores"]
fn hall_sets() {
    let tmp = tempfile::tempdir().unwrap();
    let cpath = hall(&tmp.path().join("in"), 80.0, 32);
    let sets = hall_set_models();
    for (k, (name, model)) in sets.iter().enumerate() {
        let dir = tmp.path().join(format!("set{k}"));
        let e = synth(&dir, &cpath, model, 11);
        let t = Instant::now();
        let got = calibrate(&e, &cpath, &dir.join("cal.toml"), 1200, 300, 5, None, None);
        let wall = t.elapsed().as_secs_f64();
        let (failures, covered) = score(name, &got, model, 0.15);
        eprintln!(
            "{name}: {wall:.1} s ({:.1} simulations/s); outside 15 %: {}; intervals covering the truth {}/8",
            1200.0 / wall,
            failures.len(),
            covered.iter().filter(|c| **c).count()
        );
    }
}

/// Credible-interval coverage and width over environments: the corridor, Table 1 model,
/// 20 environments (synth seeds 1000..=1019), each calibrated with `distance` at 600
/// simulations (population 200, seed = the repetition), `--no-walls` (the model has no
/// `[diffuse]`/`[walls]`), then the calibrated model's posterior predictive check
/// (`check --posterior`); the model itself checked (plug-in) against each environment as
/// the reference. Prints per environment and per quantity: coverage, median |error| of the
/// median, median and largest interval hi/lo; and the checks' pass counts. Measurement
/// switches (environment): `PRADAR_COVERAGE_ENVS=5` the first 5 environments (the
/// proxy; 0 stops the test with a message), `PRADAR_COVERAGE_NO_CHECK=1` no `pradar
/// check`, `PRADAR_COVERAGE_SIMS` and `PRADAR_COVERAGE_POP` another budget and population
/// (default 600 and 200),
/// `PRADAR_COVERAGE_POSES=n` (1–24; unset or 0: the corridor's own 12) the first n of
/// the corridor's poses continued along it, `PRADAR_TEST_RIDGE=fixed|cv` adds `--ridge`,
/// `PRADAR_ABC_TRACE=1` passes the sampler's trace through.
fn coverage(distance: &str) {
    let tmp = tempfile::tempdir().unwrap();
    // `PRADAR_COVERAGE_POSES=24`: the corridor's poses continued along it at the same
    // 0.405 m spacing (x = 0.5 + 0.405·i m, the fixture's values for i < 12; 24 fit inside
    // its end wall at x = 10 m; measurements of the widths' contraction with the campaign)
    let mut t = common::corridor();
    let n = env_usize("PRADAR_COVERAGE_POSES", 0);
    if n > 0 {
        assert!(n <= 24, "PRADAR_COVERAGE_POSES in 1..=24");
        let poses: Vec<toml::Value> = (0..n)
            .map(|i| {
                let mut p = toml::Table::new();
                p.insert("x_m".into(), ((500 + 405 * i) as f64 / 1000.0).into());
                p.insert("y_m".into(), (-0.3).into());
                p.insert("heading_deg".into(), 0.0.into());
                toml::Value::Table(p)
            })
            .collect();
        t.insert("poses".into(), toml::Value::Array(poses));
    }
    let cpath = common::write_campaign(&tmp.path().join("in"), &t);
    let truth = ModelConfig::table1_defaults();
    // `PRADAR_COVERAGE_ENVS=5`: the five-environment proxy (synth seeds 1000-1004)
    let reps = env_usize("PRADAR_COVERAGE_ENVS", 20);
    assert!(reps > 0, "PRADAR_COVERAGE_ENVS=0: no environment to cover");
    // `PRADAR_COVERAGE_SIMS=3000 PRADAR_COVERAGE_POP=400`: another budget (measurements of
    // whether the widths are set by the sampler's budget or by the data)
    let (sims, pop) = (
        env_usize("PRADAR_COVERAGE_SIMS", 600),
        env_usize("PRADAR_COVERAGE_POP", 200),
    );
    let t = Instant::now();
    let mut all = Vec::new();
    let mut truth_pass = 0;
    for r in 0..reps {
        let dir = tmp.path().join(format!("r{r}"));
        let sc = environment(
            &dir,
            &cpath,
            &truth,
            1000 + r as u64,
            sims,
            pop,
            r as u64,
            Some(distance),
        );
        // the model drawn from, checked (plug-in: it is the model) as the reference
        let (tp, tr) = if no_check() {
            (false, f64::NAN)
        } else {
            check(&dir.join("model.toml"), &cpath, &dir.join("e.parquet"))
        };
        truth_pass += usize::from(tp);
        eprintln!(
            "ENV {distance} {r}: covered {}/8, hi/lo {:.1?}, posterior predictive check {:?}, truth's check ({tp}, p {tr:.3})",
            sc.covered.iter().filter(|c| **c).count(),
            sc.hilo,
            sc.check,
        );
        all.push(sc);
    }
    let wall = t.elapsed().as_secs_f64();
    eprintln!("== {distance}: coverage over {reps} environments ({wall:.0} s)");
    eprintln!("quantity | covered | median |error| | median hi/lo | largest hi/lo");
    for (i, (q, _)) in QUANTITIES.iter().enumerate() {
        let cov = all.iter().filter(|a| a.covered[i]).count();
        let mut e: Vec<f64> = all.iter().map(|a| a.err[i]).collect();
        let mut h: Vec<f64> = all.iter().map(|a| a.hilo[i]).collect();
        e.sort_by(f64::total_cmp);
        h.sort_by(f64::total_cmp);
        let med = |v: &[f64]| {
            if reps % 2 == 1 {
                v[reps / 2]
            } else {
                0.5 * (v[reps / 2 - 1] + v[reps / 2])
            }
        };
        eprintln!(
            "SUMMARY {distance} | {q} | {cov}/{reps} | {:.0} % | {:.2} | {:.2}",
            100.0 * med(&e),
            med(&h),
            h[reps - 1]
        );
    }
    let passes = all.iter().filter(|a| a.check.0).count();
    eprintln!(
        "SUMMARY {distance} | the calibrated model passes the posterior predictive check {passes}/{reps}; the model itself (plug-in) {truth_pass}/{reps}"
    );
}

/// [`coverage`] with the default `--distance summaries-quantiles` (issue 30: the 42
/// pooled statistics and the check statistics' quantiles) and the default `--ridge cv`.
///
/// Measured (5 Dec 2026, idle, 244 s): covered 20/20 λ, AoA, d_p, γ, σ; 19/20 d_c, rays;
/// 18/20 Γ; median hi/lo λ 8.3, AoA 6.7, d_c 5.2, Γ 5.6 (issue 30's halves,
/// 4.9/3.2/3.0/3.6, were not reached; that "sharper" target is withdrawn, issue 45 item
/// 6); under the check's former ratio rule the calibrated model passed 14/20 plug-in, the
/// posterior predictive check (`--posterior`) 18/20, the drawn model itself 15/20. With
/// `PRADAR_TEST_RIDGE=fixed` (the default until then; 345 s): covered 16/20 d_c and rays,
/// 17/20 Γ, 18/20 λ (below 85 % for d_c and the rays), median hi/lo 5.6 / 4.5 / 4.4 / 4.0;
/// check 13/20. Issue 30's second session measured the fixed penalty before the
/// importance-weight correction (846 s): covered 18/20 λ, d_c, Γ, γ; 19/20 d_p, σ; 20/20
/// AoA, rays; median hi/lo λ 5.9, AoA 4.9, d_c 4.4, Γ 4.2; check 15/20. With `--distance summaries` (issue 19, now
/// [`corridor_coverage_pooled`]): covered 20/20 λ, AoA, Γ, γ, σ; 19/20 d_c, d_p, rays;
/// median hi/lo λ 9.7, AoA 6.3, d_c 5.9, Γ 7.2 (862 s). Figures in `docs/calibrate.md`.
/// `cargo test --release --test tests calibrate::corridor_coverage -- --ignored
/// --nocapture --exact`.
#[test]
#[ignore = "about 15 min on 2 shared cores"]
fn corridor_coverage() {
    coverage("summaries-quantiles");
}

/// [`coverage`] with `--distance summaries` (issue 19's 42 pooled statistics, the default
/// until issue 30's quantiles), the same environments and budget. Figures in
/// `docs/calibrate.md`.
#[test]
#[ignore = "about 15 min on 2 shared cores"]
fn corridor_coverage_pooled() {
    coverage("summaries");
}

/// [`coverage`] with `--distance mmd` (issue 30), the same environments and budget.
/// Figures in `docs/calibrate.md`.
#[test]
#[ignore = "about 15 min on 2 shared cores"]
fn corridor_coverage_mmd() {
    coverage("mmd");
}

/// The calibration's in-memory simulator gives exactly the energies `synth` writes for the
/// same model and seed (the corridor, Table 1 model with and without `[diffuse]`).
#[test]
fn in_memory_simulator_is_synth() {
    use pradar::campaign::manifest::Campaign;
    use pradar::model::file::{DiffuseModel, Quantity};
    use pradar::model::{EnergySimulator, SynthParams};
    use pradar::params::ParamGuard;
    let tmp = tempfile::tempdir().unwrap();
    let cpath = corridor(&tmp.path().join("in"));
    let c = Campaign::load(&cpath).unwrap();
    let sim = EnergySimulator::new(&c, &SynthParams::default().check().unwrap()).unwrap();
    let mut walls = ModelConfig::table1_defaults();
    walls.diffuse = Some(DiffuseModel {
        wall_rcs_per_m: Quantity::new(0.02, "m2/m", "constant"),
        lambert_exponent: Quantity::new(1.0, "1", "constant"),
        power_share: Quantity::new(0.5, "1", "constant"),
        decay: Quantity::new(10.0, "ns", "exponential"),
    });
    for (k, model) in [ModelConfig::table1_defaults(), walls].iter().enumerate() {
        let e = synth(&tmp.path().join(format!("s{k}")), &cpath, model, 11);
        let written = pradar::energy::EnergyMatrix::read(&e).unwrap();
        let mem = sim.energies(model, 11).unwrap();
        assert_eq!(written.data.len(), mem.len());
        assert!(
            written.data == mem,
            "model {k}: in-memory energies differ from synth's"
        );
        // the layout's rays made once serve every cluster level (`model::levels`' search):
        // the same energies, bit for bit; rays of another seed are refused
        let fixed = sim.layout_rays(model, 11).unwrap();
        let mut other = model.clone();
        other.cluster_rrcs.value *= 3.0;
        assert!(
            sim.energies_with(&other, 11, &fixed).unwrap() == sim.energies(&other, 11).unwrap()
        );
        assert!(sim.energies_with(model, 12, &fixed).is_err());
    }
}

/// A scene's name and its calibrated model's posterior predictive checks (`check
/// --posterior`; pass, max-T p): own table, second realisation.
type SceneChecks = (String, (bool, f64), (bool, f64));

/// The prior [`physics_predictive`] calibrates with.
#[derive(Clone, Copy, PartialEq)]
enum PhysicsPrior {
    /// The CLI's default prior: every quantity of the model free, the layout's parts
    /// (`[diffuse]`, `[walls]`) included, 13 quantities.
    Default,
    /// `calibrate --no-walls`: the eight cluster quantities only (the default until issue
    /// 45 item 6).
    NoWalls,
    /// The cluster chain's model of the scene (`pipeline::analyse`, what `reproduce` runs:
    /// it has `[diffuse]` and `[walls]`) with every interval removed, so the default ranges
    /// apply to its 13 free quantities.
    Chain,
}

/// The physics scenes of the predictive check (issue 29, `tests/check.rs`): the corridor,
/// the office and the furnished hall (48 poses). Each is simulated by the physics simulator
/// (`simulate` → `energy`, its manifest's seed) and at the next seed (a second
/// realisation); the first is calibrated (`calibrate --seed 5`, `sims` simulations,
/// population `pop`, the default distance, `prior`), and the calibrated model passes when
/// its posterior predictive check (`pradar check --posterior <stem>_posterior.csv`, the
/// check's default draws and rule) passes, against the scene and against the second
/// realisation. The plug-in check (every draw the posterior medians) and the realisations'
/// distance ([`realisations_apart`]) are printed as reference. Calibrate reads only the
/// energy table and the campaign (never the `[scene]` or `[clutter]` truth). Only the
/// scenes named in `scenes` are run. Returns per scene (name, own check, second check).
fn physics_predictive(
    sims: usize,
    pop: usize,
    prior: PhysicsPrior,
    scenes: &[&str],
) -> Vec<SceneChecks> {
    use pradar::campaign::manifest::SweepFormat;
    let tmp = tempfile::tempdir().unwrap();
    let mut out = Vec::new();
    for (name, t) in [
        ("corridor", common::corridor()),
        ("office", common::fixture("tests/office.toml")),
        (
            "furnished hall",
            common::fixture("tests/furnished_hall.toml"),
        ),
    ] {
        if !scenes.contains(&name) {
            continue;
        }
        // PRADAR_PREDICTIVE_SCENES=corridor,office runs only those (a shorter measurement)
        if let Ok(only) = std::env::var("PRADAR_PREDICTIVE_SCENES") {
            if !only.split(',').any(|s| s.trim() == name) {
                continue;
            }
        }
        let dir = tmp.path().join(name.replace(' ', "_"));
        let t0 = Instant::now();
        let (c, _) = common::chain(&dir.join("a"), &t, SweepFormat::Parquet);
        let mut t2 = t.clone();
        let seed = t2["seed"].as_integer().unwrap();
        common::set(&mut t2, "seed", seed + 1);
        let (c2, _) = common::chain(&dir.join("b"), &t2, SweepFormat::Parquet);
        let sim_s = t0.elapsed().as_secs_f64();
        let (e, e2) = (dir.join("a/energy.parquet"), dir.join("b/energy.parquet"));
        let cal = dir.join("cal.toml");
        let t1 = Instant::now();
        let mut args: Vec<String> = [
            "calibrate",
            "--energy",
            &s(&e),
            "--campaign",
            &s(&c.path),
            "--out",
            &s(&cal),
            "--simulations",
            &sims.to_string(),
            "--population",
            &pop.to_string(),
            "--seed",
            "5",
        ]
        .map(String::from)
        .to_vec();
        match prior {
            PhysicsPrior::Default => {}
            PhysicsPrior::NoWalls => args.push("--no-walls".to_string()),
            PhysicsPrior::Chain => {
                let em = pradar::energy::EnergyMatrix::read(&e).unwrap();
                let a = pradar::pipeline::analyse(&c, &em, &e, &dir.join("a"), false).unwrap();
                let mut m = a.fit.unwrap().model;
                for (q, _, _) in pradar::calibrate::DEFAULT_PRIOR {
                    if let Some(x) = m.quantity_mut(q) {
                        x.interval = None;
                    }
                }
                let pp = dir.join("prior.toml");
                m.save(&pp).unwrap();
                args.extend(["--prior".to_string(), s(&pp)]);
            }
        }
        run(&args, None);
        let cal_s = t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let (p1, q1, v1) = predictive(&cal, &c.path, &e);
        let (p2, q2, v2) = predictive(&cal, &c2.path, &e2);
        eprintln!(
            "== {name} ({} poses): simulate ×2 {sim_s:.0} s, calibrate {cal_s:.0} s, posterior predictive check ×2 {:.0} s\n   own scene:          {v1}\n   second realisation: {v2}",
            c.manifest.poses.len(),
            t2.elapsed().as_secs_f64()
        );
        eprintln!("{}", std::fs::read_to_string(&cal).unwrap());
        // reference: the plug-in check (the posterior medians) and the realisations' distance
        let (_, _, w1) = check_verdict(&cal, &c.path, &e);
        let (_, _, w2) = check_verdict(&cal, &c2.path, &e2);
        eprintln!("   plug-in check (reference), own scene: {w1}\n   plug-in check, second realisation: {w2}");
        realisations_apart(&c.path, &e, &e2, &cal);
        out.push((name.to_string(), (p1, q1), (p2, q2)));
    }
    eprintln!("SUMMARY scene | own scene (posterior predictive, max-T p) | second realisation");
    for (n, a, b) in &out {
        eprintln!(
            "SUMMARY {n} | {} ({:.3}) | {} ({:.3})",
            if a.0 { "PASS" } else { "FAIL" },
            a.1,
            if b.0 { "PASS" } else { "FAIL" },
            b.1
        );
    }
    out
}

/// Issue 45 item 6's predictive must-show on the physics scenes: the calibrated model of
/// each scene (corridor, office, furnished hall; CLI defaults: 3000 simulations,
/// population 400, the default prior with every quantity free, the layout's parts
/// included) passes the posterior predictive check (`check --posterior`) against its
/// scene and against the scene at another seed ([`physics_predictive`]). `cargo test
/// --release --test tests -- calibrate::physics_scenes_predictive --exact --ignored
/// --nocapture`.
///
/// Measured with this prior (then `calibrate --walls`; issue 30, 5 Dec 2026, idle 2 cores,
/// 15.5 min; the check's former ratio rule, before the check drew at the measured N0):
/// corridor calibrate 138 s, office 118 s, furnished hall 649 s; the posterior predictive
/// passed corridor (largest KS ratio 0.93 own, 1.08 seed + 1) and office (0.82, 0.99), and
/// failed the furnished hall (1.54, 1.69).
///
/// Measured under the max-T rule (issue 45, 6 Dec 2026, `PRADAR_PREDICTIVE_SCENES=
/// corridor,office`, load 6–7, 670 s): corridor calibrate 323 s, posterior predictive PASS
/// p 0.775 own and 0.475 seed + 1 (the plug-in check, reference: FAIL 0.050 and 0.025);
/// office 292 s, PASS p 0.275 and 0.200 (plug-in FAIL 0.050 and 0.025). The furnished hall
/// not run under this rule (time box). The zoo measurement is in docs/calibrate.md
/// ("Issue 45").
#[test]
#[ignore = "about 25 min on 2 shared cores; corridor and office pass (max-T p 0.775/0.475, 0.275/0.200), the furnished hall not measured under the max-T rule (it failed the former ratio rule)"]
fn physics_scenes_predictive() {
    assert_predictive(&physics_predictive(
        3000,
        400,
        PhysicsPrior::Default,
        &ALL_SCENES,
    ));
}

/// [`physics_scenes_predictive`] with `calibrate --no-walls` (the eight cluster quantities,
/// the default prior until issue 45 item 6).
///
/// Measured (issue 30, then the default prior; the check's former ratio rule, before the
/// check drew at the measured N0; cross-validated ridge, 2 threads, load 2–4, 13 min):
/// corridor calibrate 95 s, office 105 s, furnished hall 479 s; the plug-in check failed
/// all three both ways, and the posterior predictive check (corridor and office) failed
/// too (largest KS ratio 2.35 / 2.65 and 2.44 / 2.26, p = 0): without `[diffuse]` and
/// `[walls]` the model cannot reproduce the physics scenes.
#[test]
#[ignore = "unmet when last measured (former ratio rule): corridor and office fail the posterior predictive check; about 15 min on 2 idle cores"]
fn physics_scenes_predictive_no_walls() {
    assert_predictive(&physics_predictive(
        3000,
        400,
        PhysicsPrior::NoWalls,
        &ALL_SCENES,
    ));
}

/// [`physics_scenes_predictive`] with the cluster chain's model of each scene (intervals
/// removed) as the prior ([`PhysicsPrior::Chain`]). Not run yet (each simulation ~5×
/// dearer than without `[diffuse]`/`[walls]`; the corridor alone took 609 s with another
/// calibration on the cores, docs/calibrate.md).
#[test]
#[ignore = "about 1-2 h on 2 shared cores (not run)"]
fn physics_scenes_predictive_chain_prior() {
    assert_predictive(&physics_predictive(
        3000,
        400,
        PhysicsPrior::Chain,
        &ALL_SCENES,
    ));
}

/// How far apart the two realisations of a scene are, against the calibrated model's own
/// spread: per statistic of `pradar check`, the KS distance between the scene's table
/// (`e`) and the second realisation's (`e2`), divided by the model's reference distance d
/// (the median KS between two of its draws, as `check` computes it against `e`), beside
/// the check's D/d against `e`. A ratio well above 1 says the two realisations differ by
/// more than the calibrated model's draws differ from each other (printed only: a
/// diagnostic of the second-realisation check; the check's rule is its max-T p-value,
/// `src/check/mod.rs`).
fn realisations_apart(cpath: &Path, e: &Path, e2: &Path, model: &Path) {
    use pradar::check::stats::{ks_distance, Statistics};
    use pradar::params::ParamGuard;
    let c = pradar::campaign::Campaign::load(cpath).unwrap();
    let (a, b) = (
        pradar::energy::EnergyMatrix::read(e).unwrap(),
        pradar::energy::EnergyMatrix::read(e2).unwrap(),
    );
    let m = ModelConfig::load(model).unwrap();
    let params = pradar::check::CheckParams::default().check().unwrap();
    let res = pradar::check::check(&c, &a, e, &m, &params, &|_, _| {}).unwrap();
    let sb = Statistics::of(&pradar::check::context(&b), &b.data);
    for (k, st) in res.stats.iter().enumerate() {
        let ab = ks_distance(&res.measured.values[k], &sb.values[k]);
        eprintln!(
            "   realisations apart: {:<28} KS(scene, seed + 1) {ab:.3}, model d {:.3}: ratio {:.2} (check vs the scene D/d {:.2})",
            st.name,
            st.reference(),
            ab / st.reference().max(1e-12),
            st.ks() / st.reference().max(1e-12),
        );
    }
}

/// The physics scenes of [`physics_predictive`].
const ALL_SCENES: [&str; 3] = ["corridor", "office", "furnished hall"];

/// Every scene's calibrated model passes the posterior predictive check against its scene
/// and the second realisation.
fn assert_predictive(r: &[SceneChecks]) {
    let failed: Vec<String> = r
        .iter()
        .flat_map(|(n, a, b)| {
            [
                (!a.0).then(|| format!("{n}: own scene fails (max-T p {:.3})", a.1)),
                (!b.0).then(|| format!("{n}: second realisation fails (max-T p {:.3})", b.1)),
            ]
        })
        .flatten()
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("; "));
}

/// The posterior of one contraction run: per quantity of [`QUANTITIES`], (median, lo, hi).
type Marginals = Vec<(f64, f64, f64)>;

/// Contraction with the campaign: the closed-loop sets `sets` (indices into
/// [`hall_set_models`]) in the closed loop's 480 m × 12 m hall (`tests/closed_loop.rs`:
/// 240 random poses, seed 5, 3° steps); at each pose count n of `poses` the campaign has
/// the first n of those 240 poses (so the pose sets are nested), synth seed 11, calibrated
/// with `sims` simulations (population `pop`, seed 5, default prior and distance). Prints
/// per set and quantity the median's error, the 95 % interval at each pose count and the
/// width ratio ln(hi/lo) at the first pose count over ln(hi/lo) at the last, beside
/// √(last/first), the ratio of a 1/√poses contraction. Returns per set the marginals at
/// each pose count.
fn contraction(sets: &[usize], poses: &[usize], sims: usize, pop: usize) -> Vec<Vec<Marginals>> {
    let tmp = tempfile::tempdir().unwrap();
    let models = hall_set_models();
    let mut all = Vec::new();
    for &k in sets {
        let (name, model) = &models[k];
        let mut per_n = Vec::new();
        for &n in poses {
            let dir = tmp.path().join(format!("set{k}_{n}"));
            let cpath = hall(&dir.join("in"), 240.0, n);
            let e = synth(&dir, &cpath, model, 11);
            let t = Instant::now();
            let got = calibrate(&e, &cpath, &dir.join("cal.toml"), sims, pop, 5, None, None);
            let wall = t.elapsed().as_secs_f64();
            let (failures, covered) = score(&format!("{name}, {n} poses"), &got, model, 0.15);
            eprintln!(
                "{name}, {n} poses: {wall:.0} s ({:.2} simulations/s); outside 15 % (first six): {}; covered {}/8",
                sims as f64 / wall,
                failures.len(),
                covered.iter().filter(|c| **c).count()
            );
            per_n.push(
                QUANTITIES
                    .iter()
                    .map(|(q, pick)| {
                        let [lo, hi] = got.quantity(q).and_then(|x| x.interval).unwrap();
                        (pick(&got), lo, hi)
                    })
                    .collect::<Marginals>(),
            );
        }
        let (first, last) = (poses[0], poses[poses.len() - 1]);
        eprintln!(
            "SUMMARY {name} | quantity | truth | {} | ln-width ratio {first}/{last} (1/√poses: {:.2})",
            poses
                .iter()
                .map(|n| format!("{n} poses: median (error) [lo, hi] hi/lo"))
                .collect::<Vec<_>>()
                .join(" | "),
            (last as f64 / first as f64).sqrt()
        );
        for (i, (q, pick)) in QUANTITIES.iter().enumerate() {
            let t = pick(model);
            let cells: Vec<String> = per_n
                .iter()
                .map(|m| {
                    let (v, lo, hi) = m[i];
                    format!(
                        "{v:.3} ({:+.0} %) [{lo:.3}, {hi:.3}] {:.2}",
                        100.0 * (v - t) / t,
                        hi / lo
                    )
                })
                .collect();
            let w = |m: &Marginals| (m[i].2 / m[i].1).ln();
            eprintln!(
                "SUMMARY {name} | {q} | {t:.3} | {} | {:.2}",
                cells.join(" | "),
                w(&per_n[0]) / w(&per_n[per_n.len() - 1])
            );
        }
        all.push(per_n);
    }
    all
}

/// Contraction with the campaign, printed as reference (not a target: issue 45 item 6
/// withdrew issue 30's contraction must-show — medians within 15 % and 95 % intervals
/// shrinking as 1/√poses from 32 to 240 poses, ln(hi/lo)@32 / ln(hi/lo)@240 ≥ 1.83 —
/// since the measurements below show campaigns of this size do not carry that
/// information; its test `hall_contraction` is removed). Set 1 (λ 1.0/ns, AoA 8°, d_c
/// 6 m), 32 and 240 poses, 400 simulations (population 200, the smallest population at
/// which the regression adjustment still applies: 10 kept particles per coefficient).
/// Prints the table of [`contraction`]; asserts nothing (`PRADAR_CONTRACTION_SIMS` and
/// `PRADAR_CONTRACTION_POP` set another budget; 1200 and 300 were the must-show's).
/// `cargo test --release --test tests -- calibrate::hall_contraction_reduced --ignored
/// --nocapture`.
///
/// Measured (issue 30, 2 threads at load 6–8; 1671 s in all: 205 s at 32 poses, 1464 s
/// at 240): medians at 32 → 240 poses λ +38 → +24 %, AoA +23 → +30 %, d_c +2 → +28 %,
/// Γ −11 → +28 %; hi/lo λ 3.56 → 3.64, AoA 3.15 → 2.96, d_c 2.62 → 2.09, Γ 3.30 → 2.33;
/// ln-width ratio 32/240 λ 0.98, AoA 1.06, d_c 1.31, Γ 1.41 (1/√poses: 2.74); 8/8
/// intervals cover at both. A 96-pose point by the CLI on the same inputs (698 s): λ +31 %,
/// AoA +17 %, d_c +11 %, Γ +45 %, ratio 32/96 1.53/1.56/1.22/1.23 against 1.73 (λ and AoA
/// narrower at 96 than at 240). With the cross-validated ridge (the default since 5 Dec
/// 2026; 702 s in all, 85 s at 32 poses, 615 s at 240, load 2–4): medians at 32 → 240
/// poses λ +47 → +10 %, AoA −3 → −12 %, d_c −2 → +6 %, Γ −16 → +53 %; hi/lo λ 4.50 → 4.28,
/// AoA 4.55 → 9.09, d_c 3.53 → 2.60, Γ 3.05 → 2.56; ln-width ratio 32/240 λ 1.03, AoA
/// 0.69, d_c 1.32, Γ 1.18 (against 2.74); 8/8 covered at both. Set 1 at the must-show's
/// 1200 simulations (31 min): at 240 poses λ +1 %, AoA +20 %, d_c +14 %, Γ +11 %; width
/// ratios 1.20/1.04/1.47/1.20. Table in docs/calibrate.md.
#[test]
#[ignore = "reference, asserts nothing; about 30 min on 2 shared cores; figures in docs/calibrate.md"]
fn hall_contraction_reduced() {
    // `PRADAR_CONTRACTION_SIMS=1200 PRADAR_CONTRACTION_POP=300`: set 1 at another budget
    // (1200, 300: the must-show's)
    contraction(
        &[0],
        &[32, 240],
        env_usize("PRADAR_CONTRACTION_SIMS", 400),
        env_usize("PRADAR_CONTRACTION_POP", 200),
    );
}
