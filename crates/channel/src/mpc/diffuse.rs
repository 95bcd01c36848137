//! The diffuse (dense multipath) stage: every MPC labelled discrete or diffuse from the
//! walls' predicted (delay, angle) curve and the predicted diffuse level along it.
//!
//! Takes the extracted MPCs, the campaign's poses, array and band, the energy table's bin
//! width and the layout the manifest names (an input, never the simulator's truth); gives
//! each [`Mpc`] its [`Component`] and a [`DiffuseSummary`].
//!
//! A wall is a surface of many weak scatterers: seen by a beam, it returns a continuum of
//! echoes along its curve τ_w(θ) = 2·r_w(θ)/c, r_w(θ) the range at which the ray from the
//! pose at global angle θ first meets a wall ([`Layout::first_hit`]). CLEAN cuts that
//! continuum into many MPCs of Rayleigh-distributed amplitude. An MPC at pose p, beam d
//! (angle θ_d), bin b with energy E is **diffuse** when both hold:
//! 1. *on the curve*: its range r = c·τ/2 lies within [min r_w − Δr, max r_w + Δr], the
//!    extremes over the rays θ ∈ θ̂ ± w (θ̂ the MPC's angle, w half the two-way half-power
//!    beamwidth or half the direction step, whichever is larger; Δr = `range_bins` bins of
//!    c·T_b/2): inside the beam the wall's range spreads, the more the more oblique it is;
//! 2. *at the diffuse level*: ρ = E / E₁ ≤ σ̂ · 10^(`discrete_db`/10), with E₁ the expected
//!    energy of a Lambertian wall of unit backscatter per metre (σ′ = 1 m²/m) in that cell,
//!    E₁ = Σ_φ G₀²λ² · W(φ − θ_d) · K(τ(φ)/T_b − b) · r(φ)·Δφ / ((4π)³ r(φ)⁴)
//!    (W the two-way pattern and K the window kernel of the CLEAN footprint, both
//!    normalised to 1 at their peaks; the wall element ds = r·Δφ/cos α carries
//!    σ′·ds·cos α: Lambert's law, power ∝ cos α), summed over the rays φ at 0.1° out to
//!    the farthest angle where W reaches 10⁻³ (of the first beam's table); and σ̂ = median(ρ over the campaign's on-curve
//!    MPCs) / ln 2, the mean of an exponential law (the energy of a Rayleigh cell) read from
//!    its median so the discrete MPCs among them move it only by their share.
//!
//! The level is read only when the campaign has a dense component to read it from: at least
//! [`MIN_ON_CURVE`] on-curve MPCs whose 10·log10 ρ have an interquartile range of at most
//! [`MAX_IQR_DB`] (twice an exponential law's 6.83 dB); otherwise every MPC stays discrete (a scene
//! without diffuse walls, such as `synth` data from a model without `[diffuse]`).
//!
//! Everything else is discrete: off the curve (clutter in the room, multi-bounce paths
//! arriving after the wall), or on it but `discrete_db` (default 10 dB) above the diffuse
//! level — corners, edges, the specular point, objects on the wall. For an exponential
//! energy the chance of a diffuse cell above 10× its mean is e⁻¹⁰ ≈ 5·10⁻⁵.
//!
//! Why this method and not a dense component in the mixture (mclust's noise component,
//! RIMAX's dense multipath component): the layout is an input of every campaign, the wall
//! curve is a hard geometric fact the mixture would have to learn per position from a few
//! dozen MPCs, and the predicted level E₁ carries the pattern and range dependence a
//! background density could not. Its weakness: a discrete scatterer within Δr of a wall
//! and less than `discrete_db` above the diffuse level is called diffuse. Measurements
//! against the simulator's per-path truth are in `docs/mpc.md`.

use super::footprint::Footprint;
use super::{Component, Mpc, WallCell};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::Campaign;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use crate::pattern::ArrayPattern;
use crate::units::{range_m, C0};
use geo::Coord;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Parameters of the diffuse stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseParams {
    /// Label MPCs at all (false: every MPC discrete).
    pub enabled: bool,
    /// An on-curve MPC this far above the diffuse level is discrete, dB (≥ 0).
    pub discrete_db: f64,
    /// Range tolerance around the wall curve, bins (> 0).
    pub range_bins: f64,
}

impl Default for DiffuseParams {
    fn default() -> Self {
        DiffuseParams {
            enabled: true,
            discrete_db: 10.0,
            range_bins: 2.0,
        }
    }
}

/// Checked [`DiffuseParams`].
pub type DiffuseValid = Valid<DiffuseParams>;

impl ParamGuard for DiffuseParams {
    type Checked = DiffuseValid;

    /// `discrete_db` finite and ≥ 0, `range_bins` finite and > 0.
    fn check(&self) -> Result<DiffuseValid> {
        if !(self.discrete_db.is_finite() && self.discrete_db >= 0.0) {
            return Err(Error::param(
                "diffuse_db",
                format!(
                    "must be finite and >= 0 dB (--diffuse-db), got {}",
                    self.discrete_db
                ),
            ));
        }
        if !(self.range_bins.is_finite() && self.range_bins > 0.0) {
            return Err(Error::param(
                "diffuse_range_bins",
                format!("must be finite and > 0, got {}", self.range_bins),
            ));
        }
        Ok(Valid::new(*self))
    }
}

/// What the diffuse stage found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseSummary {
    /// MPCs on a wall curve.
    pub on_curve: usize,
    /// MPCs labelled diffuse.
    pub diffuse: usize,
    /// The diffuse level σ̂ (mean backscatter per metre of wall, m²/m, under Lambert's law);
    /// NaN when no MPC lies on a curve.
    pub level_m2_per_m: f64,
}

impl DiffuseSummary {
    /// Nothing labelled (the stage off, or no MPC).
    pub fn none() -> DiffuseSummary {
        DiffuseSummary {
            on_curve: 0,
            diffuse: 0,
            level_m2_per_m: f64::NAN,
        }
    }
}

/// Step of the rays cast across a beam, degrees.
const RAY_STEP_DEG: f64 = 0.1;

/// The wall-curve geometry seen from one pose.
struct PoseView<'a> {
    layout: &'a Layout,
    at: Coord<f64>,
    heading_deg: f64,
}

impl PoseView<'_> {
    /// First-hit range along the global angle `deg`.
    fn range(&self, deg: f64) -> Option<(f64, f64)> {
        self.layout
            .first_hit(self.at, deg.to_radians())
            .map(|(r, _, cos)| (r, cos))
    }

    /// (min, max) first-hit range over the rays `deg ± w`.
    fn span(&self, deg: f64, w: f64) -> Option<(f64, f64)> {
        let n = (2.0 * w / RAY_STEP_DEG).ceil().max(1.0) as usize;
        let mut out: Option<(f64, f64)> = None;
        for i in 0..=n {
            let a = deg - w + 2.0 * w * i as f64 / n as f64;
            if let Some((r, _)) = self.range(a) {
                out = Some(out.map_or((r, r), |(lo, hi)| (lo.min(r), hi.max(r))));
            }
        }
        out
    }
}

/// w: half the two-way half-power beamwidth or half the direction step, whichever is
/// larger, degrees (the rays cast across an MPC's bearing are θ̂ ± w).
pub(crate) fn beam_half_width_deg(fp: &Footprint, angles_rel_deg: &[f64]) -> f64 {
    let step = if angles_rel_deg.len() > 1 {
        (angles_rel_deg[1] - angles_rel_deg[0]).abs()
    } else {
        0.0
    };
    (fp.half_power_deg() / 2.0).max(step / 2.0)
}

/// Label every MPC of `mpcs` discrete or diffuse (in place).
pub(crate) fn label(
    mpcs: &mut [Mpc],
    c: &Campaign,
    angles_rel_deg: &[f64],
    bin_width_ns: f64,
    fp: &Footprint,
    params: &DiffuseValid,
) -> Result<DiffuseSummary> {
    if !params.enabled || mpcs.is_empty() {
        return Ok(DiffuseSummary::none());
    }
    let m = &c.manifest;
    let layout = Layout::load(&c.layout_path())?;
    let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
    let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
    let lc = C0 / m.band.center_hz();
    let w = beam_half_width_deg(fp, angles_rel_deg);
    let reach = fp.reach_deg(1e-3);
    let dr = params.range_bins * range_m(bin_width_ns);
    // per MPC: Some((ρ, cell)) when on a wall curve
    let rho: Vec<Option<(f64, WallCell)>> = mpcs
        .par_iter()
        .map(|x| {
            let pose = *m.poses.get(x.position)?;
            let view = PoseView {
                layout: &layout,
                at: Coord {
                    x: pose.x_m,
                    y: pose.y_m,
                },
                heading_deg: pose.heading_deg,
            };
            let r = range_m(x.delay_ns);
            let (lo, hi) = view.span(x.angle_global_deg, w)?;
            if r < lo - dr || r > hi + dr {
                return None;
            }
            let beam = angles_rel_deg.get(x.direction).copied()?;
            let e1 = view.unit_wall_energy(fp, x, beam, reach, bin_width_ns, g0 * g0 * lc * lc);
            let cos = view.range(x.angle_global_deg).map_or(1.0, |h| h.1);
            let cell = WallCell {
                unit_db: crate::units::db(e1),
                incidence_deg: cos.clamp(0.0, 1.0).acos().to_degrees(),
            };
            (e1 > 0.0).then(|| (10f64.powf(x.power_db / 10.0) / e1, cell))
        })
        .collect();
    let on: Vec<f64> = rho.iter().flatten().map(|x| x.0).collect();
    // no dense component to read a level from: every MPC stays discrete
    let level = if is_dense(&on) {
        crate::stats::upper_median(&on).map(|m| m / std::f64::consts::LN_2)
    } else {
        None
    };
    let limit = level.map(|l| l * 10f64.powf(params.discrete_db / 10.0));
    let mut diffuse = 0;
    for (x, r) in mpcs.iter_mut().zip(&rho) {
        x.wall = r.map(|r| r.1);
        x.component = match (r, limit) {
            (Some((v, _)), Some(limit)) if *v <= limit => {
                diffuse += 1;
                Component::Diffuse
            }
            _ => Component::Discrete,
        };
    }
    Ok(DiffuseSummary {
        on_curve: on.len(),
        diffuse,
        level_m2_per_m: level.unwrap_or(f64::NAN),
    })
}

/// At least [`MIN_ON_CURVE`] MPCs on the wall curves, their ratios ρ spread like the
/// energies of Rayleigh cells: the interquartile range of 10·log10 ρ of an exponential law
/// is 10·log10(ln 4 / ln(4/3)) = 6.83 dB; a spread above [`MAX_IQR_DB`] (twice that) is a
/// handful of discrete echoes near walls, not a continuum (`docs/mpc.md` has the figures).
fn is_dense(rho: &[f64]) -> bool {
    if rho.len() < MIN_ON_CURVE {
        return false;
    }
    let mut db: Vec<f64> = rho.iter().map(|r| 10.0 * r.log10()).collect();
    db.sort_by(f64::total_cmp);
    let q = |f: f64| crate::stats::sorted::quantile_nearest(&db, f).expect("non-empty");
    q(0.75) - q(0.25) <= MAX_IQR_DB
}

/// Fewest on-curve MPCs from which a diffuse level is read.
pub const MIN_ON_CURVE: usize = 20;

/// Largest interquartile range of 10·log10 ρ (dB) of a dense component.
pub const MAX_IQR_DB: f64 = 13.66;

impl PoseView<'_> {
    /// E₁: the expected energy in the MPC's cell (beam at `beam` deg relative, its bin) of
    /// a Lambertian wall of 1 m²/m, summed over the rays within `reach` degrees of the beam;
    /// `gl` = G₀²λ².
    fn unit_wall_energy(
        &self,
        fp: &Footprint,
        x: &Mpc,
        beam: f64,
        reach: f64,
        bin_width_ns: f64,
        gl: f64,
    ) -> f64 {
        let cell = Cell {
            fp,
            x,
            beam,
            reach,
            bin_width_ns,
            gl,
        };
        unit_wall_energy(self.layout, self.at, self.heading_deg, &cell, None)
    }
}

/// An MPC's cell as [`unit_wall_energy`] reads it: the footprint, the MPC, its beam (deg
/// relative), the rays' reach (deg), the bin width (ns) and G₀²λ².
pub(crate) struct Cell<'a> {
    pub(crate) fp: &'a Footprint,
    pub(crate) x: &'a Mpc,
    pub(crate) beam: f64,
    pub(crate) reach: f64,
    pub(crate) bin_width_ns: f64,
    pub(crate) gl: f64,
}

/// E₁ of the module docs for the pose at `at` with heading `heading_deg`; with
/// `fold_period_ns` = Some(T) only the rays whose wall lies beyond the unambiguous range
/// (delay ≥ T) count, each at its delay folded modulo T to the copy nearest the MPC's.
pub(crate) fn unit_wall_energy(
    layout: &Layout,
    at: Coord<f64>,
    heading_deg: f64,
    c: &Cell,
    fold_period_ns: Option<f64>,
) -> f64 {
    let n = (2.0 * c.reach / RAY_STEP_DEG).ceil() as usize;
    let dphi = RAY_STEP_DEG.to_radians();
    let k4 = (4.0 * PI).powi(3);
    (0..=n)
        .map(|i| {
            let rel = c.beam - c.reach + i as f64 * RAY_STEP_DEG;
            let Some((r, _, _cos)) = layout.first_hit(at, (heading_deg + rel).to_radians()) else {
                return 0.0;
            };
            let wgt = c.fp.w(rel, c.x.direction, c.beam);
            if wgt <= 0.0 {
                return 0.0;
            }
            let mut tau = crate::units::delay_ns(r);
            if let Some(t) = fold_period_ns {
                if tau < t {
                    return 0.0;
                }
                tau -= ((tau - c.x.delay_ns) / t).round() * t;
            }
            let k = c.fp.k(tau / c.bin_width_ns - c.x.bin as f64);
            c.gl * wgt * k * r * dphi / (k4 * r.powi(4))
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_are_checked() {
        assert!(DiffuseParams::default().check().is_ok());
        let e = DiffuseParams {
            discrete_db: -1.0,
            ..Default::default()
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(e.contains("diffuse_db") && e.contains(">= 0"), "{e}");
        let e = DiffuseParams {
            range_bins: 0.0,
            ..Default::default()
        }
        .check()
        .unwrap_err()
        .to_string();
        assert!(e.contains("diffuse_range_bins"), "{e}");
    }
}
