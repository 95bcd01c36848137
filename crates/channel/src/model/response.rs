//! The array and delay-domain response synth puts each ray through: the band-averaged
//! pattern ([`BandPattern`]) and the energy stage's window kernel (`Kernel`), periodic in
//! delay as the sweep's CIR is.
//!
//! * Array: each ray is seen as a = ḡ(θ_arr)·|A|·e^{−j2πf_c(τ + τ_g)}, ḡ the
//!   window-weighted band average of |F|²λ over the pattern table's frequency knots and τ_g
//!   the antenna group delay (the weighted least-squares slope of the unwrapped arg F²
//!   against frequency, over 2π; it matters for the 1-bit transmitarray), zero where the
//!   gain is below 10⁻³ of its peak and clamped to ±1 ns.
//! * Delay domain: a sweep of K points at step Δf (B = (K − 1)Δf) sampled on a flat echo
//!   a·e^{−j2πfτ}, windowed and put through the zero-padded IFFT, gives
//!   h(t) = e^{jπBt}·a·e^{−j2πf_cτ}·r(t − τ), with the real kernel (symmetric window)
//!   r(t) = Σ_k w_k cos(2π(k − m)Δf t) / Σ_k w_k, m = (K − 1)/2.
//!   Sampled at frequency steps Δf, the CIR is periodic in delay with period T = 1/Δf
//!   (801 points over 6 GHz: T = 133.3 ns, c·T/2 = 20 m): with T, each term's argument
//!   moves by 2π(k − m), so r(t + T) = cos(2π(k − m))·r(t) = (−1)^{K−1}·r(t) — periodic for
//!   an odd K (m an integer), anti-periodic for an even K (m half an integer), while
//!   e^{jπB(t+T)} = (−1)^{K−1}·e^{jπBt}, so h itself is periodic either way. An echo at any
//!   delay τ thus reaches the span through its images: r(t − τ) = Σ_k ε^k·r̃(t − τ − kT),
//!   ε = (−1)^{K−1}, r̃ the kernel over one period centred on 0, for every integer k that
//!   brings τ + kT within the span ± the kernel's reach; the carrier phase e^{−j2πf_cτ}
//!   stays on the true τ. r̃ is tabulated at T_b/64 over ±min(16, ⌊(K − 1)/2⌋) bins (no two
//!   images overlap) and read linearly; beyond it r is taken as 0 (a Hann kernel is below
//!   −80 dB at ±16 bins; a rectangular window's, or a sweep of so few points that the
//!   reach is capped below 16 bins, is cut higher, near −34 dB for `rect`).

use crate::campaign::manifest::WindowKind;
use crate::energy::{self, EnergyProcessor};
use crate::pattern::PatternTable;
use crate::units::C0;
use num_complex::Complex64;
use std::f64::consts::PI;

/// Kernel table: samples per bin and half-width in bins.
const KERNEL_FINE: usize = 64;
/// Half-width of the kernel table, bins.
const KERNEL_BINS: usize = 16;

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

/// The real window kernel r(t) of the energy stage, tabulated at T_b/64 over ±16 bins (at
/// most half the period), and its periodic continuation (module docs).
pub(super) struct Kernel {
    step_s: f64,
    half: usize,
    r: Vec<f64>,
    /// tail[k] = max r(t)² over |t| ≥ k bins, k = 0..=bins (non-increasing).
    tail: Vec<f64>,
    /// Bins of the table's half-width: min(16, ⌊(K − 1)/2⌋).
    bins: usize,
    /// The period T = 1/Δf, s.
    period_s: f64,
    /// ε in r(t + T) = ε·r(t): +1 for an odd number of points K, −1 for an even one.
    sign: f64,
    /// The window w_k / Σw, Δf and (K − 1)/2, for the exact sum.
    w: Vec<f64>,
    df: f64,
    mid: f64,
}

impl Kernel {
    pub(super) fn new(proc: &EnergyProcessor) -> Kernel {
        let band = proc.band();
        let w = energy::window(proc.processing().window, band.points);
        let wsum: f64 = w.iter().sum();
        let w: Vec<f64> = w.iter().map(|v| v / wsum).collect();
        let df = band.step_hz();
        let mid = (band.points - 1) as f64 / 2.0;
        let step_s = proc.bin_width_ns() * 1e-9 / KERNEL_FINE as f64;
        // the images of one period must not overlap: at most half the period's K − 1 bins
        let bins = KERNEL_BINS.min((band.points - 1) / 2);
        let half = KERNEL_FINE * bins;
        let mut k = Kernel {
            step_s,
            half,
            r: Vec::new(),
            tail: Vec::new(),
            bins,
            period_s: 1.0 / df,
            sign: if band.points % 2 == 1 { 1.0 } else { -1.0 },
            w,
            df,
            mid,
        };
        k.r = (0..=2 * half)
            .map(|i| k.exact((i as f64 - half as f64) * step_s))
            .collect();
        k.tail = (0..=bins)
            .map(|b| {
                let m = b * KERNEL_FINE;
                (k.r.iter().enumerate())
                    .filter(|(i, _)| i.abs_diff(half) >= m)
                    .map(|(_, v)| v * v)
                    .fold(0.0, f64::max)
            })
            .collect();
        k
    }

    /// r(t) = Σ_k w_k cos(2π(k − (K − 1)/2)Δf t) / Σ_k w_k, summed (exact at any t).
    pub(super) fn exact(&self, t: f64) -> f64 {
        (self.w.iter().enumerate())
            .map(|(k, wk)| wk * (2.0 * PI * (k as f64 - self.mid) * self.df * t).cos())
            .sum()
    }

    /// The table's half-width, s: the reach of one image.
    pub(super) fn half_width_s(&self) -> f64 {
        self.bins as f64 * KERNEL_FINE as f64 * self.step_s
    }

    /// The reach, s, beyond which r(t)² stays below `frac` (a ray's cull level over its
    /// power): whole bins, at most the table's half-width.
    pub(super) fn reach_s(&self, frac: f64) -> f64 {
        let k = self
            .tail
            .iter()
            .position(|&t| t < frac)
            .unwrap_or(self.bins);
        k as f64 * KERNEL_FINE as f64 * self.step_s
    }

    /// The table, read linearly: r(t) for −half-width ≤ t < half-width, else 0.
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

    /// h[n + half] += a·r̃(n·dt − τ) for n = `n_lo`..=`n_hi`, the samples with
    /// |n·dt| < `gate` left out: [`Kernel::at`] sample by sample (the same operations in the
    /// same order, so the same sums bit for bit), in blocks whose positions x on the table
    /// are computed first, where the divisions vectorise.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(super) fn accumulate(
        &self,
        h: &mut [Complex64],
        a: Complex64,
        tau: f64,
        n_lo: i64,
        n_hi: i64,
        dt: f64,
        half: i64,
        gate: f64,
    ) {
        const BLOCK: usize = 32;
        let (step, off) = (self.step_s, self.half as f64);
        let last = (self.r.len() - 1) as f64;
        let r = &self.r[..];
        let mut n = n_lo;
        while n <= n_hi {
            let m = ((n_hi - n + 1) as usize).min(BLOCK);
            let n0 = n as f64;
            let mut ts = [0.0f64; BLOCK];
            let mut xs = [0.0f64; BLOCK];
            for j in 0..m {
                // (n + j) as f64, exactly (|n| < 2⁵³)
                ts[j] = (n0 + j as f64) * dt;
                xs[j] = (ts[j] - tau) / step + off;
            }
            let base = (n + half) as usize;
            let hs = &mut h[base..base + m];
            for ((hv, &t), &x) in hs.iter_mut().zip(&ts[..m]).zip(&xs[..m]) {
                if t.abs() < gate || x < 0.0 || x >= last {
                    continue;
                }
                let i = x as usize;
                let f = x - i as f64;
                *hv += a * (r[i] * (1.0 - f) + r[i + 1] * f);
            }
            n += m as i64;
        }
    }

    /// The images of an echo at delay `tau` that reach a sample in [`lo`, `hi`] (s) within
    /// `reach` of them: (τ + mT, ε^m) for every integer m with τ + mT in
    /// [lo − reach, hi + reach], so r(t − τ) = Σ_m ε^m·r̃(t − τ − mT) on the samples, r̃ the
    /// table.
    pub(super) fn images(
        &self,
        tau: f64,
        lo: f64,
        hi: f64,
        reach: f64,
    ) -> impl Iterator<Item = (f64, f64)> + '_ {
        let t = self.period_s;
        let m0 = ((lo - reach - tau) / t).ceil() as i64;
        let m1 = ((hi + reach - tau) / t).floor() as i64;
        (m0..=m1).map(move |m| {
            let sign = if m.rem_euclid(2) == 1 { self.sign } else { 1.0 };
            (tau + m as f64 * t, sign)
        })
    }

    /// r(t) from the table and its images, Σ_m ε^m·r̃(t − mT) (what a sample at delay t
    /// gets from an echo at delay 0).
    #[cfg(test)]
    pub(super) fn folded(&self, t: f64) -> f64 {
        let reach = self.half_width_s();
        self.images(0.0, t, t, reach)
            .map(|(tm, sign)| sign * self.at(t - tm))
            .sum()
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

    /// r(t + T) = ε·r(t), ε = +1 for an odd number of points and −1 for an even one (the
    /// exact sum), and the table's periodic continuation (its images with their signs)
    /// equals the exact sum at any delay, several periods out and at negative delays.
    #[test]
    fn kernel_folds_periodic_for_odd_points_and_anti_periodic_for_even() {
        for points in [401usize, 400, 801, 64, 65] {
            let band = Band {
                start_hz: 57.5e9,
                stop_hz: 63.5e9,
                points,
            };
            let proc = EnergyProcessor::new(band, Processing::default()).unwrap();
            let k = Kernel::new(&proc);
            let t_per = 1.0 / band.step_hz();
            let tb = proc.bin_width_ns() * 1e-9;
            let eps = if points % 2 == 1 { 1.0 } else { -1.0 };
            assert_eq!(k.sign, eps);
            let mut worst: f64 = 0.0;
            for i in -400..=400 {
                // fractions of a bin near 0 (the main lobe) and over the side lobes
                let u = i as f64 * 0.0173 * tb;
                for m in [-2.0, -1.0, 1.0, 1.3, 2.4, 3.0] {
                    let t = u + m * t_per;
                    let whole = m.fract() == 0.0;
                    if whole {
                        let want = eps.powi(m as i32) * k.exact(u);
                        assert!(
                            (k.exact(t) - want).abs() < 1e-9,
                            "K = {points}: r({m}T + {u:e}) = {} vs {want}",
                            k.exact(t)
                        );
                    }
                    worst = worst.max((k.folded(t) - k.exact(t)).abs());
                }
            }
            eprintln!("K = {points}: |folded − exact| ≤ {worst:.2e}");
            // the linear reading of a T_b/64 table and the tails beyond it (4–7·10⁻⁵ of the
            // peak measured)
            let tol = 2e-4;
            assert!(worst < tol, "K = {points}: {worst:e}");
            // the sign matters: an echo one period late reads −r for an even K
            let t = 0.2 * tb + t_per;
            assert!((k.folded(t) - eps * k.exact(0.2 * tb)).abs() < 1e-3);
        }
    }
}
