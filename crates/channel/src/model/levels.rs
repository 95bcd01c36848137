//! The model's levels read from the measured energy table through the model's own forward
//! response: the walls' specular |Γ|, the walls' diffuse σ′ and the clusters' σ
//! ([`fit_levels`]).
//!
//! Takes a model whose structure is fitted (the cluster chain's: rates, AoA, perimeter,
//! decays, rays per cluster, the Lambert exponent), the campaign (poses, layout, array,
//! band, processing — never its truth) and its measured energy table; gives the model with
//! `[walls]` added and `diffuse.wall_rcs_per_m` and `cluster_rrcs` replaced, each
//! estimated from the table alone, and a [`LevelReport`] of what each estimate used.
//!
//! The cluster chain reads levels from CLEAN peaks, which are the largest cells of each
//! echo: a wall's specular return and corner become "clusters" of σ ≈ 1–2 m², and the
//! diffuse σ′ reads the continuum's local maxima (about 4× its mean). Levels read where
//! the layout says each part must be, against what the model's forward response predicts
//! there, do not depend on the clustering. With μ the table's noise mean (N0·TW) and
//! S = max(E − μ, 0):
//!
//! 1. **Specular |Γ|** (`walls.specular_gamma`): for every pose and every wall whose
//!    normal-incidence point the pose sees inside the scanned sector (`Layout::feet`; at
//!    most half a direction step beyond its edges), the direction d* nearest the foot's
//!    bearing and the bins within ±2 of its delay 2d/c (for a wall so near that its echo
//!    falls inside the coupling gate, the first 3 bins after the gate, where its range
//!    side lobes show): r = max S / max U over those bins, U the expected
//!    energy of that wall's specular return alone with |Γ| = 1
//!    ([`EnergySimulator::expected_profiles`]), kept where max U > 10μ (a unit echo
//!    below the noise there says nothing about |Γ|). |Γ|² = median r (robust to the other
//!    echoes that share the cell), over every pair (`specular_gamma`) and, when the layout
//!    names more than one material among them, over each material's pairs where it has
//!    at least [`MIN_MATERIAL_PAIRS`] (`material_gamma`). Not estimable without a pair.
//! 2. **Diffuse σ′** (`diffuse.wall_rcs_per_m`, when the model has `[diffuse]`): for
//!    every (pose, direction) whose first wall along the beam (the layout's) is not within
//!    10° of a visible normal-incidence point (those cells are the specular return's) and
//!    lies inside the table's delay span, the bin b* of the hit's delay:
//!    r = (S − W_s) / W_d, W_d the expected energy there of every wall's diffuse points
//!    with σ′ = 1 m²/m at the model's Lambert exponent ([`super::DiffuseWalls::unit_mean`])
//!    and W_s that of the specular returns at the |Γ| of step 1. σ′ = median r / ln 2: a
//!    Rayleigh cell's energy is exponential, whose median is ln 2 times its mean. Cells
//!    where W_d is below the noise mean are left out.
//!
//! 2b. **Vertices' σ** (`walls.corner_rcs`, `walls.edge_rcs`): for every pose and every
//!    layout vertex it sees (`walls::vertices`) inside the sector and not within 10° of a
//!    visible normal-incidence point, the bin of the vertex's delay (±1, where the unit
//!    response U of a σ = 1 m² point there peaks): r = (S − σ′·W_d − W_s)/U, W_d and W_s
//!    the expected energies there of the diffuse walls at σ′ = 1 and of the specular
//!    returns. σ = median r over the corners and over the edges (at least 1e-9 m²); a
//!    class no pose sees is left out of the model.
//! 3. **Cluster σ** (`cluster_rrcs`), by the method of moments on what the clusters add
//!    to the geometry: the mean number of signal bins per profile (E > 10μ, after the
//!    coupling gate). With the geometry fixed at steps 1–2b, more cluster power lifts more
//!    bins above the threshold; σ is the value at which the model's draws give the table's
//!    mean. (The profiles' signal energy was tried first: the geometry sets its median, so
//!    it pinned σ at its lower end and left the clusters' delay spread out; docs/model.md.)
//!    The draws carry the table's recorded N0 (as `check`'s draws do) and are
//!    ⌈384 / poses⌉ `synth` draws (4 to 8) at fixed seeds (common random numbers: only
//!    the clusters' level changes with σ). σ is the smallest value in [1e-6, 10] m² at
//!    which the draws' mean reaches the table's; at either end the end is kept and the
//!    report says so. It is found in one pass: the clusters' rays, the layout's and the
//!    noise add in the CIR and the clusters' amplitudes scale with √σ, so with
//!    s = √(σ/σ_ref) every bin's energy is a quadratic A + 2B·s + C·s²
//!    ([`EnergySimulator::energy_quadratics`], the clusters drawn at σ_ref = 10 m², the
//!    bracket's top, where synth's cull keeps the most of their rays). A bin is above
//!    the threshold t outside the roots s₁ ≤ s₂ of C·s² + 2B·s + (A − t), so the count at
//!    every σ is the count at s = 0 plus the crossings (σ_ref·s², ±1) at or below σ; the
//!    crossings of every draw, sorted, give the mean at every σ and the first σ where it
//!    reaches the table's exactly. (A regula falsi over full `synth` draws, 7 of them on
//!    the corridor, did this before; docs/model.md has both's figures.)
//!
//! Choices: |Γ| per layout material where the table sees the material's walls, one |Γ|
//! for the rest (module [`super::walls`]; a ratio above 1 is clamped to the passive bound
//! 1); the medians make each estimate robust to the parts the cell also holds; the
//! cluster level is the one free level left once the geometry's returns are fixed, and
//! the mean number of signal bins is the statistic that moves with it. Without a wall foot
//! in the sector the model gets no `[walls]` (nor vertices) and σ is matched without them.
//! Nothing reads the simulator's `[scene]` or `[clutter]`.

use super::channel::SeenRay;
use super::diffuse::DiffuseWalls;
use super::walls::{specular_ray, vertex_ray, vertex_seen, vertices, VertexKind, WallModel};
use super::{EnergySimulator, SynthParams};
use crate::campaign::layout::{Foot, Layout};
use crate::campaign::manifest::Campaign;
use crate::energy::EnergyMatrix;
use crate::error::Result;
use crate::model::file::{ModelConfig, Quantity};
use crate::params::ParamGuard;
use crate::stats::median;
use crate::units::wrap_rad;
use rayon::prelude::*;

/// What the level estimates used.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReport {
    /// (pose, wall) pairs behind |Γ|.
    pub specular_pairs: usize,
    /// On-wall cells behind σ′ (0 without `[diffuse]`).
    pub diffuse_cells: usize,
    /// (pose, vertex) pairs behind the corners' and edges' σ.
    pub vertex_cells: usize,
    /// The table's mean signal bins per profile.
    pub measured_bins: f64,
    /// The model's at the σ found.
    pub model_bins: f64,
    /// Whether σ stopped at an end of its range.
    pub sigma_at_bound: bool,
}

/// (pose, wall) pairs a material needs for a |Γ| of its own.
pub const MIN_MATERIAL_PAIRS: usize = 1;

/// Pose-draws the moment matching averages over (draws = ⌈this / poses⌉, in [4, 8]).
pub const LEVEL_POSES: usize = 384;

/// Seeds of the moment-matching draws.
pub const LEVEL_SEEDS: [u64; 8] = [11, 12, 13, 14, 15, 16, 17, 18];

/// The mean number of signal bins (E > 10μ, after the gate) per profile of energies `e`
/// (one or more matrices of `nb`-bin profiles; module docs, step 3).
pub fn mean_signal_bins(e: &[f64], nb: usize, first_bin: usize, mu: f64) -> f64 {
    let (n, profiles) = signal_bins(e, nb, first_bin, mu);
    n as f64 / profiles.max(1) as f64
}

/// (signal bins, profiles) of [`mean_signal_bins`]: its sums, which add over sets of
/// profiles.
fn signal_bins(e: &[f64], nb: usize, first_bin: usize, mu: f64) -> (usize, usize) {
    // a profile without a sweep (NaN, `[sweeps] missing`) is not counted
    let present = |prof: &&[f64]| !prof.first().is_some_and(|v| v.is_nan());
    let profiles = e.chunks(nb.max(1)).filter(present).count();
    let n: usize = e
        .chunks(nb.max(1))
        .filter(present)
        .map(|prof| {
            prof[first_bin.min(nb)..]
                .iter()
                .filter(|&&x| x > 10.0 * mu)
                .count()
        })
        .sum();
    (n, profiles)
}

/// Estimate `[walls]`, σ′ and σ of `model` from the energy table `em` of campaign `c`
/// (module docs).
pub fn fit_levels(
    c: &Campaign,
    em: &EnergyMatrix,
    model: &ModelConfig,
) -> Result<(ModelConfig, LevelReport)> {
    // the draws carry the table's own noise (as `check`'s), so their signal bins are
    // counted against the threshold the table's are
    let n0 = Some(em.meta.n0).filter(|n| n.is_finite() && *n > 0.0);
    let sim = EnergySimulator::new(
        c,
        &SynthParams {
            n0,
            ..Default::default()
        }
        .check()?,
    )?;
    let layout = sim.layout().clone();
    let t = Cells::of(em, &sim, &layout);
    // 1. specular |Γ|
    let (ratios, feet_at) = specular_ratios(&t);
    let specular_pairs = ratios.len();
    let mut out = model.clone();
    let (gamma, walls) = wall_model(&ratios);
    out.walls = Some(walls);
    let g = gamma.unwrap_or(0.0);
    // the walls' expected energies per pose: specular at |Γ|, diffuse at σ′ = 1 (zero
    // without [diffuse])
    let w = wall_energies(&t, c, &out, &feet_at, g);
    // 2. diffuse σ′
    let (diffuse_cells, sigma_d) = fit_diffuse(&t, &mut out, &w, &feet_at);
    // 2b. the vertices' σ: corners and edges
    let by_kind = vertex_ratios(&t, &w, &feet_at, sigma_d);
    let vertex_cells = by_kind[0].len() + by_kind[1].len();
    let walls = out.walls.as_mut().expect("set above");
    for (slot, samples) in [&mut walls.corner_rcs, &mut walls.edge_rcs]
        .into_iter()
        .zip(by_kind)
    {
        let n = samples.len();
        *slot = median(&samples).map(|m| Quantity {
            n: Some(n),
            ..Quantity::new(m.max(1e-9), "m2", "constant")
        });
    }
    // 3. cluster σ by the method of moments
    let measured = mean_signal_bins(&em.data, t.nb, t.first_bin, t.mu);
    let (sigma, at_bound, model_bins) = cluster_sigma(&t, &out, gamma, g, measured)?;
    if out.cluster_rrcs.value.is_finite() {
        out.cluster_rrcs = Quantity {
            value: sigma,
            interval: None,
            ks: None,
            ks_p: None,
            family: out.cluster_rrcs.family.clone(),
            ..out.cluster_rrcs.clone()
        };
    }
    if gamma.is_none() {
        // no wall foot in the sector: a model without the layout's returns (σ was matched
        // without them), not one that synth would refuse for a missing |Γ|
        out.walls = None;
    }
    let out = out.with_stated_values();
    out.check()?;
    Ok((
        out,
        LevelReport {
            specular_pairs,
            diffuse_cells,
            vertex_cells,
            measured_bins: measured,
            model_bins,
            sigma_at_bound: at_bound,
        },
    ))
}

/// The measured table as the level estimates read it, with the campaign's simulator and
/// its layout: dimensions, noise mean μ, first bin after the coupling gate, direction
/// step.
struct Cells<'a> {
    /// The measured energy table.
    em: &'a EnergyMatrix,
    /// The campaign's simulator (the table's N0).
    sim: &'a EnergySimulator,
    /// The campaign's layout.
    layout: &'a Layout,
    /// Positions.
    np: usize,
    /// Directions.
    nd: usize,
    /// Bins.
    nb: usize,
    /// The table's noise mean N0·TW.
    mu: f64,
    /// Bin width, ns.
    bin_ns: f64,
    /// The first bin after the coupling gate.
    first_bin: usize,
    /// The direction step, degrees (5 with one direction).
    step: f64,
}

impl<'a> Cells<'a> {
    /// Takes the table, the simulator and its layout; gives their cells.
    fn of(em: &'a EnergyMatrix, sim: &'a EnergySimulator, layout: &'a Layout) -> Cells<'a> {
        let (np, nd, nb) = (em.positions, em.directions(), em.bins);
        let mu = em.meta.noise_mean();
        let bin_ns = em.meta.bin_width_ns;
        let first_bin = ((em.meta.gate_ns() / bin_ns).ceil() as usize).min(nb);
        let step = if nd > 1 {
            (em.angles_rel_deg[1] - em.angles_rel_deg[0]).abs()
        } else {
            5.0
        };
        Cells {
            em,
            sim,
            layout,
            np,
            nd,
            nb,
            mu,
            bin_ns,
            first_bin,
            step,
        }
    }

    /// Takes a cell (position, direction, bin); gives its signal S = max(E − μ, 0).
    fn sig(&self, p: usize, d: usize, b: usize) -> f64 {
        (self.em.data[(p * self.nd + d) * self.nb + b] - self.mu).max(0.0)
    }

    /// Takes an angle relative to the heading, degrees; gives the table's nearest
    /// direction, if within half a step of it.
    fn nearest(&self, rel_deg: f64) -> Option<usize> {
        let (i, a) = self
            .em
            .angles_rel_deg
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - rel_deg).abs().total_cmp(&(b.1 - rel_deg).abs()))?;
        ((a - rel_deg).abs() <= 0.5 * self.step + 1e-9).then_some(i)
    }

    /// Takes a round-trip delay, s; gives its bin (rounded, possibly outside the table).
    fn bin_of(&self, tau_s: f64) -> isize {
        (tau_s * 1e9 / self.bin_ns).round() as isize
    }
}

/// Step 1 (module docs): takes the cells; gives the (material, S/U) ratio of every
/// (pose, wall) pair whose unit specular echo reaches 10μ, and each pose's
/// normal-incidence points.
fn specular_ratios(t: &Cells) -> (Vec<(String, f64)>, Vec<Vec<Foot>>) {
    let (em, sim, layout) = (t.em, t.sim, t.layout);
    let (np, nb, first_bin, mu) = (t.np, t.nb, t.first_bin, t.mu);
    let mut ratios = Vec::new();
    let mut feet_at = Vec::with_capacity(np);
    for p in 0..np {
        let (at, heading) = sim.pose(p);
        let f = layout.feet(at);
        for foot in &f {
            let rel = wrap_rad(foot.bearing - heading.to_radians()).to_degrees();
            let Some(d) = t.nearest(rel) else { continue };
            if !em.has(p, d) {
                continue; // no sweep there
            }
            let b = t.bin_of(crate::units::delay_s(foot.d_m));
            // the bins ±2 around the echo, or, for an echo inside the coupling gate, the
            // first 3 bins after it (where its range side lobes show)
            let lo = (b - 2).max(first_bin as isize);
            let hi = (b + 2).max(first_bin as isize + 2);
            if hi >= nb as isize {
                continue;
            }
            let u = sim.expected_profile(p, d, &[specular_ray(foot, 1.0, 0.0)]);
            let (lo, hi) = (lo as usize, hi as usize);
            let umax = (lo..=hi).map(|k| u[k]).fold(0.0, f64::max);
            let smax = (lo..=hi).map(|k| t.sig(p, d, k)).fold(0.0, f64::max);
            // a unit echo that would not reach the noise level there says nothing
            if umax > 10.0 * mu {
                ratios.push((layout.walls[foot.wall].material.clone(), smax / umax));
            }
        }
        feet_at.push(f);
    }
    (ratios, feet_at)
}

/// Step 1's estimate: takes the specular ratios; gives |Γ| (None without a pair) and the
/// `[walls]` with it and each material's |Γ| (no vertices yet).
fn wall_model(ratios: &[(String, f64)]) -> (Option<f64>, WallModel) {
    let specular_pairs = ratios.len();
    let gamma =
        median(&ratios.iter().map(|r| r.1).collect::<Vec<_>>()).map(|r| r.sqrt().clamp(1e-6, 1.0));
    let mut material_gamma = std::collections::BTreeMap::new();
    let materials: std::collections::BTreeSet<&String> = ratios.iter().map(|r| &r.0).collect();
    if materials.len() > 1 {
        for mat in materials {
            let v: Vec<f64> = ratios.iter().filter(|r| &r.0 == mat).map(|r| r.1).collect();
            let n = v.len();
            if n >= MIN_MATERIAL_PAIRS {
                let g = median(&v).expect("non-empty").sqrt().clamp(1e-6, 1.0);
                material_gamma.insert(
                    mat.clone(),
                    Quantity {
                        n: Some(n),
                        ..Quantity::new(g, "1", "constant")
                    },
                );
            }
        }
    }
    let walls = WallModel {
        material_gamma,
        specular_gamma: match gamma {
            Some(g) => Quantity {
                n: Some(specular_pairs),
                ..Quantity::new(g, "1", "constant")
            },
            None => Quantity {
                n: Some(0),
                ..Quantity::not_estimable(
                    "1",
                    "constant",
                    "no wall's normal-incidence point inside the scanned sector",
                )
            },
        },
        corner_rcs: None,
        edge_rcs: None,
    };
    (gamma, walls)
}

/// The walls' expected energies per pose (steps 2 and 2b).
struct WallEnergies {
    /// The diffuse walls at σ′ = 1 m²/m (None without `[diffuse]` or a finite exponent).
    unit: Option<DiffuseWalls>,
    /// Per pose, the specular returns at |Γ| (directions × bins).
    ws: Vec<Vec<f64>>,
    /// Per pose, the diffuse walls at σ′ = 1 (zero without `[diffuse]`).
    wd: Vec<Vec<f64>>,
}

/// Takes the cells, the campaign, the model with its `[walls]`, each pose's
/// normal-incidence points and |Γ| (`g`, 0 for none); gives the walls' expected energies
/// per pose: specular at |Γ|, diffuse at σ′ = 1.
fn wall_energies(
    t: &Cells,
    c: &Campaign,
    out: &ModelConfig,
    feet_at: &[Vec<Foot>],
    g: f64,
) -> WallEnergies {
    let (sim, layout) = (t.sim, t.layout);
    let (np, nd, nb) = (t.np, t.nd, t.nb);
    let wm = out.walls.clone().expect("set above");
    let unit = out
        .diffuse
        .as_ref()
        .filter(|d| d.lambert_exponent.value.is_finite())
        .map(|d| {
            DiffuseWalls::unit_mean(
                layout,
                d.lambert_exponent.value,
                c.manifest.band.bandwidth_hz(),
            )
        });
    let mut ws = Vec::with_capacity(np);
    let mut wd = Vec::with_capacity(np);
    for (p, pose_feet) in feet_at.iter().enumerate() {
        let (at, _) = sim.pose(p);
        let spec: Vec<SeenRay> = pose_feet
            .iter()
            .filter(|_| g > 0.0)
            .map(|f| specular_ray(f, wm.gamma(&layout.walls[f.wall].material), 0.0))
            .collect();
        ws.push(sim.expected_profiles(p, &spec));
        wd.push(match &unit {
            Some(u) => sim.expected_profiles(p, &u.rays_from(layout, at, 0.0)),
            None => vec![0.0; nd * nb],
        });
    }
    WallEnergies { unit, ws, wd }
}

/// Takes each pose's normal-incidence points, a pose and an absolute angle (rad); gives
/// whether the angle is within 10° of one of them (a cell of the specular return).
fn near_foot(feet_at: &[Vec<Foot>], p: usize, ang: f64) -> bool {
    feet_at[p]
        .iter()
        .any(|f| wrap_rad(f.bearing - ang).abs() < 10f64.to_radians())
}

/// Step 2 (module docs): takes the cells, the model (its `[diffuse]` σ′ replaced here when
/// it has one and a cell gives a ratio), the walls' expected energies and each pose's
/// normal-incidence points; gives (on-wall cells used, σ′; 0 when not estimated).
fn fit_diffuse(
    t: &Cells,
    out: &mut ModelConfig,
    w: &WallEnergies,
    feet_at: &[Vec<Foot>],
) -> (usize, f64) {
    let (em, sim, layout) = (t.em, t.sim, t.layout);
    let (np, nd, nb, first_bin, mu) = (t.np, t.nd, t.nb, t.first_bin, t.mu);
    let (ws, wd) = (&w.ws, &w.wd);
    let mut diffuse_cells = 0;
    let mut sigma_d = 0.0;
    if let (Some(dm), Some(_)) = (out.diffuse.as_mut(), w.unit.as_ref()) {
        let mut r = Vec::new();
        for p in 0..np {
            let (at, heading) = sim.pose(p);
            for d in 0..nd {
                let ang = heading.to_radians() + em.angles_rel_deg[d].to_radians();
                if near_foot(feet_at, p, ang) || !em.has(p, d) {
                    continue;
                }
                let Some((range, _, _)) = layout.first_hit(at, ang) else {
                    continue;
                };
                let b = t.bin_of(crate::units::delay_s(range));
                if b < first_bin as isize || b >= nb as isize {
                    continue;
                }
                let k = d * nb + b as usize;
                // the diffuse part: what the specular returns leave, over a unit wall
                if wd[p][k] < mu {
                    continue;
                }
                r.push((t.sig(p, d, b as usize) - ws[p][k]) / wd[p][k]);
            }
        }
        diffuse_cells = r.len();
        if let Some(m) = median(&r) {
            sigma_d = (m / std::f64::consts::LN_2).max(1e-9);
            dm.wall_rcs_per_m = Quantity {
                value: sigma_d,
                n: Some(diffuse_cells),
                interval: None,
                ks: None,
                ks_p: None,
                ..dm.wall_rcs_per_m.clone()
            };
        }
    }
    (diffuse_cells, sigma_d)
}

/// Step 2b (module docs): takes the cells, the walls' expected energies, each pose's
/// normal-incidence points and σ′; gives the ratios r of the corners (`[0]`) and of the
/// edges (`[1]`).
fn vertex_ratios(
    t: &Cells,
    w: &WallEnergies,
    feet_at: &[Vec<Foot>],
    sigma_d: f64,
) -> [Vec<f64>; 2] {
    let (em, sim, layout) = (t.em, t.sim, t.layout);
    let (np, nb, first_bin) = (t.np, t.nb, t.first_bin);
    let (ws, wd) = (&w.ws, &w.wd);
    let verts = vertices(layout);
    let mut by_kind: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for p in 0..np {
        let (at, heading) = sim.pose(p);
        for (i, v) in verts.iter().enumerate() {
            let Some((r, bearing)) = vertex_seen(layout, at, v) else {
                continue;
            };
            let rel = wrap_rad(bearing - heading.to_radians()).to_degrees();
            let Some(d) = t.nearest(rel) else { continue };
            if !em.has(p, d) {
                continue; // no sweep there
            }
            if near_foot(feet_at, p, bearing) {
                continue;
            }
            let b = t.bin_of(crate::units::delay_s(r));
            if b < first_bin as isize + 1 || b + 1 >= nb as isize {
                continue;
            }
            let u = sim.expected_profile(p, d, &[vertex_ray(i, v, r, bearing, 1.0, 0.0)]);
            let (lo, hi) = ((b - 1) as usize, (b + 1) as usize);
            let (k, umax) = (lo..=hi)
                .map(|k| (k, u[k]))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .expect("three bins");
            if umax <= 0.0 {
                continue;
            }
            let kk = d * nb + k;
            let excess = t.sig(p, d, k) - sigma_d * wd[p][kk] - ws[p][kk];
            by_kind[(v.kind == VertexKind::Edge) as usize].push(excess / umax);
        }
    }
    by_kind
}

/// Step 3 (module docs): takes the cells, the model with its walls' levels, |Γ| (and `g`,
/// 0 for none) and the table's mean signal bins; gives (σ, whether it stopped at an end of
/// its range, the model's mean signal bins there; NaN when the search did not run).
fn cluster_sigma(
    t: &Cells,
    out: &ModelConfig,
    gamma: Option<f64>,
    g: f64,
    measured: f64,
) -> Result<(f64, bool, f64)> {
    let (em, sim) = (t.em, t.sim);
    let (np, nd, nb, first_bin, mu) = (t.np, t.nd, t.nb, t.first_bin, t.mu);
    let mut base = out.clone();
    if !g.is_finite() || gamma.is_none() {
        base.walls = None;
    }
    let usable = {
        let mut m = base.clone();
        m.cluster_rrcs.value = 1.0;
        m.require_estimable(&Default::default()).is_ok()
    };
    // enough draws for LEVEL_POSES pose-draws (at least 4, at most the seeds)
    let draws = LEVEL_POSES.div_ceil(np.max(1)).clamp(4, LEVEL_SEEDS.len());
    let (lo, hi) = (1e-6f64, SIGMA_REF);
    if !usable || !measured.is_finite() || !out.cluster_rrcs.value.is_finite() {
        return Ok((out.cluster_rrcs.value, true, f64::NAN));
    }
    // every draw's energies as quadratics in the clusters' amplitude, the clusters at the
    // bracket's top (their cull at its largest), so one pass reads the signal bins at
    // every σ of the bracket; draws in parallel, each its own crossings (the bytes do not
    // depend on the thread count)
    let threshold = 10.0 * mu;
    let missing = |i: usize| em.meta.is_missing(i / nd, i % nd);
    let per_draw = (LEVEL_SEEDS[..draws].par_iter())
        .map(|&s| draw_crossings(sim, &base, s, nb, first_bin, threshold, &missing))
        .collect::<Result<Vec<_>>>()?;
    Ok(Crossings::merge(per_draw).solve(measured, lo, hi))
}

/// σ_ref of the quadratics, m²: the top of the search's bracket (where synth's cull keeps
/// the most of the clusters' rays).
const SIGMA_REF: f64 = 10.0;

/// The crossings of one draw (`seed`) of `base` with its clusters at [`SIGMA_REF`]
/// (profiles of `nb` bins, counted from `first_bin` against `threshold`, `missing(i)` for
/// profile i without a sweep).
fn draw_crossings(
    sim: &EnergySimulator,
    base: &ModelConfig,
    seed: u64,
    nb: usize,
    first_bin: usize,
    threshold: f64,
    missing: &(impl Fn(usize) -> bool + Sync),
) -> Result<Crossings> {
    let mut m = base.clone();
    m.cluster_rrcs.value = SIGMA_REF;
    let fixed = sim.layout_rays(&m, seed)?;
    let q = sim.energy_quadratics(&m, seed, &fixed)?;
    Ok(Crossings::of(
        &q, nb, first_bin, threshold, SIGMA_REF, missing,
    ))
}

/// The signal bins of a set of draws at every σ: each bin's energy is a quadratic in
/// s = √(σ/σ_ref) ([`EnergySimulator::energy_quadratics`]), so whether it is above the
/// threshold changes at most at its two roots; the count is the bins above at σ → 0 plus
/// the changes (σ, ±1) at or below σ.
#[derive(Debug, Default)]
struct Crossings {
    /// Bins above the threshold as σ → 0 (s = 0).
    above: i64,
    /// Profiles counted (those with a sweep).
    profiles: usize,
    /// (σ, +1 or −1): where a bin crosses the threshold upwards or downwards.
    changes: Vec<(f64, i8)>,
}

impl Crossings {
    /// The crossings of the quadratics `q` (profiles of `nb` bins; `missing(i)` for
    /// profile i with no sweep, which is not counted), bins from `first_bin`, threshold
    /// `t`, the quadratics' σ_ref `sigma_ref`. A bin A + 2Bs + Cs² > t with C > 0 holds
    /// outside the roots s₁ ≤ s₂ of Cs² + 2Bs + (A − t) (everywhere when they are not
    /// real): above at s = 0 when A > t, down at s₁ > 0, up at s₂ > 0.
    fn of(
        q: &[[f64; 3]],
        nb: usize,
        first_bin: usize,
        t: f64,
        sigma_ref: f64,
        missing: impl Fn(usize) -> bool,
    ) -> Crossings {
        let mut out = Crossings::default();
        for (i, prof) in q.chunks(nb.max(1)).enumerate() {
            if missing(i) {
                continue;
            }
            out.profiles += 1;
            for &[a, b, c] in &prof[first_bin.min(nb)..] {
                let a0 = a - t;
                if a0 > 0.0 {
                    out.above += 1;
                }
                if c <= 0.0 {
                    continue;
                }
                let disc = b * b - c * a0;
                if disc <= 0.0 {
                    continue;
                }
                // the roots without cancellation: s₁s₂ = (A − t)/C
                let qq = -(b + b.signum() * disc.sqrt());
                let (r1, r2) = if qq == 0.0 {
                    (0.0, 0.0)
                } else {
                    let (x, y) = (qq / c, a0 / qq);
                    (x.min(y), x.max(y))
                };
                if r1 > 0.0 {
                    out.changes.push((sigma_ref * r1 * r1, -1));
                }
                if r2 > 0.0 {
                    out.changes.push((sigma_ref * r2 * r2, 1));
                }
            }
        }
        out
    }

    /// The crossings of several sets of draws together, sorted by σ.
    fn merge(parts: Vec<Crossings>) -> Crossings {
        let mut out = Crossings::default();
        for p in parts {
            out.above += p.above;
            out.profiles += p.profiles;
            out.changes.extend(p.changes);
        }
        out.changes
            .sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        out
    }

    /// (σ, whether it is an end of [lo, hi], the mean signal bins there): the smallest σ in
    /// [lo, hi] at which the mean signal bins per profile reaches `measured`; `lo` when it
    /// is already reached there, `hi` when it is not reached below `hi`.
    fn solve(&self, measured: f64, lo: f64, hi: f64) -> (f64, bool, f64) {
        let per = 1.0 / self.profiles.max(1) as f64;
        let mut n = self.above;
        let mut k = 0;
        while k < self.changes.len() && self.changes[k].0 <= lo {
            n += self.changes[k].1 as i64;
            k += 1;
        }
        if n as f64 * per >= measured {
            return (lo, true, n as f64 * per);
        }
        // every change at one σ applied before the mean there is read
        let rest = &self.changes[k..];
        let mut i = 0;
        while i < rest.len() {
            let sigma = rest[i].0;
            if sigma.is_nan() || sigma > hi {
                break;
            }
            while i < rest.len() && rest[i].0 == sigma {
                n += rest[i].1 as i64;
                i += 1;
            }
            if n as f64 * per >= measured {
                return (sigma, false, n as f64 * per);
            }
        }
        (hi, true, n as f64 * per)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The wiring of step 3: one draw's crossings on the corridor (its layout, the Table 1
    /// model with `[diffuse]` and `[walls]` off, its recorded noise), a profile without a
    /// sweep and the first bins left out, give at σ_ref the count of `signal_bins` on
    /// `synth`'s own energies there with that profile masked.
    #[test]
    fn one_draw_s_crossings_count_synth_s_signal_bins_at_sigma_ref() {
        use crate::campaign::manifest::Campaign;
        let p = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/corridor/campaign.toml"
        );
        let c = Campaign::load(std::path::Path::new(p)).unwrap();
        let sim = EnergySimulator::new(&c, &SynthParams::default().check().unwrap()).unwrap();
        let (_, nd, nb) = sim.shape();
        let (mu, _) = sim.noise();
        let mut base = ModelConfig::table1_defaults();
        base.diffuse = None;
        base.walls = None;
        let (first_bin, threshold) = (25, 10.0 * mu);
        let gone = 3 * nd + 7;
        let missing = |i: usize| i == gone;
        let x = draw_crossings(&sim, &base, 11, nb, first_bin, threshold, &missing).unwrap();
        let x = Crossings::merge(vec![x]);
        let mut m = base.clone();
        m.cluster_rrcs.value = SIGMA_REF;
        let mut e = sim.energies(&m, 11).unwrap();
        e[gone * nb..(gone + 1) * nb].fill(f64::NAN);
        let (want, profiles) = signal_bins(&e, nb, first_bin, mu);
        assert_eq!(x.profiles, profiles);
        let (sigma, at_end, mean) = x.solve(f64::INFINITY, 1e-6, SIGMA_REF);
        assert!(sigma == SIGMA_REF && at_end);
        let got = mean * profiles as f64;
        eprintln!("signal bins at σ_ref: crossings {got}, synth {want}");
        assert!(want > 100, "{want}");
        assert!(
            (got - want as f64).abs() <= 1e-6 * want as f64 + 1.0,
            "{got} vs {want}"
        );
    }

    /// Crossings read the signal bins of quadratic energies at every σ as counting them
    /// there does, and `solve` gives the smallest σ at which the mean reaches the target.
    #[test]
    fn crossings_count_the_bins_above_at_every_sigma() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (nb, first, t, sigma_ref) = (40, 3, 1.0, 10.0);
        let q: Vec<[f64; 3]> = (0..6 * nb)
            .map(|i| {
                let a: f64 = rng.gen_range(0.0..3.0);
                let b: f64 = rng.gen_range(-1.0..1.0);
                // some bins without any cluster energy
                let c: f64 = if i % 7 == 0 {
                    0.0
                } else {
                    rng.gen_range(0.0..4.0)
                };
                [
                    a,
                    if c == 0.0 {
                        0.0
                    } else {
                        b * c.sqrt() * a.sqrt()
                    },
                    c,
                ]
            })
            .collect();
        // profile 2 has no sweep
        let missing = |i: usize| i == 2;
        let x = Crossings::merge(vec![Crossings::of(&q, nb, first, t, sigma_ref, missing)]);
        assert_eq!(x.profiles, 5);
        let direct = |sigma: f64| -> f64 {
            let s = (sigma / sigma_ref).sqrt();
            let n = (q.chunks(nb).enumerate())
                .filter(|(i, _)| !missing(*i))
                .flat_map(|(_, p)| &p[first..])
                .filter(|[a, b, c]| a + 2.0 * b * s + c * s * s > t)
                .count();
            n as f64 / 5.0
        };
        let mut downs = 0;
        for k in 0..60 {
            let sigma = 1e-6 * 10f64.powf(k as f64 / 8.3);
            let (mut n, mut seen) = (x.above, 0);
            for &(sg, dn) in &x.changes {
                if sg <= sigma {
                    n += dn as i64;
                    seen += usize::from(dn < 0);
                }
            }
            downs = downs.max(seen);
            assert_eq!(n as f64 / 5.0, direct(sigma), "σ = {sigma:e}");
        }
        // bins that dip below and come back (B < 0) are among them
        assert!(downs > 0);
        // solve: the smallest σ at which the mean reaches the target
        let (bottom, top) = (direct(1e-6), direct(10.0));
        assert!(top > bottom + 1.0, "{bottom} {top}");
        for target in [bottom + 0.1, 0.5 * (bottom + top), top - 0.1] {
            let (sigma, at_end, mean) = x.solve(target, 1e-6, 10.0);
            assert!(!at_end);
            // at σ the bin that crosses sits on the threshold: read just above it
            assert!((mean - direct(sigma * (1.0 + 1e-9))).abs() < 1e-9, "{mean}");
            assert!(mean >= target);
            assert!(
                direct(sigma * (1.0 - 1e-9)) < target,
                "{target}: σ {sigma:e}"
            );
        }
        let (sigma, at_end, mean) = x.solve(0.0, 1e-6, 10.0);
        assert!(sigma == 1e-6 && at_end && (mean - bottom).abs() < 1e-9);
        let (sigma, at_end, mean) = x.solve(1e9, 1e-6, 10.0);
        assert!(sigma == 10.0 && at_end && (mean - top).abs() < 1e-9);
    }
}
