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
//!   segment pose → foot crosses no other wall (1 mm slack). The ray arrives from the
//!   foot's bearing at τ = 2d/c with amplitude G·λ·|Γ|/(4π·2d), i.e.
//!   |A|² = |Γ|² / ((4π)²·4d²) (falls as d⁻², not d⁻⁴: a mirror, not a point).
//! * **One |Γ| for every wall**, frequency- and angle-independent (only normal incidence
//!   reaches a monostatic radar), phase π (a reflection off a denser medium). The layout's
//!   materials are not used: the model knows what the data told it, not the materials'
//!   permittivities.
//! * The estimator of |Γ| from a measured table is in [`super::levels`].

use super::channel::{RaySource, SeenRay};
use crate::campaign::layout::Layout;
use geo::Coord;
use std::f64::consts::PI;

pub use crate::campaign::modelfile::WallModel;

/// One wall's normal-incidence point seen from a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Foot {
    /// Wall index (into the layout's walls).
    pub wall: usize,
    /// The normal-incidence point, m.
    pub pos: Coord<f64>,
    /// Distance pose → foot, m.
    pub d_m: f64,
    /// Global bearing of the foot from the pose, rad.
    pub bearing: f64,
}

/// The walls whose normal-incidence point `at` sees (module docs' rule), in wall order.
pub fn feet(layout: &Layout, at: Coord<f64>) -> Vec<Foot> {
    let mut out = Vec::new();
    for (wi, w) in layout.walls.iter().enumerate() {
        let dl = w.line.delta();
        let l2 = dl.x * dl.x + dl.y * dl.y;
        if l2 <= 0.0 {
            continue;
        }
        let t = ((at.x - w.line.start.x) * dl.x + (at.y - w.line.start.y) * dl.y) / l2;
        if !(0.0..=1.0).contains(&t) {
            continue;
        }
        let foot = w.line.start + dl * t;
        let n = w.normal();
        let v = at - foot;
        let d = v.x.hypot(v.y);
        if d < 0.05 || v.x * n.x + v.y * n.y <= 0.0 || layout.occluded(at, foot, 1e-3) {
            continue;
        }
        out.push(Foot {
            wall: wi,
            pos: foot,
            d_m: d,
            bearing: (-v.y).atan2(-v.x),
        });
    }
    out
}

/// |A|² of a specular return at distance `d_m` with reflection magnitude `gamma`.
pub fn specular_amp2(gamma: f64, d_m: f64) -> f64 {
    gamma * gamma / ((4.0 * PI).powi(2) * 4.0 * d_m * d_m)
}

/// The specular rays seen from `at` with |Γ| = `gamma`.
pub fn specular_rays(layout: &Layout, at: Coord<f64>, gamma: f64) -> Vec<SeenRay> {
    feet(layout, at)
        .into_iter()
        .map(|f| SeenRay {
            source: RaySource::Specular(f.wall),
            tau_s: crate::units::delay_s(f.d_m),
            theta: f.bearing,
            amp2: specular_amp2(gamma, f.d_m),
            pos: f.pos,
            phase: PI,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corridor_pose_sees_both_side_walls() {
        let p = concat!(env!("CARGO_MANIFEST_DIR"), "/data/corridor/layout.geojson");
        let layout = Layout::load(std::path::Path::new(p)).unwrap();
        let at = Coord { x: 0.5, y: -0.3 };
        let f = feet(&layout, at);
        // the south wall (y = −1) at 0.7 m and the north wall (y = 1) at 1.3 m, the back
        // wall (x = −1) at 1.5 m
        let mut d: Vec<f64> = f.iter().map(|f| f.d_m).collect();
        d.sort_by(f64::total_cmp);
        for want in [0.7, 1.3, 1.5] {
            assert!(d.iter().any(|x| (x - want).abs() < 1e-9), "{d:?}");
        }
        let south = f.iter().find(|f| (f.d_m - 0.7).abs() < 1e-9).unwrap();
        assert!((south.bearing + PI / 2.0).abs() < 1e-9);
        let r = specular_rays(&layout, at, 0.5);
        let a = r
            .iter()
            .find(|r| r.source == RaySource::Specular(south.wall))
            .unwrap();
        assert!((a.amp2 - 0.25 / ((4.0 * PI).powi(2) * 4.0 * 0.49)).abs() < 1e-15);
    }
}
