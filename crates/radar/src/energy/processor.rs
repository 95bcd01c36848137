//! The per-sweep energy processor: window, zero-padded inverse FFT and bin energies, with
//! the window's noise statistics (TW, ENBW).
//!
//! Takes a [`Band`] and the manifest's [`Processing`] options; gives, per sweep S_k, the
//! energy of every delay bin:
//! * window w_k (symmetric Hann w_k = ½ − ½·cos(2πk/(K−1)), or rectangular), zero-padded
//!   IFFT of length N = (K−1)·L, normalised so a flat unit S21 gives |h(0)| = 1:
//!   h_n = Σ_k w_k S_k e^{j2πkn/N} / Σ_k w_k;
//! * bin b is centred at delay b·T_b, T_b = 1/B, and its energy is the mean of |h_n|² over
//!   its L samples n = bL − (L−1)/2 … bL + (L−1)/2 (circular);
//! * `gate` coupling removal zeroes the ⌈gate/dt⌉ samples at each end of the CIR (signed
//!   delays in [−gate, gate));
//! * TW = L² / Σ_{n,m∈bin} |ρ(n−m)|², ρ(Δ) = Σ w_k² e^{j2πkΔ/N} / Σ w_k², and
//!   ENBW = K·Σw²/(Σw)².
//!
//! The steps are public ([`EnergyProcessor::cir_into`], [`EnergyProcessor::add_baseband`],
//! [`EnergyProcessor::gate`], [`EnergyProcessor::bins_into`]; together
//! [`EnergyProcessor::receive_into`]) so `synth` puts its receiver noise through the same
//! code, with its rays added to the CIR in the delay domain.
//!
//! `Band` and `Processing` are validated by their own inherent `check` (manifest file
//! contents, checked where the manifest is read and again here, cheaply): they are not a
//! `ParamGuard` parameter set, since the values come from the campaign file, not from flags.
//!
//! ```
//! use pradar_formats::campaign::manifest::{Band, Processing};
//! use pradar_radar::energy::EnergyProcessor;
//!
//! let band = Band { start_hz: 57.5e9, stop_hz: 63.5e9, points: 401 };
//! let p = EnergyProcessor::new(band, Processing::default())?;
//! // a point echo's energy peaks in the bin of its delay
//! let e = p.point_echo_energy(1.0, 10.0e-9);
//! let peak = (0..e.len()).max_by(|&i, &j| e[i].total_cmp(&e[j])).unwrap();
//! assert_eq!(peak, (10.0 / p.bin_width_ns()).round() as usize);
//! # Ok::<(), pradar_formats::error::Error>(())
//! ```

use crate::campaign::manifest::{Band, CouplingRemoval, Processing, WindowKind};
use crate::campaign::sweeps::PositionSweeps;
use crate::error::Result;
use num_complex::Complex64;
use rayon::prelude::*;
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

/// Window coefficients.
pub fn window(kind: WindowKind, points: usize) -> Vec<f64> {
    match kind {
        WindowKind::Rect => vec![1.0; points],
        WindowKind::Hann => (0..points)
            .map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / (points - 1) as f64).cos())
            .collect(),
    }
}

/// The per-sweep processor (window, IFFT, bins).
#[derive(Clone)]
pub struct EnergyProcessor {
    band: Band,
    proc: Processing,
    win: Vec<f64>,
    wsum: f64,
    nfft: usize,
    fft: Arc<dyn Fft<f64>>,
    nbins_full: usize,
    nbins: usize,
    tw: f64,
    enbw: f64,
    /// e^{jπi/L}, i = 0..2L: the baseband rotation of sample n is rot[n mod 2L].
    rot: Vec<Complex64>,
}

impl std::fmt::Debug for EnergyProcessor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnergyProcessor")
            .field("nfft", &self.nfft)
            .field("nbins", &self.nbins)
            .field("tw", &self.tw)
            .finish()
    }
}

impl EnergyProcessor {
    /// Build for a band and processing options.
    pub fn new(band: Band, proc: Processing) -> Result<Self> {
        band.check()?;
        proc.check()?;
        let win = window(proc.window, band.points);
        let wsum: f64 = win.iter().sum();
        let w2: f64 = win.iter().map(|w| w * w).sum();
        let l = proc.oversample;
        let nfft = (band.points - 1) * l;
        let fft = FftPlanner::new().plan_fft_inverse(nfft);
        let nbins_full = band.points - 1;
        let tb_ns = 1e9 / band.bandwidth_hz();
        let nbins = ((proc.max_delay_ns / tb_ns).floor() as usize + 1).min(nbins_full);
        // equivalent number of independent samples per bin
        let rho = |d: i64| -> f64 {
            let z: Complex64 = win
                .iter()
                .enumerate()
                .map(|(k, w)| {
                    Complex64::from_polar(w * w, 2.0 * PI * k as f64 * d as f64 / nfft as f64)
                })
                .sum();
            z.norm() / w2
        };
        let mut s = 0.0;
        for n in 0..l as i64 {
            for m in 0..l as i64 {
                s += rho(n - m).powi(2);
            }
        }
        let tw = (l * l) as f64 / s;
        let enbw = band.points as f64 * w2 / (wsum * wsum);
        let rot = (0..2 * l)
            .map(|i| Complex64::from_polar(1.0, PI * i as f64 / l as f64))
            .collect();
        Ok(EnergyProcessor {
            band,
            proc,
            win,
            wsum,
            nfft,
            fft,
            nbins_full,
            nbins,
            tw,
            enbw,
            rot,
        })
    }

    /// Bin width T_b, ns.
    pub fn bin_width_ns(&self) -> f64 {
        1e9 / self.band.bandwidth_hz()
    }
    /// Bins written (0..=max_delay).
    pub fn nbins(&self) -> usize {
        self.nbins
    }
    /// Bins computed (the whole unambiguous delay span).
    pub fn nbins_full(&self) -> usize {
        self.nbins_full
    }
    /// Equivalent independent samples per bin.
    pub fn tw(&self) -> f64 {
        self.tw
    }
    /// Equivalent noise bandwidth of the window, in frequency steps.
    pub fn enbw(&self) -> f64 {
        self.enbw
    }
    /// The complex correlation of the CIR noise between samples `d` apart, d = 0..L−1:
    /// ρ(d) = Σ w_k² e^{j2πkd/N} / Σ w_k² (ρ(0) = 1, ρ(−d) = ρ(d)*); the L samples of a bin
    /// have the Hermitian Toeplitz correlation matrix R_nm = ρ(n − m).
    pub fn bin_correlation(&self) -> Vec<Complex64> {
        let w2: f64 = self.win.iter().map(|w| w * w).sum();
        (0..self.proc.oversample)
            .map(|d| {
                self.win
                    .iter()
                    .enumerate()
                    .map(|(k, w)| {
                        Complex64::from_polar(
                            w * w,
                            2.0 * PI * k as f64 * d as f64 / self.nfft as f64,
                        )
                    })
                    .sum::<Complex64>()
                    / w2
            })
            .collect()
    }
    /// Per-sample CIR noise mean N0_h for S21 noise variance `sigma2`.
    pub fn noise_per_sample(&self, sigma2: f64) -> f64 {
        sigma2 * self.win.iter().map(|w| w * w).sum::<f64>() / (self.wsum * self.wsum)
    }
    /// Processing options.
    pub fn processing(&self) -> &Processing {
        &self.proc
    }
    /// The band.
    pub fn band(&self) -> &Band {
        &self.band
    }

    /// Scratch buffer for [`Self::profile_into`].
    pub fn scratch(&self) -> (Vec<Complex64>, Vec<Complex64>) {
        (
            vec![Complex64::new(0.0, 0.0); self.nfft],
            vec![Complex64::new(0.0, 0.0); self.fft.get_inplace_scratch_len()],
        )
    }

    /// Energy of every bin (`nbins_full` of them) of one sweep, added with weight `scale` to
    /// `out`: [`Self::cir_into`], [`Self::gate`], [`Self::bins_into`].
    pub fn profile_into(
        &self,
        s21: &[Complex64],
        scratch: &mut (Vec<Complex64>, Vec<Complex64>),
        scale: f64,
        out: &mut [f64],
    ) {
        let nb = out.len().min(self.nbins_full);
        self.receive_into(s21, 0, &[], scratch, scale, &mut out[..nb]);
    }

    /// One sweep of the receiver with a CIR added in the delay domain: the spectrum `s21`
    /// through the window and zero-padded IFFT ([`Self::cir_into`]), plus the baseband CIR
    /// `g` given at the signed samples `first`, `first + 1`, … ([`Self::add_baseband`]),
    /// gated ([`Self::gate`]), and the energies of the first `out.len()` bins added with
    /// weight `scale` to `out` ([`Self::bins_into`]). With `g` empty this is
    /// [`Self::profile_into`]; `synth` passes the receiver noise as `s21` and its rays as `g`.
    pub fn receive_into(
        &self,
        s21: &[Complex64],
        first: i64,
        g: &[Complex64],
        scratch: &mut (Vec<Complex64>, Vec<Complex64>),
        scale: f64,
        out: &mut [f64],
    ) {
        self.cir_into(s21, scratch);
        let buf = &mut scratch.0;
        self.add_baseband(buf, first, g);
        self.gate(buf);
        self.bins_into(buf, scale, out);
    }

    /// The CIR of one sweep into `scratch.0` (N = (K−1)·L samples, sample n at delay
    /// n·dt, circular): h_n = Σ_k w_k S_k e^{j2πkn/N} / Σ_k w_k.
    pub fn cir_into(&self, s21: &[Complex64], scratch: &mut (Vec<Complex64>, Vec<Complex64>)) {
        let (buf, fft_scratch) = scratch;
        let inv = 1.0 / self.wsum;
        for (b, (s, w)) in buf.iter_mut().zip(s21.iter().zip(&self.win)) {
            *b = s * (w * inv);
        }
        for b in buf[s21.len()..].iter_mut() {
            *b = Complex64::new(0.0, 0.0);
        }
        self.fft.process_with_scratch(buf, fft_scratch);
    }

    /// Add to the CIR `cir` ([`Self::cir_into`]) a baseband CIR `g` given at the signed
    /// samples n = `first` + i: cir[n mod N] += e^{jπn/L}·g_i. A flat echo a·e^{−j2πfτ} over
    /// the band gives h_n = e^{jπn/L}·a·e^{−j2πf_cτ}·r(n·dt − τ), f_c the centre frequency
    /// and r(t) = Σ_k w_k cos(2π(k − (K−1)/2)Δf t) / Σ_k w_k the real window kernel
    /// (e^{jπn/L} = e^{jπB·n·dt}); `g` is the sum of a·e^{−j2πf_cτ}·r(t_n − τ) over the
    /// echoes.
    pub fn add_baseband(&self, cir: &mut [Complex64], first: i64, g: &[Complex64]) {
        let (n, l2) = (self.nfft, self.rot.len());
        let mut j = first.rem_euclid(n as i64) as usize;
        let mut r = first.rem_euclid(l2 as i64) as usize;
        for v in g {
            cir[j] += v * self.rot[r];
            j = if j + 1 == n { 0 } else { j + 1 };
            r = if r + 1 == l2 { 0 } else { r + 1 };
        }
    }

    /// The `gate` coupling removal: zero the ⌈gate/dt⌉ samples at each end of the CIR
    /// (signed delays in [−gate, gate)); nothing for the other removals.
    pub fn gate(&self, cir: &mut [Complex64]) {
        if self.proc.coupling == CouplingRemoval::Gate {
            let dt_ns = self.bin_width_ns() / self.proc.oversample as f64;
            let g = (self.proc.gate_ns / dt_ns).ceil() as usize;
            let g = g.min(self.nfft / 2);
            for b in cir[..g].iter_mut() {
                *b = Complex64::new(0.0, 0.0);
            }
            for b in cir[self.nfft - g..].iter_mut() {
                *b = Complex64::new(0.0, 0.0);
            }
        }
    }

    /// The energies of bins 0..`out.len()` (at most `nbins_full`) of the CIR `cir`, added
    /// with weight `scale` to `out`: bin b the mean of |h_n|² over its L samples
    /// n = bL − (L−1)/2 … bL + (L−1)/2 (circular).
    pub fn bins_into(&self, cir: &[Complex64], scale: f64, out: &mut [f64]) {
        let l = self.proc.oversample;
        let norm = scale / l as f64;
        let n = self.nfft;
        for (bin, o) in out.iter_mut().enumerate().take(self.nbins_full) {
            // contiguous but for the bins that wrap past either end, summed in the same
            // order either way
            let start = self.bin_start(bin);
            let e = if start + l <= n {
                cir[start..start + l]
                    .iter()
                    .map(|v| v.norm_sqr())
                    .sum::<f64>()
            } else {
                let (a, b) = (&cir[start..], &cir[..start + l - n]);
                a.iter().chain(b).map(|v| v.norm_sqr()).sum::<f64>()
            };
            *o += e * norm;
        }
    }

    /// The first of bin `bin`'s L samples in the circular CIR: bin·L − (L − 1)/2.
    fn bin_start(&self, bin: usize) -> usize {
        let l = self.proc.oversample;
        (bin * l + self.nfft - (l - 1) / 2) % self.nfft
    }

    /// The bin sums of two CIRs for energies quadratic in a real scale s of the second: bin
    /// b of `u + s·v` has energy A + 2s·B + s²·C, A = Σ|u_n|², B = Σ Re(ū_n v_n) and
    /// C = Σ|v_n|² over the bin's L samples (as [`Self::bins_into`] takes them), each × 1/L
    /// and added with weight `scale` to `out[b] = [A, B, C]`.
    pub fn bin_quadratics_into(
        &self,
        u: &[Complex64],
        v: &[Complex64],
        scale: f64,
        out: &mut [[f64; 3]],
    ) {
        let l = self.proc.oversample;
        let norm = scale / l as f64;
        let n = self.nfft;
        for (bin, o) in out.iter_mut().enumerate().take(self.nbins_full) {
            let start = self.bin_start(bin);
            let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
            for j in 0..l {
                let i = (start + j) % n;
                let (x, y) = (u[i], v[i]);
                a += x.norm_sqr();
                b += x.re * y.re + x.im * y.im;
                c += y.norm_sqr();
            }
            o[0] += a * norm;
            o[1] += b * norm;
            o[2] += c * norm;
        }
    }

    /// Expected bin energies (noise-free) of a point echo of complex amplitude spectrum
    /// `a(f)` = `amp`·e^{−j2πfτ} (flat magnitude) at delay `tau_s`: the window kernel
    /// averaged over each bin. Returns `nbins` values.
    pub fn point_echo_energy(&self, amp2: f64, tau_s: f64) -> Vec<f64> {
        (0..self.nbins)
            .map(|b| self.point_echo_energy_at(amp2, tau_s, b))
            .collect()
    }

    /// Expected energy of bin `bin` for a point echo of power `amp2` at delay `tau_s`.
    pub fn point_echo_energy_at(&self, amp2: f64, tau_s: f64, bin: usize) -> f64 {
        let df = self.band.step_hz();
        let l = self.proc.oversample;
        let dt = 1.0 / (self.nfft as f64 * df);
        let half = ((l - 1) / 2) as i64;
        let mut e = 0.0;
        for j in -half..=half {
            let t = (bin as i64 * l as i64 + j) as f64 * dt;
            let k: Complex64 = self
                .win
                .iter()
                .enumerate()
                .map(|(k, w)| Complex64::from_polar(*w, 2.0 * PI * k as f64 * df * (t - tau_s)))
                .sum();
            e += (k / self.wsum).norm_sqr();
        }
        amp2 * e / l as f64
    }

    /// Energies of one position: `[direction][bin]` (nbins_full per direction), mean over
    /// pulses, coupling removed as configured.
    pub fn position_energy(&self, sw: &PositionSweeps) -> Vec<f64> {
        let nf = sw.points;
        let nd = sw.directions;
        let nk = sw.pulses;
        let mean: Option<Vec<Complex64>> =
            (self.proc.coupling == CouplingRemoval::Mean).then(|| {
                let mut m = vec![Complex64::new(0.0, 0.0); nk * nf];
                // the mean over the directions swept (a missing one is NaN, not a sweep)
                let swept = (0..nd).filter(|&d| sw.has(d)).count().max(1);
                for d in (0..nd).filter(|&d| sw.has(d)) {
                    for k in 0..nk {
                        for (acc, v) in m[k * nf..(k + 1) * nf].iter_mut().zip(sw.sweep(d, k)) {
                            *acc += v;
                        }
                    }
                }
                m.iter_mut().for_each(|v| *v /= swept as f64);
                m
            });
        let nb = self.nbins_full;
        let mut out = vec![0.0; nd * nb];
        out.par_chunks_mut(nb).enumerate().for_each_init(
            || (self.scratch(), vec![Complex64::new(0.0, 0.0); nf]),
            |(scratch, tmp), (d, o)| {
                for k in 0..nk {
                    let s = sw.sweep(d, k);
                    let s: &[Complex64] = match &mean {
                        Some(m) => {
                            for ((t, v), mv) in tmp.iter_mut().zip(s).zip(&m[k * nf..(k + 1) * nf])
                            {
                                *t = v - mv;
                            }
                            tmp
                        }
                        None => s,
                    };
                    self.profile_into(s, scratch, 1.0 / nk as f64, o);
                }
            },
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band() -> Band {
        Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points: 401,
        }
    }

    #[test]
    fn point_echo_lands_in_its_bin_with_kernel_energy() {
        let b = band();
        let proc = Processing {
            coupling: CouplingRemoval::None,
            max_delay_ns: 60.0,
            ..Processing::default()
        };
        let p = EnergyProcessor::new(b, proc).unwrap();
        let tau = 20.0e-9;
        let a = 0.01;
        let s: Vec<Complex64> = (0..b.points)
            .map(|k| Complex64::from_polar(a, -2.0 * PI * b.freq(k) * tau))
            .collect();
        let mut out = vec![0.0; p.nbins_full()];
        p.profile_into(&s, &mut p.scratch(), 1.0, &mut out);
        let peak = (0..p.nbins())
            .max_by(|&i, &j| out[i].total_cmp(&out[j]))
            .unwrap();
        assert_eq!(peak, (20.0 / p.bin_width_ns()).round() as usize);
        let expect = p.point_echo_energy(a * a, tau);
        for bi in peak - 3..=peak + 3 {
            assert!(
                (out[bi] - expect[bi]).abs() < 1e-6 * expect[peak],
                "bin {bi}: {} vs {}",
                out[bi],
                expect[bi]
            );
        }
    }

    #[test]
    fn hann_enbw_and_tw() {
        let p = EnergyProcessor::new(band(), Processing::default()).unwrap();
        assert!((p.enbw() - 1.5).abs() < 0.01, "enbw {}", p.enbw());
        assert!(p.tw() > 1.0 && p.tw() < 1.5, "tw {}", p.tw());
    }
}
