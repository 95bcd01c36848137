//! `pradar check`: the posterior-predictive check of a channel model against a measured
//! energy table, cluster-free (DESIGN §2 "Model check").
//!
//! Takes a model file (fitted, calibrated or hand-made), the campaign (poses, directions,
//! band, array, noise, processing, layout — never its `[scene]`/`[clutter]` truth) and
//! the campaign's energy table; gives, for each statistic of [`stats`], how far the
//! measured table is from R `synth` draws of the model over the campaign's poses compared
//! with how far the draws are from each other.
//!
//! * **Draws**: R matrices y_r = synth(model, seed_r), r = 1..R, in memory
//!   ([`EnergySimulator`]: the same draws and detector as `synth`), seed_r from a ChaCha
//!   stream keyed by (seed, "Check", r): never the data's own seed, so a model checked
//!   against its own `synth` output at the campaign seed does not replay it. The draws
//!   run in parallel and are collected in order (same bytes with any thread count).
//!   With a posterior sample (`--posterior`, `calibrate`'s final population,
//!   [`PosteriorSample`]) draw r's free quantities are those of particle j_r, drawn by
//!   weight from a stream keyed by (seed, r): y_r ~ p(y | θ_j), θ_j ~ p(θ | data), the
//!   posterior predictive (Gelman, Meng & Stern 1996). Without it every draw is the model
//!   file's (a plug-in check: the posterior medians, no parameter uncertainty), whose draws
//!   differ less from each other than data from a model known only to its posterior do.
//! * **Like with like**: the draws carry the measured table's recorded noise level N0
//!   (metadata `n0`, [`EnergySimulator::for_table`]), not the manifest's `[noise]` floor:
//!   the model is a model of this campaign's system, noise included. Each table's
//!   statistics threshold it at its own noise mean μ = N0·TW ([`stats`]): the measured
//!   table at its recorded N0, a draw at the N0 it was drawn with.
//! * **Noise floor**: each table's floor is also read from its own bins, robustly, as the
//!   energy stage reads N0 ([`crate::energy::noise`]) but from a lower quantile:
//!   N̂0 = Q_¼(bins after the coupling gate) / (TW · q_k), q_k the lower quartile of the
//!   detector's Gamma(k, k) law, k = TW·N_p. The quartile, not the median: in a furnished
//!   room a third of the bins after the gate hold signal, which lifts their median 1.7 dB
//!   above N0 (the office) and makes the floor follow the model's signal density; a
//!   fraction ε of signal bins moves the quartile only to the law's ¼/(1 − ε) quantile. Under the model the measured table's N̂0 is one more
//!   draw's; a recorded N0 that its own bins do not bear out (an N0 read from echoes, a
//!   table whose metadata was edited) puts it away from the draws' median N̂0. More than
//!   [`MAX_NOISE_DB`] dB apart fails the check, with one line naming both.
//! * **Distances**, per statistic s: D_r = KS(s(y_obs), s(y_r)) (the measured table's
//!   distance to each draw) and d_ij = KS(s(y_i), s(y_j)) (the draws', the KS distance of
//!   [`stats::ks_distance`]). Summaries shown as information: D = median_r D_r,
//!   d = median_{i<j} d_ij and the ratio D/d.
//! * **Leave-one-out distances**: among the R + 1 tables (the measured one and the R
//!   draws) each table's distance to the others is the median of its R KS distances:
//!   D_obs = median_r D_r, and for draw i, D_i = median({d_ij : j ≠ i} ∪ {D_i,obs}). The
//!   measured table enters every D_i once, so that under the model the R + 1 tables are
//!   exchangeable and D_obs's rank among them is uniform (a Monte Carlo test, Barnard
//!   1963; Besag & Clifford 1989): the rank is exact, not a large-sample approximation.
//!   The per-statistic p-value p_s = (1 + #{i : D_i ≥ D_obs}) / (R + 1) (shown).
//! * **Rule** (Westfall & Young 1993, single-step max-T, calibrated on the same R + 1
//!   tables): per statistic the R + 1 distances are standardised by their median and a
//!   scale σ_s = max(1.4826·MAD_s, mean absolute deviation_s), z_t,s = (D_t,s − med_s) /
//!   σ_s (the same scale for every table, so the scores stay exchangeable); each table's
//!   score is
//!   T_t = max_s z_t,s. The adjusted p-value of statistic s is
//!   p̃_s = (1 + #{i : T_i ≥ z_obs,s}) / (R + 1) and the check's p = min_s p̃_s =
//!   (1 + #{i : T_i ≥ T_obs}) / (R + 1). The check **fails** when p ≤ α = [`ALPHA`]
//!   (the statistics with p̃_s ≤ α are its misses) or when the noise floors differ by more
//!   than [`MAX_NOISE_DB`] dB. Since T_obs's rank among the R + 1 exchangeable scores is
//!   uniform (ties counted against the measured table), the family-wise false rejection
//!   over the statistics is at most ⌊α(R + 1)⌋/(R + 1): 5 % at the default R = 39
//!   ([`DEFAULT_DRAWS`]). Why max-T of standardised distances and not the min over
//!   statistics of the rank p-values: with R = 39 a rank p-value cannot go below 1/40, and
//!   every draw that is the farthest on any one of the nine statistics ties there, so a
//!   table far off on two statistics could not be told from the draws; standardised
//!   distances keep the margin. Without `--posterior` the check is a plug-in one: every
//!   draw is the model file's (no parameter uncertainty).
//!
//! * **Measured** (tests/check.rs `check_calibration_and_power`, synth tables of a model
//!   checked against it, R = 39): false rejection 2/50 on the corridor's fitted model and
//!   1/50 on the office model; level +10 dB rejected 20/20 on both, rays per cluster ×3
//!   18/20 and 19/20, a recorded N0 3 dB off its bins 20/20. **Not seen**: the
//!   intra-cluster AoA std ×0.3 (rejected 0/20 and 1/20: the statistics do not resolve a
//!   cluster's angular spread behind the geometry's returns). The noise floor is read from
//!   bins that in a dense scene hold signal (the corridor's lower quartile sits about 3 dB
//!   above N0), so it also moves with the model's signal density (rays ×3 trips it in 15 of
//!   20 corridor tables) and is not an exact-level test as the max-T rule is.
//!
//! Layout: [`stats`] (the statistics and the KS distance); `options` (the options, α and
//! the draw counts), `posterior` (the posterior sample and each draw's particle), `noise`
//! (the noise floors), `rule` (rank p-values, leave-one-out distances, max-T), `result`
//! (per statistic and the whole check: verdict, table), all re-exported here; this module
//! runs the check ([`check`]); [`holdout`] runs it on positions the fit did not see (fit on
//! one half of the walk, check on the other, both ways). The table and plots are in
//! [`crate::report::check`].

pub mod holdout;
mod noise;
mod options;
mod posterior;
mod result;
mod rule;
pub mod stats;

pub use holdout::{holdout, Estimator, EstimatorKind, HoldoutResult};
pub use noise::{noise_floor, NoiseFloors, FLOOR_QUANTILE};
pub use options::{
    draws_why, CheckParams, CheckValid, ALPHA, DEFAULT_DRAWS, DRAWS_RANGE, MAX_NOISE_DB, MIN_DRAWS,
};
pub use posterior::PosteriorSample;
pub use result::{CheckResult, StatResult};
pub use rule::{leave_one_out, max_t, rank_p};

use crate::campaign::manifest::Campaign;
use crate::energy::EnergyMatrix;
use crate::error::Result;
use crate::model::file::ModelConfig;
use crate::model::EnergySimulator;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use stats::{ks_distance, StatContext, Statistics, NAMES};
use std::borrow::Cow;
use std::path::Path;

/// Key of the draws' seed stream (xor-ed into the seed): "Check\0\0\0".
const STREAM: u64 = 0x4368_6563_6b00_0000;

/// The statistics' context of a campaign's energy table (μ its recorded N0·TW).
pub fn context(energy: &EnergyMatrix) -> StatContext {
    let bin_ns = energy.meta.bin_width_ns;
    StatContext {
        np: energy.positions,
        nd: energy.directions(),
        nb: energy.bins,
        bin_ns,
        first_bin: ((energy.meta.gate_ns() / bin_ns).ceil() as usize).min(energy.bins),
        mu: energy.meta.noise_mean(),
        angles_deg: energy.angles_rel_deg.clone(),
    }
}

/// The seed of draw r.
fn draw_seed(seed: u64, r: usize) -> u64 {
    keyed_seed(seed, STREAM, r)
}

/// The seed of draw r of the stream `key` (xor-ed into `seed`): ChaCha8 keyed by
/// `seed ^ key`, stream r + 1, its first word. The check's draws use [`STREAM`]; another
/// user of synth draws (the refinement, [`crate::smm`]) its own key, so it never replays
/// the check's draws.
pub fn keyed_seed(seed: u64, key: u64, r: usize) -> u64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ key);
    rng.set_stream(r as u64 + 1);
    rng.next_u64()
}

/// The statistics' context of a draw of `energy`'s table by `sim`: the table's, thresholded
/// at the N0·TW the draw was made with (each table at its own noise).
pub fn draw_context(energy: &EnergyMatrix, sim: &EnergySimulator) -> StatContext {
    StatContext {
        mu: sim.noise().0,
        ..context(energy)
    }
}

/// A draw of `model` with `seed` shaped as the measured table `energy`: its missing sweeps
/// are missing from the draw too.
pub fn table_draw(
    sim: &EnergySimulator,
    energy: &EnergyMatrix,
    model: &ModelConfig,
    seed: u64,
) -> Result<Vec<f64>> {
    let mut e = sim.energies(model, seed)?;
    (energy.meta).mask_missing(energy.directions(), energy.bins, &mut e);
    Ok(e)
}

/// Check `model` against the energy table `energy` (read from `energy_path`) of campaign
/// `c`. `progress(done, R)` after each draw.
pub fn check(
    c: &Campaign,
    energy: &EnergyMatrix,
    energy_path: &Path,
    model: &ModelConfig,
    params: &CheckValid,
    progress: &dyn Fn(usize, usize),
) -> Result<CheckResult> {
    let t0 = std::time::Instant::now();
    // the draws carry the table's recorded N0
    let sim = EnergySimulator::for_table(c, energy, energy_path, params.cull)?;
    let ctx = context(energy);
    // each table thresholded at its own noise: a draw at the N0·TW it was drawn with
    let draw_ctx = draw_context(energy, &sim);
    let (tw, pulses) = (energy.meta.tw, energy.meta.pulses);
    let measured = Statistics::of(&ctx, &energy.data);
    let measured_floor = noise_floor(&ctx, &energy.data, tw, pulses);
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let r = params.draws;
    progress(0, r);
    // draws in parallel, a thread's worth at a time, so progress is called from this
    // thread only (and needs not be Sync)
    let chunk = rayon::current_num_threads().max(1);
    let mut draws: Vec<Statistics> = Vec::with_capacity(r);
    let mut floors: Vec<f64> = Vec::with_capacity(r);
    for start in (0..r).step_by(chunk) {
        let part: Vec<(Statistics, f64)> = (start..(start + chunk).min(r))
            .into_par_iter()
            .map(|i| -> Result<(Statistics, f64)> {
                let drawn = match &params.posterior {
                    Some(post) => Cow::Owned(post.model(model, post.particle(seed, i))?),
                    None => Cow::Borrowed(model),
                };
                let e = table_draw(&sim, energy, &drawn, draw_seed(seed, i))?;
                Ok((
                    Statistics::of(&draw_ctx, &e),
                    noise_floor(&draw_ctx, &e, tw, pulses),
                ))
            })
            .collect::<Result<_>>()?;
        for (s, f) in part {
            draws.push(s);
            floors.push(f);
        }
        progress(draws.len(), r);
    }
    let mut stats: Vec<StatResult> = (0..NAMES.len())
        .map(|k| {
            let measured_ks: Vec<f64> = draws
                .iter()
                .map(|d| ks_distance(&measured.values[k], &d.values[k]))
                .collect();
            let mut pair = vec![0.0; r * r];
            let mut reference_ks = Vec::with_capacity(r * (r - 1) / 2);
            for i in 0..r {
                for j in i + 1..r {
                    let d = ks_distance(&draws[i].values[k], &draws[j].values[k]);
                    pair[i * r + j] = d;
                    pair[j * r + i] = d;
                    reference_ks.push(d);
                }
            }
            let draws_loo = leave_one_out(&measured_ks, |i, j| pair[i * r + j]);
            let draw_medians: Vec<f64> = draws
                .iter()
                .map(|d| d.values[k].median(ctx.bin_ns))
                .filter(|v| v.is_finite())
                .collect();
            StatResult {
                name: NAMES[k].0,
                unit: NAMES[k].1,
                measured_ks,
                reference_ks,
                draws_loo,
                measured_median: measured.values[k].median(ctx.bin_ns),
                draws_median: crate::stats::median(&draw_medians).unwrap_or(f64::NAN),
                adjusted_p: f64::NAN,
            }
        })
        .collect();
    let obs: Vec<f64> = stats.iter().map(StatResult::ks).collect();
    let loo: Vec<Vec<f64>> = stats.iter().map(|s| s.draws_loo.clone()).collect();
    let (adjusted, joint_p) = max_t(&obs, &loo);
    for (s, p) in stats.iter_mut().zip(adjusted) {
        s.adjusted_p = p;
    }
    Ok(CheckResult {
        stats,
        measured,
        draws,
        noise: NoiseFloors {
            recorded_n0: energy.meta.n0,
            measured: measured_floor,
            draws: floors,
        },
        joint_p,
        seed,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamGuard;

    /// A posterior CSV as `calibrate` writes it is read (weights normalised, the `_raw`
    /// columns skipped), particles are drawn by weight and deterministically, and a bad
    /// file is one line naming the file and the field.
    #[test]
    fn posterior_sample_reads_draws_and_refuses() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cal_posterior.csv");
        std::fs::write(
            &p,
            "weight,distance,intra_cluster_rate,intra_cluster_rate_raw,walls.specular_gamma,walls.specular_gamma_raw\n\
             3e0,1,0.5,0.6,0.2,0.3\n\
             1e0,2,2.0,2.1,0.4,0.5\n\
             0,3,9.0,9.0,0.9,0.9\n",
        )
        .unwrap();
        let s = PosteriorSample::read(&p).unwrap();
        assert_eq!(s.names, ["intra_cluster_rate", "walls.specular_gamma"]);
        assert_eq!(s.weights, [0.75, 0.25, 0.0]);
        assert_eq!(s.values[1], [2.0, 0.4]);
        let picks: Vec<usize> = (0..4000).map(|r| s.particle(11, r)).collect();
        assert_eq!(
            picks,
            (0..4000).map(|r| s.particle(11, r)).collect::<Vec<_>>()
        );
        assert!(!picks.contains(&2), "a zero weight is never drawn");
        let share = picks.iter().filter(|&&i| i == 0).count() as f64 / 4000.0;
        assert!((share - 0.75).abs() < 0.03, "{share}");
        // a quantity the model file lacks (Table 1 has no [walls]) is named
        let e = s.model(&ModelConfig::table1_defaults(), 1).unwrap_err();
        assert!(e.to_string().contains("walls.specular_gamma"), "{e}");
        let one = PosteriorSample {
            names: vec!["intra_cluster_rate".into()],
            weights: vec![1.0],
            values: vec![vec![2.0]],
        };
        let m = one.model(&ModelConfig::table1_defaults(), 0).unwrap();
        assert_eq!(m.intra_cluster_rate.value, 2.0);
        for (text, field) in [
            ("", "empty"),
            ("w,d,a,a_raw\n1,1,1,1\n", "header"),
            ("weight,distance,a,a_raw\n1,1,1\n", "row 1"),
            ("weight,distance,a,a_raw\n1,1,x,1\n", "row 1, a"),
            ("weight,distance,a,a_raw\n-1,1,1,1\n", "weight"),
            ("weight,distance,a,a_raw\n0,1,1,1\n", "positive weight"),
            ("weight,distance,a,a_raw\n1,1,NaN,1\n", "row 1, a"),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = PosteriorSample::read(&p).unwrap_err().to_string();
            assert!(e.contains("cal_posterior.csv") && e.contains(field), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }

    fn result(measured_ks: Vec<f64>, reference_ks: Vec<f64>, draws_loo: Vec<f64>) -> StatResult {
        StatResult {
            name: "x",
            unit: "u",
            measured_ks,
            reference_ks,
            draws_loo,
            measured_median: 0.0,
            draws_median: 0.0,
            adjusted_p: 1.0,
        }
    }

    /// The per-statistic arithmetic: D, d, the ratio, the leave-one-out distances (the
    /// measured table counted once in each) and the Monte Carlo p-value.
    #[test]
    fn p_value_ratio_and_leave_one_out() {
        let r = result(
            vec![0.2, 0.3, 0.4],
            vec![0.1, 0.2, 0.3, 0.4],
            vec![0.1, 0.3, 0.5],
        );
        assert_eq!(r.ks(), 0.3);
        assert_eq!(r.reference(), 0.25);
        assert!((r.ratio() - 1.2).abs() < 1e-12);
        // D_i ≥ 0.3: two of three; (1 + 2) / 4
        assert!((r.p_value() - 0.75).abs() < 1e-12);
        let far = result(vec![0.9; 3], vec![0.1; 3], vec![0.1; 3]);
        assert_eq!(far.p_value(), 0.25);
        assert_eq!(result(vec![0.0], vec![0.0], vec![0.0]).ratio(), 0.0);
        assert!(result(vec![0.1], vec![0.0], vec![0.0])
            .ratio()
            .is_infinite());
        // three draws: d_01 = 0.1, d_02 = 0.2, d_12 = 0.3; measured 0.5, 0.6, 0.7
        let d = [[0.0, 0.1, 0.2], [0.1, 0.0, 0.3], [0.2, 0.3, 0.0]];
        let loo = leave_one_out(&[0.5, 0.6, 0.7], |i, j| d[i][j]);
        // draw 0: median {0.1, 0.2, 0.5}; draw 1: {0.1, 0.3, 0.6}; draw 2: {0.2, 0.3, 0.7}
        assert_eq!(loo, vec![0.2, 0.3, 0.3]);
        assert_eq!(rank_p(0.3, &loo), 0.75);
        assert_eq!(rank_p(0.31, &loo), 0.25);
    }

    /// max-T: a measured table beyond every draw on one statistic gets the smallest
    /// p = 1/(R + 1) there even when each draw is the farthest on another statistic (where
    /// the min of rank p-values would tie); a measured table inside the draws passes; the
    /// joint p is the smallest adjusted one.
    #[test]
    fn max_t_arithmetic() {
        let r = 39;
        let base = |k: usize| -> Vec<f64> {
            (0..r)
                .map(|i| 0.1 + 0.001 * ((i * 7 + k * 13) % r) as f64)
                .collect()
        };
        // statistic 0: the measured table far out; 1, 2: inside
        let draws = vec![base(0), base(1), base(2)];
        let (adj, joint) = max_t(&[0.5, 0.115, 0.12], &draws);
        assert_eq!(adj[0], 1.0 / 40.0);
        assert!(adj[1] > 0.5 && adj[2] > 0.3, "{adj:?}");
        assert_eq!(joint, adj[0]);
        let (adj, joint) = max_t(&[0.12, 0.115, 0.12], &draws);
        assert!(joint > ALPHA, "{adj:?}");
        // every table equal: nothing stands out, p = 1
        let (adj, joint) = max_t(&[0.2, 0.2], &[vec![0.2; r], vec![0.2; r]]);
        assert_eq!((adj, joint), (vec![1.0, 1.0], 1.0));
        // under exchangeability the measured table's rank is uniform: swapping it with a
        // draw gives that draw's rank, so over all R + 1 swaps exactly 2 of 40 reject
        let mut t: Vec<Vec<f64>> = (0..3)
            .map(|k| {
                let mut v = base(k);
                v.push(0.1 + 0.0005 * k as f64);
                v
            })
            .collect();
        t[0][5] = 0.3;
        t[2][9] = 0.25;
        let rejections = (0..=r)
            .filter(|&o| {
                let obs: Vec<f64> = t.iter().map(|v| v[o]).collect();
                let rest: Vec<Vec<f64>> = t
                    .iter()
                    .map(|v| (0..=r).filter(|&i| i != o).map(|i| v[i]).collect())
                    .collect();
                max_t(&obs, &rest).1 <= ALPHA
            })
            .count();
        assert_eq!(rejections, 2);
    }

    /// The noise floor is the lower quartile of the bins after the gate over TW·q_k:
    /// noise-only bins drawn at N0 give N0 back, a table with a quarter of its bins lifted
    /// moves it by less than 1.5 dB, NaN profiles are left out.
    #[test]
    fn noise_floor_reads_n0() {
        use rand_distr::{Distribution, Gamma};
        let (tw, pulses, n0) = (1.6, 2usize, 3e-13);
        let k = tw * pulses as f64;
        let g = Gamma::new(k, n0 * tw / k).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let ctx = StatContext {
            np: 10,
            nd: 10,
            nb: 500,
            bin_ns: 0.25,
            first_bin: 8,
            mu: n0 * tw,
            angles_deg: vec![0.0; 10],
        };
        let mut e: Vec<f64> = (0..50_000).map(|_| g.sample(&mut rng)).collect();
        // bins inside the gate do not count
        for prof in e.chunks_mut(500) {
            prof[..8].fill(1.0);
        }
        let f = noise_floor(&ctx, &e, tw, pulses);
        assert!((f / n0 - 1.0).abs() < 0.03, "{f:e}");
        e[..500].fill(f64::NAN);
        for (i, v) in e.iter_mut().enumerate() {
            if i % 4 == 0 {
                *v *= 1e4;
            }
        }
        let f = noise_floor(&ctx, &e, tw, pulses);
        assert!(10.0 * (f / n0).log10() < 1.5, "{f:e}");
        let floors = NoiseFloors {
            recorded_n0: 2.0 * n0,
            measured: n0,
            draws: vec![2.0 * n0, 2.1 * n0, 1.9 * n0],
        };
        assert!(!floors.agree());
        let line = floors.line();
        assert!(
            line.contains("3.000e-13") && line.contains("-3.0 dB") && line.contains("6.000e-13"),
            "{line}"
        );
    }

    #[test]
    fn params_checked() {
        let with = |draws: usize| CheckParams {
            draws,
            ..Default::default()
        };
        assert!(with(1).check().is_err());
        assert!(CheckParams::default().check().is_ok());
        // the fewest draws whose p-value can reach α: 1/(R + 1) ≤ 0.05 first at R = 19
        assert_eq!(MIN_DRAWS, 19);
        assert!(1.0 / (MIN_DRAWS as f64 + 1.0) <= ALPHA);
        assert!(1.0 / (MIN_DRAWS as f64) > ALPHA);
        assert!(with(19).check().is_ok());
        let e = with(18).check().unwrap_err().to_string();
        assert!(
            e.contains("[19, 1000]") && e.contains("cannot reach α = 0.05") && e.contains("18"),
            "{e}"
        );
    }

    #[test]
    fn draw_seeds_differ() {
        let s: Vec<u64> = (0..5).map(|r| draw_seed(7, r)).collect();
        let mut u = s.clone();
        u.sort();
        u.dedup();
        assert_eq!(u.len(), 5);
        assert_ne!(draw_seed(7, 0), 7);
    }
}
