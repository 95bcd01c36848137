//! The angle of a CLEAN peak near either end of a mechanical scan.
//!
//! A peak within 20° (at least two beams) of either end of the scan may come from a source
//! beyond the scanned sector, behind the device's half-plane: such a source is seen through
//! the edge beams' main lobe and side lobes, and its strongest beam need not be the edge
//! beam, so the parabola through the peak's beams cannot place it. Its angle is fitted
//! (0.05° grid, from half a step inward of the peak's beam to 30° beyond the edge) to the
//! beam-space signature: the energies, relative to the peak, of the beams from the edge to
//! 20° inward of the peak, against the two-way pattern's prediction (least squares in dB;
//! an observation below the floor only bounds the ratio).
//!
//! * A component found beyond the sector (more than half a step outside) is subtracted with
//!   that footprint but not reported (its angle is not measured).
//! * A peak inside the sector, not in the edge beam, keeps its parabola angle.
//! * Electronic steering, or a scan of two beams or fewer: the parabola angle stands.

use super::footprint::Footprint;
use super::PositionView;
use crate::campaign::manifest::Steering;
use crate::units::db;

/// Grid step of the signature fit, degrees.
const FIT_STEP_DEG: f64 = 0.05;

/// The scan's end near beam `d` (within 20°, at least two beams): Some(the inward direction
/// of the scan, +1 from the first beam, −1 from the last) with the number of beams in 20°.
fn near_edge(nd: usize, d: usize, step: f64) -> (Option<i64>, usize) {
    let nj = ((20.0 / step.abs()).ceil() as usize).max(2);
    let near = if d < nj {
        Some(1i64)
    } else if d + nj >= nd {
        Some(-1i64)
    } else {
        None
    };
    (near, nj)
}

/// The angle (deg, relative) of the peak at (d, b) and whether it lies beyond the scanned
/// sector; `theta_parabola` is the parabola's angle.
pub(crate) fn edge_angle(
    v: &PositionView,
    fp: &Footprint,
    d: usize,
    b: usize,
    theta_parabola: f64,
) -> (f64, bool) {
    let nd = v.nd;
    let (near, nj) = near_edge(nd, d, v.step);
    let (Steering::Mechanical, true, Some(inward)) = (fp.steering, nd > 2, near) else {
        return (theta_parabola, false);
    };
    let angles = v.angles();
    let edge_d: i64 = if inward == 1 { 0 } else { nd as i64 - 1 };
    let last = (d as i64 + inward * nj as i64).clamp(0, nd as i64 - 1);
    let beams: Vec<usize> = (edge_d.min(last)..=edge_d.max(last))
        .filter(|&j| j != d as i64)
        .map(|j| j as usize)
        .collect();
    let l0 = v.log_energy(v.energy(d, b));
    let obs: Vec<f64> = beams
        .iter()
        .map(|&j| v.log_energy(v.energy(j, b)) - l0)
        .collect();
    let edge = angles[edge_d as usize];
    let start = angles[d] + inward as f64 * 0.5 * v.step.abs();
    // below the floor an observation only bounds the ratio
    let floor_rel = v.log_energy(v.floor * 1e-3) - l0;
    let mut theta = theta_parabola;
    let mut best_err = f64::INFINITY;
    // from half a step inward of the peak's beam to 30° beyond the edge
    let span = (start - (edge - inward as f64 * 30.0)).abs();
    for i in 0..=((span / FIT_STEP_DEG) as i64) {
        let th = start - inward as f64 * i as f64 * FIT_STEP_DEG;
        let w0 = fp.w(th, d, angles[d]);
        if w0 <= 0.0 {
            continue;
        }
        let mut err = 0.0;
        for (&dj, o) in beams.iter().zip(&obs) {
            let m = db(fp.w(th, dj, angles[dj])) - db(w0);
            err += (o - m.max(o.min(floor_rel))).powi(2);
        }
        if err < best_err {
            best_err = err;
            theta = th;
        }
    }
    let outside = (theta - edge) * (inward as f64) < -0.5 * v.step.abs();
    if !outside && d as i64 != edge_d {
        // inside the sector the parabola through the peak's beams stands
        theta = theta_parabola;
    }
    (theta, outside)
}
