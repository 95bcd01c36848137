//! Propagation paths of a scene seen from one pose.
//!
//! Takes a [`Scene`] and a pose position; gives every visible [`Path1`] (delay, global
//! angle of arrival, frequency-independent amplitude A with S21 = F²·λ·A·e^{−j2πfτ}):
//! * point scatterer at range d with complex RRCS x: A = x / ((4π)^{3/2} d²), τ = 2d/c, times
//!   √cos(incidence) for diffuse wall scatterers (dropped when seen from behind);
//! * specular wall (image method, monostatic): only when the pose's foot point lies on the
//!   wall, A = Γ / (4π · 2d) at the normal-incidence distance d, Γ the Fresnel coefficient;
//! * a path is dropped when closer than 5 cm or when the segment from the pose to its
//!   anchor (the cluster centre for clutter) crosses a wall before reaching it (1 mm slack).

use super::scene::{Scatterer, ScattererKind, Scene};
use geo::Coord;
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// One propagation path seen from a pose.
#[derive(Debug, Clone, Copy)]
pub struct Path1 {
    /// Round-trip delay, s.
    pub tau_s: f64,
    /// Global angle of arrival, rad.
    pub theta: f64,
    /// Frequency-independent amplitude factor A (S21 = F²·λ·A·e^{−j2πfτ}).
    pub amp: Complex64,
    /// Index into the scatterer list (usize::MAX for specular).
    pub scatterer: usize,
    /// Kind.
    pub kind: ScattererKind,
    /// The wall of a specular path or of a diffuse wall scatterer (index into the layout's
    /// `walls`).
    pub wall: Option<usize>,
    /// Reflection point, m.
    pub pos: Coord<f64>,
}

impl Scene {
    /// Every path visible from `pose` (x, y).
    pub fn paths(&self, at: Coord<f64>) -> Vec<Path1> {
        let mut out: Vec<Path1> = self
            .scatterers
            .par_iter()
            .enumerate()
            .filter_map(|(i, s)| self.scatterer_path(at, i, s))
            .collect();
        if self.cfg.walls && self.cfg.specular {
            self.specular_paths(at, &mut out);
        }
        out
    }

    /// The path of scatterer `i` from `at`, if visible.
    fn scatterer_path(&self, at: Coord<f64>, i: usize, s: &Scatterer) -> Option<Path1> {
        let k = (4.0 * PI).powf(1.5);
        let d = s.pos - at;
        let r = d.x.hypot(d.y);
        if r < 0.05 {
            return None;
        }
        let mut amp = s.x / (k * r * r);
        if let Some(n) = s.normal {
            let cos = -(d.x * n.x + d.y * n.y) / r;
            if cos <= 0.0 {
                return None;
            }
            amp *= cos.sqrt();
        }
        let occluded = if self.cfg.walls {
            self.layout.occluded(at, s.anchor, 1e-3)
        } else {
            false
        };
        if occluded {
            return None;
        }
        Some(Path1 {
            tau_s: crate::units::delay_s(r),
            theta: d.y.atan2(d.x),
            amp,
            scatterer: i,
            kind: s.kind,
            wall: s.wall,
            pos: s.pos,
        })
    }

    /// The specular (normal-incidence) path of every wall seen from `at`, appended to `out`.
    fn specular_paths(&self, at: Coord<f64>, out: &mut Vec<Path1>) {
        for f in self.layout.feet(at) {
            let w = &self.layout.walls[f.wall];
            let gamma = self.cfg.material(&w.material).gamma();
            out.push(Path1 {
                tau_s: crate::units::delay_s(f.d_m),
                theta: f.bearing,
                amp: gamma / (4.0 * PI * 2.0 * f.d_m),
                scatterer: usize::MAX,
                kind: ScattererKind::Specular,
                wall: Some(f.wall),
                pos: f.pos,
            });
        }
    }
}
