//! The receiver's noise: complex white Gaussian noise per frequency point of a sweep, the
//! one draw the physics simulator (`simulate`) and the statistical model (`synth`) share.
//!
//! A sweep of K points carries n_k = σ/√2·(a_k + j·b_k), a_k, b_k ~ N(0, 1) drawn in that
//! order for k = 0..K−1 from the caller's stream: circular, variance σ² per point,
//! independent across points (and across pulses, each pulse its own draw). Through the
//! energy stage ([`super::EnergyProcessor`]: window, zero-padded IFFT, bins) it is
//! coloured: per CIR sample mean N0_h = σ²·Σw²/(Σw)², correlation
//! ρ(Δ) = Σ w_k² e^{j2πkΔ/N} / Σ w_k² between samples Δ apart (so neighbouring bins are
//! correlated), and a noise-only bin has mean N0_h = N0·TW ([`WhiteNoise::for_n0`] inverts
//! this).

use super::EnergyProcessor;
use num_complex::Complex64;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Complex white Gaussian noise of variance σ² per frequency point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WhiteNoise {
    /// σ/√2, the standard deviation of each quadrature.
    sigma: f64,
}

impl WhiteNoise {
    /// Noise of variance `sigma2` per point (the manifest's `[noise]` floor:
    /// `NoiseConfig::s21_variance`).
    pub fn new(sigma2: f64) -> WhiteNoise {
        WhiteNoise {
            sigma: (sigma2 / 2.0).sqrt(),
        }
    }

    /// The noise whose noise-only bins read N0 through `proc`: σ² = N0·TW·(Σw)²/Σw², so the
    /// mean noise-bin energy is N0·TW.
    pub fn for_n0(proc: &EnergyProcessor, n0: f64) -> WhiteNoise {
        WhiteNoise::new(n0 * proc.tw() / proc.noise_per_sample(1.0))
    }

    /// The variance σ² per point.
    pub fn variance(&self) -> f64 {
        2.0 * self.sigma * self.sigma
    }

    /// `out[k] = clean[k] + n_k` for every point of `clean`, drawn from `rng`.
    pub fn add<R: Rng + ?Sized>(&self, clean: &[Complex64], out: &mut [Complex64], rng: &mut R) {
        for (o, cv) in out.iter_mut().zip(clean) {
            let a: f64 = StandardNormal.sample(rng);
            let b: f64 = StandardNormal.sample(rng);
            *o = cv + Complex64::new(a, b) * self.sigma;
        }
    }

    /// `out[k] = n_k` for every point of `out`, drawn from `rng` (the draws of
    /// [`WhiteNoise::add`]).
    pub fn draw<R: Rng + ?Sized>(&self, out: &mut [Complex64], rng: &mut R) {
        for o in out.iter_mut() {
            let a: f64 = StandardNormal.sample(rng);
            let b: f64 = StandardNormal.sample(rng);
            *o = Complex64::new(a, b) * self.sigma;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::manifest::{Band, Processing};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Noise-only bins through the processor read N0·TW for the N0 asked, and neighbouring
    /// bins are correlated as the window makes them.
    #[test]
    fn noise_for_n0_reads_n0_and_is_coloured() {
        let band = Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 401,
        };
        let proc = EnergyProcessor::new(band, Processing::default()).unwrap();
        let n0 = 3.7e-12;
        let noise = WhiteNoise::for_n0(&proc, n0);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut spec = vec![Complex64::new(0.0, 0.0); band.points];
        let mut scratch = proc.scratch();
        let nb = proc.nbins_full();
        let (mut sum, mut lag1, mut sq, mut count) = (0.0, 0.0, 0.0, 0usize);
        let mut all = Vec::new();
        for _ in 0..400 {
            noise.draw(&mut spec, &mut rng);
            let mut out = vec![0.0; nb];
            proc.profile_into(&spec, &mut scratch, 1.0, &mut out);
            // away from the gate at either end
            let e = &out[30..nb - 30];
            sum += e.iter().sum::<f64>();
            count += e.len();
            all.push(e.to_vec());
        }
        let mean = sum / count as f64;
        for e in &all {
            for w in e.windows(2) {
                lag1 += (w[0] - mean) * (w[1] - mean);
                sq += (w[0] - mean).powi(2);
            }
        }
        let rho1 = lag1 / sq;
        let want = n0 * proc.tw();
        assert!(
            (mean / want - 1.0).abs() < 0.01,
            "mean {mean:e} vs N0·TW {want:e}"
        );
        assert!(rho1 > 0.1, "lag-1 correlation {rho1}");
    }
}
