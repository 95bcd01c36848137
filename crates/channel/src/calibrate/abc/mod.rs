//! Adaptive ABC population Monte Carlo (APMC, Lenormand, Jabot & Deffuant 2013; the
//! sequential scheme of Beaumont, Cornuet, Marin & Robert 2009 with the tolerance chosen
//! adaptively as in Del Moral, Doucet & Jasra 2012) over a box prior in log-parameter
//! space, with semi-automatic summaries (Fearnhead & Prangle 2012) and a final local-linear
//! regression adjustment (Beaumont, Zhang & Balding 2002). Generic over the simulator: a
//! function from (log-parameters, seed) to raw summaries; the module docs of
//! [`calibrate`](super) give the equations.
//!
//! Determinism: every draw of particle i of generation t comes from
//! `ChaCha8Rng::seed_from_u64(key(seed, t, i))` (its ancestor, its perturbation, the
//! simulator's seed), simulations run in parallel (rayon) and are collected in particle
//! order, and ties in distance are broken by position in the merged population (stable
//! sort), so the result does not depend on the thread count.
//!
//! The semi-automatic projection of the summaries, its ridge penalty and its held-out R²
//! are in the `projection` submodule.

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

mod projection;

use projection::choose_ridge;
pub(crate) use projection::median_mad;
use projection::Projection;

/// A box prior, uniform in log-parameter space (log-uniform in the parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPrior {
    /// Lower bounds, ln units.
    pub lo: Vec<f64>,
    /// Upper bounds, ln units.
    pub hi: Vec<f64>,
}

impl BoxPrior {
    /// Dimension.
    pub fn dim(&self) -> usize {
        self.lo.len()
    }
    fn inside(&self, x: &[f64]) -> bool {
        x.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi)
    }
    fn draw(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.lo
            .iter()
            .zip(&self.hi)
            .map(|(lo, hi)| lo + (hi - lo) * rng.gen::<f64>())
            .collect()
    }
}

/// How the sampler gets a particle's distance to the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DistanceKind {
    /// The simulator gives raw summaries; the distance is the scaled Euclidean distance
    /// of their semi-automatic projections (refitted each generation), and the final
    /// particles are regression-adjusted on them.
    Projected,
    /// The simulator gives the distance itself, as its one output (the MMD of
    /// [`mmd`](super::mmd)); nothing is refitted and there is no regression adjustment.
    Direct,
}

/// Options of the sampler (from [`CalibrateValid`](super::CalibrateValid)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbcOptions {
    /// Simulation budget.
    pub simulations: usize,
    /// Population size N.
    pub population: usize,
    /// Particles kept per generation, N_α.
    pub kept: usize,
    /// Stop below this acceptance rate.
    pub min_acceptance: f64,
    /// Seed.
    pub seed: u64,
    /// What the simulator's output is.
    pub distance: DistanceKind,
    /// How the projection's ridge penalty is chosen.
    pub ridge: Ridge,
}

/// The ridge penalty of the semi-automatic projection (`--ridge`; no effect with the MMD).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ridge {
    /// λ = 1e-3·n for every parameter.
    Fixed,
    /// λ_k = c_k·n per parameter, c_k from [`RIDGE_GRID`] by 5-fold cross-validation on
    /// the particles the projection is fitted on.
    Cv,
    /// As [`Ridge::Cv`], and a parameter whose projection's held-out R² is ≤ 0 (it
    /// predicts its parameter no better than the mean) is left out of the distance (all
    /// kept when every R² is ≤ 0); it stays in the regression adjustment.
    CvDrop,
}

impl Ridge {
    /// Every value, in the order the command line lists them.
    pub const ALL: [Ridge; 3] = [Ridge::Fixed, Ridge::Cv, Ridge::CvDrop];

    /// Name (`fixed`, `cv`, `cv-drop`): the command-line value and the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            Ridge::Fixed => "fixed",
            Ridge::Cv => "cv",
            Ridge::CvDrop => "cv-drop",
        }
    }
}

impl std::fmt::Display for Ridge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Ridge {
    type Err = Error;
    /// Parse a [`Ridge::name`].
    fn from_str(s: &str) -> Result<Ridge> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "calibrate.ridge", "ridge")
    }
}

/// The relative ridge penalties c (λ = c·n) the cross-validation chooses from: 1e-3 …
/// 1e3, half-decade steps.
pub const RIDGE_GRID: [f64; 13] = [
    1e-3, 3.162e-3, 1e-2, 3.162e-2, 1e-1, 3.162e-1, 1.0, 3.162, 1e1, 3.162e1, 1e2, 3.162e2, 1e3,
];

/// The fixed relative penalty ([`Ridge::Fixed`]).
const FIXED_RIDGE: f64 = 1e-3;

/// The final weighted population and the run's figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Posterior {
    /// Particles (ln parameters), unadjusted.
    pub theta: Vec<Vec<f64>>,
    /// Particles after the regression adjustment (clamped to the prior box); the raw
    /// particles when it was not applied.
    pub adjusted: Vec<Vec<f64>>,
    /// Whether the regression adjustment was applied (at least 10 particles per
    /// coefficient of its regression, and a non-singular fit).
    pub regression_adjusted: bool,
    /// Normalised importance weights.
    pub weights: Vec<f64>,
    /// Distances of the particles.
    pub distances: Vec<f64>,
    /// Final tolerance ε.
    pub epsilon: f64,
    /// Generations run (the prior generation included).
    pub generations: usize,
    /// Simulations run.
    pub simulations: usize,
    /// Acceptance rate of the last generation.
    pub acceptance: f64,
    /// Held-out (5-fold cross-validated) R² per parameter of the last generation's
    /// projection of the summaries ([`heldout_r2`]); empty for a direct distance.
    pub heldout_r2: Vec<f64>,
}

/// The stream key of particle `i` of generation `t`.
fn key(seed: u64, t: usize, i: usize) -> u64 {
    let mut x = seed ^ 0x4162_6353_4d43_0000; // "AbcSMC"
    for v in [t as u64, i as u64, 0x6361_6c69] {
        x = (x ^ v).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x ^= x >> 31;
        x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
        x ^= x >> 29;
    }
    x
}

/// Weighted mean and covariance of particles.
fn weighted_cov(theta: &[Vec<f64>], w: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
    let p = theta[0].len();
    let tw: f64 = w.iter().sum();
    let mean: Vec<f64> = (0..p)
        .map(|k| theta.iter().zip(w).map(|(t, w)| w * t[k]).sum::<f64>() / tw)
        .collect();
    let cov = DMatrix::from_fn(p, p, |a, b| {
        theta
            .iter()
            .zip(w)
            .map(|(t, w)| w * (t[a] - mean[a]) * (t[b] - mean[b]))
            .sum::<f64>()
            / tw
    });
    (mean, cov)
}

/// Weighted posterior correlation matrix of particles.
pub fn correlations(theta: &[Vec<f64>], w: &[f64]) -> Vec<Vec<f64>> {
    let (_, c) = weighted_cov(theta, w);
    let p = c.nrows();
    (0..p)
        .map(|a| {
            (0..p)
                .map(|b| {
                    let d = (c[(a, a)] * c[(b, b)]).sqrt();
                    if d > 0.0 {
                        c[(a, b)] / d
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        })
        .collect()
}

/// A particle: ln parameters, raw summaries, projected summaries, distance, weight.
#[derive(Debug, Clone)]
struct Particle {
    theta: Vec<f64>,
    f: Vec<f64>,
    s: Vec<f64>,
    d: f64,
    w: f64,
}

/// Fit the projection on `pts` (all of them), its penalties by [`choose_ridge`], and
/// recompute every particle's projected summaries and distance; returns the observed
/// projected summaries, the projection's held-out R² per parameter on `pts` (5 folds) and
/// the relative penalties.
fn refit(
    pts: &mut [Particle],
    observed: &[f64],
    kind: DistanceKind,
    ridge: Ridge,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    if kind == DistanceKind::Direct {
        for p in pts.iter_mut() {
            p.d = p.f.first().copied().unwrap_or(f64::INFINITY);
            if p.d.is_nan() {
                p.d = f64::INFINITY;
            }
        }
        return Ok((Vec::new(), Vec::new(), Vec::new()));
    }
    let features: Vec<Vec<f64>> = pts.iter().map(|p| p.f.clone()).collect();
    let theta: Vec<Vec<f64>> = pts.iter().map(|p| p.theta.clone()).collect();
    let (c, r2) = choose_ridge(&features, &theta, ridge);
    let mut proj = Projection::fit_with(&features, &theta, &c)?;
    if ridge == Ridge::CvDrop && r2.iter().any(|r| *r > 0.0) {
        proj.used = r2.iter().map(|r| *r > 0.0).collect();
    }
    let s_obs = proj.project(observed);
    for p in pts.iter_mut() {
        p.s = proj.project(&p.f);
        p.d = proj.distance(&p.s, &s_obs);
    }
    Ok((s_obs, r2, c))
}

/// The relative penalties as `[1e-3, 3e1, …]` for the trace.
fn fmt_c(c: &[f64]) -> String {
    let v: Vec<String> = c.iter().map(|x| format!("{x:.0e}")).collect();
    format!("[{}]", v.join(", "))
}

/// Whether `PRADAR_ABC_TRACE` asks for a per-generation trace on stderr.
fn trace() -> bool {
    std::env::var("PRADAR_ABC_TRACE").is_ok_and(|v| v == "1")
}

/// Run APMC. `simulate(theta, seed)` gives the raw summaries of one simulation at ln
/// parameters `theta`; `observed` the data's; `progress(done, budget)` after each
/// generation. The projection of the semi-automatic summaries is fitted on the prior
/// generation, then refitted at every generation on the kept and new particles (the
/// distance adapted per generation, Prangle 2017), every distance recomputed with it.
pub fn apmc<F>(
    prior: &BoxPrior,
    observed: &[f64],
    opts: &AbcOptions,
    simulate: F,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Posterior>
where
    F: Fn(&[f64], u64) -> Result<Vec<f64>> + Sync,
{
    let (n, na) = (opts.population, opts.kept);
    // generation 0: the prior (also the first fit of the semi-automatic summaries)
    let mut pop = prior_generation(prior, opts, &simulate)?;
    let mut used = n;
    progress(used, opts.simulations);
    let (mut s_obs, mut r2, c) = refit(&mut pop, observed, opts.distance, opts.ridge)?;
    if trace() {
        eprintln!(
            "abc: prior generation, held-out R² of the projection {r2:.2?}, ridge c {}",
            fmt_c(&c)
        );
    }
    let mut eps = keep(&mut pop, na);
    let mut generations = 1;
    let mut acceptance = 1.0;
    while used + (n - na) <= opts.simulations && acceptance >= opts.min_acceptance {
        let kernel = Kernel::of(&pop, prior)?;
        let new: Vec<Particle> = (0..n - na)
            .into_par_iter()
            .map(|i| kernel.propose(prior, opts, generations, i, &simulate))
            .collect::<Result<_>>()?;
        used += n - na;
        generations += 1;
        let old = pop.len();
        pop.extend(new);
        let (so, r, c) = refit(&mut pop, observed, opts.distance, opts.ridge)?;
        s_obs = so;
        r2 = r;
        // the previous tolerance under the refitted distance: the kept particles' largest
        let eps_prev = pop[..old].iter().map(|p| p.d).fold(0.0, f64::max);
        acceptance = pop[old..].iter().filter(|p| p.d < eps_prev).count() as f64 / (n - na) as f64;
        eps = keep(&mut pop, na);
        if trace() {
            eprintln!(
                "abc: generation {generations}, {used} simulations, acceptance {acceptance:.3}, ε {eps:.3}, held-out R² {r2:.2?}, ridge c {}",
                fmt_c(&c)
            );
        }
        progress(used, opts.simulations);
    }
    let tw: f64 = pop.iter().map(|p| p.w).sum();
    let weights: Vec<f64> = pop.iter().map(|p| p.w / tw).collect();
    let theta: Vec<Vec<f64>> = pop.iter().map(|p| p.theta.clone()).collect();
    let adjusted = match opts.distance {
        DistanceKind::Projected => adjust(prior, &pop, &s_obs, eps, &weights),
        DistanceKind::Direct => None,
    };
    Ok(Posterior {
        regression_adjusted: adjusted.is_some(),
        adjusted: adjusted.unwrap_or_else(|| theta.clone()),
        theta,
        weights,
        distances: pop.iter().map(|p| p.d).collect(),
        epsilon: eps,
        generations,
        simulations: used,
        acceptance,
        heldout_r2: r2,
    })
}

/// Generation 0: takes the prior, the options and the simulator; gives the population
/// drawn from the prior (weight 1 each, distances not yet computed), particle i from its
/// own stream [`key`]`(seed, 0, i)`.
fn prior_generation<F>(prior: &BoxPrior, opts: &AbcOptions, simulate: &F) -> Result<Vec<Particle>>
where
    F: Fn(&[f64], u64) -> Result<Vec<f64>> + Sync,
{
    (0..opts.population)
        .into_par_iter()
        .map(|i| {
            let mut rng = ChaCha8Rng::seed_from_u64(key(opts.seed, 0, i));
            let theta = prior.draw(&mut rng);
            let f = simulate(&theta, rng.gen())?;
            Ok(Particle {
                theta,
                f,
                s: Vec::new(),
                d: 0.0,
                w: 1.0,
            })
        })
        .collect::<Result<_>>()
}

/// Takes the population and the number to keep; keeps the `na` nearest (a stable sort:
/// ties keep their order) and gives the tolerance, the largest kept distance (infinite
/// for an empty population).
fn keep(pop: &mut Vec<Particle>, na: usize) -> f64 {
    pop.sort_by(|a, b| a.d.total_cmp(&b.d)); // stable: ties keep their order
    pop.truncate(na);
    pop.last().map_or(f64::INFINITY, |p| p.d)
}

/// A generation's proposal: the kept particles, their weights, the Gaussian kernel of
/// twice their weighted covariance (its Cholesky factor) and the densities' constants.
struct Kernel {
    /// The kept particles' parameters.
    theta: Vec<Vec<f64>>,
    /// Their weights.
    w: Vec<f64>,
    /// The weights' total.
    tw: f64,
    /// The lower Cholesky factor L of the kernel's covariance Σ.
    l: DMatrix<f64>,
    /// ln π on the prior's box.
    ln_prior: f64,
    /// ln φ_Σ(0).
    ln_phi0: f64,
    /// The normalised weights' running sums (the particle a proposal starts from).
    cum: Vec<f64>,
}

impl Kernel {
    /// Takes the kept population and the prior; gives the generation's proposal, or an
    /// error when the particles' covariance is singular.
    fn of(pop: &[Particle], prior: &BoxPrior) -> Result<Kernel> {
        let dim = prior.dim();
        let theta: Vec<Vec<f64>> = pop.iter().map(|p| p.theta.clone()).collect();
        let w: Vec<f64> = pop.iter().map(|p| p.w).collect();
        let tw: f64 = w.iter().sum();
        let (_, cov) = weighted_cov(&theta, &w);
        // Gaussian kernel of twice the weighted covariance (a small floor keeps it definite)
        let sigma = DMatrix::from_fn(dim, dim, |a, b| {
            2.0 * cov[(a, b)]
                + if a == b {
                    1e-9 + 1e-6 * (prior.hi[a] - prior.lo[a]).powi(2)
                } else {
                    0.0
                }
        });
        let chol = sigma
            .cholesky()
            .ok_or_else(|| Error::param("calibrate", "the particles' covariance is singular"))?;
        let l = chol.l();
        // ln of the normalising constants, so that new particles' weights are on the scale
        // of the generation-0 draws (weight π/π = 1) and of earlier kept particles:
        // ln π = −Σ ln(hi − lo) on the box, ln φ_Σ(0) = −(d/2)·ln 2π − Σ ln L_kk
        let ln_prior: f64 = -prior
            .lo
            .iter()
            .zip(&prior.hi)
            .map(|(lo, hi)| (hi - lo).max(f64::MIN_POSITIVE).ln())
            .sum::<f64>();
        let ln_phi0 = -0.5 * dim as f64 * (2.0 * std::f64::consts::PI).ln()
            - (0..dim).map(|k| l[(k, k)].ln()).sum::<f64>();
        let cum: Vec<f64> = w
            .iter()
            .scan(0.0, |acc, x| {
                *acc += x / tw;
                Some(*acc)
            })
            .collect();
        Ok(Kernel {
            theta,
            w,
            tw,
            l,
            ln_prior,
            ln_phi0,
            cum,
        })
    }

    /// Takes the prior, the options, the generation, the new particle's index and the
    /// simulator; gives the new particle: a kept particle drawn by weight, moved by the
    /// kernel until inside the prior's box (from its own stream [`key`]`(seed,
    /// generation, i)`), simulated, and weighted π(θ) / Σ_j (w_j/Σw) φ_Σ(θ − θ_j).
    fn propose<F>(
        &self,
        prior: &BoxPrior,
        opts: &AbcOptions,
        generations: usize,
        i: usize,
        simulate: &F,
    ) -> Result<Particle>
    where
        F: Fn(&[f64], u64) -> Result<Vec<f64>> + Sync,
    {
        let (theta, w, tw, l, cum) = (&self.theta, &self.w, self.tw, &self.l, &self.cum);
        let (ln_prior, ln_phi0) = (self.ln_prior, self.ln_phi0);
        let dim = prior.dim();
        let na = opts.kept;
        let mut rng = ChaCha8Rng::seed_from_u64(key(opts.seed, generations, i));
        let mut th = Vec::new();
        for attempt in 0..10_000 {
            let u: f64 = rng.gen();
            let a = cum.partition_point(|c| *c < u).min(na - 1);
            let z = DVector::from_fn(dim, |_, _| rng.sample::<f64, _>(StandardNormal));
            let step = l * z;
            th = (0..dim).map(|k| theta[a][k] + step[k]).collect();
            if prior.inside(&th) {
                break;
            }
            if attempt == 9_999 {
                // never in practice: the kernel is centred on particles inside the box
                th = th
                    .iter()
                    .enumerate()
                    .map(|(k, v)| v.clamp(prior.lo[k], prior.hi[k]))
                    .collect();
            }
        }
        let f = simulate(&th, rng.gen())?;
        // w = π(θ) / Σ_j (w_j/Σw) φ_Σ(θ − θ_j), both densities normalised (π is
        // constant on the box); q is the sum without φ's constant
        let q: f64 = theta
            .iter()
            .zip(w)
            .map(|(tj, wj)| {
                let dv = DVector::from_fn(dim, |k, _| th[k] - tj[k]);
                let y = l.solve_lower_triangular(&dv).unwrap_or(dv);
                wj / tw * (-0.5 * y.norm_squared()).exp()
            })
            .sum();
        Ok(Particle {
            theta: th,
            f,
            s: Vec::new(),
            d: 0.0,
            w: (ln_prior - ln_phi0 - q.max(1e-300).ln()).exp(),
        })
    }
}

/// Local-linear regression adjustment (Beaumont, Zhang & Balding 2002):
/// θ_i* = θ_i − β̂ᵀ(s_i − s_obs), β̂ the weighted least-squares slopes of θ on the
/// projected summaries, weights w_i·K(d_i/ε) with the Epanechnikov kernel; clamped to the
/// prior box. None (the unadjusted particles stand) when there are fewer than 10
/// particles per coefficient (p + 1) or the fit is singular.
fn adjust(
    prior: &BoxPrior,
    pop: &[Particle],
    s_obs: &[f64],
    eps: f64,
    w: &[f64],
) -> Option<Vec<Vec<f64>>> {
    let n = pop.len();
    let p = s_obs.len();
    if p == 0 || n < 10 * (p + 1) {
        return None;
    }
    let dim = prior.dim();
    let kw: Vec<f64> = pop
        .iter()
        .zip(w)
        .map(|(x, w)| {
            let r = if eps > 0.0 { x.d / (eps * 1.0001) } else { 0.0 };
            w * (1.0 - r * r).max(0.0)
        })
        .collect();
    let x = DMatrix::from_fn(n, p + 1, |i, j| {
        if j == 0 {
            1.0
        } else {
            pop[i].s[j - 1] - s_obs[j - 1]
        }
    });
    let y = DMatrix::from_fn(n, dim, |i, k| pop[i].theta[k]);
    let sw = DMatrix::from_fn(n, 1, |i, _| kw[i].sqrt());
    let xw = DMatrix::from_fn(n, p + 1, |i, j| x[(i, j)] * sw[(i, 0)]);
    let yw = DMatrix::from_fn(n, dim, |i, k| y[(i, k)] * sw[(i, 0)]);
    let mut xtx = xw.transpose() * &xw;
    for j in 1..=p {
        xtx[(j, j)] += 1e-9;
    }
    let chol = xtx.cholesky()?;
    let beta = chol.solve(&(xw.transpose() * yw));
    let adjusted = (0..n)
        .map(|i| {
            (0..dim)
                .map(|k| {
                    let corr: f64 = (1..=p).map(|j| beta[(j, k)] * x[(i, j)]).sum();
                    (pop[i].theta[k] - corr).clamp(prior.lo[k], prior.hi[k])
                })
                .collect()
        })
        .collect();
    Some(adjusted)
}

#[cfg(test)]
mod tests;
