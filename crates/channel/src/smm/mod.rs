//! The simulated-minimum-distance refinement (issue 54 item 4's "simulated-moments fit
//! started at the chain's reading with common random numbers").
//!
//! Takes a campaign, its energy table and a starting model (the chain's: `fit` and the
//! layout's levels); gives the model whose `synth` draws come closest to the table in the
//! predictive check's own statistics ([`Refinement`]): the free quantities moved, the rest
//! copied, `[calibration]` recording the method, the evaluations and the distance.
//!
//! **Distance.** For a model θ, R draws y_r(θ) of the table by [`EnergySimulator`] (the
//! same receiver, fold, noise and detector as `synth`), each with a fixed seed s_r
//! (common random numbers: the same R streams at every θ, so the distance is a
//! deterministic function of θ and two models are compared on the same noise). The
//! clusters are drawn from one stream in order, so a θ that changes a count (clusters,
//! rays) shifts every later draw: D is not smooth in the rates and counts, and with R
//! fixed streams it can be fitted to those streams — a refined model may reach a lower D
//! than the generating model (`tests/smm.rs` measures it). What judges the result is
//! therefore the check on positions the refinement did not see. The statistics are the check's nine ([`Statistics`]: signal energy, mean delay,
//! RMS delay spread, signal bins, first arrival, peaks, angular spread, the angular and
//! the delay power profiles), each table at its own noise as the check reads it. Then
//!
//!   D(θ) = (1/K) Σ_k (1/R) Σ_r KS(m_k, y_r,k(θ)) / s_k,
//!
//! the mean over the statistics of the mean KS distance between the measured
//! statistic and a draw's, each in units of s_k, the median KS distance between two draws
//! of the starting model (the draws' own spread: a statistic the model reproduces sits
//! near 1, so no statistic dominates by its scale). This is the check's own comparison
//! (its ratio column), averaged rather than maximised so that D moves smoothly with θ.
//! The check that judges the result uses other seeds (its own stream), and the verdict
//! that counts is on positions the refinement did not see (`check --holdout --estimator
//! smm`).
//!
//! **Free quantities**: those of calibrate's list ([`DEFAULT_PRIOR`]: λ, AoA std, d_c,
//! d_p, Γ, γ, σ, rays per cluster, and the layout's σ′, Lambert n, |Γ|, corner and edge σ
//! when the model has them) that the starting model can draw; Λ and the diffuse share and
//! decay are not drawn by `synth` and are copied; a quantity whose value is 0 or NaN is not
//! moved. Minimised in x = ln θ, so steps are relative, inside a box: calibrate's prior
//! range ([`DEFAULT_PRIOR`], [`EXCESS_DECAY_PRIOR`] for a schema-2 Γ) widened to hold the
//! start (the search stays among indoor channels; without it one expansion can reach a
//! thousand rays per cluster, whose draws take minutes). A Γ = ∞ start (no excess decay)
//! sits at the box's upper end, 10 µs, as a coordinate, and the model keeps ∞ until Γ
//! moves. A θ outside the box, refused by the model schema or giving a distance that is
//! not finite costs [`REFUSED`] (the simplex moves away).
//!
//! **Minimiser**: Nelder–Mead (argmin's; a derivative-free simplex: D is piecewise
//! smooth, a Poisson count changes it by a step) from the simplex x₀, x₀ + h·e_k with
//! h = ln 1.5 (a 50 % step of each quantity; −h where +h is refused), reflection 1,
//! contraction ½, and the dimension-adapted expansion 1 + 2/n and shrink 1 − 1/n of Gao &
//! Han (Comput. Optim. Appl. 2012), which keep the simplex from collapsing in the 8 to 13
//! dimensions here. It stops after the iteration budget or when the simplex's costs agree
//! within 10⁻³. The best vertex is written; the starting model is returned unchanged when
//! no vertex beats it.
//!
//! **Intervals**: a moved quantity's `interval`, `ks` and `ks_p` are dropped (they were the
//! chain's estimate's, not this one's; none is better than a wrong one), `n` is kept.
//! Quantities not moved (within [`SAME_LN`] of the start) keep their value and theirs,
//! bit for bit.
//!
//! Cost: the start's R draws (its scale and its D), then n + 1 evaluations (the simplex)
//! before the first iteration and 1 to n + 2 per iteration (a shrink re-evaluates the
//! simplex), each R draws; at the defaults (R = 8, 60 iterations, 12 free quantities) about
//! 100–170 evaluations on the zoo's halves.
//! `[calibration]` records the draws made (`simulations`).

use crate::calibrate::{DEFAULT_PRIOR, EXCESS_DECAY_PRIOR};
use crate::campaign::manifest::Campaign;
use crate::check::stats::{ks_distance, StatContext, Statistics, NAMES};
use crate::check::{context, draw_context, keyed_seed, table_draw};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::model::file::{CalibrationMeta, ModelConfig};
use crate::model::EnergySimulator;
use crate::params::{ParamGuard, Valid};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Key of the refinement's draw seeds (xor-ed into the seed): "Smm\0\0\0\0\0", not the
/// check's stream, so the check that judges a refined model never replays its draws.
const STREAM: u64 = 0x536d_6d00_0000_0000;

/// The cost of a θ the model schema refuses.
pub const REFUSED: f64 = 1e6;

/// The initial simplex's step, ln units (a 50 % step).
pub const STEP_LN: f64 = 0.405_465_108_108_164_4; // ln 1.5

/// Two ln values this close are the same value ([`unmoved`]).
pub const SAME_LN: f64 = 1e-12;

/// The simplex's cost spread at which the minimiser stops.
pub const SD_TOLERANCE: f64 = 1e-3;

/// Options of a refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct SmmParams {
    /// Draws per evaluation R (common random numbers), 2 to 100 (default 8).
    pub draws: usize,
    /// Nelder–Mead iterations, 1 to 10 000 (default 60).
    pub iterations: u64,
    /// Seed (default: the campaign's).
    pub seed: Option<u64>,
    /// synth's ray cull (default 1e-3, as synth).
    pub cull: f64,
}

impl Default for SmmParams {
    fn default() -> Self {
        SmmParams {
            draws: 8,
            iterations: 60,
            seed: None,
            cull: 1e-3,
        }
    }
}

/// Checked refinement options.
pub type SmmValid = Valid<SmmParams>;

impl ParamGuard for SmmParams {
    type Checked = SmmValid;

    /// Every field in its range; the error names the field.
    fn check(&self) -> Result<SmmValid> {
        if !(2..=100).contains(&self.draws) {
            return Err(Error::param(
                "smm.draws",
                format!("must be in [2, 100], got {}", self.draws),
            ));
        }
        if !(1..=10_000).contains(&self.iterations) {
            return Err(Error::param(
                "smm.iterations",
                format!("must be in [1, 10000], got {}", self.iterations),
            ));
        }
        if !(self.cull >= 0.0 && self.cull < 1.0) {
            return Err(Error::param(
                "smm.cull",
                format!("must be in [0, 1), got {}", self.cull),
            ));
        }
        Ok(Valid::new(self.clone()))
    }
}

/// What the refinement gives.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// The refined model (the starting one when nothing beat it).
    pub model: ModelConfig,
    /// The free quantities, in order.
    pub free: Vec<String>,
    /// Their starting values (schema units).
    pub start: Vec<f64>,
    /// Their refined values.
    pub refined: Vec<f64>,
    /// D at the start.
    pub start_distance: f64,
    /// D at the refined model.
    pub distance: f64,
    /// Evaluations of D (each R draws, but for a θ outside the box or the schema).
    pub evaluations: usize,
    /// synth draws made (the starting model's scale draws included).
    pub simulations: usize,
    /// Nelder–Mead iterations run.
    pub iterations: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

/// The free quantities of `start` (module docs).
struct Free {
    /// Names, in [`DEFAULT_PRIOR`]'s order.
    names: Vec<String>,
    /// Starting values, schema units.
    v0: Vec<f64>,
    /// Their ln.
    x0: Vec<f64>,
    /// The search box in ln units: calibrate's prior range widened to hold the start.
    lo: Vec<f64>,
    /// Upper ends.
    hi: Vec<f64>,
}

/// The free quantities of `start`, their starting values and the search box.
fn free_quantities(start: &ModelConfig) -> Free {
    let excess = start.schema_version >= 2;
    let mut f = Free {
        names: Vec::new(),
        v0: Vec::new(),
        x0: Vec::new(),
        lo: Vec::new(),
        hi: Vec::new(),
    };
    for (name, a, b) in DEFAULT_PRIOR {
        let Some(q) = start.quantity(name) else {
            continue;
        };
        if !q.is_drawable() {
            continue;
        }
        let v = if q.value.is_finite() {
            q.value
        } else if name == "cluster_decay" {
            EXCESS_DECAY_PRIOR.1
        } else {
            continue;
        };
        let (a, b) = if excess && name == "cluster_decay" {
            EXCESS_DECAY_PRIOR
        } else {
            (a, b)
        };
        if v > 0.0 {
            f.names.push(name.to_string());
            f.x0.push(v.ln());
            f.v0.push(v);
            f.lo.push(a.min(v).ln());
            f.hi.push(b.max(v).ln());
        }
    }
    f
}

/// Whether ln value `x` is the start `x0` (within [`SAME_LN`]: the simplex's centroid
/// and contractions give back an unmoved coordinate a rounding error away).
fn unmoved(x: f64, x0: f64) -> bool {
    (x - x0).abs() <= SAME_LN
}

/// The model at ln values `x` of the free quantities, or None outside the search box or
/// where the schema refuses it. A quantity at its starting ln value ([`unmoved`]) keeps
/// `start`'s value bit for bit (exp(ln v) can round past a schema bound the start sits on,
/// Γ at 10 µs); a moved one loses its interval, KS and KS p (they were the chain's).
fn model_at(start: &ModelConfig, f: &Free, x: &[f64]) -> Option<ModelConfig> {
    let mut m = start.clone();
    for (k, name) in f.names.iter().enumerate() {
        if unmoved(x[k], f.x0[k]) {
            continue;
        }
        if !(x[k] >= f.lo[k] && x[k] <= f.hi[k]) {
            return None;
        }
        let q = m.quantity_mut(name)?;
        q.value = x[k].exp();
        q.interval = None;
        q.ks = None;
        q.ks_p = None;
    }
    m.check().ok().map(|_| m)
}

/// The distance's setting: the simulator, the measured statistics, the seeds, the scales.
struct Objective<'a> {
    sim: &'a EnergySimulator,
    energy: &'a EnergyMatrix,
    draw_ctx: StatContext,
    measured: Statistics,
    seeds: Vec<u64>,
    start: &'a ModelConfig,
    free: &'a Free,
    scale: Vec<f64>,
    evaluations: &'a AtomicUsize,
    simulations: &'a AtomicUsize,
    progress: &'a (dyn Fn(usize) + Sync),
}

impl Objective<'_> {
    /// The statistics of the R draws of `model` (in seed order).
    fn draws(&self, model: &ModelConfig) -> Result<Vec<Statistics>> {
        self.seeds
            .par_iter()
            .map(|s| {
                let e = table_draw(self.sim, self.energy, model, *s)?;
                Ok(Statistics::of(&self.draw_ctx, &e))
            })
            .collect()
    }

    /// D at ln values `x` (module docs); [`REFUSED`] where the schema or synth refuses.
    fn distance(&self, x: &[f64]) -> f64 {
        let n = self.evaluations.fetch_add(1, Ordering::Relaxed) + 1;
        (self.progress)(n);
        let Some(model) = model_at(self.start, self.free, x) else {
            return REFUSED;
        };
        let Ok(draws) = self.draws(&model) else {
            return REFUSED;
        };
        self.simulations.fetch_add(draws.len(), Ordering::Relaxed);
        self.distance_of(&draws)
    }

    /// D of the draws `draws` (module docs); [`REFUSED`] when it is not finite.
    fn distance_of(&self, draws: &[Statistics]) -> f64 {
        let k = NAMES.len();
        let mut d = 0.0;
        for (j, s) in self.scale.iter().enumerate() {
            let ks: f64 = (draws.iter())
                .map(|y| ks_distance(&self.measured.values[j], &y.values[j]))
                .sum::<f64>()
                / draws.len() as f64;
            d += ks / s;
        }
        let d = d / k as f64;
        // a NaN would stall the simplex's comparisons
        if d.is_finite() {
            d
        } else {
            REFUSED
        }
    }
}

impl CostFunction for Objective<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.distance(x))
    }
}

/// The draws' own KS spread per statistic: the median over pairs of draws, floored at
/// 0.01 (a statistic every draw gives alike would otherwise divide by zero).
fn scales(draws: &[Statistics]) -> Vec<f64> {
    (0..NAMES.len())
        .map(|k| {
            let mut pairs = Vec::new();
            for i in 0..draws.len() {
                for j in i + 1..draws.len() {
                    pairs.push(ks_distance(&draws[i].values[k], &draws[j].values[k]));
                }
            }
            crate::stats::median(&pairs).unwrap_or(0.0).max(0.01)
        })
        .collect()
}

/// Refine `start` on the energy table `energy` (read from `energy_path`) of campaign `c`
/// (module docs). `progress(evaluations)` after each evaluation of D.
pub fn refine(
    c: &Campaign,
    energy: &EnergyMatrix,
    energy_path: &Path,
    start: &ModelConfig,
    params: &SmmValid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Refinement> {
    let t0 = std::time::Instant::now();
    let start = start.require_estimable(&Default::default())?;
    let free = free_quantities(&start);
    if free.names.is_empty() {
        return Err(Error::param(
            "model",
            "no quantity the refinement can move (none of calibrate's list is drawable)",
        ));
    }
    let x0 = free.x0.clone();
    let sim = EnergySimulator::for_table(c, energy, energy_path, params.cull)?;
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let (evaluations, simulations) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let mut obj = Objective {
        sim: &sim,
        energy,
        draw_ctx: draw_context(energy, &sim),
        measured: Statistics::of(&context(energy), &energy.data),
        seeds: (0..params.draws)
            .map(|r| keyed_seed(seed, STREAM, r))
            .collect(),
        start: &start,
        free: &free,
        scale: vec![1.0; NAMES.len()],
        evaluations: &evaluations,
        simulations: &simulations,
        progress,
    };
    // the start's draws give the scale and the start's D (its ln values are x0)
    let first = obj.draws(&start)?;
    simulations.fetch_add(first.len(), Ordering::Relaxed);
    obj.scale = scales(&first);
    let start_distance = obj.distance_of(&first);
    // the initial simplex: x0 and a step along each quantity (back where forward is refused)
    let n = x0.len();
    let mut simplex = vec![x0.clone()];
    for k in 0..n {
        let mut x = x0.clone();
        x[k] += STEP_LN;
        if model_at(&start, &free, &x).is_none() {
            x[k] = x0[k] - STEP_LN;
        }
        simplex.push(x);
    }
    let nf = n as f64;
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(SD_TOLERANCE)
        .and_then(|s| s.with_gamma(1.0 + 2.0 / nf))
        .and_then(|s| s.with_sigma(if n > 1 { 1.0 - 1.0 / nf } else { 0.5 }))
        .map_err(|e| Error::param("smm", e.to_string()))?;
    let res = Executor::new(obj, solver)
        .configure(|s| s.max_iters(params.iterations))
        .run()
        .map_err(|e| Error::param("smm", e.to_string()))?;
    let state = res.state();
    let iterations = state.get_iter();
    let (best, distance) = match (state.get_best_param(), state.get_best_cost()) {
        (Some(p), d) if d < start_distance => (p.clone(), d),
        _ => (x0.clone(), start_distance),
    };
    let (evaluations, simulations) = (
        evaluations.load(Ordering::Relaxed),
        simulations.load(Ordering::Relaxed),
    );
    let moved = best.iter().zip(&x0).any(|(x, x0)| !unmoved(*x, *x0));
    let model = if !moved {
        // nothing beat the start: the starting model, unchanged
        start.clone()
    } else {
        let mut m = model_at(&start, &free, &best).expect("the best vertex was drawable");
        m.calibration = Some(CalibrationMeta {
            method: format!(
                "smm (simulated minimum distance from the chain's model: Nelder-Mead, {} draws per evaluation with common random numbers, distance {distance:.4} from {start_distance:.4})",
                params.draws
            ),
            simulations,
            particles: 1,
            generations: iterations as usize,
            epsilon: distance,
            seed,
            free: free.names.clone(),
        });
        m
    };
    let refined: Vec<f64> = (free.names.iter())
        .map(|n| model.quantity(n).map_or(f64::NAN, |q| q.value))
        .collect();
    Ok(Refinement {
        model,
        free: free.names.clone(),
        start: free.v0.clone(),
        refined,
        start_distance,
        distance,
        evaluations,
        simulations,
        iterations,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each option out of its range is refused naming it; the defaults pass.
    #[test]
    fn params_out_of_range_are_refused_by_name() {
        assert!(SmmParams::default().check().is_ok());
        for (p, field) in [
            (
                SmmParams {
                    draws: 1,
                    ..Default::default()
                },
                "smm.draws",
            ),
            (
                SmmParams {
                    iterations: 0,
                    ..Default::default()
                },
                "smm.iterations",
            ),
            (
                SmmParams {
                    cull: 1.0,
                    ..Default::default()
                },
                "smm.cull",
            ),
            (
                SmmParams {
                    cull: f64::NAN,
                    ..Default::default()
                },
                "smm.cull",
            ),
        ] {
            let e = p.check().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    /// The free quantities of a fitted schema-2 model: calibrate's list where drawable, Γ = ∞
    /// started at 10 µs (the model keeps ∞ until Γ moves); the box holds calibrate's range
    /// and the start; an unmoved quantity keeps its value (and interval) bit for bit, a
    /// rounding error from the start included; a step past a bound or out of the box is
    /// refused; a moved quantity loses its interval.
    #[test]
    fn free_quantities_and_the_start_on_a_bound() {
        let mut m = ModelConfig::table1_defaults();
        m.cluster_decay.value = f64::INFINITY;
        m.cluster_decay.interval = Some([20.0, f64::INFINITY]);
        m.ray_decay.value = 100.0; // beyond calibrate's 0.5–20 ns
        m.perimeter_offset.value = f64::NAN;
        m.perimeter_offset.not_estimable = Some("few clusters".into());
        let f = free_quantities(&m);
        assert!(
            !f.names.contains(&"perimeter_offset".to_string()),
            "{:?}",
            f.names
        );
        assert_eq!(f.names.len(), 7, "{:?}", f.names);
        let k = f.names.iter().position(|n| n == "cluster_decay").unwrap();
        assert_eq!(f.v0[k], EXCESS_DECAY_PRIOR.1);
        let g = f.names.iter().position(|n| n == "ray_decay").unwrap();
        assert!((f.lo[g].exp() - 0.5).abs() < 1e-12 && (f.hi[g].exp() - 100.0).abs() < 1e-9);
        let mut start = m.clone();
        start.perimeter_offset.value = 0.3;
        start.perimeter_offset.not_estimable = None;
        let mut near = f.x0.clone();
        near[k] += 1e-15;
        let at = model_at(&start, &f, &near).expect("the start is accepted");
        assert_eq!(at, start);
        let mut up = f.x0.clone();
        up[k] += STEP_LN;
        assert!(model_at(&start, &f, &up).is_none());
        let mut out = f.x0.clone();
        out[g] += STEP_LN;
        assert!(model_at(&start, &f, &out).is_none(), "beyond the box");
        let mut down = f.x0.clone();
        down[k] -= STEP_LN;
        let d = model_at(&start, &f, &down).unwrap();
        assert!((d.cluster_decay.value - 1e4 / 1.5).abs() < 1e-6);
        assert_eq!(d.cluster_decay.interval, None);
        assert_eq!(d.ray_decay, start.ray_decay);
    }
}
