//! Table 1 without the clustering's bias: indirect inference by simulation of the whole
//! chain at the fitted point (Gourieroux, Monfort & Renault 1993; Smith 1993).
//!
//! Takes the campaign, its energy table, the fit of its clustered MPCs (the paper's
//! method: CLEAN → per-position K-means → the Table 1 estimators, [`ChannelFit`], with the
//! levels read from the table) and checked [`CorrectionValid`] parameters; gives a
//! [`Corrected`]: per quantity the paper's method's value, the bias-corrected value, its
//! 95 % interval and the binding function's own slope, or "not identifiable from this
//! campaign" with that slope. `fit` writes the corrected values into the model file
//! ([`ChannelFit::model_out`]) and both columns into Table 1.
//!
//! Why: from each pose the clusters of an indoor scene overlap in delay and angle, so no
//! partition recovers them (`docs/correction.md` has the ceilings measured), and the
//! estimators on a partition that merges and splits clusters are biased — by tens of
//! percent, in either direction, depending on the scene. The bias is a property of the
//! chain at the point where the campaign sits, so it is measured there, by simulation,
//! and removed.
//!
//! The binding function. θ are the quantities synth draws from that the chain reads back:
//! λ, the AoA std, d_c, d_p, Γ, γ and the mean rays per cluster (Λ is not drawn: synth
//! derives it from the geometry). u = the natural scale of each: log θ for the positive
//! ones, the rate 1/Γ for Γ (0 is no excess decay, Γ = ∞). T(u) is the chain applied to a
//! synth draw of the fitted model with θ set to u, over the campaign's own poses, layout,
//! array, noise level N0 and missing sweeps (in memory: [`EnergySimulator`], then
//! `mpc::extract`, `cluster::cluster` and the estimators with their defaults, the
//! clustering's sector the campaign's), on the same natural scales; T̄(u) its mean over R
//! draws with common seeds (common random numbers: every evaluation point sees the same
//! R environments' random numbers, so differences between points are not drawn noise).
//! t = the chain on the data (the fit's raw values), so u₀ = t.
//!
//! The iteration. One batch evaluates T̄ at u₀ and at u₀ + hᵢeᵢ for each quantity (h = ln
//! 1.25 on the log scale; on Γ's rate 0.25 times the rate, at least the rate whose e-fold
//! is the table's delay span): the Jacobian J of T̄ by forward differences of the common
//! draws. Its diagonal Jᵢᵢ is quantity i's own slope; below `min_slope` (0.25) the quantity
//! is not identifiable — the chain's estimate barely moves with it — and it is held at its
//! raw value (drawn as stated, flagged in the model file), as is one the chain reads in
//! fewer than half of the draws. The fold check, a second batch on the quantities the local
//! rule keeps: each also at 1/F and F times its fitted value (F = `far_factor`, 3; Γ's rate
//! likewise, from rate 0 only up), on the first ⌈R/3⌉ (at least 2) of the common draws; the
//! secant slope (mean change of T̄ᵢ over those draws / the move) below `min_slope` on
//! either side flags the quantity too: values a factor F apart read alike, so the data's
//! value may sit on either branch of a fold. Why: the local slope alone cannot see a fold —
//! on zoo `z01-office` the chain reads d_c 7.6 m at the truth 1.42 m and again when
//! simulated at 7.6 m, with slope 1.46 there (`docs/correction.md`). Each far point costs
//! ⌈R/3⌉ runs; a side outside the schema's range is not checked. Then steps on the
//! identifiable set S from the best point so far, two candidates evaluated together at
//! each: the Levenberg–Marquardt step (Levenberg 1944; Marquardt 1963) Δ = (JᵀWJ +
//! μ·diag(JᵀWJ))⁻¹ JᵀW (t − T̄), W = diag(1/sⱼ²) with sⱼ the draws' spread of estimate j, μ
//! from 1, divided by 3 after this step won and multiplied by 4 otherwise; and the diagonal
//! step Δᵢ = (tᵢ − T̄ᵢ)/Jᵢᵢ. Each component at most a factor 2 (Γ's rate between half of
//! itself and the larger of twice itself and itself plus two slope steps, so it can leave
//! 0) and inside the schema's range. R draws per candidate, until every remaining bias |tⱼ
//! − T̄ⱼ| is within the simulation noise of its mean sⱼ/√R (settled) or `iterations` steps
//! are made; the point with the smallest Σ ((tⱼ − T̄ⱼ)/(sⱼ/√R))² is kept. Why two: the
//! binding function's cross terms are large and real on a 150-pose hall (d_p's estimate
//! moves −3 times the AoA's log), so the diagonal alone cannot converge where they dominate
//! (the unit test's function), yet on that hall the diagonal steps lowered the remaining
//! bias to 38 where the damped whole-J steps reached 57 (the function is rugged over a
//! step: K-means' choices jump): `docs/correction.md`. Cost: R·(1 + n + 2·iterations) +
//! ⌈R/3⌉·2m chain runs for n quantities moved, m of them kept by the local rule; the
//! defaults (R 8, 3 iterations, n = 7) make at most 154.
//!
//! The interval. Linearised at the kept point û, the corrected value moves as
//! (tᵢ − T̄ᵢ)/Jᵢᵢ (the diagonal: the whole J⁻¹ carries its noise into every interval), and the chain's estimate on a campaign drawn at û scatters as the R
//! draws do: the draws stand for the data's sampling spread (a parametric bootstrap of
//! the correction). So per quantity the sample sd of T_{r,i}/Jᵢᵢ over the draws,
//! times √(1 + 1/R) for the simulation noise of T̄ (Gourieroux et al.'s factor), and
//! Student's t with R − 1 degrees of freedom: û ± t·sd, back on the quantity's scale.
//!
//! Λ. With T_r^Λ the chain's Λ and L_r the same estimators on the draw's true clusters
//! (synth's truth, in memory, every ray of the half-plane within the table's delay span,
//! as `fit_truth`), the bias at û is b = mean(log T_r^Λ − log L_r), and Λ is corrected
//! to exp(log t^Λ − b); its slope is d mean log T^Λ / d mean log L along d_c's step (the
//! quantity that moves Λ; not finite or below `min_slope`: not identifiable), its interval
//! log t^Λ − b ± t·s_b·√(1 + 1/n), s_b the draws' spread of log T_r^Λ − log L_r: the
//! target is the campaign's own environment, which the chain misses by that much.
//!
//! What it assumes, stated: the clustering and extraction the data went through are the
//! defaults (a clustered table made with other options is corrected as if made with
//! them: use `fit --no-correction` then); the levels (walls, diffuse, σ) stay as `fit`
//! read them at the raw values (σ is not refitted at the corrected ones); the slopes are taken at the start, not refreshed along the steps.
//!
//! Partition stability (beside, [`stability`]): the ARI between the data's clusters and
//! the chain's clusters of random 80 % subsamples of each position's MPCs.
//!
//! Deterministic: the draws' seeds come from one ChaCha stream keyed by the seed, the
//! chain runs in parallel (rayon) and every result lands in its own slot.

pub mod params;
pub mod stability;

pub use params::{CorrectionParams, CorrectionValid};

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, C0};
use crate::cluster::{ClusterParams, ClusterValid};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::fit::channel::{clustered_rays, fit_clustered, ChannelFit, ClusteredRay};
use crate::fit::corrected::{Corrected, CorrectedQuantity};
use crate::fit::quantities::NO_EXCESS_RATE_PER_NS;
use crate::model::channel::{ChannelModel, RaySource};
use crate::model::file::ModelConfig;
use crate::model::{EnergySimulator, SynthParams};
use crate::mpc::ExtractParams;
use crate::params::ParamGuard;
use crate::pattern::ArrayPattern;
use geo::Coord;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// How a quantity is moved and read: its log, or (Γ) its rate 1/Γ.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scale {
    Log,
    Rate,
}

/// The quantities the correction moves (θ), by model-file key, in Table 1's order after Λ.
const MOVED: [(&str, Scale); 7] = [
    ("intra_cluster_rate", Scale::Log),
    ("intra_cluster_aoa", Scale::Log),
    ("perimeter_spacing", Scale::Log),
    ("perimeter_offset", Scale::Log),
    ("cluster_decay", Scale::Rate),
    ("ray_decay", Scale::Log),
    ("rays_per_cluster", Scale::Log),
];

/// d_c's index in [`MOVED`]: its step gives Λ's slope.
const SPACING: usize = 2;

/// One Levenberg–Marquardt step on the identifiable set: Δ = (JᵀWJ + μ·diag(JᵀWJ))⁻¹ JᵀW r,
/// W the squared `weights` (1/sⱼ, the draws' spread of each estimate); None when the
/// system is singular.
fn lm_step(
    jac: &[Vec<f64>],
    set: &[usize],
    r: &[f64],
    weights: &[f64],
    mu: f64,
) -> Option<Vec<f64>> {
    let n = set.len();
    let j = nalgebra::DMatrix::from_fn(n, n, |p, q| weights[p] * jac[set[p]][set[q]]);
    let rv = nalgebra::DVector::from_fn(n, |p, _| weights[p] * r[p]);
    let jtj = j.transpose() * &j;
    let mut a = jtj.clone();
    for p in 0..n {
        a[(p, p)] += mu * jtj[(p, p)];
    }
    let x = a.lu().solve(&(j.transpose() * rv))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

/// The largest move of a log-scale quantity in one step (a factor 2).
const MAX_LOG_STEP: f64 = std::f64::consts::LN_2;

/// The stream the draws' seeds come from.
const STREAM: u64 = 0x6269_6173_636f_7272;

/// A positive value on its natural scale (NaN for a value that has none).
fn to_u(scale: Scale, v: f64) -> f64 {
    match scale {
        Scale::Log if v.is_finite() && v > 0.0 => v.ln(),
        Scale::Rate if v == f64::INFINITY => 0.0,
        Scale::Rate if v.is_finite() && v > 0.0 => 1.0 / v,
        _ => f64::NAN,
    }
}

/// Back from the natural scale (a rate below the no-excess floor is Γ = ∞).
fn from_u(scale: Scale, u: f64) -> f64 {
    match scale {
        Scale::Log => u.exp(),
        Scale::Rate if u < NO_EXCESS_RATE_PER_NS => f64::INFINITY,
        Scale::Rate => 1.0 / u,
    }
}

/// A model's value of `key` if estimated (NaN when not estimable).
fn estimate(m: &ModelConfig, key: &str) -> f64 {
    match m.quantity(key) {
        Some(q) if q.is_estimable() => q.value,
        _ => f64::NAN,
    }
}

/// What one simulated campaign gives: the chain's estimates on the natural scales (NaN
/// where the chain gives none), and log Λ of the chain and of the draw's true clusters.
#[derive(Debug, Clone, Copy)]
struct Draw {
    t: [f64; 7],
    log_lambda_chain: f64,
    log_lambda_truth: f64,
}

/// The chain on simulated campaigns, set up once.
struct Chain<'a> {
    c: &'a Campaign,
    em: &'a EnergyMatrix,
    sim: EnergySimulator,
    layout: Layout,
    extract: crate::mpc::ExtractValid,
    cluster: ClusterValid,
    headings_deg: Vec<f64>,
    /// G₀²λ_c² (the truth rows' power through the broadside gain).
    gain_den: f64,
    max_delay_ns: f64,
    /// What errors name.
    name: PathBuf,
}

impl<'a> Chain<'a> {
    fn new(c: &'a Campaign, em: &'a EnergyMatrix, energy_path: &Path) -> Result<Chain<'a>> {
        let m = &c.manifest;
        let sim = EnergySimulator::for_table(c, em, energy_path, SynthParams::default().cull)?;
        let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
        let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
        let lc = C0 / m.band.center_hz();
        Ok(Chain {
            c,
            em,
            layout: Layout::load(&c.layout_path())?,
            sim,
            extract: ExtractParams::default().check()?,
            cluster: ClusterParams::default()
                .sector_deg(m.directions.width_deg())
                .check()?,
            headings_deg: m.poses.iter().map(|p| p.heading_deg).collect(),
            gain_den: g0 * g0 * lc * lc,
            max_delay_ns: m.processing.max_delay_ns,
            name: energy_path.to_path_buf(),
        })
    }

    /// The chain on the campaign drawn from `model` with `seed`.
    fn run(&self, model: &ModelConfig, seed: u64) -> Result<Draw> {
        let mut e = self.sim.energies(model, seed)?;
        let (nd, nb) = (self.em.directions(), self.em.bins);
        self.em.meta.mask_missing(nd, nb, &mut e);
        // the measured table's axes and metadata with the drawn energies (cloning the
        // whole table would copy its energies once per run only to drop them)
        let em = self.em;
        let drawn = EnergyMatrix {
            meta: em.meta.clone(),
            positions: em.positions,
            angles_rel_deg: em.angles_rel_deg.clone(),
            headings_deg: em.headings_deg.clone(),
            bins: em.bins,
            first: em.first,
            data: e,
        };
        let nan = Draw {
            t: [f64::NAN; 7],
            log_lambda_chain: f64::NAN,
            log_lambda_truth: f64::NAN,
        };
        // a simulated campaign the chain cannot read counts as read nowhere (the 2n ≥ R rule)
        let Ok(mpcs) = crate::mpc::extract(&drawn, self.c, &self.extract) else {
            return Ok(nan);
        };
        let Ok(clustering) = crate::cluster::cluster(&mpcs, &self.headings_deg, &self.cluster)
        else {
            return Ok(nan);
        };
        // a draw where the chain estimates nothing reads as NaN everywhere
        let Ok(chain) = fit_clustered(&self.name, clustered_rays(&clustering), self.c, None) else {
            return Ok(nan);
        };
        let mut t = [f64::NAN; 7];
        for (j, (key, scale)) in MOVED.iter().enumerate() {
            t[j] = to_u(*scale, estimate(&chain.model, key));
        }
        let truth = self.truth_lambda(model, seed)?;
        Ok(Draw {
            t,
            log_lambda_chain: estimate(&chain.model, "inter_cluster_rate").ln(),
            log_lambda_truth: truth.ln(),
        })
    }

    /// Λ of the same estimators on the draw's true clusters (as `fit_truth` on synth's
    /// truth folder: every cluster ray of the half-plane within the table's delay span).
    fn truth_lambda(&self, model: &ModelConfig, seed: u64) -> Result<f64> {
        let ch = ChannelModel::draw(&self.layout, model, seed)?;
        let mut rays = Vec::new();
        for (p, pose) in self.c.manifest.poses.iter().enumerate() {
            let at = Coord {
                x: pose.x_m,
                y: pose.y_m,
            };
            for r in ch.rays_from(&self.layout, at, pose.heading_deg) {
                let RaySource::Cluster(l) = r.source else {
                    continue;
                };
                let ray = ClusteredRay {
                    position: p,
                    cluster: l,
                    delay_ns: r.tau_s * 1e9,
                    angle_rel_deg: crate::units::wrap_deg(r.theta.to_degrees() - pose.heading_deg),
                    power_db: 10.0 * (self.gain_den * r.amp2).log10(),
                };
                if ray.angle_rel_deg.abs() <= 90.0 && ray.delay_ns <= self.max_delay_ns {
                    rays.push(ray);
                }
            }
        }
        Ok(fit_clustered(&self.name, rays, self.c, None)
            .map_or(f64::NAN, |f| estimate(&f.model, "inter_cluster_rate")))
    }
}

/// Quantity `i`'s far points from its fitted value `u` (natural scale): the quantity at
/// 1/`factor` and `factor` times its value (the rate 1/Γ likewise, its up side at least
/// `factor` slope steps `step`, so from rate 0, Γ = ∞, it goes only up), inside the
/// schema's range; None for a side the range cuts to less than half its move (a secant
/// over a sliver of the range would be the chain's noise over it).
fn far_points(i: usize, u: f64, step: f64, factor: f64) -> [Option<f64>; 2] {
    let (down, up) = match MOVED[i].1 {
        Scale::Log => (u - factor.ln(), u + factor.ln()),
        Scale::Rate if u <= 0.0 => (u, factor * step),
        Scale::Rate => (u / factor, (u * factor).max(factor * step)),
    };
    [down, up].map(|target| {
        let v = within_bounds(i, target);
        ((v - u).abs() >= 0.5 * (target - u).abs() && (v - u).abs() > 1e-9).then_some(v)
    })
}

/// A quantity's value as the fold check's reason names it (∞ for Γ without excess decay).
fn shown_value(v: f64) -> String {
    if v.is_infinite() {
        "∞".to_string()
    } else {
        format!("{v:.3}")
    }
}

/// The seed of draw r.
fn draw_seed(seed: u64, r: usize) -> u64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
    rng.set_stream(r as u64 + 1);
    rng.next_u64()
}

/// The model drawn at natural-scale point `u` (NaN entries keep the base's value).
fn model_at(base: &ModelConfig, u: &[f64; 7]) -> ModelConfig {
    let mut m = base.clone();
    for (j, (key, scale)) in MOVED.iter().enumerate() {
        if u[j].is_nan() {
            continue;
        }
        let q = m.quantity_mut(key).expect("a moved quantity");
        q.value = from_u(*scale, u[j]);
        q.interval = None;
    }
    m
}

/// `u` (quantity `i` of [`MOVED`] on its natural scale) inside the model schema's range of
/// the quantity ([`ModelConfig::bounds`]).
fn within_bounds(i: usize, u: f64) -> f64 {
    let (key, scale) = MOVED[i];
    let Some((lo, hi, _)) = ModelConfig::bounds(key) else {
        return u;
    };
    match scale {
        Scale::Log => u.clamp(lo.max(1e-9).ln(), hi.ln()),
        // Γ ≤ hi is a rate ≥ 1/hi, or 0 (no excess decay)
        Scale::Rate if u <= 0.0 => 0.0,
        Scale::Rate => u.max(1.0 / hi),
    }
}

/// Per quantity: the mean of the finite values over draws, their sd and their count.
fn moments(draws: &[Draw], j: usize) -> (f64, f64, usize) {
    let v: Vec<f64> = draws
        .iter()
        .map(|d| d.t[j])
        .filter(|x| x.is_finite())
        .collect();
    moments_of(&v)
}

fn moments_of(v: &[f64]) -> (f64, f64, usize) {
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    (mean, sd, n)
}

/// The standardised remaining bias Σ ((tⱼ − T̄ⱼ)/(sⱼ/√nⱼ))² over `set`, sⱼ the start's
/// spread of estimate j (`spread`: every point judged on one scale, so a point where the
/// chain scatters more does not score better), and whether every term is within one
/// simulation standard error (never for an empty set).
fn residual(
    t: &[f64; 7],
    draws: &[Draw],
    set: &[usize],
    spread: &[f64; 7],
) -> (f64, bool, Vec<f64>) {
    let mut score = 0.0;
    // nothing to move is nothing settled
    let mut settled = !set.is_empty();
    let mut r = Vec::with_capacity(set.len());
    for &j in set {
        let (mean, _, n) = moments(draws, j);
        let se = (spread[j] / (n.max(1) as f64).sqrt()).max(1e-12);
        let z = (t[j] - mean) / se;
        score += if z.is_finite() { z * z } else { 1e12 };
        settled &= z.abs() <= 1.0;
        r.push(t[j] - mean);
    }
    (score, settled, r)
}

/// What the iteration gives: the Jacobian at the start, why quantities are held, the
/// identifiable set, the kept point and its draws, the start batch, the steps made and
/// whether the remaining bias settled within the simulation noise.
struct Solved {
    jac: Vec<Vec<f64>>,
    reasons: Vec<Option<String>>,
    set: Vec<usize>,
    u_hat: [f64; 7],
    draws: Vec<Draw>,
    batch: Vec<Vec<Draw>>,
    iterations: usize,
    settled: bool,
}

/// The iteration of the module docs on the binding function `evaluate` (R draws at each
/// point asked, common seeds): from the data's estimates `t` (natural scales), moving the
/// `active` quantities by `steps` for the slopes.
fn solve_binding(
    t: &[f64; 7],
    active: &[usize],
    steps: &[f64],
    params: &CorrectionValid,
    mut evaluate: impl FnMut(&[([f64; 7], usize)]) -> Result<Vec<Vec<Draw>>>,
) -> Result<Solved> {
    // the start and the slopes, one batch
    let t = *t;
    let r_draws = params.draws;
    let mut points = vec![t];
    for &i in active {
        let mut u = t;
        u[i] = within_bounds(i, u[i] + steps[i]);
        points.push(u);
    }
    let batch = evaluate(&points.iter().map(|u| (*u, r_draws)).collect::<Vec<_>>())?;
    let start = &batch[0];
    // J[j][i]: the mean over common draws of the change of T_j per unit step of u_i
    let mut jac = vec![vec![0.0; MOVED.len()]; MOVED.len()];
    for (k, &i) in active.iter().enumerate() {
        let moved = &batch[k + 1];
        for (j, row) in jac.iter_mut().enumerate() {
            let d: Vec<f64> = (start.iter().zip(moved))
                .map(|(a, b)| b.t[j] - a.t[j])
                .filter(|x| x.is_finite())
                .collect();
            // the step taken (a bound can shorten it; none at all leaves the slope NaN)
            let h = points[k + 1][i] - t[i];
            row[i] = if h != 0.0 {
                moments_of(&d).0 / h
            } else {
                f64::NAN
            };
        }
    }
    let mut reasons: Vec<Option<String>> = vec![None; MOVED.len()];
    for &i in active {
        let n = moments(start, i).2;
        let slope = jac[i][i];
        if 2 * n < r_draws {
            reasons[i] = Some(format!(
                "not identifiable from this campaign: the chain reads it in {n} of {r_draws} simulated campaigns"
            ));
        } else if slope.is_nan() {
            reasons[i] = Some(
                "not identifiable from this campaign: no slope could be measured (the step left the quantity's range, or no draw read it twice)".to_string(),
            );
        } else if slope < params.min_slope {
            reasons[i] = Some(format!(
                "not identifiable from this campaign: the chain's estimate moves {:.2} times the quantity's move (slope below {})",
                slope, params.min_slope
            ));
        }
    }
    let trace = std::env::var_os("PRADAR_CORRECTION_TRACE").is_some();
    // the fold check on what the local rule keeps: each quantity at 1/F and F times the
    // fitted value, on the first draws; the secants, common draws
    let far: Vec<(usize, usize, [f64; 7])> = active
        .iter()
        .filter(|&&i| reasons[i].is_none())
        .flat_map(|&i| {
            far_points(i, t[i], steps[i], params.far_factor)
                .into_iter()
                .enumerate()
                .filter_map(move |(side, v)| {
                    let mut u = t;
                    u[i] = v?;
                    Some((i, side, u))
                })
        })
        .collect();
    let far_batch = if far.is_empty() {
        Vec::new()
    } else {
        evaluate(
            &far.iter()
                .map(|(_, _, u)| (*u, params.far_draws()))
                .collect::<Vec<_>>(),
        )?
    };
    for ((i, side, u), moved) in far.iter().zip(&far_batch) {
        let (i, side) = (*i, *side);
        if reasons[i].is_some() {
            continue;
        }
        let d: Vec<f64> = (start.iter().zip(moved))
            .map(|(a, b)| b.t[i] - a.t[i])
            .filter(|x| x.is_finite())
            .collect();
        // no draw reads it at both points (these few start draws, or the far point): the
        // side is not checked
        if d.is_empty() {
            continue;
        }
        let secant = moments_of(&d).0 / (u[i] - t[i]);
        if secant < params.min_slope {
            let f = params.far_factor;
            let scale = MOVED[i].1;
            let (at, far_at) = (from_u(scale, t[i]), from_u(scale, u[i]));
            // named by the values (the rate's down side is Γ's up side; its floor or a
            // bound can make the move other than the factor)
            let ratio = far_at / at;
            let factor = if (ratio * f - 1.0).abs() < 1e-6 {
                format!(", 1/{f} times it,")
            } else if (ratio / f - 1.0).abs() < 1e-6 {
                format!(", {f} times it,")
            } else {
                String::new()
            };
            reasons[i] = Some(format!(
                "not identifiable from this campaign: between the fitted value {} and {}{factor} the chain's estimate moves {:.2} times the quantity's move (secant slope below {}; local slope {:.2}): values that far apart read alike",
                shown_value(at),
                shown_value(far_at),
                secant,
                params.min_slope,
                jac[i][i]
            ));
        }
        if trace {
            eprintln!("far {i} side {side} u {} secant {secant:.3}", u[i]);
        }
    }
    let set: Vec<usize> = active
        .iter()
        .copied()
        .filter(|&i| reasons[i].is_none())
        .collect();
    if trace {
        eprintln!("t      {:?}", t);
        for (k, row) in jac.iter().enumerate() {
            eprintln!(
                "J[{k}]   {:?}",
                row.iter()
                    .map(|v| (v * 100.0).round() / 100.0)
                    .collect::<Vec<_>>()
            );
        }
    }
    // Newton steps with the start's J on the identifiable set
    let mut spread = [f64::NAN; 7];
    for (j, s) in spread.iter_mut().enumerate() {
        *s = moments(start, j).1;
    }
    let (score, settled, r) = residual(&t, start, &set, &spread);
    if trace {
        let m: Vec<f64> = (0..7).map(|j| moments(start, j).0).collect();
        eprintln!("start  T̄ {m:?} score {score:.2} r {r:?}");
    }
    let mut best = (score, t, start.clone(), settled);
    let mut iterations = 0;
    // Levenberg–Marquardt's damping: smaller after a step that lowered the remaining bias,
    // larger after one that raised it
    let mut mu = 1.0;
    let weights: Vec<f64> = set
        .iter()
        .map(|&j| 1.0 / moments(start, j).1.max(1e-6))
        .collect();
    while !best.3 && iterations < params.iterations && !set.is_empty() {
        let (_, from, from_draws, _) = &best;
        let (_, _, r) = residual(&t, from_draws, &set, &spread);
        // two candidates, one batch: the damped whole-J step and the diagonal one
        let diagonal: Vec<f64> = (set.iter().zip(&r)).map(|(&i, r)| r / jac[i][i]).collect();
        let whole = lm_step(&jac, &set, &r, &weights, mu).unwrap_or_else(|| diagonal.clone());
        let candidates: Vec<[f64; 7]> = [&whole, &diagonal]
            .iter()
            .map(|dx| {
                let mut u = *from;
                for (k, &i) in set.iter().enumerate() {
                    let to = match MOVED[i].1 {
                        Scale::Log => from[i] + dx[k].clamp(-MAX_LOG_STEP, MAX_LOG_STEP),
                        Scale::Rate => (from[i] + dx[k])
                            .clamp(from[i] / 2.0, (2.0 * from[i]).max(from[i] + 2.0 * steps[i])),
                    };
                    // inside the schema's range (synth refuses a model outside it)
                    u[i] = within_bounds(i, to);
                }
                u
            })
            .collect();
        let asked: Vec<([f64; 7], usize)> = candidates.iter().map(|u| (*u, r_draws)).collect();
        let evaluated = evaluate(&asked)?;
        iterations += 1;
        let mut improved_whole = false;
        for (c, (u, draws)) in candidates.iter().zip(evaluated).enumerate() {
            let (score, settled, _) = residual(&t, &draws, &set, &spread);
            if trace {
                let m: Vec<f64> = (0..7).map(|j| moments(&draws, j).0).collect();
                eprintln!(
                    "iter {iterations} {} u {u:?}\n       T̄ {m:?} score {score:.2}",
                    ["whole", "diagonal"][c]
                );
            }
            if score < best.0 {
                best = (score, *u, draws, settled);
                improved_whole = c == 0;
            }
        }
        mu = if improved_whole {
            (mu / 3.0).max(1e-3)
        } else {
            mu * 4.0
        };
    }
    let (_, u_hat, draws, settled) = best;
    Ok(Solved {
        jac,
        reasons,
        set,
        u_hat,
        draws,
        batch,
        iterations,
        settled,
    })
}

/// Correct the fit `fit` (the paper's method on campaign `c`; its model with the levels
/// read from `em`, the energy table read from `energy_path`) for the chain's bias, as the
/// module docs say. `progress(done, total)` after each chain run (total is the most runs
/// the correction can make).
pub fn correct(
    c: &Campaign,
    em: &EnergyMatrix,
    energy_path: &Path,
    fit: &ChannelFit,
    params: &CorrectionValid,
    progress: &dyn Fn(usize, usize),
) -> Result<Corrected> {
    let t0 = std::time::Instant::now();
    let chain = Chain::new(c, em, energy_path)?;
    let base = fit.model.clone().with_stated_values();
    if let Err(e) = base.require_estimable(&Default::default()) {
        return Err(Error::param(
            "correction",
            format!("the fitted model cannot be drawn ({e}); use --no-correction"),
        ));
    }
    let r_draws = params.draws;
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let seeds: Vec<u64> = (0..r_draws).map(|r| draw_seed(seed, r)).collect();
    let mut t = [f64::NAN; 7];
    for (j, (key, scale)) in MOVED.iter().enumerate() {
        t[j] = to_u(*scale, estimate(&fit.model, key));
    }
    let active: Vec<usize> = (0..MOVED.len()).filter(|&j| t[j].is_finite()).collect();
    // Γ's smallest rate step: the rate whose e-fold is the table's delay span
    let span_ns = (em.delay_ns(em.bins.saturating_sub(1)) - em.meta.gate_ns()).max(1.0);
    let steps: Vec<f64> = (0..MOVED.len())
        .map(|j| match MOVED[j].1 {
            Scale::Log => (1.0 + params.step).ln(),
            Scale::Rate => (params.step * t[j]).max(1.0 / span_ns),
        })
        .collect();
    let far_runs: usize = (active.iter())
        .map(|&i| {
            let n = far_points(i, t[i], steps[i], params.far_factor);
            n.iter().flatten().count()
        })
        .sum();
    let total =
        r_draws * (1 + active.len() + 2 * params.iterations) + params.far_draws() * far_runs;
    let done = AtomicUsize::new(0);
    progress(0, total);
    let evaluate = |points: &[([f64; 7], usize)]| -> Result<Vec<Vec<Draw>>> {
        let jobs: Vec<(usize, usize)> = (points.iter().enumerate())
            .flat_map(|(p, (_, n))| (0..*n).map(move |r| (p, r)))
            .collect();
        // a few runs per thread at a time, so progress is called from this thread only
        let chunk = 2 * rayon::current_num_threads().max(1);
        let mut out: Vec<Draw> = Vec::with_capacity(jobs.len());
        for part in jobs.chunks(chunk) {
            let drawn: Vec<Draw> = part
                .par_iter()
                .map(|&(p, r)| chain.run(&model_at(&base, &points[p].0), seeds[r]))
                .collect::<Result<_>>()?;
            out.extend(drawn);
            progress(
                done.fetch_add(part.len(), Ordering::Relaxed) + part.len(),
                total,
            );
        }
        let mut rest = out.as_slice();
        Ok(points
            .iter()
            .map(|(_, n)| {
                let (head, tail) = rest.split_at(*n);
                rest = tail;
                head.to_vec()
            })
            .collect())
    };
    let Solved {
        jac,
        reasons,
        set,
        u_hat,
        draws,
        batch,
        iterations,
        settled: settled_best,
    } = solve_binding(&t, &active, &steps, params, evaluate)?;
    // the interval: the draws' spread through the slopes, × √(1 + 1/R), Student's t
    let complete: Vec<&Draw> = draws
        .iter()
        .filter(|d| set.iter().all(|&j| d.t[j].is_finite()))
        .collect();
    let mut sd = vec![f64::NAN; MOVED.len()];
    if complete.len() >= 2 {
        for &i in &set {
            let v: Vec<f64> = complete.iter().map(|d| d.t[i] / jac[i][i]).collect();
            sd[i] = moments_of(&v).1;
        }
    }
    let df = (complete.len().max(2) - 1) as f64;
    let tq = statrs_t(df);
    let inflate = (1.0 + 1.0 / r_draws as f64).sqrt();
    let mut quantities = Vec::with_capacity(MOVED.len() + 1);
    // Λ first (Table 1's order)
    quantities.push(lambda_row(fit, &batch, &active, &draws, tq, params));
    for (i, (key, scale)) in MOVED.iter().enumerate() {
        let raw = estimate(&fit.model, key);
        let slope = if active.contains(&i) {
            jac[i][i]
        } else {
            f64::NAN
        };
        let (value, interval, why) = if !active.contains(&i) {
            (
                f64::NAN,
                None,
                Some("not estimable by the paper's method on these data".to_string()),
            )
        } else if let Some(why) = &reasons[i] {
            (f64::NAN, None, Some(why.clone()))
        } else {
            let half = tq * sd[i] * inflate;
            let (a, b) = (u_hat[i] - half, u_hat[i] + half);
            let iv = match scale {
                _ if !half.is_finite() => None,
                Scale::Log => Some([a.exp(), b.exp()]),
                // the rate's ends inverted: [1/hi, 1/lo], ∞ where the rate reaches 0; none
                // when the whole rate interval is below the no-excess floor (Γ = ∞ only)
                Scale::Rate if b < NO_EXCESS_RATE_PER_NS => None,
                Scale::Rate => Some([from_u(*scale, b), from_u(*scale, a.max(0.0))]),
            };
            (from_u(*scale, u_hat[i]), iv, None)
        };
        quantities.push(CorrectedQuantity {
            key,
            raw,
            value,
            interval,
            slope,
            not_identifiable: why,
        });
    }
    Ok(Corrected {
        quantities,
        draws: r_draws,
        iterations,
        settled: settled_best,
        chain_runs: done.load(Ordering::Relaxed),
        seconds: t0.elapsed().as_secs_f64(),
        seed,
        min_slope: params.min_slope,
        far_factor: params.far_factor,
        stability: None,
    })
}

/// Student's t quantile 0.975 with `df` degrees of freedom.
fn statrs_t(df: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, df.max(1.0)).map_or(1.96, |d| d.inverse_cdf(0.975))
}

/// Λ's row: the bias of the chain's log Λ against the truth's at the kept point, its slope
/// along d_c's step (the start batch), its interval.
fn lambda_row(
    fit: &ChannelFit,
    batch: &[Vec<Draw>],
    active: &[usize],
    draws: &[Draw],
    tq: f64,
    params: &CorrectionValid,
) -> CorrectedQuantity {
    let raw = estimate(&fit.model, "inter_cluster_rate");
    let mut row = CorrectedQuantity {
        key: "inter_cluster_rate",
        raw,
        value: f64::NAN,
        interval: None,
        slope: f64::NAN,
        not_identifiable: None,
    };
    if !(raw.is_finite() && raw > 0.0) {
        row.not_identifiable = Some("not estimable by the paper's method on these data".into());
        return row;
    }
    // the slope: along d_c's step, chain against truth, common draws
    if let Some(k) = active.iter().position(|&i| i == SPACING) {
        let pairs = |f: fn(&Draw) -> f64| -> f64 {
            let d: Vec<f64> = (batch[0].iter().zip(&batch[k + 1]))
                .map(|(a, b)| f(b) - f(a))
                .filter(|x| x.is_finite())
                .collect();
            moments_of(&d).0
        };
        let dc = pairs(|d| d.log_lambda_chain);
        let dt = pairs(|d| d.log_lambda_truth);
        row.slope = dc / dt;
    }
    let bias: Vec<f64> = draws
        .iter()
        .map(|d| d.log_lambda_chain - d.log_lambda_truth)
        .filter(|x| x.is_finite())
        .collect();
    let (b, b_sd, n) = moments_of(&bias);
    if !row.slope.is_finite() || row.slope < params.min_slope || 2 * n < draws.len() {
        row.not_identifiable = Some(if 2 * n < draws.len() {
            format!(
                "not identifiable from this campaign: the chain reads it in {n} of {} simulated campaigns",
                draws.len()
            )
        } else if !row.slope.is_finite() {
            "not identifiable from this campaign: no slope along d_c could be measured (d_c not moved, or the true Λ did not move with it)".to_string()
        } else {
            format!(
                "not identifiable from this campaign: the chain's Λ moves {:.2} times the true Λ along d_c (slope below {})",
                row.slope,
                params.min_slope
            )
        });
        return row;
    }
    // the target is the environment's own Λ: log t − b̂ misses it by the spread of the
    // chain's log Λ about the truth's, plus the noise of b̂'s mean
    let centre = raw.ln() - b;
    let sd = b_sd * (1.0 + 1.0 / n as f64).sqrt();
    row.value = centre.exp();
    let half = tq * sd;
    row.interval = half
        .is_finite()
        .then(|| [(centre - half).exp(), (centre + half).exp()]);
    row
}

/// Refuse a fit the correction cannot run on: no model quantity to move.
pub fn check_correctable(fit: &ChannelFit, clusters: &Path) -> Result<()> {
    let any = MOVED
        .iter()
        .any(|(k, _)| estimate(&fit.model, k).is_finite());
    if any {
        return Ok(());
    }
    Err(Error::input(
        clusters,
        "no Table 1 quantity estimated: nothing to correct (use --no-correction)",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_scales_round_trip_and_gamma_infinity_is_rate_zero() {
        for v in [0.01, 1.0, 37.5] {
            assert!((from_u(Scale::Log, to_u(Scale::Log, v)) - v).abs() < 1e-12 * v);
            assert!((from_u(Scale::Rate, to_u(Scale::Rate, v)) - v).abs() < 1e-9 * v);
        }
        assert_eq!(to_u(Scale::Rate, f64::INFINITY), 0.0);
        assert_eq!(from_u(Scale::Rate, 0.0), f64::INFINITY);
        assert_eq!(
            from_u(Scale::Rate, 0.5 * NO_EXCESS_RATE_PER_NS),
            f64::INFINITY
        );
        assert!(to_u(Scale::Log, -1.0).is_nan());
        assert!(to_u(Scale::Log, f64::NAN).is_nan());
    }

    /// A known binding function's draws at the points asked (each its number of draws).
    fn draws_of(
        binding: &impl Fn(&[f64; 7], usize) -> [f64; 7],
        points: &[([f64; 7], usize)],
    ) -> Vec<Vec<Draw>> {
        (points.iter())
            .map(|(u, n)| {
                (0..*n)
                    .map(|r| Draw {
                        t: binding(u, r),
                        log_lambda_chain: 0.0,
                        log_lambda_truth: 0.0,
                    })
                    .collect()
            })
            .collect()
    }

    /// The iteration on a known binding function T(u) = A u + b (+ a fixed per-draw
    /// noise, the common draws): A with a diagonal of 0.5–1.5 and cross terms of 0.1 (the
    /// diagonal alone does not converge there: row 5 is 0.5 against 0.5 off it), a
    /// bias b of up to ±0.3 (on the log scale, ±35 %), and one quantity whose T moves 0.1
    /// times it. The identifiable ones come back within 0.02 of the truth; the flat one is
    /// held, with its slope in the reason.
    #[test]
    fn the_iteration_removes_a_known_bias_and_holds_a_flat_quantity() {
        let diag = [0.8, 1.2, 0.6, 1.5, 0.5, 1.0, 0.1];
        let bias = [0.3, -0.2, 0.25, -0.3, 0.01, 0.1, 0.0];
        let truth = [-0.3, 2.5, 1.4, -1.4, 0.05, 1.6, 1.8];
        let binding = |u: &[f64; 7], r: usize| -> [f64; 7] {
            let mut t = [0.0; 7];
            for j in 0..7 {
                t[j] = diag[j] * u[j] + bias[j] + 0.005 * ((r * 7 + j) as f64).sin();
                for i in 0..7 {
                    if i != j && i != 6 && j != 6 {
                        t[j] += 0.1 * (u[i] - truth[i]);
                    }
                }
            }
            t
        };
        let data = binding(&truth, 99);
        let params = CorrectionParams {
            iterations: 12,
            ..Default::default()
        }
        .check()
        .unwrap();
        let mut calls = 0;
        let solved = solve_binding(
            &data,
            &[0, 1, 2, 3, 4, 5, 6],
            &[0.22, 0.22, 0.22, 0.22, 0.01, 0.22, 0.22],
            &params,
            |points| {
                calls += points.iter().map(|(_, n)| n).sum::<usize>();
                Ok(draws_of(&binding, points))
            },
        )
        .unwrap();
        assert!(
            solved.reasons[6].as_deref().unwrap().contains("0.1"),
            "{:?}",
            solved.reasons
        );
        assert_eq!(solved.set, vec![0, 1, 2, 3, 4, 5]);
        for i in 0..6 {
            assert!(
                (solved.u_hat[i] - truth[i]).abs() < 0.02,
                "{i}: {} vs {} (slope {})",
                solved.u_hat[i],
                truth[i],
                solved.jac[i][i]
            );
            assert!((solved.jac[i][i] - diag[i]).abs() < 1e-6, "{i}");
        }
        // the flat quantity stays where the data put it
        assert_eq!(solved.u_hat[6], data[6]);
        // runs: R at the start and 7 slopes, ⌈R/3⌉ at 12 far points (the six the local
        // rule keeps, both ways), R at two candidates per step
        let r = params.draws;
        assert_eq!(
            calls,
            8 * r + 12 * params.far_draws() + 2 * r * solved.iterations
        );
    }

    /// A binding function that folds: quantity 2 reads the same (1.4) at every value
    /// below 1.4, so data drawn at 0.5 read 1.4, and at 1.4 the local slope is 1 (the step
    /// goes up). The fold check (at a third of it) flags it with its secant; likewise Γ's
    /// rate (4) reads 0.05 at every rate below, so at 3 times Γ; the linear ones, with
    /// slope 1 both ways, are kept.
    #[test]
    fn the_fold_check_flags_a_quantity_that_reads_alike_far_below() {
        let binding = |u: &[f64; 7], r: usize| -> [f64; 7] {
            let mut t = *u;
            t[2] = u[2].max(1.4);
            t[4] = u[4].max(0.05);
            for (j, x) in t.iter_mut().enumerate() {
                *x += 0.005 * ((r * 7 + j) as f64).sin();
            }
            t
        };
        let truth = [-0.3, 2.5, 0.5, -1.4, 0.01, 1.6, 1.8];
        let data = binding(&truth, 99);
        let params = CorrectionValid::default();
        let solved = solve_binding(
            &data,
            &[0, 1, 2, 3, 4, 5, 6],
            &[0.22, 0.22, 0.22, 0.22, 0.01, 0.22, 0.22],
            &params,
            |points| Ok(draws_of(&binding, points)),
        )
        .unwrap();
        assert!(
            (solved.jac[2][2] - 1.0).abs() < 0.05,
            "{}",
            solved.jac[2][2]
        );
        let why = solved.reasons[2].as_deref().expect("d_c flagged");
        let dc = from_u(Scale::Log, data[2]);
        let want = format!(
            "between the fitted value {dc:.3} and {:.3}, 1/3 times it,",
            dc / 3.0
        );
        assert!(
            why.contains(&want) && why.contains("0.00 times the quantity"),
            "{why}"
        );
        // Γ's rate falls to a third: Γ three times
        let why = solved.reasons[4].as_deref().expect("Γ flagged");
        let g = from_u(Scale::Rate, data[4]);
        let want = format!(
            "between the fitted value {g:.3} and {:.3}, 3 times it,",
            3.0 * g
        );
        assert!(
            why.contains(&want) && why.contains("0.00 times the quantity"),
            "{why}"
        );
        assert_eq!(solved.set, vec![0, 1, 3, 5, 6], "{:?}", solved.reasons);
        // held where the data put them
        assert_eq!((solved.u_hat[2], solved.u_hat[4]), (data[2], data[4]));
    }

    #[test]
    fn far_points_are_a_factor_either_side_inside_the_range() {
        let [d, u] = far_points(0, 0.0, 0.2, 3.0);
        assert!((d.unwrap() + 3f64.ln()).abs() < 1e-12 && (u.unwrap() - 3f64.ln()).abs() < 1e-12);
        // Γ = ∞ (rate 0): only up, to three slope steps
        assert_eq!(far_points(4, 0.0, 0.01, 3.0), [None, Some(0.03)]);
        let [d, u] = far_points(4, 0.1, 0.025, 3.0);
        assert!((d.unwrap() - 0.1 / 3.0).abs() < 1e-12 && (u.unwrap() - 0.3).abs() < 1e-12);
        // at the schema's bounds: 1.2 rays per cluster has no room down (rays ≥ 1), an
        // AoA of 100° keeps its up side cut at 180° (more than half the move)
        let [d, u] = far_points(6, 1.2f64.ln(), 0.2, 3.0);
        assert!(d.is_none() && (u.unwrap() - 3.6f64.ln()).abs() < 1e-12);
        let [_, u] = far_points(1, 100f64.ln(), 0.2, 3.0);
        assert!((u.unwrap() - 180f64.ln()).abs() < 1e-12);
        // Γ at the schema's 10 µs (rate 1e-4): three times Γ is out of range
        assert!(far_points(4, 1e-4, 1e-5, 3.0)[0].is_none());
    }

    #[test]
    fn draw_seeds_differ_and_repeat() {
        let a: Vec<u64> = (0..8).map(|r| draw_seed(7, r)).collect();
        let b: Vec<u64> = (0..8).map(|r| draw_seed(7, r)).collect();
        assert_eq!(a, b);
        let mut s = a.clone();
        s.sort();
        s.dedup();
        assert_eq!(s.len(), 8);
        assert_ne!(draw_seed(8, 0), a[0]);
    }
}
