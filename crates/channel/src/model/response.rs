//! The array and delay-domain response synth puts each ray through: the band-averaged
//! pattern ([`BandPattern`]) and the energy stage's window kernel (`Kernel`).
//!
//! * Array: each ray is seen as a = ḡ(θ_arr)·|A|·e^{−j2πf_c(τ + τ_g)}, ḡ the
//!   window-weighted band average of |F|²λ over the pattern table's frequency knots and τ_g
//!   the antenna group delay (the weighted least-squares slope of the unwrapped arg F²
//!   against frequency, over 2π; it matters for the 1-bit transmitarray), zero where the
//!   gain is below 10⁻³ of its peak and clamped to ±1 ns.
//! * Delay domain: the windowed, zero-padded IFFT of a flat echo is the window kernel
//!   κ(t − τ) = e^{jπB(t−τ)}·r(t − τ) with r real (symmetric window), so the CIR on the
//!   energy stage's oversampled grid is h(t_n) = e^{jπBt_n}·Σ a·r(t_n − τ) (the common
//!   phase drops out of |h|²); r is tabulated at T_b/64 over ±16 bins and read linearly.

use crate::campaign::manifest::WindowKind;
use crate::energy::{self, EnergyProcessor};
use crate::pattern::PatternTable;
use crate::units::C0;
use std::f64::consts::PI;

/// Kernel table: samples per bin and half-width in bins.
const KERNEL_FINE: usize = 64;
/// Half-width of the kernel table, bins.
pub(super) const KERNEL_BINS: usize = 16;

/// The band-averaged pattern of one steering table: ḡ(θ) = Σ w(f)|F(θ,f)|²λ(f) / Σ w(f) and
/// the group delay τ_g(θ) on the table's angle grid.
#[derive(Debug, Clone)]
pub struct BandPattern {
    step_deg: f64,
    g: Vec<f64>,
    tau_g: Vec<f64>,
}

impl BandPattern {
    /// Average a pattern table over its knots with `window` weights.
    pub fn new(table: &PatternTable, window: WindowKind) -> BandPattern {
        let nk = table.knots();
        let w: Vec<f64> = match window {
            WindowKind::Rect => vec![1.0; nk],
            WindowKind::Hann => (0..nk)
                .map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / (nk - 1) as f64).cos())
                .collect(),
        };
        let wsum: f64 = w.iter().sum();
        let f: Vec<f64> = (0..nk).map(|k| table.knot_hz(k)).collect();
        let mut g = Vec::with_capacity(table.angles());
        let mut tau_g = Vec::with_capacity(table.angles());
        for i in 0..table.angles() {
            let v = table.knots_at(i);
            let gi = v
                .iter()
                .zip(&w)
                .zip(&f)
                .map(|((x, w), f)| w * x.norm_sqr() * C0 / f)
                .sum::<f64>()
                / wsum;
            // weighted least-squares slope of the unwrapped phase of F² against frequency
            let (mut sw, mut sf, mut sp, mut sff, mut sfp) = (0.0, 0.0, 0.0, 0.0, 0.0);
            let mut prev: Option<f64> = None;
            let mut unwrap = 0.0;
            for ((x, wk), fk) in v.iter().zip(&w).zip(&f) {
                let ph = (x * x).arg();
                if let Some(p) = prev {
                    let d = ph - p;
                    unwrap -= 2.0 * PI * (d / (2.0 * PI)).round();
                }
                prev = Some(ph);
                let y = ph + unwrap;
                let wt = wk * x.norm_sqr();
                let fx = fk - f[0];
                sw += wt;
                sf += wt * fx;
                sp += wt * y;
                sff += wt * fx * fx;
                sfp += wt * fx * y;
            }
            let den = sw * sff - sf * sf;
            let slope = if sw > 0.0 && den > 0.0 {
                (sw * sfp - sf * sp) / den
            } else {
                0.0
            };
            tau_g.push((-slope / (2.0 * PI)).clamp(-1e-9, 1e-9));
            g.push(gi);
        }
        // the group delay is meaningless where there is no gain
        let gmax = g.iter().copied().fold(0.0, f64::max);
        for (t, gi) in tau_g.iter_mut().zip(&g) {
            if *gi < 1e-3 * gmax {
                *t = 0.0;
            }
        }
        BandPattern {
            step_deg: table.step_deg(),
            g,
            tau_g,
        }
    }

    /// The peak of ḡ over the angle grid.
    pub fn peak(&self) -> f64 {
        self.g.iter().copied().fold(0.0, f64::max)
    }

    /// (ḡ, τ_g) towards `theta` (rad, array frame), linear in angle; None behind the array.
    pub fn at(&self, theta: f64) -> Option<(f64, f64)> {
        let deg = theta.to_degrees();
        if !(-90.0..=90.0).contains(&deg) {
            return None;
        }
        let x = (deg + 90.0) / self.step_deg;
        let i = (x.floor() as usize).min(self.g.len() - 2);
        let t = x - i as f64;
        Some((
            self.g[i] * (1.0 - t) + self.g[i + 1] * t,
            self.tau_g[i] * (1.0 - t) + self.tau_g[i + 1] * t,
        ))
    }
}

/// The real window kernel r(t) of the energy stage, tabulated at T_b/64 over ±16 bins.
pub(super) struct Kernel {
    step_s: f64,
    half: usize,
    r: Vec<f64>,
    /// tail[k] = max r(t)² over |t| ≥ k bins, k = 0..=KERNEL_BINS (non-increasing).
    tail: Vec<f64>,
}

impl Kernel {
    pub(super) fn new(proc: &EnergyProcessor) -> Kernel {
        let band = proc.band();
        let w = energy::window(proc.processing().window, band.points);
        let wsum: f64 = w.iter().sum();
        let df = band.step_hz();
        let mid = (band.points - 1) as f64 / 2.0;
        let step_s = proc.bin_width_ns() * 1e-9 / KERNEL_FINE as f64;
        let half = KERNEL_FINE * KERNEL_BINS;
        let r = (0..=2 * half)
            .map(|i| {
                let t = (i as f64 - half as f64) * step_s;
                w.iter()
                    .enumerate()
                    .map(|(k, wk)| wk * (2.0 * PI * (k as f64 - mid) * df * t).cos())
                    .sum::<f64>()
                    / wsum
            })
            .collect::<Vec<f64>>();
        let tail = (0..=KERNEL_BINS)
            .map(|k| {
                let m = k * KERNEL_FINE;
                r.iter()
                    .enumerate()
                    .filter(|(i, _)| i.abs_diff(half) >= m)
                    .map(|(_, v)| v * v)
                    .fold(0.0, f64::max)
            })
            .collect();
        Kernel {
            step_s,
            half,
            r,
            tail,
        }
    }

    /// The reach, s, beyond which r(t)² stays below `frac` (a ray's cull level over its
    /// power): whole bins, at most the table's half-width.
    pub(super) fn reach_s(&self, frac: f64) -> f64 {
        let k = self
            .tail
            .iter()
            .position(|&t| t < frac)
            .unwrap_or(KERNEL_BINS);
        k as f64 * KERNEL_FINE as f64 * self.step_s
    }

    #[inline]
    pub(super) fn at(&self, t: f64) -> f64 {
        let x = t / self.step_s + self.half as f64;
        if x < 0.0 || x >= (self.r.len() - 1) as f64 {
            return 0.0;
        }
        let i = x as usize;
        let f = x - i as f64;
        self.r[i] * (1.0 - f) + self.r[i + 1] * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::manifest::{Band, Processing};

    #[test]
    fn kernel_is_the_energy_stage_kernel() {
        let band = Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 401,
        };
        let proc = EnergyProcessor::new(band, Processing::default()).unwrap();
        let k = Kernel::new(&proc);
        assert!((k.at(0.0) - 1.0).abs() < 1e-12);
        // |κ(t)|² averaged over a bin equals the energy stage's point-echo energy
        let tau = 10.3e-9;
        for bin in 58..66 {
            let l = proc.processing().oversample;
            let dt = proc.bin_width_ns() * 1e-9 / l as f64;
            let half = (l as i64 - 1) / 2;
            let e: f64 = (-half..=half)
                .map(|j| k.at((bin as i64 * l as i64 + j) as f64 * dt - tau).powi(2))
                .sum::<f64>()
                / l as f64;
            let want = proc.point_echo_energy_at(1.0, tau, bin);
            assert!(
                (e - want).abs() < 1e-3 * want + 1e-7,
                "bin {bin}: {e} vs {want}"
            );
        }
    }
}
