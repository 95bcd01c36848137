//! The per-bin energy detector of the occupancy grids: the noise threshold at a
//! false-alarm rate ([`detection_threshold`]) and the peak / range-side-lobe tests
//! ([`Detector`]).

use crate::energy::EnergyMeta;
use crate::error::{Error, Result};
use statrs::distribution::{ContinuousCDF, Gamma};

/// Energy threshold of the per-bin detector at false-alarm rate `pfa`: the (1 − pfa)
/// quantile of Gamma(shape TW·N_p, rate N_p/N0). `file` names the energy table in errors.
pub fn detection_threshold(meta: &EnergyMeta, pfa: f64, file: &std::path::Path) -> Result<f64> {
    meta.check_noise(file)?;
    let shape = meta.tw * meta.pulses as f64;
    let rate = meta.pulses as f64 / meta.n0;
    let g = Gamma::new(shape, rate)
        .map_err(|e| Error::input(file, format!("noise statistics: {e}")))?;
    let t = g.inverse_cdf(1.0 - pfa);
    if !t.is_finite() || t <= 0.0 {
        return Err(Error::input(
            file,
            "could not compute the detection threshold",
        ));
    }
    Ok(t)
}

/// The per-bin energy detector shared by both inverse sensor models.
///
/// Bin k is a detection when (1) E_k > η_E (noise threshold at the false-alarm rate),
/// (2) E_k is a local maximum of the profile (E_k ≥ E_{k−1}, E_k > E_{k+1}, k − 1 usable):
/// one detection
/// per echo, at its peak, instead of the window kernel's 4-5 bins, and (3) E_k is not
/// explained by the window kernel's range side lobes of a stronger bin j:
/// E_k ≥ β·E_j·K(|k − j|) for every j within ±M bins, K the bin-averaged kernel of a point
/// echo normalised to its peak (from the run's band and processing), β = `mask_db` (10 dB:
/// the kernel seen through frequency-dependent patterns is wider than the ideal one).
#[derive(Debug, Clone)]
pub struct Detector {
    /// Noise threshold η_E.
    pub threshold: f64,
    /// Kernel K(m), m = 0..=M (K(0) = 1).
    pub kernel: Vec<f64>,
    /// Margin β (linear).
    pub margin: f64,
    /// First usable bin.
    pub min_bin: usize,
}

impl Detector {
    /// Detector from the threshold, the window kernel (`kernel[m]` = energy at m bins from the
    /// peak, any scale) and the masking margin in dB. Kernel values below −80 dB of the peak
    /// are dropped.
    pub fn new(threshold: f64, kernel: &[f64], mask_db: f64, min_bin: usize) -> Detector {
        let k0 = kernel
            .first()
            .copied()
            .unwrap_or(1.0)
            .max(f64::MIN_POSITIVE);
        let mut k: Vec<f64> = kernel.iter().map(|v| v / k0).collect();
        while k.len() > 1 && k[k.len() - 1] < 1e-8 {
            k.pop();
        }
        k.truncate(32);
        Detector {
            threshold,
            kernel: k,
            margin: 10f64.powf(mask_db / 10.0),
            min_bin,
        }
    }

    /// Detections of every direction of pose `p` (in parallel over directions, in
    /// direction order).
    pub fn detect_pose(&self, em: &crate::energy::EnergyMatrix, p: usize) -> Vec<Vec<bool>> {
        use rayon::prelude::*;
        (0..em.directions())
            .into_par_iter()
            .map(|d| {
                let mut det = Vec::new();
                if em.has(p, d) {
                    self.detect(em.profile(p, d), &mut det);
                } else {
                    // a direction without a sweep detects nothing (and the mappers skip it)
                    det.resize(em.bins, false);
                }
                det
            })
            .collect()
    }

    /// Detections of one profile (true = detected), bins before `min_bin` never.
    pub fn detect(&self, prof: &[f64], out: &mut Vec<bool>) {
        let n = prof.len();
        out.clear();
        out.resize(n, false);
        let m = self.kernel.len();
        // k − 1 must be usable too: a profile still falling at the first usable bin is the
        // tail of a gated echo, not a new one
        for k in self.min_bin + 1..n {
            let e = prof[k];
            if e <= self.threshold || prof[k - 1] > e {
                continue;
            }
            if k + 1 < n && prof[k + 1] >= e {
                continue;
            }
            let lo = k.saturating_sub(m - 1);
            let hi = (k + m).min(n);
            let masked = (lo..hi)
                .any(|j| prof[j] > e && e < self.margin * prof[j] * self.kernel[j.abs_diff(k)]);
            if !masked {
                out[k] = true;
            }
        }
    }
}
