//! Issue 4: coverage of the 95 % position-bootstrap intervals over 50 seeded repetitions of
//! one model set. Each repetition draws a new channel with `synth` (seed 1..=50) over the
//! same 60 poses, a walk down a 120 m × 12 m hall (synth draws about 30 clusters there;
//! the 16 m × 10 m hall held 2–7, so one draw's environment was far from the model), and
//! applies the fit's estimators to synth's own truth (the true clusters and rays, as
//! `pradar fit --truth` does): this measures the interval machinery and the estimators'
//! bias on data that follow the model, without extraction or clustering (the chain's
//! closed loop is `tests/closed_loop.rs` and `scripts/closed-loop`).

use crate::common;

use pradar::campaign::manifest::Campaign;
use pradar::fit::channel::{fit_truth, FitParams};
use pradar::model::file::{ModelConfig, Quantity};
use pradar::model::{synth, SynthParams};
use pradar::params::ParamGuard;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn hall_campaign(dir: &std::path::Path) -> Campaign {
    std::fs::copy(
        common::root().join("data/tests/long_hall.geojson"),
        dir.join("hall.geojson"),
    )
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    // a walk down the hall: poses in order of x (neighbours see the same clusters)
    let mut poses: Vec<[f64; 3]> = (0..60)
        .map(|_| {
            [
                rng.gen_range(-57.0..57.0),
                rng.gen_range(-3.5..3.5),
                rng.gen_range(-180.0..180.0),
            ]
        })
        .collect();
    poses.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let path = dir.join("campaign.toml");
    std::fs::write(&path, common::hall_manifest(90.0, 801, &poses)).unwrap();
    Campaign::load(&path).unwrap()
}

type Pick = fn(&ModelConfig) -> &Quantity;

/// On synth's own truth the block-bootstrap intervals (see `fit::channel`) cover the true
/// values in 92 % (λ), 92 % (AoA std), 90 % (d_p), 88 % (d_c), 100 % (Γ) and 92 % (γ) of
/// the draws. History: in the small hall with the ordinary position bootstrap it was
/// 18/16/10/12/74/100 %, the estimates varying 4–10× more between draws than the bootstrap
/// said; the long hall brought that to 2.6–3.0×, the moving blocks to 1.0–1.6× (coverage
/// 72–92 %), and the few-blocks widening (t(G − 1)/z·√(G/(G − 1)), G = 5 blocks) to
/// 0.8–1.0×. The AoA from clusters 2·b̂ inside the sector took its mean from 16.0° to
/// 16.7° (true 16.9°), the signed d_p from 0.474 m to 0.448 m, and the same 2·b̂ margin for
/// the perimeter statistics to 0.435 m (true 0.40 m; synth caps offsets at 1.5 m, which
/// leaves a mean of 0.391 m). The intervals that miss cover the environment synth drew
/// (its clusters' mean offset, perimeter / clusters): 49 of 50 for d_p and 50 of 50 for
/// d_c; what they miss is a draw far from the model, which five blocks of positions see
/// only in part. d_c covers exactly 44 of 50, at the target: a change to the estimators
/// can tip it either way, and the test says so.
#[test]
fn bootstrap_intervals_cover_the_true_values_in_88_percent_of_50_repetitions() {
    let tmp = tempfile::tempdir().unwrap();
    let c = hall_campaign(tmp.path());
    let truth = common::hall_model(0.43, 16.9, 8.0);
    let picks: [(&str, Pick); 6] = [
        ("λ (1/ns)", |m| &m.intra_cluster_rate),
        ("AoA std (deg)", |m| &m.intra_cluster_aoa),
        ("d_p (m)", |m| &m.perimeter_offset),
        ("d_c (m)", |m| &m.perimeter_spacing),
        ("Γ (ns)", |m| &m.cluster_decay),
        ("γ (ns)", |m| &m.ray_decay),
    ];
    let reps = 50;
    let mut covered = [0usize; 6];
    let mut sums = [0.0f64; 6];
    let mut widths = [0.0f64; 6];
    let mut fitted = [0usize; 6];
    let mut estimates: Vec<Vec<f64>> = vec![Vec::new(); 6];
    for r in 0..reps {
        let out = tmp.path().join(format!("e{r}.parquet"));
        let tdir = tmp.path().join(format!("t{r}"));
        let params = SynthParams::default()
            .seed(r as u64 + 1)
            .truth_dir(&tdir)
            .check()
            .unwrap();
        synth(&c, &truth, &out, &params, &|_, _| {}).unwrap();
        let fit = fit_truth(
            &tdir,
            &c,
            &FitParams {
                bootstrap: 200,
                seed: 1,
            }
            .check()
            .unwrap(),
        )
        .unwrap();
        for (k, (_, pick)) in picks.iter().enumerate() {
            let q = pick(&fit.model);
            let want = pick(&truth).value;
            if let Some([lo, hi]) = q.interval {
                fitted[k] += 1;
                sums[k] += q.value;
                estimates[k].push(q.value);
                widths[k] += hi - lo;
                if lo <= want && want <= hi {
                    covered[k] += 1;
                }
            }
        }
        std::fs::remove_file(&out).unwrap();
    }
    let mut worst = 1.0f64;
    eprintln!(
        "quantity       | true   | mean estimate | spread over draws / bootstrap spread | coverage"
    );
    for (k, (name, pick)) in picks.iter().enumerate() {
        let cov = covered[k] as f64 / reps as f64;
        worst = worst.min(cov);
        // the standard deviation of the estimates over the 50 channel draws against the mean
        // bootstrap standard deviation (95 % width / 3.92)
        let e = &estimates[k];
        let mean = e.iter().sum::<f64>() / e.len().max(1) as f64;
        let sd = (e.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (e.len().max(2) - 1) as f64)
            .sqrt();
        let boot_sd = widths[k] / fitted[k].max(1) as f64 / 3.92;
        eprintln!(
            "{name:14} | {:6.3} | {mean:13.3} | {sd:.3} / {boot_sd:.3} = {:.1} | {}/{reps} ({cov:.2}), {} with an interval",
            pick(&truth).value,
            sd / boot_sd,
            covered[k],
            fitted[k]
        );
    }
    assert!(worst >= 0.88, "worst coverage {worst:.2} < 0.88");
}
