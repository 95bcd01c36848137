//! Scan-to-map matching of a pose's echoes (issue 56, item 1's front end).
//!
//! Takes a pose's detections (the OG's per-bin detector, [`crate::og::Detector`]) as
//! points in the pose's frame, and a reference (the points of other poses placed at their
//! estimated poses); gives the pose of the scan that best fits the reference near a
//! predicted pose, and that pose's covariance.
//!
//! * A detection in bin b of direction d is the point (r cos φ, r sin φ), r = c·τ_b/2,
//!   φ the direction's angle relative to the heading. Its spread is
//!   σ = max(Δr, r·Δφ/2), Δr = c·T_b/2 the range bin and Δφ the steering grid's median
//!   spacing: the
//!   matcher cannot place an echo finer than the bin and the grid of directions.
//! * The reference is a likelihood field on a square grid: f(c) = max over reference
//!   points of exp(−d²/(2σ²)), d the distance from cell c's centre to the point
//!   (Olson, "Real-time correlative scan matching", ICRA 2009).
//! * Score of a candidate pose X: S(X) = Σ_j f(X ⊕ q_j) over the scan's points; every
//!   candidate of a grid around the prediction (±3σ of the prediction in x, y and θ;
//!   steps of one cell and of Δφ/4) is scored; the match is the best.
//! * Covariance: the candidates' weighted covariance with weights e^{S − S_max} (each
//!   point's log-likelihood taken as its field value), plus the search grid's own
//!   (step²/12) per axis. A direction along which no structure constrains the scan (a
//!   straight corridor's axis) keeps a flat score, so a wide covariance (at most the
//!   window's own, 3σ² of the prediction: known limit, docs/slam.md). Among equal best
//!   scores the one nearest the prediction is the match; a best score of 0 (no point near
//!   the map) is no match. The window is at most ±60° and 4·10⁶ candidates (refused
//!   beyond, by name).
//!
//! Choices: no constant of the scene: the spread comes from the bin and the steering
//! grid, the search from the prediction's σ, the cell is the map grid's.

use super::graph::Pose2;
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::units::C0;
use nalgebra::Matrix3;
use std::f64::consts::PI;

/// A pose's detections in its own frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Scan {
    /// (x forward, y left), m.
    pub points: Vec<[f64; 2]>,
    /// Each point's spread σ, m.
    pub sigma_m: Vec<f64>,
}

impl Scan {
    /// The detections `det` (per direction, per bin; [`crate::og::Detector::detect_pose`])
    /// of pose `p` of `em` as points (module docs).
    pub fn from_detections(em: &EnergyMatrix, det: &[Vec<bool>]) -> Scan {
        let dr = C0 * em.meta.bin_width_ns * 1e-9 / 2.0;
        let step = steering_step_rad(&em.angles_rel_deg);
        let mut s = Scan::default();
        for (d, row) in det.iter().enumerate() {
            let phi = em.angles_rel_deg[d].to_radians();
            for (b, _) in row.iter().enumerate().filter(|x| *x.1) {
                let r = C0 * em.delay_ns(b) * 1e-9 / 2.0;
                s.points.push([r * phi.cos(), r * phi.sin()]);
                s.sigma_m.push(dr.max(r * step / 2.0));
            }
        }
        s
    }
}

/// The median spacing of the steering grid, rad (π for a single direction).
pub fn steering_step_rad(angles_deg: &[f64]) -> f64 {
    let mut a: Vec<f64> = angles_deg.to_vec();
    a.sort_by(f64::total_cmp);
    let mut gaps: Vec<f64> = (a.windows(2))
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 1e-6)
        .collect();
    gaps.sort_by(f64::total_cmp);
    match gaps.get(gaps.len() / 2) {
        Some(g) => g.to_radians(),
        None => PI,
    }
}

/// The likelihood field of reference points (module docs) on a grid of `cell_m`.
#[derive(Debug, Clone)]
pub struct Field {
    x0: f64,
    y0: f64,
    cell_m: f64,
    cols: usize,
    rows: usize,
    f: Vec<f32>,
}

impl Field {
    /// The field of world points `points` with spreads `sigma_m`; None without points.
    pub fn new(points: &[[f64; 2]], sigma_m: &[f64], cell_m: f64) -> Option<Field> {
        let reach = sigma_m.iter().copied().fold(0.0, f64::max) * 3.0 + cell_m;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !lo[0].is_finite() {
            return None;
        }
        let (x0, y0) = (lo[0] - reach, lo[1] - reach);
        let cols = ((hi[0] + reach - x0) / cell_m).ceil() as usize + 1;
        let rows = ((hi[1] + reach - y0) / cell_m).ceil() as usize + 1;
        let mut f = vec![0f32; rows * cols];
        for (p, &s) in points.iter().zip(sigma_m) {
            let r = 3.0 * s;
            let (c0, c1) = (
                ((p[0] - r - x0) / cell_m).floor().max(0.0) as usize,
                ((p[0] + r - x0) / cell_m).ceil() as usize,
            );
            let (r0, r1) = (
                ((p[1] - r - y0) / cell_m).floor().max(0.0) as usize,
                ((p[1] + r - y0) / cell_m).ceil() as usize,
            );
            for row in r0..r1.min(rows) {
                let y = y0 + (row as f64 + 0.5) * cell_m;
                for col in c0..c1.min(cols) {
                    let x = x0 + (col as f64 + 0.5) * cell_m;
                    let d2 = (x - p[0]).powi(2) + (y - p[1]).powi(2);
                    let v = (-d2 / (2.0 * s * s)).exp() as f32;
                    let cell = &mut f[row * cols + col];
                    if v > *cell {
                        *cell = v;
                    }
                }
            }
        }
        Some(Field {
            x0,
            y0,
            cell_m,
            cols,
            rows,
            f,
        })
    }

    /// The field at world point (x, y) (0 off the grid).
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let (c, r) = ((x - self.x0) / self.cell_m, (y - self.y0) / self.cell_m);
        if c < 0.0 || r < 0.0 || c >= self.cols as f64 || r >= self.rows as f64 {
            return 0.0;
        }
        self.f[r as usize * self.cols + c as usize] as f64
    }

    /// S(X) = Σ_j f(X ⊕ q_j).
    pub fn score(&self, x: &Pose2, scan: &Scan) -> f64 {
        let (s, c) = x.theta.sin_cos();
        (scan.points.iter())
            .map(|q| self.at(x.x + c * q[0] - s * q[1], x.y + s * q[0] + c * q[1]))
            .sum()
    }
}

/// A match: the scan's pose, its covariance (x, y, θ) and its score with the number of
/// candidates scored.
#[derive(Debug, Clone, PartialEq)]
pub struct Match {
    /// The best candidate pose.
    pub pose: Pose2,
    /// The candidates' weighted covariance (module docs).
    pub covariance: Matrix3<f64>,
    /// S at the best candidate.
    pub score: f64,
    /// Candidates scored.
    pub candidates: usize,
}

/// Match `scan` against `field` around the prediction `pred` whose σ are `sigma_m` (x and
/// y) and `sigma_rad`; the angle step `step_rad` (Δφ/4 of the steering grid).
pub fn match_scan(
    field: &Field,
    scan: &Scan,
    pred: &Pose2,
    sigma_m: f64,
    sigma_rad: f64,
    step_rad: f64,
) -> Result<Option<Match>> {
    let dxy = field.cell_m;
    // ±3σ, the window never wider than ±60° (a hair under whole steps: 3σ/step landing on
    // an integer is that integer)
    let nxy = (((3.0 * sigma_m / dxy) - 1e-9).ceil() as i64).max(1);
    let nth = (((3.0 * sigma_rad.min(PI / 3.0) / step_rad) - 1e-9).ceil() as i64).max(1);
    let count = (2 * nxy + 1).pow(2) as u128 * (2 * nth + 1) as u128;
    if count > MAX_CANDIDATES {
        return Err(Error::param(
            "slam.search",
            format!("{count} candidate poses (the odometry's σ against the cell and the steering step); at most {MAX_CANDIDATES}"),
        ));
    }
    let mut cands: Vec<(Pose2, f64)> = Vec::new();
    for it in -nth..=nth {
        let th = pred.theta + it as f64 * step_rad;
        let (s, c) = th.sin_cos();
        let rotated: Vec<[f64; 2]> = (scan.points.iter())
            .map(|q| [c * q[0] - s * q[1], s * q[0] + c * q[1]])
            .collect();
        for ix in -nxy..=nxy {
            for iy in -nxy..=nxy {
                let (x, y) = (pred.x + ix as f64 * dxy, pred.y + iy as f64 * dxy);
                let sc: f64 = rotated.iter().map(|q| field.at(x + q[0], y + q[1])).sum();
                cands.push((Pose2::new(x, y, th), sc));
            }
        }
    }
    // the best score; among equal ones the nearest the prediction
    let near = |p: &Pose2| {
        (p.x - pred.x).powi(2) + (p.y - pred.y).powi(2) + (p.theta - pred.theta).powi(2)
    };
    let (best, smax) = cands
        .iter()
        .copied()
        .fold((*pred, f64::NEG_INFINITY), |a, b| {
            if b.1 > a.1 || (b.1 == a.1 && near(&b.0) < near(&a.0)) {
                b
            } else {
                a
            }
        });
    if smax <= 0.0 {
        // no point of the scan near the map: nothing measured
        return Ok(None);
    }
    // weighted mean and covariance, angles relative to the best
    let (mut w, mut m) = (0.0, [0.0; 3]);
    for (p, sc) in &cands {
        let wi = (sc - smax).exp();
        w += wi;
        m[0] += wi * p.x;
        m[1] += wi * p.y;
        m[2] += wi * super::graph::wrap(p.theta - best.theta);
    }
    let m = m.map(|v| v / w);
    let mut cov = Matrix3::zeros();
    for (p, sc) in &cands {
        let wi = (sc - smax).exp() / w;
        let d = [
            p.x - m[0],
            p.y - m[1],
            super::graph::wrap(p.theta - best.theta) - m[2],
        ];
        for r in 0..3 {
            for c in 0..3 {
                cov[(r, c)] += wi * d[r] * d[c];
            }
        }
    }
    let floor = [
        dxy * dxy / 12.0,
        dxy * dxy / 12.0,
        step_rad * step_rad / 12.0,
    ];
    for k in 0..3 {
        cov[(k, k)] += floor[k];
    }
    Ok(Some(Match {
        pose: best,
        covariance: cov,
        score: smax,
        candidates: cands.len(),
    }))
}

/// The most candidate poses one match scores (a search this wide is refused by name).
pub const MAX_CANDIDATES: u128 = 4_000_000;

#[cfg(test)]
mod tests {
    use super::*;

    /// Points along an L-shaped corner (two walls) seen from a known pose: matched against
    /// the field of the same points seen from the truth, the scan lands on the truth from a
    /// prediction 0.2 m and 4° off; along a single straight wall the covariance along it
    /// is far wider than across it.
    #[test]
    fn a_corner_pins_the_pose_and_a_wall_only_its_normal() {
        let corner: Vec<[f64; 2]> = (0..60)
            .map(|i| [3.0, -2.0 + 0.05 * i as f64])
            .chain((0..60).map(|i| [0.0 + 0.05 * i as f64, 1.0]))
            .collect();
        let truth = Pose2::new(0.3, -0.2, 0.15);
        // the scan: the world points in the truth's frame
        let inv = truth.inverse();
        let scan = |world: &[[f64; 2]]| {
            let (s, c) = inv.theta.sin_cos();
            Scan {
                points: (world.iter())
                    .map(|p| [inv.x + c * p[0] - s * p[1], inv.y + s * p[0] + c * p[1]])
                    .collect(),
                sigma_m: vec![0.05; world.len()],
            }
        };
        let field = Field::new(&corner, &vec![0.05; corner.len()], 0.02).unwrap();
        let pred = Pose2::new(0.5, -0.05, 0.15 + 4f64.to_radians());
        let m = match_scan(
            &field,
            &scan(&corner),
            &pred,
            0.1,
            2f64.to_radians(),
            0.25f64.to_radians(),
        )
        .unwrap()
        .unwrap();
        eprintln!(
            "corner: {:?}, σ {:.3} {:.3} m {:.2}°",
            m.pose,
            m.covariance[(0, 0)].sqrt(),
            m.covariance[(1, 1)].sqrt(),
            m.covariance[(2, 2)].sqrt().to_degrees()
        );
        assert!((m.pose.x - truth.x).abs() <= 0.02 && (m.pose.y - truth.y).abs() <= 0.02);
        assert!((m.pose.theta - truth.theta).abs() <= 0.5f64.to_radians());
        // one wall along y (x = 3): x is pinned, y is not
        let wall: Vec<[f64; 2]> = corner[..60].to_vec();
        let field = Field::new(&wall, &vec![0.05; 60], 0.02).unwrap();
        let m = match_scan(
            &field,
            &scan(&wall),
            &Pose2::new(0.3, -0.2, 0.15),
            0.1,
            1f64.to_radians(),
            0.25f64.to_radians(),
        )
        .unwrap()
        .unwrap();
        let (sx, sy) = (m.covariance[(0, 0)].sqrt(), m.covariance[(1, 1)].sqrt());
        eprintln!("wall: σ x {sx:.3} m, σ y {sy:.3} m");
        assert!(sy > 5.0 * sx, "{sx} {sy}");
        // ±3σ/cell = ±15 cells and ±12 angle steps
        assert_eq!(m.candidates, 31 * 31 * 25);
        // far from the map: nothing measured; a window too wide: refused by name
        let (step, far) = (0.25f64.to_radians(), Pose2::new(40.0, 40.0, 0.0));
        let none = match_scan(&field, &scan(&wall), &far, 0.1, 0.02, step).unwrap();
        assert!(none.is_none());
        let wide = match_scan(&field, &scan(&wall), &far, 10.0, 1.0, step);
        assert!(wide.unwrap_err().to_string().contains("slam.search"));
    }

    #[test]
    fn the_steering_step_is_the_grid_s_median_spacing() {
        assert!((steering_step_rad(&[-90.0, -85.0, -80.0]) - 5f64.to_radians()).abs() < 1e-12);
        assert!((steering_step_rad(&[10.0]) - std::f64::consts::PI).abs() < 1e-12);
        // a jittered grid: its median spacing, not the smallest
        let step = steering_step_rad(&[0.0, 5.0, 5.001, 10.0, 15.0, 20.0]);
        assert!((step - 5f64.to_radians()).abs() < 1e-3);
        assert!(Field::new(&[], &[], 0.1).is_none());
    }
}
