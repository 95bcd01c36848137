//! Odometry of a walk (issue 56, item 1's input): the steps a phone's dead reckoning
//! reports between consecutive poses, with their stated σ.
//!
//! Takes the campaign's poses (the truth, for a simulated walk) and [`OdometryNoise`]
//! (σ of x and y per step in the step's own frame, m; σ of the heading change per step,
//! degrees; a seed); gives [`Odometry`]: per step k ≥ 1 the measured relative pose
//! ũ_k = u_k + (n_x, n_y, n_θ), u_k = X_{k−1}⁻¹ ⊕ X_k, the n drawn independently from
//! N(0, σ²) (a ChaCha stream of the seed; x, y, θ per step in that order), the dead
//! reckoning X̃_0 = X_0, X̃_k = X̃_{k−1} ⊕ ũ_k, and the pose graph of those steps (each
//! an edge with the stated diagonal covariance; the graph's poses the dead reckoning).
//!
//! Choices: the noise is per step, not per pose ([`crate::pose_noise`] draws each pose
//! independently, which no walk does): its errors add up along the walk, so the position
//! error grows with the steps and turns; the start is known (the graph's frame).

use super::graph::{Edge, Pose2, PoseGraph};
use crate::campaign::manifest::Pose;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The noise of the odometry per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryNoise {
    /// σ of x and of y per step, in the step's frame, m.
    pub step_m: f64,
    /// σ of the heading change per step, degrees.
    pub step_deg: f64,
    /// Seed of the draws.
    pub seed: u64,
}

impl Default for OdometryNoise {
    /// 0.1 m and 3° per step (issue 56's middle level), seed 1.
    fn default() -> Self {
        OdometryNoise {
            step_m: 0.1,
            step_deg: 3.0,
            seed: 1,
        }
    }
}

/// Where the mapper's poses come from (`pradar map --poses-from`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PosesFrom {
    /// The manifest's poses (with `--pose-noise-*` if given).
    #[default]
    Manifest,
    /// The dead reckoning of an odometry drawn from the manifest's poses.
    Odometry,
    /// Estimated from the sweeps and that odometry.
    Sweeps,
}

impl PosesFrom {
    /// Every value, in the order the command line lists them.
    pub const ALL: [PosesFrom; 3] = [PosesFrom::Manifest, PosesFrom::Odometry, PosesFrom::Sweeps];

    /// Name (`manifest`, `odometry`, `sweeps`): the command-line value and the `Display`.
    pub fn name(&self) -> &'static str {
        match self {
            PosesFrom::Manifest => "manifest",
            PosesFrom::Odometry => "odometry",
            PosesFrom::Sweeps => "sweeps",
        }
    }
}

impl std::fmt::Display for PosesFrom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for PosesFrom {
    type Err = Error;
    /// Parse a [`PosesFrom::name`].
    fn from_str(s: &str) -> Result<PosesFrom> {
        crate::params::parse_name(s, &Self::ALL, Self::name, "poses_from", "poses source")
    }
}

/// [`OdometryNoise`] that passed [`ParamGuard::check`].
pub type OdometryNoiseValid = Valid<OdometryNoise>;

impl ParamGuard for OdometryNoise {
    type Checked = OdometryNoiseValid;

    /// Both σ finite and > 0 (an edge needs a finite information).
    fn check(&self) -> Result<OdometryNoiseValid> {
        if !(self.step_m.is_finite() && self.step_m > 0.0) {
            return Err(Error::param("odometry.step_m", "must be > 0"));
        }
        if !(self.step_deg.is_finite() && self.step_deg > 0.0) {
            return Err(Error::param("odometry.step_deg", "must be > 0"));
        }
        Ok(Valid::new(*self))
    }
}

/// A campaign pose as a [`Pose2`] (heading in radians).
pub fn pose2(p: &Pose) -> Pose2 {
    Pose2::new(p.x_m, p.y_m, p.heading_deg.to_radians())
}

/// The measured steps of a walk and their stated σ.
#[derive(Debug, Clone, PartialEq)]
pub struct Odometry {
    /// The first pose (known: the map's frame).
    pub start: Pose2,
    /// ũ_k for k = 1..n: the relative pose of step k.
    pub steps: Vec<Pose2>,
    /// σ of x and y per step, m.
    pub sigma_m: f64,
    /// σ of the heading change per step, rad.
    pub sigma_rad: f64,
}

impl Odometry {
    /// The odometry of a walk through `truth` with `noise` (module docs).
    pub fn simulate(truth: &[Pose2], noise: &OdometryNoiseValid) -> Odometry {
        let mut rng = ChaCha8Rng::seed_from_u64(noise.seed ^ 0x6f64_6f6d_6574_7279);
        let sigma_rad = noise.step_deg.to_radians();
        let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
        let steps = (truth.windows(2))
            .map(|w| {
                let u = w[0].between(&w[1]);
                let (dx, dy, dt) = (n(), n(), n());
                Pose2::new(
                    u.x + noise.step_m * dx,
                    u.y + noise.step_m * dy,
                    u.theta + sigma_rad * dt,
                )
            })
            .collect();
        Odometry {
            start: truth.first().copied().unwrap_or_default(),
            steps,
            sigma_m: noise.step_m,
            sigma_rad,
        }
    }

    /// The dead reckoning: the start, then each step composed on the last pose.
    pub fn dead_reckoning(&self) -> Vec<Pose2> {
        let mut out = Vec::with_capacity(self.steps.len() + 1);
        out.push(self.start);
        for s in &self.steps {
            let last = out[out.len() - 1];
            out.push(last.compose(s));
        }
        out
    }

    /// The pose graph of the steps: the dead reckoning as its poses, one edge per step
    /// (refused by name when a step or a σ is not usable).
    pub fn graph(&self) -> Result<PoseGraph> {
        if !(self.sigma_m.is_finite() && self.sigma_m > 0.0) {
            return Err(Error::param("odometry.sigma_m", "must be > 0"));
        }
        if !(self.sigma_rad.is_finite() && self.sigma_rad > 0.0) {
            return Err(Error::param("odometry.sigma_rad", "must be > 0"));
        }
        let mut g = PoseGraph::new(self.dead_reckoning());
        for (k, s) in self.steps.iter().enumerate() {
            g.add_edge(Edge::diagonal(k, k + 1, *s, self.sigma_m, self.sigma_rad))?;
        }
        Ok(g)
    }
}

/// The root mean square of the position errors of `est` against `truth` (pose by pose), m.
pub fn position_rmse(est: &[Pose2], truth: &[Pose2]) -> f64 {
    let n = est.len().min(truth.len());
    if n == 0 {
        return f64::NAN;
    }
    let s: f64 = (est.iter().zip(truth))
        .map(|(a, b)| (a.x - b.x).powi(2) + (a.y - b.y).powi(2))
        .sum();
    (s / n as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::super::graph::SolveParams;
    use super::*;

    fn walk(n: usize) -> Vec<Pose2> {
        // 0.4 m steps along a corridor with a slow turn
        let mut p = vec![Pose2::new(0.5, -0.3, 0.0)];
        for k in 1..n {
            let s = Pose2::new(0.4, 0.0, if k % 5 == 0 { 0.1 } else { 0.0 });
            p.push(p[k - 1].compose(&s));
        }
        p
    }

    #[test]
    fn the_dead_reckoning_drifts_with_the_steps_and_its_graph_is_at_rest() {
        let truth = walk(40);
        let tiny = OdometryNoise {
            step_m: 1e-12,
            step_deg: 1e-12,
            seed: 1,
        };
        let o = Odometry::simulate(&truth, &tiny.check().unwrap());
        assert_eq!(o.steps.len(), 39);
        assert!(position_rmse(&o.dead_reckoning(), &truth) < 1e-9);
        // σ 0.1 m and 3° per step: the error of pose k grows with k (mean over 50 draws of
        // the error at the tenth and at the last pose)
        let (mut e10, mut e39) = (0.0, 0.0);
        for seed in 0..50 {
            let noise = OdometryNoise {
                step_m: 0.1,
                step_deg: 3.0,
                seed,
            };
            let d = Odometry::simulate(&truth, &noise.check().unwrap()).dead_reckoning();
            let err = |k: usize| (d[k].x - truth[k].x).hypot(d[k].y - truth[k].y);
            e10 += err(10) / 50.0;
            e39 += err(39) / 50.0;
        }
        eprintln!("mean position error: pose 10 {e10:.2} m, pose 39 {e39:.2} m");
        // at least the √(39/10) of a random walk in position; the heading's walk adds more
        assert!(e39 > 2.0 * e10 && e10 > 0.2, "{e10} {e39}");
        // the same seed draws the same steps; the odometry's own graph is at its optimum
        let noise = OdometryNoise {
            step_m: 0.1,
            step_deg: 3.0,
            seed: 7,
        }
        .check()
        .unwrap();
        assert_eq!(
            Odometry::simulate(&truth, &noise),
            Odometry::simulate(&truth, &noise)
        );
        let mut g = Odometry::simulate(&truth, &noise).graph().unwrap();
        let sol = g
            .optimise(&SolveParams::default().check().unwrap())
            .unwrap();
        assert!(sol.cost_before < 1e-18 && sol.iterations <= 1);
        assert!(
            position_rmse(
                &g.poses,
                &Odometry::simulate(&truth, &noise).dead_reckoning()
            ) < 1e-9
        );
    }

    #[test]
    fn noise_without_spread_is_refused() {
        for (m, d) in [
            (0.0, 1.0),
            (0.1, 0.0),
            (f64::NAN, 1.0),
            (0.1, f64::INFINITY),
        ] {
            let n = OdometryNoise {
                step_m: m,
                step_deg: d,
                seed: 1,
            };
            let msg = n.check().unwrap_err().to_string();
            assert!(msg.contains("odometry."), "{msg}");
        }
        let o = Odometry {
            start: Pose2::default(),
            steps: vec![Pose2::new(1.0, 0.0, 0.0)],
            sigma_m: 0.0,
            sigma_rad: 0.1,
        };
        assert!(o
            .graph()
            .unwrap_err()
            .to_string()
            .contains("odometry.sigma_m"));
    }
}
