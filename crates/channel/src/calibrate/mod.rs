//! `pradar calibrate`: the statistical channel model fitted without clustering, by
//! simulation-based inference (DESIGN §1 "[calibrate]").
//!
//! Takes a campaign's energy matrices (`pradar energy` or `pradar synth` output), the
//! campaign (layout, poses, directions, band, array, noise, processing — never its
//! `[scene]`/`[clutter]` truth) and a prior; gives the posterior over the model's free
//! quantities and a model file in the model schema: per quantity the posterior median as
//! `value`, the 95 % credible interval (2.5 % and 97.5 % weighted quantiles) as `interval`,
//! the final population size as `n`, and `[calibration]` recording the method
//! (`method = "abc-smc (…)"`), the simulations, generations, tolerance, seed and free
//! quantities. The simulator is `synth`'s model run in memory
//! ([`EnergySimulator`](crate::model::EnergySimulator): the same draws and detector as
//! `synth`, without writing files).
//!
//! **Free quantities** θ (inferred in ln units): λ `intra_cluster_rate`, AoA std
//! `intra_cluster_aoa`, d_c `perimeter_spacing`, d_p `perimeter_offset`, Γ
//! `cluster_decay`, γ `ray_decay`, σ `cluster_rrcs`, `rays_per_cluster`, when the
//! prior has `[diffuse]` (the default prior has), `diffuse.wall_rcs_per_m` and
//! `diffuse.lambert_exponent`, and when it has `[walls]` (the default prior has),
//! `walls.specular_gamma` (0.01–1), `walls.corner_rcs` and `walls.edge_rcs` (1e-4–10 m²,
//! when present; the per-material |Γ| are copied). A
//! quantity whose 95 % interval spans ≥ 90 % of its prior's ln-range
//! ([`Calibration::informed`]) is reported as not informed by the data. The
//! others (Λ, which the model derives from geometry; the diffuse `power_share` and
//! `decay`, which synth does not draw from) are copied from the prior file.
//!
//! **Prior**: independent log-uniform, p(θ_k) ∝ 1/θ_k on [a_k, b_k]. Defaults
//! ([`DEFAULT_PRIOR`], wide for indoor mm-wave): λ 0.05–3 /ns, AoA 2–60°, d_c 0.3–20 m,
//! d_p 0.05–1.5 m (synth caps offsets at 1.5 m), Γ 2–60 ns (2 ns–10 µs for the excess decay of a schema-2 model, [`EXCESS_DECAY_PRIOR`]), γ 0.5–20 ns, σ 1e-4–1 m²,
//! rays 1–20; σ′ 1e-3–1 m²/m, Lambert n 0.2–10; |Γ| 0.01–1, corner and edge σ
//! 1e-4–10 m². The default prior ([`Prior::default_prior`]) frees every quantity of the
//! model, the layout's parts included: the clusters' eight and the `[diffuse]` and
//! `[walls]` five, 13 in all — the layout's own returns (the walls' continuum, specular
//! feet, corners) are part of what a measured table holds and the clusters alone cannot
//! stand in for them. `--no-walls` ([`Prior::no_walls`]): the clusters' eight only, no
//! `[diffuse]` or `[walls]` — the matching prior for a table drawn from a model without
//! them (`synth` of a cluster-only model), and several times cheaper per simulation.
//! `--prior FILE` (model schema): a free quantity's `interval = [a, b]` is its prior range
//! (a > 0); `a = b` holds it fixed at a; no interval keeps the default range; a section
//! the file lacks is not in the model.
//!
//! **Method**: adaptive ABC population Monte Carlo (APMC; Lenormand, Jabot & Deffuant,
//! Comput. Stat. 2013), the ABC-SMC of Beaumont, Cornuet, Marin & Robert (Biometrika 2009)
//! with the tolerance sequence chosen adaptively (Del Moral, Doucet & Jasra, Stat. Comput.
//! 2012), in ln-parameter space x = ln θ ([`abc`]):
//! 1. t = 0: draw N particles x_i ~ π (uniform on the box), simulate y_i ~ p(y | x_i),
//!    compute the raw summaries f(y_i) ([`summaries`]).
//! 2. Summaries (semi-automatic ABC, Fearnhead & Prangle, JRSS-B 2012): standardise each
//!    raw summary by its median and MAD over the t = 0 draws, z = (f − med)/MAD, fit
//!    x ≈ β₀ + Bᵀz by ridge least squares on them, and use s(y) = β₀ + Bᵀz(y) (one
//!    summary per parameter, an estimate of E[x | y]). Distance
//!    ρ(y, y_obs) = (Σ_k ((s_k(y) − s_k(y_obs))/MAD_k)²)^½, MAD_k of s_k under the prior
//!    predictive (the t = 0 draws).
//!
//!    The raw summaries f (default, [`Distance::SummariesQuantiles`]) are the 42
//!    pooled statistics of [`summaries::summaries`] followed by 45 quantiles
//!    ([`summaries::quantile_summaries`]): the 10, 25, 50, 75 and 90 % quantiles of each
//!    component of the predictive check's per-profile 7-vectors and per-position 2-vectors
//!    (the sets of [`mmd::statistic_sets`]). They describe the distributions the check
//!    compares, where the 42 pool them into means; the regression picks what carries
//!    information. `--distance summaries` ([`Distance::Summaries`]) uses the 42 alone.
//!
//!    With `--distance mmd` ([`Distance::Mmd`]) the distance is instead
//!    ρ = MMD²_u(profiles) + MMD²_u(positions), the unbiased squared maximum mean
//!    discrepancy between the measured and the simulated table's per-profile and
//!    per-position statistics of `pradar check`, standardised by the measured set's
//!    median/MAD, Gaussian kernel with the median-heuristic length scale of the measured
//!    set, sets over 1000 vectors subsampled ([`mmd`] gives the definitions): fixed for the
//!    run, no projection, and no regression adjustment in step 6 (there are no summaries
//!    to regress on).
//! 3. Keep the N_α = ⌊αN⌋ particles with the smallest ρ, weights w_i = 1; ε_1 their
//!    largest ρ.
//! 4. t ≥ 1: Σ = 2·Cov_w(x) (the weighted covariance of the kept particles, Beaumont et
//!    al.'s optimal Gaussian kernel). Draw N − N_α new particles: an ancestor j with
//!    probability w_j/Σw, x* ~ N(x_j, Σ) (redrawn until inside the box), simulate,
//!    ρ*; weight w* = π(x*) / Σ_j (w_j/Σw)·φ_Σ(x* − x_j). The acceptance rate
//!    p_acc = #{ρ* < ε_t}/(N − N_α). Merge with the kept particles, keep the N_α with
//!    the smallest ρ, ε_{t+1} their largest.
//! 5. Stop when p_acc < p_min (`min_acceptance`) or the budget `--simulations` is spent.
//! 6. Regression adjustment (Beaumont, Zhang & Balding, Genetics 2002):
//!    x_i* = x_i − β̂ᵀ(s(y_i) − s(y_obs)), β̂ the least-squares slopes of x on s with weights
//!    w_i·(1 − (ρ_i/ε)²) (Epanechnikov), clamped to the box; skipped (and not named in
//!    the method) with fewer than 10 particles per coefficient. The posterior median and the
//!    2.5/97.5 % quantiles are the weighted quantiles of the adjusted particles (of the raw
//!    ones with `adjust = false`), mapped back by exp.
//!
//! **Determinism**: particle i of generation t draws everything (ancestor, perturbation,
//! the simulator's seed) from `ChaCha8Rng` keyed by (seed, t, i); simulations run in
//! parallel over particles (rayon) and are collected in order, so the same seed gives the
//! same bytes with any number of threads. The keys differ from synth's streams: the
//! simulations never replay the data's own draw even at the campaign seed.
//!
//! Layout: [`params`] (options), [`summaries`] (raw summary statistics and the check
//! statistics' quantiles), [`mmd`] (the MMD
//! distance), [`abc`] (the sampler).

pub mod abc;
pub mod mmd;
pub mod params;
pub mod summaries;

pub use abc::{correlations, BoxPrior, Posterior, Ridge};
pub use params::{CalibrateParams, CalibrateValid, Distance};

use crate::campaign::manifest::Campaign;
use crate::energy::EnergyMatrix;
use crate::error::{short, Error, Result};
use crate::model::file::{BinSettings, CalibrationMeta, ModelConfig, Quantity};
use crate::model::EnergySimulator;
use crate::stats::weighted_quantile;
use std::path::Path;
use summaries::SummaryContext;

/// Default prior ranges (log-uniform): (quantity, lower, upper), in the schema's units.
/// The `diffuse.*` and `walls.*` ones are free only when the prior has that section (the
/// default prior has both, `--no-walls` neither).
pub const DEFAULT_PRIOR: [(&str, f64, f64); 13] = [
    ("intra_cluster_rate", 0.05, 3.0),
    ("intra_cluster_aoa", 2.0, 60.0),
    ("perimeter_spacing", 0.3, 20.0),
    ("perimeter_offset", 0.05, 1.5),
    ("cluster_decay", 2.0, 60.0),
    ("ray_decay", 0.5, 20.0),
    ("cluster_rrcs", 1e-4, 1.0),
    ("rays_per_cluster", 1.0, 20.0),
    ("diffuse.wall_rcs_per_m", 1e-3, 1.0),
    ("diffuse.lambert_exponent", 0.2, 10.0),
    ("walls.specular_gamma", 0.01, 1.0),
    ("walls.corner_rcs", 1e-4, 10.0),
    ("walls.edge_rcs", 1e-4, 10.0),
];

/// The excess cluster decay's default prior range in a schema-2 model (`cluster_decay`
/// is then the decay beyond each cluster's own r⁻⁴, and its schema bound 10 µs is no
/// excess decay over any indoor profile): 2 ns to 10 µs, log-uniform. A prior file's
/// interval whose upper end is `inf` (what `fit` writes when the data show no excess
/// decay) takes this upper end.
pub const EXCESS_DECAY_PRIOR: (f64, f64) = (2.0, 1e4);

/// A free quantity whose 95 % interval spans at least this share of its prior range in
/// ln units is reported as not informed by the data ([`Calibration::width_share`]).
pub const UNINFORMED_SHARE: f64 = 0.9;

/// The prior: a model template (units, families, the quantities not inferred) and the
/// free quantities' log-uniform ranges.
#[derive(Debug, Clone, PartialEq)]
pub struct Prior {
    /// The model the free quantities are written into.
    pub template: ModelConfig,
    /// Free quantities, by file name.
    pub free: Vec<String>,
    /// Their ranges, schema units.
    pub lo: Vec<f64>,
    /// Upper ends.
    pub hi: Vec<f64>,
}

impl Prior {
    /// The default prior: every quantity of the model free at its [`DEFAULT_PRIOR`]
    /// range, 13 in all — the template `table1_defaults` with a `[diffuse]` section (σ′,
    /// Lambert n free; `power_share` 0.5 and `decay` 10 ns, which synth does not draw from)
    /// and a `[walls]` section (|Γ| one value for every material, corner σ and edge σ
    /// free); a schema-2 model, so Γ is the excess decay over [`EXCESS_DECAY_PRIOR`].
    pub fn default_prior() -> Prior {
        use crate::model::file::{DiffuseModel, WallModel};
        let mut m = ModelConfig::table1_defaults();
        m.diffuse = Some(DiffuseModel {
            wall_rcs_per_m: Quantity::new(0.02, "m2/m", "exponential"),
            lambert_exponent: Quantity::new(1.0, "1", "constant"),
            power_share: Quantity::new(0.5, "1", "constant"),
            decay: Quantity::new(10.0, "ns", "exponential"),
        });
        m.walls = Some(WallModel {
            specular_gamma: Quantity::new(0.3, "1", "constant"),
            material_gamma: Default::default(),
            corner_rcs: Some(Quantity::new(0.05, "m2", "constant")),
            edge_rcs: Some(Quantity::new(0.05, "m2", "constant")),
        });
        Prior::from_template(m, Path::new("(default prior)")).expect("the default prior is valid")
    }

    /// The clusters' prior (`calibrate --no-walls`): [`DEFAULT_PRIOR`] over
    /// `table1_defaults` without `[diffuse]` or `[walls]`, the eight cluster quantities
    /// free.
    pub fn no_walls() -> Prior {
        Prior::from_template(
            ModelConfig::table1_defaults(),
            Path::new("(default prior without walls)"),
        )
        .expect("the clusters' prior is valid")
    }

    /// Read a prior file (model schema; see the module docs); errors name the file and field.
    pub fn load(path: &Path) -> Result<Prior> {
        let m = ModelConfig::load(path)?;
        Prior::from_template(m, path)
    }

    /// The prior of a model template: a free quantity's interval is its range.
    pub fn from_template(mut template: ModelConfig, path: &Path) -> Result<Prior> {
        let (mut free, mut lo, mut hi) = (Vec::new(), Vec::new(), Vec::new());
        // the intervals the file gives: (quantity, as printed, ends)
        let mut given = Vec::new();
        let excess = template.schema_version >= 2;
        for (name, a, b) in DEFAULT_PRIOR {
            let Some(q) = template.quantity(name) else {
                continue; // a diffuse or walls quantity without its section
            };
            let (a, b) = if excess && name == "cluster_decay" {
                EXCESS_DECAY_PRIOR
            } else {
                (a, b)
            };
            // a schema-2 excess decay open upwards (no excess decay in the data's
            // bootstrap) reaches the schema's bound
            let interval = match q.interval {
                Some([x, y]) if excess && name == "cluster_decay" && y == f64::INFINITY => {
                    Some([x.min(EXCESS_DECAY_PRIOR.1), EXCESS_DECAY_PRIOR.1])
                }
                i => i,
            };
            let (a, b) = match interval {
                Some([x, y]) => {
                    let range = format!("{name}.interval [{}, {}]", short(x), short(y));
                    if !(x > 0.0 && x <= y && y.is_finite()) {
                        return Err(Error::input(
                            path,
                            format!("{range}: a prior range needs 0 < lo <= hi"),
                        ));
                    }
                    given.push((name, range, [x, y]));
                    (x, y)
                }
                None => (a, b),
            };
            let q = template
                .quantity_mut(name)
                .expect("the quantity exists (read above)");
            if a == b {
                // held fixed
                q.value = a;
                q.not_estimable = None;
                continue;
            }
            // a value inside the range keeps the template checkable
            q.value = (a * b).sqrt();
            q.not_estimable = None;
            free.push(name.to_string());
            lo.push(a);
            hi.push(b);
        }
        template.calibration = None;
        // the sampler draws up to either end of a range: each must be a value the model
        // takes (judged on this quantity alone: another's fault is reported below)
        for (name, range, ends) in given {
            for end in ends {
                let mut m = template.clone();
                m.quantity_mut(name).expect("read above").value = end;
                if let Err(Error::Param { field, msg }) = m.check() {
                    if field == format!("{name}.value") {
                        return Err(Error::input(path, format!("{range}: {msg}")));
                    }
                }
            }
        }
        template
            .require_estimable(&Default::default())
            .map_err(|e| Error::input(path, e.to_string()))?;
        if free.is_empty() {
            return Err(Error::input(
                path,
                "no free quantity (every interval is a point)",
            ));
        }
        Ok(Prior {
            template,
            free,
            lo,
            hi,
        })
    }

    /// The box in ln units.
    pub fn box_prior(&self) -> BoxPrior {
        BoxPrior {
            lo: self.lo.iter().map(|v| v.ln()).collect(),
            hi: self.hi.iter().map(|v| v.ln()).collect(),
        }
    }

    /// The model at ln parameters `x`.
    pub fn model_at(&self, x: &[f64]) -> ModelConfig {
        let mut m = self.template.clone();
        for (k, (name, v)) in self.free.iter().zip(x).enumerate() {
            if let Some(q) = m.quantity_mut(name) {
                q.value = in_range(v.exp(), self.lo[k], self.hi[k]);
            }
        }
        m
    }
}

/// What `calibrate` gives.
#[derive(Debug, Clone)]
pub struct Calibration {
    /// The calibrated model (posterior medians, 95 % credible intervals, `[calibration]`).
    pub model: ModelConfig,
    /// The final population (ln units).
    pub posterior: Posterior,
    /// The free quantities, in the posterior's order.
    pub free: Vec<String>,
    /// Wall time, s.
    pub wall_s: f64,
    /// The prior ranges of the free quantities (schema units), lower ends.
    pub prior_lo: Vec<f64>,
    /// Upper ends.
    pub prior_hi: Vec<f64>,
}

impl Calibration {
    /// The width of free quantity `k`'s 95 % interval as a share of its prior range, in
    /// ln units: ln(hi/lo) / ln(prior hi/prior lo); 1 is the prior (a posterior that
    /// the data left flat has ≈ 0.95), 0 a point.
    pub fn width_share(&self, k: usize) -> f64 {
        let Some([lo, hi]) = self.model.quantity(&self.free[k]).and_then(|q| q.interval) else {
            return f64::NAN;
        };
        (hi / lo).ln() / (self.prior_hi[k] / self.prior_lo[k]).ln()
    }

    /// Whether the data informed free quantity `k`: its [`width_share`](Self::width_share)
    /// is below [`UNINFORMED_SHARE`] (the interval cut at least a tenth of the prior's
    /// ln-range). A quantity not informed has a median that means little: the
    /// posterior is about the prior.
    pub fn informed(&self, k: usize) -> bool {
        self.width_share(k) < UNINFORMED_SHARE
    }

    /// Free quantity `k`'s value (schema units) at ln value `ln_v`, kept inside its prior
    /// range: a particle on the range's edge comes back from ln units a rounding error
    /// outside it (Γ at 1e4 read as 10000.00000000001 ns), which `check --posterior` and
    /// the model schema refuse.
    pub fn value(&self, k: usize, ln_v: f64) -> f64 {
        in_range(ln_v.exp(), self.prior_lo[k], self.prior_hi[k])
    }

    /// The particles reported (adjusted or raw, as the model file), ln units.
    pub fn particles(&self) -> &[Vec<f64>] {
        if self
            .model
            .calibration
            .as_ref()
            .is_some_and(|c| c.method.contains("adjusted"))
        {
            &self.posterior.adjusted
        } else {
            &self.posterior.theta
        }
    }

    /// Posterior correlations of the reported particles (ln units).
    pub fn correlations(&self) -> Vec<Vec<f64>> {
        correlations(self.particles(), &self.posterior.weights)
    }

    /// The final population as the posterior predictive check takes it
    /// ([`crate::check::PosteriorSample`]: the free quantities' reported values, schema
    /// units, and the normalised weights) — what [`Calibration::write_posterior_csv`]
    /// writes and `check --posterior` reads back, without the file.
    pub fn posterior_sample(&self) -> crate::check::PosteriorSample {
        crate::check::PosteriorSample::normalised(
            self.free.clone(),
            self.posterior.weights.clone(),
            (self.particles().iter())
                .map(|x| {
                    (x.iter().enumerate())
                        .map(|(k, v)| self.value(k, *v))
                        .collect()
                })
                .collect(),
        )
    }

    /// Write the final population as CSV: `weight, distance`, then per free quantity its
    /// reported value (schema units) and raw value.
    pub fn write_posterior_csv(&self, path: &Path) -> Result<()> {
        let mut t = String::from("weight,distance");
        for f in &self.free {
            t.push_str(&format!(",{f},{f}_raw"));
        }
        t.push('\n');
        let rep = self.particles();
        let post = &self.posterior;
        for (i, (w, d)) in post.weights.iter().zip(&post.distances).enumerate() {
            t.push_str(&format!("{w:e},{d:e}"));
            for (k, (a, r)) in rep[i].iter().zip(&post.theta[i]).enumerate() {
                t.push_str(&format!(",{:e},{:e}", self.value(k, *a), self.value(k, *r)));
            }
            t.push('\n');
        }
        crate::io::write_bytes(path, t.as_bytes())
    }
}

/// Calibrate the model on the energy table `energy` (read from `energy_path`, of campaign
/// `c`) under `prior`. `progress(done, budget)` after each generation.
pub fn calibrate(
    c: &Campaign,
    energy: &EnergyMatrix,
    energy_path: &Path,
    prior: &Prior,
    params: &CalibrateValid,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Calibration> {
    let t0 = std::time::Instant::now();
    let m = &c.manifest;
    let sim = EnergySimulator::for_table(c, energy, energy_path, params.cull)?;
    let nb = energy.bins;
    let poses: Vec<(f64, f64, f64)> = m
        .poses
        .iter()
        .map(|p| (p.x_m, p.y_m, p.heading_deg))
        .collect();
    let ctx = SummaryContext::new(
        &poses,
        &energy.angles_rel_deg,
        nb,
        energy.meta.bin_width_ns,
        energy.meta.noise_mean(),
        energy.meta.tw * energy.meta.pulses as f64,
        energy.meta.gate_ns(),
        sim.layout(),
    );
    let seed = params.seed.unwrap_or(m.seed);
    let mmd_mode = params.distance == Distance::Mmd;
    let opts = abc::AbcOptions {
        simulations: params.simulations,
        population: params.population,
        kept: params.kept(),
        min_acceptance: params.min_acceptance,
        seed,
        distance: if mmd_mode {
            abc::DistanceKind::Direct
        } else {
            abc::DistanceKind::Projected
        },
        ridge: params.ridge,
    };
    let stat_ctx = crate::check::context(energy);
    // the check statistics' quantiles appended to the pooled summaries
    let quant = params.distance == Distance::SummariesQuantiles;
    let (observed, reference) = if mmd_mode {
        let r = mmd::MmdDistance::new(&stat_ctx, &energy.data);
        (vec![0.0], Some(r))
    } else {
        let mut f = summaries::summaries(&ctx, &energy.data);
        if quant {
            f.extend(summaries::quantile_summaries(&stat_ctx, &energy.data));
        }
        (f, None)
    };
    let simulate = |x: &[f64], s: u64| -> Result<Vec<f64>> {
        let e = crate::check::table_draw(&sim, energy, &prior.model_at(x), s)?;
        Ok(match &reference {
            // the subsample's stream: the simulation's seed, under its own key
            Some(r) => vec![r.distance(&stat_ctx, &e, s ^ 0x4d4d_445f_5355_4253)],
            None => {
                let mut f = summaries::summaries(&ctx, &e);
                if quant {
                    f.extend(summaries::quantile_summaries(&stat_ctx, &e));
                }
                f
            }
        })
    };
    let post = abc::apmc(&prior.box_prior(), &observed, &opts, simulate, progress)?;
    let adjusted = params.adjust && post.regression_adjusted;
    let particles = if adjusted {
        &post.adjusted
    } else {
        &post.theta
    };
    let mut model = prior.template.clone();
    for (k, name) in prior.free.iter().enumerate() {
        let x: Vec<f64> = particles.iter().map(|t| t[k]).collect();
        let q = model.quantity_mut(name).expect("a free quantity exists");
        let w = &post.weights;
        let at = |p: f64| weighted_quantile(&x, w, p).expect("a non-empty population");
        let (lo, hi) = (prior.lo[k], prior.hi[k]);
        *q = Quantity {
            value: in_range(at(0.5).exp(), lo, hi),
            interval: Some([
                in_range(at(0.025).exp(), lo, hi),
                in_range(at(0.975).exp(), lo, hi),
            ]),
            n: Some(w.len()),
            ks: None,
            ks_p: None,
            not_estimable: None,
            ..q.clone()
        };
    }
    model.array = Some(m.array);
    model.band = Some(m.band);
    model.bins = Some(BinSettings {
        bin_width_ns: energy.meta.bin_width_ns,
        window: format!("{:?}", m.processing.window).to_lowercase(),
    });
    model.calibration = Some(CalibrationMeta {
        method: if mmd_mode {
            "abc-smc (APMC, MMD of per-profile and per-position statistics)".into()
        } else {
            format!(
                "abc-smc (APMC, semi-automatic summaries{}{}{})",
                if quant {
                    " with the check statistics' quantiles"
                } else {
                    ""
                },
                match params.ridge {
                    Ridge::Fixed => "",
                    Ridge::Cv => ", ridge by cross-validation",
                    Ridge::CvDrop => {
                        ", ridge by cross-validation, uninformative projections dropped"
                    }
                },
                if adjusted {
                    ", regression-adjusted"
                } else {
                    ""
                }
            )
        },
        simulations: post.simulations,
        particles: post.weights.len(),
        generations: post.generations,
        epsilon: post.epsilon,
        seed,
        free: prior.free.clone(),
    });
    model.check()?;
    Ok(Calibration {
        model,
        posterior: post,
        free: prior.free.clone(),
        wall_s: t0.elapsed().as_secs_f64(),
        prior_lo: prior.lo.clone(),
        prior_hi: prior.hi.clone(),
    })
}

/// `v` moved into [lo, hi] (a value from ln units on the range's edge is a rounding error
/// outside it; a regression-adjusted particle may lie anywhere, and the prior gives no
/// weight outside its range).
fn in_range(v: f64, lo: f64, hi: f64) -> f64 {
    v.clamp(lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prior_from_template() {
        // the default frees every quantity of the model, the layout's parts included
        let d = Prior::default_prior();
        assert_eq!(d.free.len(), 13);
        for (k, (name, a, b)) in DEFAULT_PRIOR.iter().enumerate() {
            // a schema-2 template's Γ is the excess decay, over its own range
            let (a, b) = if *name == "cluster_decay" {
                EXCESS_DECAY_PRIOR
            } else {
                (*a, *b)
            };
            assert_eq!((d.free[k].as_str(), d.lo[k], d.hi[k]), (*name, a, b));
        }
        let n = Prior::no_walls();
        assert_eq!(n.free.len(), 8);
        assert!(n.template.diffuse.is_none() && n.template.walls.is_none());
        assert_eq!(n.free[..], d.free[..8]);
        assert_eq!((n.lo[0], n.hi[0]), (0.05, 3.0));
        // a schema-1 template keeps the total decay's range, and a fitted schema-2 file's
        // interval open upwards reaches the excess range's end
        let mut v1 = ModelConfig::table1_defaults();
        v1.schema_version = 1;
        let p1 = Prior::from_template(v1, Path::new("p.toml")).unwrap();
        let k = p1.free.iter().position(|f| f == "cluster_decay").unwrap();
        assert_eq!((p1.lo[k], p1.hi[k]), (2.0, 60.0));
        let mut open = ModelConfig::table1_defaults();
        open.cluster_decay.value = f64::INFINITY;
        open.cluster_decay.interval = Some([30.0, f64::INFINITY]);
        let po = Prior::from_template(open, Path::new("p.toml")).unwrap();
        assert_eq!((po.lo[k], po.hi[k]), (30.0, EXCESS_DECAY_PRIOR.1));
        let mut m = ModelConfig::table1_defaults();
        m.ray_decay.interval = Some([1.0, 8.0]);
        m.rays_per_cluster.interval = Some([4.0, 4.0]); // held fixed
        let p = Prior::from_template(m.clone(), Path::new("p.toml")).unwrap();
        assert_eq!(p.free.len(), 7);
        let k = p.free.iter().position(|f| f == "ray_decay").unwrap();
        assert_eq!((p.lo[k], p.hi[k]), (1.0, 8.0));
        assert_eq!(p.template.rays_per_cluster.value, 4.0);
        let x: Vec<f64> = p.lo.iter().map(|v| v.ln()).collect();
        let at = p.model_at(&x);
        assert!((at.ray_decay.value - 1.0).abs() < 1e-12);
        at.check().unwrap();
        m.cluster_decay.interval = Some([-1.0, 8.0]);
        let e = Prior::from_template(m, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("p.toml") && e.contains("cluster_decay.interval"),
            "{e}"
        );
        // an end beyond the model's range is the interval's fault, its numbers short
        for (hi, shown) in [(2e4, "[2, 20000]"), (1e300, "[2, 1e300]")] {
            let mut m = ModelConfig::table1_defaults();
            m.cluster_decay.interval = Some([2.0, hi]);
            let e = Prior::from_template(m, Path::new("p.toml"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("p.toml: cluster_decay.interval ")
                    && e.contains(shown)
                    && e.contains("outside")
                    && e.len() < 160,
                "{e}"
            );
        }
    }

    #[test]
    fn walls_are_free_when_the_prior_has_them() {
        use crate::model::file::WallModel;
        let mut m = ModelConfig::table1_defaults();
        m.walls = Some(WallModel {
            specular_gamma: Quantity::new(0.3, "1", "constant"),
            material_gamma: Default::default(),
            corner_rcs: Some(Quantity::new(0.05, "m2", "constant")),
            edge_rcs: None,
        });
        let p = Prior::from_template(m.clone(), Path::new("p.toml")).unwrap();
        assert_eq!(p.free.len(), 10);
        let k = p
            .free
            .iter()
            .position(|f| f == "walls.specular_gamma")
            .unwrap();
        assert_eq!((p.lo[k], p.hi[k]), (0.01, 1.0));
        assert!(p.free.iter().any(|f| f == "walls.corner_rcs"));
        assert!(!p.free.iter().any(|f| f == "walls.edge_rcs"));
        let x: Vec<f64> = p.hi.iter().map(|v| v.ln()).collect();
        let at = p.model_at(&x);
        assert!((at.walls.as_ref().unwrap().specular_gamma.value - 1.0).abs() < 1e-12);
        // an interval [a, a] holds it fixed
        m.walls.as_mut().unwrap().specular_gamma.interval = Some([0.3, 0.3]);
        let p = Prior::from_template(m, Path::new("p.toml")).unwrap();
        assert_eq!(p.free.len(), 9);
    }

    /// The in-memory posterior sample is exactly what `check --posterior` reads back from
    /// the posterior CSV (the report's posterior predictive check uses the former).
    #[test]
    fn posterior_sample_is_the_csv_read_back() {
        let mut model = ModelConfig::table1_defaults();
        model.calibration = Some(CalibrationMeta {
            method: "abc-smc (APMC, regression-adjusted)".into(),
            simulations: 10,
            particles: 3,
            generations: 2,
            epsilon: 0.5,
            seed: 1,
            free: vec!["ray_decay".into(), "cluster_rrcs".into()],
        });
        let cal = Calibration {
            model,
            posterior: Posterior {
                theta: vec![vec![0.1, -3.0], vec![1.0 / 3.0, -4.7], vec![2.2, -1e-3]],
                adjusted: vec![vec![0.2, -2.9], vec![0.7 / 3.0, -4.1], vec![2.5, -7.3]],
                regression_adjusted: true,
                weights: vec![0.3, 1.0 / 7.0, 2.9],
                distances: vec![0.1, 0.2, 0.3],
                epsilon: 0.3,
                generations: 2,
                simulations: 10,
                acceptance: 0.5,
                heldout_r2: Vec::new(),
            },
            free: vec!["ray_decay".into(), "cluster_rrcs".into()],
            wall_s: 1.0,
            prior_lo: vec![0.5, 1e-4],
            prior_hi: vec![20.0, 1.0],
        };
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cal_posterior.csv");
        cal.write_posterior_csv(&p).unwrap();
        let read = crate::check::PosteriorSample::read(&p).unwrap();
        assert_eq!(cal.posterior_sample(), read);
        assert_eq!(read.values[1][0], (0.7f64 / 3.0).exp());
    }

    /// A particle on the prior's upper edge (Γ = 1e4 ns: ln then exp gives
    /// 10000.00000000001) is written inside the range, and `check --posterior` reads it.
    #[test]
    fn a_particle_on_the_prior_edge_stays_inside_the_schema() {
        assert!(1e4f64.ln().exp() > 1e4, "the rounding this test is about");
        let ln_hi = 1e4f64.ln();
        let cal = Calibration {
            model: ModelConfig::table1_defaults(),
            posterior: Posterior {
                theta: vec![vec![ln_hi], vec![2f64.ln()]],
                adjusted: vec![vec![ln_hi + 0.5], vec![2f64.ln() - 0.5]],
                regression_adjusted: false,
                weights: vec![0.5, 0.5],
                distances: vec![0.1, 0.2],
                epsilon: 0.3,
                generations: 1,
                simulations: 2,
                acceptance: 1.0,
                heldout_r2: Vec::new(),
            },
            free: vec!["cluster_decay".into()],
            wall_s: 1.0,
            prior_lo: vec![2.0],
            prior_hi: vec![1e4],
        };
        assert_eq!(cal.value(0, ln_hi), 1e4);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cal_posterior.csv");
        cal.write_posterior_csv(&p).unwrap();
        let read = crate::check::PosteriorSample::read(&p).unwrap();
        assert_eq!(read.values[0][0], 1e4);
        assert_eq!(read.values[1][0], 2.0);
    }

    #[test]
    fn calibrated_model_round_trips() {
        let mut m = ModelConfig::table1_defaults();
        m.calibration = Some(CalibrationMeta {
            method: "abc-smc".into(),
            simulations: 10,
            particles: 5,
            generations: 2,
            epsilon: 0.5,
            seed: 1,
            free: vec!["ray_decay".into()],
        });
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.toml");
        m.save(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains("[calibration]") && text.contains("method = \"abc-smc\""));
        assert_eq!(ModelConfig::load(&p).unwrap(), m);
    }
}
