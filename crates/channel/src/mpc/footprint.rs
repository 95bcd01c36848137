//! The CLEAN footprint model: the energy a component at (θ̂, b̂) leaves at beam d and bin b,
//! A·W(θ_d − θ̂)·K(b − b̂).
//!
//! * W(θ) = Σ_f w_f |F(θ,f)|⁴ / max_θ Σ_f w_f |F(θ,f)|⁴, the two-way array pattern averaged
//!   over the band with the window's weights (33 frequencies; the energy of a bin integrates
//!   the band), tabulated over the array-frame angle −90°..90° every 0.05°. Mechanical
//!   steering: one table, the scatterer at θ̂ seen with the beam at θ_d; electronic: one
//!   table per beam (the pattern of beam d).
//! * K(δ): the window kernel's bin energy of a unit point echo at a fractional bin offset δ,
//!   tabulated every 0.02 bin over ±`kernel_bins` and normalised to K(0) = 1.
//!
//! Both are read by linear interpolation and are 0 outside their tables.

use crate::campaign::manifest::{Campaign, Steering};
use crate::energy::{EnergyMatrix, EnergyProcessor};
use crate::error::Result;
use crate::pattern::ArrayPattern;
use rayon::prelude::*;

/// The CLEAN footprint model: two-way pattern and window kernel.
pub(crate) struct Footprint {
    /// Kernel K(δ) at δ = i·KSTEP − kernel_bins, normalised to K(0) = 1.
    kernel: Vec<f64>,
    kernel_bins: usize,
    /// Two-way pattern weight over the array-frame angle −90°..90° at WSTEP, one table per
    /// beam (a single shared table for mechanical steering).
    w: Vec<Vec<f64>>,
    pub(crate) steering: Steering,
}

/// Step of the kernel table, bins.
const KSTEP: f64 = 0.02;
/// Step of the pattern table, degrees.
const WSTEP: f64 = 0.05;

/// Linear interpolation of `table` at fractional index `x` (0 outside).
fn interpolate(table: &[f64], x: f64) -> f64 {
    if x < 0.0 || x >= (table.len() - 1) as f64 {
        return 0.0;
    }
    let i = x.floor() as usize;
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

impl Footprint {
    /// The footprint model of campaign `c`'s array, band and processing for the energy
    /// matrix `em`.
    pub(crate) fn new(c: &Campaign, em: &EnergyMatrix, kernel_bins: usize) -> Result<Self> {
        let m = &c.manifest;
        Ok(Footprint {
            kernel: kernel_table(c, em, kernel_bins)?,
            kernel_bins,
            w: pattern_tables(c, em)?,
            steering: m.array.steering,
        })
    }

    /// K at a fractional bin offset.
    pub(crate) fn k(&self, delta: f64) -> f64 {
        interpolate(&self.kernel, (delta + self.kernel_bins as f64) / KSTEP)
    }

    /// Two-way weight of a scatterer at `theta` (deg, relative to heading) seen with beam
    /// `d` pointing at `beam` (deg).
    pub(crate) fn w(&self, theta: f64, d: usize, beam: f64) -> f64 {
        let (table, th) = match self.steering {
            Steering::Mechanical => (&self.w[0], theta - beam),
            Steering::Electronic => (&self.w[d], theta),
        };
        interpolate(table, (th + 90.0) / WSTEP)
    }
}

impl Footprint {
    /// The first beam's weight table and the index of its peak.
    fn broadside(&self) -> (&[f64], usize) {
        let t = &self.w[0];
        let peak = t
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |x| x.0);
        (t, peak)
    }

    /// The two-way half-power beamwidth, degrees (of the broadside table for mechanical
    /// steering, of beam 0's for electronic).
    pub(crate) fn half_power_deg(&self) -> f64 {
        let (t, peak) = self.broadside();
        let up = (peak..t.len()).find(|&i| t[i] < 0.5).unwrap_or(t.len() - 1) - peak;
        let down = peak - (0..=peak).rev().find(|&i| t[i] < 0.5).unwrap_or(0);
        (up + down) as f64 * WSTEP
    }

    /// The largest angle from the beam at which the two-way weight still reaches `thr`,
    /// degrees (at most 90°).
    pub(crate) fn reach_deg(&self, thr: f64) -> f64 {
        let (t, peak) = self.broadside();
        let far = t
            .iter()
            .enumerate()
            .filter(|(_, &v)| v >= thr)
            .map(|(i, _)| i.abs_diff(peak))
            .max()
            .unwrap_or(0);
        (far as f64 * WSTEP).min(90.0)
    }
}

/// K(δ) every KSTEP over ±`kernel_bins`: bin energies of a unit echo at delay (kb − δ)·T_b,
/// read at bin kb (well inside), normalised to K(0) = 1.
fn kernel_table(c: &Campaign, em: &EnergyMatrix, kernel_bins: usize) -> Result<Vec<f64>> {
    let m = &c.manifest;
    let proc = EnergyProcessor::new(m.band, m.processing)?;
    let tb = em.meta.bin_width_ns * 1e-9;
    let kb = (kernel_bins + 2) as f64;
    let n = (2.0 * kernel_bins as f64 / KSTEP).round() as usize + 1;
    let k0 = proc.point_echo_energy_at(1.0, kb * tb, kb as usize);
    Ok((0..n)
        .into_par_iter()
        .map(|i| {
            let delta = i as f64 * KSTEP - kernel_bins as f64;
            proc.point_echo_energy_at(1.0, (kb - delta) * tb, kb as usize) / k0
        })
        .collect())
}

/// W(θ) every WSTEP over −90°..90°, one table per beam (one for mechanical steering): the
/// two-way pattern averaged over the band with the window's weights,
/// W(θ) = Σ_f w_f |F(θ,f)|⁴ / Σ_f w_f |F(θ_peak,f)|⁴.
fn pattern_tables(c: &Campaign, em: &EnergyMatrix) -> Result<Vec<Vec<f64>>> {
    let m = &c.manifest;
    let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
    let knots = 33;
    let wk = crate::energy::window(m.processing.window, knots + 2);
    let beams: Vec<f64> = match m.array.steering {
        Steering::Mechanical => vec![0.0],
        Steering::Electronic => em.angles_rel_deg.iter().map(|a| a.to_radians()).collect(),
    };
    Ok(beams
        .par_iter()
        .map(|&ts| {
            let t = pattern.table(ts, &m.band, knots, WSTEP);
            let na = (180.0 / WSTEP).round() as usize + 1;
            let mut v: Vec<f64> = (0..na)
                .map(|i| {
                    let th = (-90.0 + i as f64 * WSTEP).to_radians();
                    (0..knots)
                        .map(|k| wk[k + 1] * t.at_knot(th, k).norm_sqr().powi(2))
                        .sum::<f64>()
                })
                .collect();
            let peak = v.iter().cloned().fold(0.0, f64::max).max(1e-300);
            v.iter_mut().for_each(|x| *x /= peak);
            v
        })
        .collect())
}
