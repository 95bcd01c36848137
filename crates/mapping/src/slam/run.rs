//! The poses of a walk from its odometry and its scans (issue 56, item 1): incremental
//! scan-to-map matching feeding the pose graph.
//!
//! Takes the odometry ([`Odometry`]: the start, the steps and their σ), every pose's scan
//! ([`Scan`]) and the steering step; gives the estimated poses with their marginal
//! covariances, the dead reckoning beside them, and per pose whether its scan matched.
//!
//! For each pose k ≥ 1 in walk order:
//! 1. predict X̂_k = X̂_{k−1} ⊕ ũ_k and add the odometry edge (k − 1 → k, σ per step);
//! 2. build the likelihood field of the scans of poses 0..k−1 placed at their current
//!    estimates (the map so far) and match scan k around the prediction, searching ±3σ of
//!    one step ([`match_scan`]; the map is placed by the estimates, so the prediction is
//!    one step uncertain against it);
//! 3. add the match as an edge from k − 1 (Z = X̂_{k−1}⁻¹ ⊕ X*, its covariance turned
//!    into k − 1's frame) when the scan and the map both have points;
//! 4. solve the graph ([`PoseGraph::optimise_poses`]) and go on from its poses; the
//!    covariances once, at the end.
//!
//! A match that scores nothing (no point of the scan near the map) adds no edge.
//! Known limit: a direction of the match the scan does not constrain keeps the search
//! window's own spread (3σ² of the step), which the graph takes as a measurement beside the
//! odometry's (docs/slam.md).
//!
//! Not yet: loop closures (a match is tied to the pose before it, so a revisit corrects
//! the current pose but not the drift behind it); a scan without points leaves its pose
//! to the odometry.

use super::graph::{Edge, Pose2, PoseGraph, SolveValid};
use super::matching::{match_scan, Field, Scan};
use super::odometry::Odometry;
use crate::error::{Error, Result};
use nalgebra::Matrix3;

/// The estimate of a walk's poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The estimated poses.
    pub poses: Vec<Pose2>,
    /// Their marginal covariances (x, y, θ); the first pose's is zero.
    pub covariances: Vec<Matrix3<f64>>,
    /// The odometry's dead reckoning.
    pub dead_reckoning: Vec<Pose2>,
    /// Per pose, whether its scan was matched against the map (pose 0: false).
    pub matched: Vec<bool>,
}

/// Estimate the poses of a walk (module docs); `cell_m` the likelihood field's cell,
/// `steering_step_rad` the steering grid's step (the angle search steps a quarter of it).
pub fn estimate(
    odo: &Odometry,
    scans: &[Scan],
    cell_m: f64,
    steering_step_rad: f64,
    solve: &SolveValid,
) -> Result<Estimate> {
    let n = odo.steps.len() + 1;
    if scans.len() != n {
        return Err(Error::param(
            "slam.scans",
            format!("{} scans for {n} poses", scans.len()),
        ));
    }
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(Error::param("slam.cell_m", "must be > 0"));
    }
    if !(odo.sigma_m.is_finite()
        && odo.sigma_m > 0.0
        && odo.sigma_rad.is_finite()
        && odo.sigma_rad > 0.0)
    {
        return Err(Error::param("slam.odometry", "σ per step must be > 0"));
    }
    if !(steering_step_rad.is_finite() && steering_step_rad > 0.0) {
        return Err(Error::param("slam.steering_step_rad", "must be > 0"));
    }
    let step_rad = steering_step_rad / 4.0;
    let mut g = PoseGraph::new(vec![odo.start]);
    let mut matched = vec![false; n];
    let mut covariances = vec![Matrix3::zeros()];
    for k in 1..n {
        let u = odo.steps[k - 1];
        let prev = g.poses[k - 1];
        g.poses.push(prev.compose(&u));
        g.add_edge(Edge::diagonal(k - 1, k, u, odo.sigma_m, odo.sigma_rad))?;
        let (mut pts, mut sig) = (Vec::new(), Vec::new());
        for (j, s) in scans[..k].iter().enumerate() {
            let x = g.poses[j];
            let (sn, cs) = x.theta.sin_cos();
            pts.extend(
                (s.points.iter())
                    .map(|q| [x.x + cs * q[0] - sn * q[1], x.y + sn * q[0] + cs * q[1]]),
            );
            sig.extend_from_slice(&s.sigma_m);
        }
        let field = match scans[k].points.is_empty() {
            true => None,
            false => Field::new(&pts, &sig, cell_m),
        };
        let m = match &field {
            Some(f) => match_scan(
                f,
                &scans[k],
                &g.poses[k],
                odo.sigma_m,
                odo.sigma_rad,
                step_rad,
            )?,
            None => None,
        };
        if let Some(m) = m {
            let z = prev.between(&m.pose);
            // the edge's error lives in the frame of the measured pose (X̂_{k−1} ⊕ Z = X*,
            // `graph`): R(θ*)ᵀ Σ R(θ*) on x, y
            let (s, c) = m.pose.theta.sin_cos();
            let r = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
            let cov = r * m.covariance * r.transpose();
            let info = cov
                .try_inverse()
                .map(|i| 0.5 * (i + i.transpose()))
                .ok_or_else(|| Error::param("slam.match", "singular match covariance"))?;
            g.add_edge(Edge {
                from: k - 1,
                to: k,
                measured: z,
                information: info,
            })?;
            matched[k] = true;
        }
        g.optimise_poses(solve)?;
    }
    if n > 1 {
        covariances = g.optimise(solve)?.covariances;
    }
    Ok(Estimate {
        poses: g.poses,
        covariances,
        dead_reckoning: odo.dead_reckoning(),
        matched,
    })
}
