//! Pose noise of the mapper (the pose-noise experiment and `map --pose-noise-*`): what it
//! takes (σ per axis, σ of the heading, a seed) and the poses it gives the mapper.

use crate::campaign::manifest::Pose;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use serde::Serialize;

/// Pose noise of the mapper: the energy was recorded at the manifest's poses, the mapper is
/// given x̃ = x + N(0, σ_p²), ỹ = y + N(0, σ_p²), h̃ = h + N(0, σ_h²), drawn independently
/// per pose (no drift) from a ChaCha stream keyed by (`seed`, run index). The observable
/// region and the reference stay those of the true poses, so maps with and without noise are
/// scored on the same cells.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PoseNoise {
    /// Position standard deviation per axis, m.
    pub position_m: f64,
    /// Heading standard deviation, degrees.
    pub heading_deg: f64,
    /// Seed of the draws.
    pub seed: u64,
}

/// Pose noise that passed [`ParamGuard::check`].
pub type PoseNoiseValid = Valid<PoseNoise>;

impl ParamGuard for PoseNoise {
    type Checked = PoseNoiseValid;

    /// Both standard deviations finite and ≥ 0.
    fn check(&self) -> Result<PoseNoiseValid> {
        if !(self.position_m.is_finite() && self.position_m >= 0.0) {
            return Err(Error::param("pose_noise.position_m", "must be >= 0"));
        }
        if !(self.heading_deg.is_finite() && self.heading_deg >= 0.0) {
            return Err(Error::param("pose_noise.heading_deg", "must be >= 0"));
        }
        Ok(Valid::new(*self))
    }
}

impl PoseNoise {
    /// The seed `pradar map` draws with when `--pose-seed` is not given.
    pub const DEFAULT_SEED: u64 = 1;
    /// Whether it changes any pose.
    pub fn is_none(&self) -> bool {
        self.position_m == 0.0 && self.heading_deg == 0.0
    }
    /// The poses the mapper believes for run `run` (the true poses when there is no noise).
    pub fn apply(&self, poses: &[Pose], run: usize) -> Vec<Pose> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        if self.is_none() {
            return poses.to_vec();
        }
        let key = self.seed ^ (run as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(key);
        poses
            .iter()
            .map(|p| {
                let dx: f64 = StandardNormal.sample(&mut rng);
                let dy: f64 = StandardNormal.sample(&mut rng);
                let dh: f64 = StandardNormal.sample(&mut rng);
                Pose {
                    x_m: p.x_m + self.position_m * dx,
                    y_m: p.y_m + self.position_m * dy,
                    heading_deg: p.heading_deg + self.heading_deg * dh,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Vec<Pose> {
        (0..n)
            .map(|i| Pose {
                x_m: i as f64 * 0.4,
                y_m: -0.3,
                heading_deg: 10.0,
            })
            .collect()
    }

    #[test]
    fn no_pose_noise_keeps_the_poses() {
        let p = line(5);
        assert_eq!(PoseNoise::default().apply(&p, 0), p);
    }

    #[test]
    fn pose_noise_has_the_stated_spread_and_is_seeded() {
        let p = line(20_000);
        let n = PoseNoise {
            position_m: 0.05,
            heading_deg: 2.0,
            seed: 7,
        };
        let a = n.apply(&p, 0);
        assert_eq!(a, n.apply(&p, 0), "same seed, same draws");
        assert_ne!(a, n.apply(&p, 1), "another run, other draws");
        // mean within 4 standard errors of 0, sample std returned
        let sd = |f: &dyn Fn(&Pose, &Pose) -> f64, sigma: f64| {
            let v: Vec<f64> = a.iter().zip(&p).map(|(x, y)| f(x, y)).collect();
            let m = v.iter().sum::<f64>() / v.len() as f64;
            assert!(m.abs() < 4.0 * sigma / (v.len() as f64).sqrt(), "mean {m}");
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let sx = sd(&|x, y| x.x_m - y.x_m, 0.05);
        let sy = sd(&|x, y| x.y_m - y.y_m, 0.05);
        let sh = sd(&|x, y| x.heading_deg - y.heading_deg, 2.0);
        // 20,000 draws: the sample std is within 2 % of σ (≈ 4 standard errors)
        assert!((sx / 0.05 - 1.0).abs() < 0.02, "x {sx}");
        assert!((sy / 0.05 - 1.0).abs() < 0.02, "y {sy}");
        assert!((sh / 2.0 - 1.0).abs() < 0.02, "heading {sh}");
        assert!(PoseNoise {
            position_m: -1.0,
            ..n
        }
        .check()
        .is_err());
        assert!(PoseNoise {
            heading_deg: f64::NAN,
            ..n
        }
        .check()
        .is_err());
    }
}
