//! One (pose, direction) observation of the EKF: the energy-detector noise model
//! ([`NoiseModel`]), the truncated window kernel ([`truncate_kernel`]), the observation
//! with kernel-folded coefficients ([`Observation`]) and its linearisation at the current
//! mean ([`Linearized`]).
//!
//! Takes a [`Beam`] (c_{m,i} by bin), the measured profile and the kernel; gives the rows
//! k ≥ `min_bin` with at least one illuminated cell, CSR over cells, with
//!   c̃_{k,i} = Σ_m c_{m,i}·K(k − m),
//! and at the mean x⁻: h_k = Σ_i c̃_{k,i}·x_i² + N0·TW, ν_k = z_k − h_k, H_{k,i} = 2·c̃_{k,i}·x_i
//! and R_k = (N0²·TW + 2·N0·Ê_k)/N_p + (ε·Ê_k)² (Ê_k = Σ_i c̃_{k,i}·x_i², the predicted
//! signal energy; the detector statistics of `energy`'s module docs plus a relative model
//! error ε).

use crate::energy::EnergyMeta;
use crate::error::Result;
use crate::grid::Beam;

/// Energy-detector noise statistics of a run (from [`EnergyMeta`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// N0.
    pub n0: f64,
    /// TW (equivalent independent samples per bin).
    pub tw: f64,
    /// Pulses averaged N_p.
    pub pulses: f64,
    /// Relative model error ε.
    pub model_error: f64,
}

impl NoiseModel {
    /// From an energy table's metadata (`file` names it in errors).
    pub fn new(meta: &EnergyMeta, model_error: f64, file: &std::path::Path) -> Result<Self> {
        meta.check_noise(file)?;
        Ok(NoiseModel {
            n0: meta.n0,
            tw: meta.tw,
            pulses: meta.pulses as f64,
            model_error,
        })
    }
    /// Mean energy of a noise-only bin N0·TW.
    pub fn mean(&self) -> f64 {
        self.n0 * self.tw
    }
    /// Variance of a bin with signal energy `es` (≥ 0).
    pub fn variance(&self, es: f64) -> f64 {
        let es = es.max(0.0);
        (self.n0 * self.n0 * self.tw + 2.0 * self.n0 * es) / self.pulses
            + (self.model_error * es).powi(2)
    }
}

/// Window kernel K(0..=J) truncated at `floor_db` below K(0).
pub fn truncate_kernel(kernel: &[f64], floor_db: f64) -> Vec<f64> {
    let k0 = kernel.first().copied().unwrap_or(0.0);
    let floor = k0 * 10f64.powf(floor_db / 10.0);
    let mut j = 0;
    while j + 1 < kernel.len() && kernel[j + 1] >= floor {
        j += 1;
    }
    kernel[..=j.min(kernel.len().saturating_sub(1))].to_vec()
}

/// One (pose, direction) observation: rows = bins, CSR over cells with the kernel-folded
/// coefficients c̃ (cells ascending within a row).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observation {
    /// Bin of each row.
    pub bin: Vec<u32>,
    /// Measured energy of each row.
    pub z: Vec<f64>,
    /// `ptr[j]..ptr[j+1]` are the entries of row j.
    pub ptr: Vec<usize>,
    /// Cell of each entry.
    pub cell: Vec<u32>,
    /// c̃ of each entry.
    pub coef: Vec<f64>,
}

impl Observation {
    /// Rows (bins).
    pub fn rows(&self) -> usize {
        self.bin.len()
    }
    /// Build from a beam (c_{m,i} by bin), the measured profile, the truncated kernel
    /// K(0..=J) and the usable bins `[min_bin, profile.len())`. `scratch` must hold one
    /// f64 per grid cell, all zero (it is left zero).
    pub fn build(
        beam: &Beam,
        profile: &[f64],
        kernel: &[f64],
        min_bin: usize,
        scratch: &mut [f64],
    ) -> Observation {
        let bins = profile.len().min(beam.ptr.len().saturating_sub(1));
        let jmax = kernel.len().saturating_sub(1);
        let mut o = Observation {
            ptr: vec![0],
            ..Default::default()
        };
        let mut touched: Vec<u32> = Vec::new();
        for k in min_bin..bins {
            let lo = k.saturating_sub(jmax);
            let hi = (k + jmax).min(bins - 1);
            for m in lo..=hi {
                let kv = kernel[k.abs_diff(m)];
                for e in beam.bin_range(m) {
                    let c = beam.cell[e];
                    let v = &mut scratch[c as usize];
                    if *v == 0.0 {
                        touched.push(c);
                    }
                    *v += beam.coef[e] as f64 * kv;
                }
            }
            if touched.is_empty() {
                continue;
            }
            touched.sort_unstable();
            for &c in &touched {
                let v = std::mem::take(&mut scratch[c as usize]);
                if v > 0.0 {
                    o.cell.push(c);
                    o.coef.push(v);
                }
            }
            touched.clear();
            if o.cell.len() > *o.ptr.last().unwrap_or(&0) {
                o.bin.push(k as u32);
                o.z.push(profile[k]);
                o.ptr.push(o.cell.len());
            }
        }
        o
    }
}

impl Observation {
    /// Keep only the rows whose bin satisfies `keep` (entries of the others dropped).
    pub fn retain_rows(&mut self, keep: impl Fn(u32) -> bool) {
        let mut out = Observation {
            ptr: vec![0],
            ..Default::default()
        };
        for j in 0..self.rows() {
            if !keep(self.bin[j]) {
                continue;
            }
            let (a, b) = (self.ptr[j], self.ptr[j + 1]);
            out.cell.extend_from_slice(&self.cell[a..b]);
            out.coef.extend_from_slice(&self.coef[a..b]);
            out.bin.push(self.bin[j]);
            out.z.push(self.z[j]);
            out.ptr.push(out.cell.len());
        }
        *self = out;
    }
}

/// An observation linearised at the mean x⁻: per row the predicted energy h (with the noise
/// mean), the innovation ν = z − h and R; per entry H = 2·c̃·x⁻ and x⁻.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Linearized {
    /// Predicted energy h_k(x⁻) (signal + noise mean).
    pub h: Vec<f64>,
    /// Innovation ν_k.
    pub nu: Vec<f64>,
    /// Measurement variance R_k.
    pub r: Vec<f64>,
    /// Jacobian entry H_{k,i} (aligned with the observation's entries).
    pub hval: Vec<f64>,
    /// x⁻_i of each entry.
    pub x0: Vec<f64>,
}

impl Linearized {
    /// A direct measurement of the cells of `obs` (one entry per row): row j observes
    /// z_j = x_{cell_j} + noise of variance `r[j]` (H = 1, linear, so the linearisation is
    /// exact). The free-space evidence of [`crate::ekf`] (z = 0).
    pub fn direct(obs: &Observation, x: &[f64], r: &[f64]) -> Linearized {
        let mut l = Linearized {
            h: Vec::with_capacity(obs.rows()),
            nu: Vec::with_capacity(obs.rows()),
            r: r.to_vec(),
            hval: Vec::with_capacity(obs.rows()),
            x0: Vec::with_capacity(obs.rows()),
        };
        for j in 0..obs.rows() {
            debug_assert_eq!(obs.ptr[j + 1] - obs.ptr[j], 1);
            let xi = x[obs.cell[obs.ptr[j]] as usize];
            l.h.push(xi);
            l.nu.push(obs.z[j] - xi);
            l.hval.push(1.0);
            l.x0.push(xi);
        }
        l
    }

    /// Linearise `obs` at `x` with the noise model.
    pub fn new(obs: &Observation, x: &[f64], noise: &NoiseModel) -> Linearized {
        let n = obs.cell.len();
        let mut l = Linearized {
            h: Vec::with_capacity(obs.rows()),
            nu: Vec::with_capacity(obs.rows()),
            r: Vec::with_capacity(obs.rows()),
            hval: Vec::with_capacity(n),
            x0: Vec::with_capacity(n),
        };
        for j in 0..obs.rows() {
            let mut es = 0.0;
            for e in obs.ptr[j]..obs.ptr[j + 1] {
                let xi = x[obs.cell[e] as usize];
                let c = obs.coef[e];
                es += c * xi * xi;
                l.hval.push(2.0 * c * xi);
                l.x0.push(xi);
            }
            let h = es + noise.mean();
            l.h.push(h);
            l.nu.push(obs.z[j] - h);
            l.r.push(noise.variance(es));
        }
        l
    }

    /// Linearise `obs` at `x` with the terms of the Gaussian second-order filter
    /// (Jazwinski 1970; Bar-Shalom, Li & Kirubarajan 2001, §10.3). For h_k = Σ_i c̃_{k,i}·x_i²
    /// the Hessian is 2·diag(c̃_k), so the predicted energy gains ½·tr(H_xx·P) = Σ_i c̃_{k,i}·P_ii
    /// (the mean of a quadratic form under N(x, P)) and R_k gains
    /// ½·tr(H_xx·P·H_xx·P) = 2·Σ_ij c̃_{k,i}·c̃_{k,j}·P_ij² (its variance); the detector
    /// noise is taken at the predicted signal energy Σ_i c̃_{k,i}·(x_i² + P_ii). H is the
    /// Jacobian at `x` as in [`Linearized::new`]. `block(i)` names the block of cell i
    /// (cells of different blocks have no covariance: the tiled filter's tiles; one block for
    /// the dense filter) and `cov(i, j)` is P_ij within a block. Cost per row: the sum over
    /// its blocks of (entries in the block)².
    pub fn second_order(
        obs: &Observation,
        x: &[f64],
        noise: &NoiseModel,
        block: &dyn Fn(usize) -> u32,
        cov: &dyn Fn(usize, usize) -> f64,
    ) -> Linearized {
        let mut l = Linearized::new(obs, x, noise);
        let mut by_block: Vec<(u32, usize)> = Vec::new();
        for j in 0..obs.rows() {
            let (e0, e1) = (obs.ptr[j], obs.ptr[j + 1]);
            let mut es = 0.0;
            let mut bias = 0.0;
            let mut var2 = 0.0;
            by_block.clear();
            for e in e0..e1 {
                let ci = obs.cell[e] as usize;
                let c = obs.coef[e];
                es += c * x[ci] * x[ci];
                let pii = cov(ci, ci);
                bias += c * pii;
                var2 += c * c * pii * pii;
                by_block.push((block(ci), e));
            }
            by_block.sort_unstable();
            let mut a = 0;
            while a < by_block.len() {
                let mut b = a + 1;
                while b < by_block.len() && by_block[b].0 == by_block[a].0 {
                    b += 1;
                }
                for (u, &(_, e)) in by_block[a..b].iter().enumerate() {
                    let (ci, c) = (obs.cell[e] as usize, obs.coef[e]);
                    for &(_, f) in &by_block[a + u + 1..b] {
                        let pij = cov(ci, obs.cell[f] as usize);
                        var2 += 2.0 * c * obs.coef[f] * pij * pij;
                    }
                }
                a = b;
            }
            let h = es + bias + noise.mean();
            l.h[j] = h;
            l.nu[j] = obs.z[j] - h;
            l.r[j] = noise.variance(es + bias) + 2.0 * var2;
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One row over two cells, c̃ = (1, 2), x = (0.1, 0.2), P = [[0.01, 0.005], [0.005, 0.04]],
    /// no detector noise: h = Σ c̃ (x² + P_ii) = 0.09 + 0.09, and the quadratic term's
    /// variance 2·Σ_ij c̃_i c̃_j P_ij² = 2·(1e-4 + 2·2·2.5e-5 + 4·1.6e-3) = 0.0132 (0.013
    /// when the two cells are in different blocks: no covariance between them).
    #[test]
    fn second_order_terms_are_the_quadratic_forms_mean_and_variance() {
        let obs = Observation {
            bin: vec![5],
            z: vec![0.5],
            ptr: vec![0, 2],
            cell: vec![0, 1],
            coef: vec![1.0, 2.0],
        };
        let noise = NoiseModel {
            n0: 0.0,
            tw: 1.0,
            pulses: 1.0,
            model_error: 0.0,
        };
        let p = [[0.01, 0.005], [0.005, 0.04]];
        let x = [0.1, 0.2];
        let one = Linearized::second_order(&obs, &x, &noise, &|_| 0, &|i, j| p[i][j]);
        assert!((one.h[0] - 0.18).abs() < 1e-15);
        assert!((one.nu[0] - 0.32).abs() < 1e-15);
        assert!((one.r[0] - 0.0132).abs() < 1e-15, "{}", one.r[0]);
        assert_eq!(one.hval, vec![0.2, 0.8]);
        let two = Linearized::second_order(&obs, &x, &noise, &|i| i as u32, &|i, j| p[i][j]);
        assert!((two.r[0] - 0.013).abs() < 1e-15, "{}", two.r[0]);
    }

    #[test]
    fn kernel_is_truncated_at_the_floor() {
        let k = [1.0, 0.5, 0.01, 0.0005, 0.0001];
        assert_eq!(truncate_kernel(&k, -30.0), vec![1.0, 0.5, 0.01]);
    }
}
