//! The dense (diffuse) component of the statistical model: the walls' diffuse returns,
//! drawn when the model file has a `[diffuse]` section ([`DiffuseModel`]).
//!
//! Takes the `[diffuse]` quantities, the layout, the band's bandwidth B and the seed;
//! gives one point scatterer per range cell of every wall ([`DiffuseWalls::draw`]) and, per
//! pose, the diffuse rays it sees ([`DiffuseWalls::rays_from`]), in the units of the
//! clusters' rays ([`SeenRay`]: received power G²λ²|A|²).
//!
//! * **Cells**: a wall of length L (every segment of `layout.walls`, perimeter and
//!   obstacles) is cut into n = ⌈L/Δ⌉ cells of Δ = c/(2B) (one range cell of wall length;
//!   the last one shorter), cell k of length ℓ_k = min(Δ, L − kΔ).
//! * **One point per cell**: at a uniform random position in the cell, with a complex
//!   Gaussian amplitude x_k (Rayleigh: the sum of many sub-scatterers): |x_k|² ~
//!   Exp(mean σ'·ℓ_k), σ' = `wall_rcs_per_m` (m²/m, at normal incidence), arg x_k ~ U[0, 2π).
//! * **Seen from a pose** p when p is on the wall's free side ((p − s_k)·n̂ > 0, n̂ the
//!   free-side unit normal), at least 5 cm away, and the segment p → s_k crosses no wall
//!   (1 mm slack). The ray has d = |s_k − p|, τ = 2d/c, θ = atan2(s_k − p),
//!   cos ψ = (p − s_k)·n̂/d (incidence from the wall normal) and, by the radar equation
//!   (absolute, not relative to the first cluster as the clusters' Γ law),
//!   |A|² = |x_k|²·cos^n ψ / ((4π)³ d⁴), n = `lambert_exponent`; its phase arg x_k is added
//!   to the path phase, so in the CIR the point is a = ḡ(θ_arr)·|A|·e^{j(arg x_k − 2πf_c(τ + τ_g))}
//!   (DESIGN §2 "Scattering"). Averaged over the draw the points add in power: a bin's mean
//!   signal energy is Σ_k ḡ²(θ_k)·E|A_k|²·e_b(τ_k), e_b a unit echo's energy in bin b —
//!   the radar equation for σ'·(wall length per bin) through the two-way pattern.
//! * **Culls** (the points are many, ≈ 40 per metre of wall at B = 6 GHz): a point with
//!   ḡ_max²·|A|² < cull·N0·TW (too weak in any direction; ḡ_max the pattern's peak) is
//!   dropped before the occlusion test; in each direction a point with ḡ²|A|² below it is
//!   skipped as the cluster rays are; and a point's kernel is summed only out to the
//!   delay beyond which the kernel's tail envelope r_max(t)²·ḡ²|A|² < cull·N0·TW.
//! * **Seeds**: the walls come from their own ChaCha stream (seed ^ "Diffuse"), so a model
//!   without `[diffuse]` draws exactly the clusters (and bytes) it drew before.
//! * `power_share` and `decay` describe fitted data and are not drawn from.

use super::channel::{RaySource, SeenRay};
use crate::campaign::layout::Layout;
use crate::error::{Error, Result};
use crate::model::file::DiffuseModel;
use crate::units::C0;
use geo::Coord;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Key of the walls' ChaCha stream (xor-ed into the seed): "Diffuse\0".
const STREAM: u64 = 0x4469_6666_7573_6500;

/// One diffuse point scatterer of a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffusePoint {
    /// Wall (index into the layout's walls).
    pub wall: usize,
    /// Position, m.
    pub pos: Coord<f64>,
    /// The wall's free-side unit normal.
    pub normal: Coord<f64>,
    /// |x|², m² (σ of the point at normal incidence).
    pub sigma_m2: f64,
    /// arg x, rad.
    pub phase: f64,
}

/// One range cell of a wall: arc length a to a + l along a wall of length `len`.
struct Cell<'a> {
    wall: usize,
    line: &'a geo::Line<f64>,
    normal: Coord<f64>,
    len: f64,
    a: f64,
    l: f64,
}

impl Cell<'_> {
    /// The point at arc length `s` along the cell's wall.
    fn at(&self, s: f64) -> Coord<f64> {
        self.line.start + self.line.delta() * (s / self.len)
    }
}

/// The cells of Δ = `cell` of every wall of `layout`, wall by wall: n = ⌈L/Δ⌉ (a wall of
/// exactly k cells has k, not k + 1: rounding), the last one shorter.
fn cells(layout: &Layout, cell: f64) -> impl Iterator<Item = Cell<'_>> + '_ {
    layout
        .walls
        .iter()
        .enumerate()
        .filter(|(_, w)| w.length() > 0.0)
        .flat_map(move |(i, w)| {
            let len = w.length();
            let n = ((len / cell) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
            let normal = w.normal();
            (0..n).map(move |k| {
                let a = k as f64 * cell;
                Cell {
                    wall: i,
                    line: &w.line,
                    normal,
                    len,
                    a,
                    l: (len - a).min(cell),
                }
            })
        })
}

/// The drawn diffuse walls.
#[derive(Debug, Clone, PartialEq)]
pub struct DiffuseWalls {
    /// Points, wall by wall in layout order.
    pub points: Vec<DiffusePoint>,
    /// Lambertian exponent n.
    pub lambert_exponent: f64,
    /// Cell length Δ = c/(2B), m.
    pub cell_m: f64,
}

impl DiffuseWalls {
    /// Draw one point per range cell of every wall of `layout` (cells of c/(2B),
    /// B = `bandwidth_hz`). Errors name a `[diffuse]` quantity without a usable value.
    pub fn draw(
        layout: &Layout,
        model: &DiffuseModel,
        bandwidth_hz: f64,
        seed: u64,
    ) -> Result<DiffuseWalls> {
        let per_m = model.wall_rcs_per_m.value;
        if !(per_m.is_finite() && per_m >= 0.0) {
            return Err(Error::param(
                "diffuse.wall_rcs_per_m",
                format!("needs a finite value >= 0, got {per_m}"),
            ));
        }
        let n_exp = model.lambert_exponent.value;
        if !(n_exp.is_finite() && n_exp >= 0.0) {
            return Err(Error::param(
                "diffuse.lambert_exponent",
                format!("needs a finite value >= 0, got {n_exp}"),
            ));
        }
        if !(bandwidth_hz.is_finite() && bandwidth_hz > 0.0) {
            return Err(Error::param("band", "the bandwidth must be > 0"));
        }
        let cell = C0 / (2.0 * bandwidth_hz);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
        let mut points = Vec::new();
        for c in cells(layout, cell) {
            let s = c.a + c.l * rng.gen::<f64>();
            let e: f64 = -(1.0 - rng.gen::<f64>()).ln(); // Exp(1)
            let phase = 2.0 * PI * rng.gen::<f64>();
            points.push(DiffusePoint {
                wall: c.wall,
                pos: c.at(s),
                normal: c.normal,
                sigma_m2: per_m * c.l * e,
                phase,
            });
        }
        Ok(DiffuseWalls {
            points,
            lambert_exponent: n_exp,
            cell_m: cell,
        })
    }

    /// The walls' mean draw for σ′ = 1 m²/m: one point at the centre of every cell with
    /// its expected |x|² = ℓ_k (cell length), phase 0 — with the rays added in power
    /// ([`super::EnergySimulator::expected_profiles`]) it gives the expected energy of a
    /// unit wall, which the level estimator ([`super::levels`]) scales.
    pub fn unit_mean(layout: &Layout, lambert_exponent: f64, bandwidth_hz: f64) -> DiffuseWalls {
        let cell = C0 / (2.0 * bandwidth_hz);
        let points = cells(layout, cell)
            .map(|c| DiffusePoint {
                wall: c.wall,
                pos: c.at(c.a + 0.5 * c.l),
                normal: c.normal,
                sigma_m2: c.l,
                phase: 0.0,
            })
            .collect();
        DiffuseWalls {
            points,
            lambert_exponent,
            cell_m: cell,
        }
    }

    /// The diffuse rays seen from `at`, in point order: free side, ≥ 5 cm, not occluded,
    /// and |A|² ≥ `min_amp2` (the caller's cull·N0·TW / ḡ_max²).
    pub fn rays_from(&self, layout: &Layout, at: Coord<f64>, min_amp2: f64) -> Vec<SeenRay> {
        let re = 1.0 / (4.0 * PI).powi(3);
        self.points
            .par_iter()
            .filter_map(|p| {
                let v = at - p.pos;
                let d = v.x.hypot(v.y);
                if d < 0.05 {
                    return None;
                }
                let cos = (v.x * p.normal.x + v.y * p.normal.y) / d;
                if cos <= 0.0 {
                    return None;
                }
                let amp2 = p.sigma_m2 * cos.powf(self.lambert_exponent) * re / d.powi(4);
                if amp2 < min_amp2 || layout.occluded(at, p.pos, 1e-3) {
                    return None;
                }
                Some(SeenRay {
                    source: RaySource::Wall(p.wall),
                    tau_s: crate::units::delay_s(d),
                    theta: (-v.y).atan2(-v.x),
                    amp2,
                    pos: p.pos,
                    phase: p.phase,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::file::{ModelConfig, Quantity};

    fn model(per_m: f64, n: f64) -> DiffuseModel {
        DiffuseModel {
            wall_rcs_per_m: Quantity::new(per_m, "m2/m", "constant"),
            lambert_exponent: Quantity::new(n, "1", "constant"),
            power_share: Quantity::new(0.5, "1", "constant"),
            decay: Quantity::new(10.0, "ns", "exponential"),
        }
    }

    fn room() -> Layout {
        let p = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/tests/room.geojson");
        Layout::load(std::path::Path::new(p)).unwrap()
    }

    #[test]
    fn one_point_per_cell_with_the_wall_rcs() {
        let layout = room();
        let w = DiffuseWalls::draw(&layout, &model(0.02, 1.0), 6e9, 5).unwrap();
        let cell = C0 / 12e9;
        let total: f64 = layout.walls.iter().map(|w| w.length()).sum();
        let cells: usize = layout
            .walls
            .iter()
            .map(|w| (w.length() / cell).ceil() as usize)
            .sum();
        assert_eq!(w.points.len(), cells);
        // mean σ per metre of wall: 0.02 m²/m within the Exp(1) sampling error
        let s: f64 = w.points.iter().map(|p| p.sigma_m2).sum::<f64>() / total;
        assert!((s / 0.02 - 1.0).abs() < 0.05, "{s}");
        // points lie in their cells, on their wall
        for (k, p) in w.points.iter().take(100).enumerate() {
            let wall = &layout.walls[p.wall];
            let t = (p.pos - wall.line.start)
                .x
                .hypot((p.pos - wall.line.start).y);
            assert!(t >= k as f64 * cell - 1e-9 && t <= (k + 1) as f64 * cell + 1e-9);
        }
        // the seed moves the draw, the same seed does not
        assert_eq!(
            w,
            DiffuseWalls::draw(&layout, &model(0.02, 1.0), 6e9, 5).unwrap()
        );
        assert_ne!(
            w.points[0],
            DiffuseWalls::draw(&layout, &model(0.02, 1.0), 6e9, 6)
                .unwrap()
                .points[0]
        );
        let mut m = ModelConfig::table1_defaults();
        m.diffuse = Some(model(f64::NAN, 1.0));
        let e = DiffuseWalls::draw(&layout, m.diffuse.as_ref().unwrap(), 6e9, 5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("diffuse.wall_rcs_per_m"), "{e}");
    }

    #[test]
    fn rays_follow_the_radar_equation_and_the_lambert_law() {
        let layout = room();
        let w = DiffuseWalls::draw(&layout, &model(0.02, 2.0), 6e9, 1).unwrap();
        let at = Coord { x: 1.0, y: -2.0 };
        let rays = w.rays_from(&layout, at, 0.0);
        // a convex room: every point is seen from inside
        assert_eq!(rays.len(), w.points.len());
        for (r, p) in rays.iter().zip(&w.points) {
            let v = at - p.pos;
            let d = v.x.hypot(v.y);
            let cos = (v.x * p.normal.x + v.y * p.normal.y) / d;
            let want = p.sigma_m2 * cos * cos / ((4.0 * PI).powi(3) * d.powi(4));
            assert!((r.amp2 / want - 1.0).abs() < 1e-12);
            assert!((r.tau_s - 2.0 * d / C0).abs() < 1e-18);
            assert_eq!(r.source, RaySource::Wall(p.wall));
        }
        // from outside the room nothing is seen; a floor drops the weak points
        assert!(w
            .rays_from(&layout, Coord { x: 12.0, y: 0.0 }, 0.0)
            .is_empty());
        let max = rays.iter().map(|r| r.amp2).fold(0.0, f64::max);
        assert!(w.rays_from(&layout, at, max * 1.0001).is_empty());
    }
}
