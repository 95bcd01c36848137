//! The layout's specular returns in the statistical model (`[walls]` of the model file,
//! [`WallModel`]): what follows from the geometry once the walls' reflection is known.
//!
//! Takes |Γ| (`walls.specular_gamma`) and the layout; gives, per pose, one ray per wall
//! whose normal-incidence point the pose sees ([`specular_rays`]), in the units of the
//! clusters' rays ([`SeenRay`]: received power G²λ²|A|²).
//!
//! * **Image method, monostatic** (DESIGN §2 "Scattering"): the pose sees wall w's mirror
//!   image of itself when the foot of the perpendicular from the pose onto the wall's line
//!   lies on the segment, the pose is on the wall's free side, at least 5 cm away, and the
//!   segment pose → foot crosses no other wall (1 mm slack; [`Layout::feet`], the
//!   simulator's rule too). The ray arrives from the
//!   foot's bearing at τ = 2d/c with amplitude G·λ·|Γ|/(4π·2d), i.e.
//!   |A|² = |Γ|² / ((4π)²·4d²) (falls as d⁻², not d⁻⁴: a mirror, not a point).
//! * **|Γ| per layout material** (the GeoJSON's `properties.material` names which walls
//!   are alike; their permittivities are never read: the model knows what the data told
//!   it), `specular_gamma` for a material without its own value; frequency- and
//!   angle-independent (only normal incidence reaches a monostatic radar), phase π (a
//!   reflection off a denser medium).
//! * **Vertices** ([`vertices`]): every vertex of the layout's rings is a point scatterer,
//!   a concave corner of the perimeter (a dihedral, `walls.corner_rcs`) or an edge (every
//!   other vertex, `walls.edge_rcs`), seen when not behind a wall (1 mm slack) and at least
//!   5 cm away, |A|² = σ/((4π)³d⁴), a phase uniform per vertex and draw.
//! * The estimators of |Γ| and the vertices' σ from a measured table are in
//!   [`super::levels`].

use super::channel::{RaySource, SeenRay};
use crate::campaign::layout::Layout;
use geo::Coord;
use std::f64::consts::PI;

pub use crate::model::file::WallModel;

pub use crate::campaign::layout::Foot;

/// The class of a layout vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VertexKind {
    /// A concave corner of the perimeter seen from the room (a dihedral).
    Corner,
    /// Any other ring vertex (a convex edge).
    Edge,
}

/// A vertex of the layout's rings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Where, m.
    pub pos: Coord<f64>,
    /// Its class.
    pub kind: VertexKind,
}

/// The vertices of the layout's rings (perimeter first, then obstacles, ring order): a
/// left turn of the counter-clockwise perimeter is a corner, every other vertex an edge.
pub fn vertices(layout: &Layout) -> Vec<Vertex> {
    let rings = std::iter::once((&layout.perimeter, true))
        .chain(layout.obstacles.iter().map(|o| (&o.polygon, false)));
    let mut out = Vec::new();
    for (poly, is_perimeter) in rings {
        let ring = &poly.exterior().0;
        let n = ring.len().saturating_sub(1);
        for i in 0..n {
            let a = ring[(i + n - 1) % n];
            let v = ring[i];
            let b = ring[(i + 1) % n];
            let cross = (v.x - a.x) * (b.y - v.y) - (v.y - a.y) * (b.x - v.x);
            out.push(Vertex {
                pos: v,
                kind: if is_perimeter && cross > 0.0 {
                    VertexKind::Corner
                } else {
                    VertexKind::Edge
                },
            });
        }
    }
    out
}

/// A vertex seen from `at`: (index, distance m, bearing rad), or None when closer than
/// 5 cm or behind a wall (1 mm slack, so the vertex's own walls do not hide it).
pub fn vertex_seen(layout: &Layout, at: Coord<f64>, v: &Vertex) -> Option<(f64, f64)> {
    let d = v.pos - at;
    let r = d.x.hypot(d.y);
    if r < 0.05 || layout.occluded(at, v.pos, 1e-3) {
        return None;
    }
    Some((r, d.y.atan2(d.x)))
}

/// The phase of vertex `i` in a draw of seed `seed` (uniform on [0, 2π)).
pub fn vertex_phase(seed: u64, i: usize) -> f64 {
    let mut x = seed ^ 0x5665_7274_6578_0000 ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 31;
    (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 * PI
}

/// The vertex rays seen from `at` with the σ of `walls` (none for a class without one),
/// phases from `seed`: |A|² = σ / ((4π)³ d⁴), the radar equation of a point.
pub fn vertex_rays(layout: &Layout, at: Coord<f64>, walls: &WallModel, seed: u64) -> Vec<SeenRay> {
    let (c, e) = (
        walls.corner_rcs.as_ref().map(|q| q.value),
        walls.edge_rcs.as_ref().map(|q| q.value),
    );
    if c.is_none() && e.is_none() {
        return Vec::new();
    }
    vertices(layout)
        .iter()
        .enumerate()
        .filter_map(|(i, v)| {
            let sigma = match v.kind {
                VertexKind::Corner => c?,
                VertexKind::Edge => e?,
            };
            let (r, bearing) = vertex_seen(layout, at, v)?;
            Some(vertex_ray(i, v, r, bearing, sigma, vertex_phase(seed, i)))
        })
        .collect()
}

/// Every geometry ray of `walls` seen from `at`: the specular returns, then the vertices.
pub fn geometry_rays(
    layout: &Layout,
    at: Coord<f64>,
    walls: &WallModel,
    seed: u64,
) -> Vec<SeenRay> {
    let mut r = specular_rays(layout, at, walls);
    r.extend(vertex_rays(layout, at, walls, seed));
    r
}

/// |A|² of a specular return at distance `d_m` with reflection magnitude `gamma`.
pub fn specular_amp2(gamma: f64, d_m: f64) -> f64 {
    gamma * gamma / ((4.0 * PI).powi(2) * 4.0 * d_m * d_m)
}

/// The specular ray of foot `f` with reflection magnitude `gamma` and phase `phase`.
pub fn specular_ray(f: &Foot, gamma: f64, phase: f64) -> SeenRay {
    SeenRay {
        source: RaySource::Specular(f.wall),
        tau_s: crate::units::delay_s(f.d_m),
        theta: f.bearing,
        amp2: specular_amp2(gamma, f.d_m),
        pos: f.pos,
        phase,
    }
}

/// The specular rays seen from `at`, each wall's |Γ| from `walls` (by its material).
pub fn specular_rays(layout: &Layout, at: Coord<f64>, walls: &WallModel) -> Vec<SeenRay> {
    layout
        .feet(at)
        .iter()
        .map(|f| specular_ray(f, walls.gamma(&layout.walls[f.wall].material), PI))
        .collect()
}

/// The ray of vertex `i` at `v` seen at range `r_m` and bearing `bearing` (rad), with σ
/// `sigma` (m²) and phase `phase`: |A|² = σ/((4π)³r⁴).
pub fn vertex_ray(i: usize, v: &Vertex, r_m: f64, bearing: f64, sigma: f64, phase: f64) -> SeenRay {
    SeenRay {
        source: RaySource::Vertex(i),
        tau_s: crate::units::delay_s(r_m),
        theta: bearing,
        amp2: sigma / ((4.0 * PI).powi(3) * r_m.powi(4)),
        pos: v.pos,
        phase,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corridor_pose_sees_both_side_walls() {
        let p = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/corridor/layout.geojson"
        );
        let layout = Layout::load(std::path::Path::new(p)).unwrap();
        let at = Coord { x: 0.5, y: -0.3 };
        let f = layout.feet(at);
        // the south wall (y = −1) at 0.7 m and the north wall (y = 1) at 1.3 m, the back
        // wall (x = −1) at 1.5 m
        let mut d: Vec<f64> = f.iter().map(|f| f.d_m).collect();
        d.sort_by(f64::total_cmp);
        for want in [0.7, 1.3, 1.5] {
            assert!(d.iter().any(|x| (x - want).abs() < 1e-9), "{d:?}");
        }
        let south = f.iter().find(|f| (f.d_m - 0.7).abs() < 1e-9).unwrap();
        assert!((south.bearing + PI / 2.0).abs() < 1e-9);
        let w = WallModel {
            specular_gamma: crate::model::file::Quantity::new(0.5, "1", "constant"),
            material_gamma: Default::default(),
            corner_rcs: None,
            edge_rcs: None,
        };
        let r = specular_rays(&layout, at, &w);
        let a = r
            .iter()
            .find(|r| r.source == RaySource::Specular(south.wall))
            .unwrap();
        assert!((a.amp2 - 0.25 / ((4.0 * PI).powi(2) * 4.0 * 0.49)).abs() < 1e-15);
    }
}
