//! EKF mapper over the root radar cross section (DESIGN §2 "Mapping", issue 6 parts 1-2).
//!
//! Takes an [`ObservationModel`], a run's [`EnergyMatrix`] (profiles and `n0`, `tw`,
//! `pulses` metadata), the run's window kernel and [`EkfParams`]; gives per cell the
//! posterior mean of the RRCS x_i (m), its standard deviation, a soft map
//! p_i = P(x_i > μ0 | data) and a binary map ([`EkfMap`]).
//!
//! State and prior: x_i = RRCS of cell i (x = √σ), independent Gaussian prior N(μ0, σ0²),
//! μ0 > 0 because the Jacobian 2·c·x vanishes at x = 0 (a cell started at 0 would never be
//! updated). Defaults μ0 = 0.01 m (σ = 1e-4 m², −40 dBsm: a weak cell, about a tenth of the
//! RRCS of a 0.1 m stretch of diffuse wall) and σ0 = 0.1 m (a wall cell, x ≈ 0.05, lies
//! within one σ0 and a corner, x ≈ 0.7, within 7 σ0).
//!
//! Observation of (pose, direction): the energy vector over the usable bins k ≥ `min_bin`
//! that have at least one illuminated cell (main and side lobes down to the observation
//! model's floor; soft input, no detection step). Prediction
//!   h_k(x) = Σ_i c̃_{k,i}·x_i² + N0·TW,
//!   c̃_{k,i} = Σ_m c_{m,i}·K(k − m),
//! c_{m,i} the observation model's radar-equation coefficient of cell i in bin m (share of its
//! sub-samples whose delay rounds to bin m) and K(j) the bin-averaged energy of a unit point
//! echo at the centre of a bin, j bins away ([`crate::mapping::job::window_kernel`], the
//! simulator's and `energy`'s own window, IFFT and bin integration), kept for |j| ≤ J where
//! K(j) ≥ `kernel_floor_db` relative to K(0) (−30 dB: the Hann kernel's main lobe). So a point
//! target of RRCS x at the centre of bin m predicts exactly `point_echo_energy(c·x², τ_m)`,
//! which is what `energy` computes from a simulated point echo (checked in the tests).
//! Jacobian H_{k,i} = 2·c̃_{k,i}·x_i over every illuminated cell. Measurement noise R
//! diagonal from the energy-detector statistics of a bin averaged over N_p pulses
//! (`energy`'s module docs), with the predicted signal energy Ê_k = Σ_i c̃_{k,i}·x_i²:
//!   R_k = (N0²·TW + 2·N0·Ê_k)/N_p + (ε·Ê_k)²,
//! ε = `model_error` (relative standard deviation of the model error of a bin's energy:
//! speckle of a cell holding several scatterers, the centre-frequency pattern; default 0.5;
//! 0 gives the detector statistics alone).
//!
//! Update of one (pose, direction), linearised once at the mean x⁻ before it (standard EKF):
//!   ν = z − h(x⁻), S = H P Hᵀ + R, K = P Hᵀ S⁻¹, x⁺ = x⁻ + K ν, P⁺ = P − K S Kᵀ.
//! After each update the sign symmetry of the model (h depends on x²) is used: a cell whose
//! mean went negative is reflected, x_i → −x_i with row and column i of P negated (an exact
//! change of variables, not an approximation), and means are kept ≥ 1e-3·μ0 so the
//! Jacobian never vanishes ([`RrcsFilter::project_positive`]).
//!
//! Two implementations of [`RrcsFilter`]:
//! * [`DenseEkf`] — exact, full n × n covariance (row-major, 8n² bytes: the reference up to a
//!   few thousand cells; refused above `max_dense_cells`). Only the na illuminated cells have
//!   nonzero columns of H (m rows = bins), so with Y = P[A, :] the update is done as a
//!   rank-r downdate, r = min(m, na):
//!   - m ≤ na: Uᵀ = H_A·Y (sparse rows of H times rows of P), S = Uᵀ[:, A]·H_Aᵀ + R,
//!     S = L·Lᵀ (Cholesky), Wᵀ = L⁻¹Uᵀ, x += Wᵀᵀ·L⁻¹ν, P −= W·Wᵀ;
//!   - m > na: M = H_Aᵀ·S⁻¹·H_A (na × na) without forming the m × m matrix S, by the
//!     push-through identity H_Aᵀ(H_A P_AA H_Aᵀ + R)⁻¹H_A = G(I + P_AA G)⁻¹,
//!     G = H_Aᵀ R⁻¹ H_A (R diagonal). In a symmetric, well-conditioned form: P_AA = L·Lᵀ,
//!     C = I + Lᵀ·G·L (eigenvalues ≥ 1), M = L⁻ᵀ·(I − C⁻¹)·L⁻¹, and the gain applied to
//!     ν is Yᵀ·L⁻ᵀ·C⁻¹·Lᵀ·H_Aᵀ R⁻¹ ν; then P −= Yᵀ·(M·Y). Cost O(nnz + na³) instead of
//!     O(m³ + m²·na) (a 451-bin observation over 90 cells: 4–6 ms per update against
//!     16–18 ms through S at 1,024 cells, `scripts/bench-ekf`). If P_AA or C is not
//!     numerically positive definite the update goes through S instead:
//!     S = H_A·P_AA·H_Aᵀ + R, V = L⁻¹H_A, M = VᵀV, x += Yᵀ·Vᵀ·L⁻¹ν, P −= Yᵀ·(M·Y).
//!
//!   All bins of the observation are processed together (one batch per (pose, direction)).
//!   The downdate is computed on the upper triangle in blocks of 64 rows (matrix products of
//!   `ndarray`/matrixmultiply, blocks in parallel) and mirrored, so P is exactly symmetric
//!   (the symmetric form P − W·Wᵀ rather than the Joseph form, whose cost is n³ per update);
//!   S is symmetrised before its Cholesky factorisation.
//! * [`TiledEkf`] — scalable: the covariance is kept block-diagonal over square tiles of
//!   `tile` × `tile` cells (4 × 4 by default): the covariances among neighbouring cells (the
//!   ones a range ring couples most strongly and that shape a wall's outline) are kept, the
//!   cross-tile ones are dropped. The bins of an observation are processed one at a time as
//!   scalar measurements of the same linearisation (frozen at x⁻: innovation
//!   ν'_k = z_k − h_k(x⁻) − H_k·(x − x⁻)), which for a full covariance is exactly the batch
//!   update above (R is diagonal); per bin: g_T = P_T·H_{k,T}ᵀ for every tile T the bin
//!   touches, s = Σ_T H_{k,T}·g_T + R_k, x_T += g_T·ν'_k/s, P_T −= g_T·g_Tᵀ/s, and the
//!   cross-tile terms g_T·g_T'ᵀ/s are dropped. The cost per bin is Σ_T (|T|·nnz + |T|²), so a
//!   campaign costs O(nnz(H)·tile²) and memory O(n·tile²). With one tile covering the grid
//!   it equals [`DenseEkf`] (tested). Dropping cross-tile covariances makes the filter
//!   somewhat overconfident about cells coupled through a range ring but in different tiles.
//!
//! Order and determinism: runs, poses and directions in order; the observations of a pose's
//! directions are built in parallel (beam, kernel convolution) and applied in direction
//! order; the dense products split P in fixed blocks, so maps are identical for any number
//! of threads.
//!
//! Binary map: occupied when x̂_i − κ·σ̂_i > μ0 (the data raised the cell above the prior
//! mean by κ posterior standard deviations; κ = 2 by default), i.e. p_i > η = Φ(κ) with
//! p_i = Φ((x̂_i − μ0)/σ̂_i). The rule uses the prior and the posterior only, never the
//! reference map; cells never illuminated stay at the prior and read as free.

use crate::energy::{EnergyMatrix, EnergyMeta};
use crate::error::{Error, Result};
use crate::mapping::grid::{Beam, ObservationModel};
use ndarray::linalg::general_mat_mul;
use ndarray::{s, ArrayView2, ArrayViewMut2};
use rayon::prelude::*;
use std::time::Instant;

/// Which implementation of the EKF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum EkfVariant {
    /// Exact dense covariance ([`DenseEkf`]).
    #[value(name = "dense", help = None::<&str>)]
    Dense,
    /// Block-diagonal covariance by tiles ([`TiledEkf`]).
    #[value(name = "scalable", help = None::<&str>)]
    Scalable,
}

impl EkfVariant {
    /// Name (`dense`, `scalable`).
    pub fn name(&self) -> &'static str {
        match self {
            EkfVariant::Dense => "dense",
            EkfVariant::Scalable => "scalable",
        }
    }
    /// Parse `dense` / `scalable`.
    pub fn parse(s: &str) -> Result<EkfVariant> {
        match s {
            "dense" => Ok(EkfVariant::Dense),
            "scalable" => Ok(EkfVariant::Scalable),
            o => Err(Error::param(
                "ekf",
                format!("unknown EKF variant `{o}` (dense|scalable)"),
            )),
        }
    }
}

/// EKF parameters (see the module docs for the reasons of the defaults).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EkfParams {
    /// Prior mean μ0 of the RRCS, m (0.01; must be > 0).
    pub mu0: f64,
    /// Prior standard deviation σ0, m (0.1).
    pub sigma0: f64,
    /// Relative model-error standard deviation ε of a bin's energy (0.5).
    pub model_error: f64,
    /// Window-kernel truncation, dB below its peak (−30).
    pub kernel_floor_db: f64,
    /// Binary rule: occupied when x̂ − κ·σ̂ > μ0 (κ = 2).
    pub kappa: f64,
    /// Implementation (scalable).
    pub variant: EkfVariant,
    /// Tile side of the scalable filter, cells (4).
    pub tile: usize,
    /// Largest grid the dense filter accepts (20,000 cells = 3.2 GB of covariance).
    pub max_dense_cells: usize,
}

impl Default for EkfParams {
    fn default() -> Self {
        EkfParams {
            mu0: 0.01,
            sigma0: 0.1,
            model_error: 0.5,
            kernel_floor_db: -30.0,
            kappa: 2.0,
            variant: EkfVariant::Scalable,
            tile: 4,
            max_dense_cells: 20_000,
        }
    }
}

impl EkfParams {
    /// Validate.
    pub fn check(&self) -> Result<()> {
        if !(self.mu0.is_finite() && self.mu0 > 0.0) {
            return Err(Error::param(
                "mu0",
                "must be > 0 (the Jacobian 2·c·x vanishes at x = 0)",
            ));
        }
        if !(self.sigma0.is_finite() && self.sigma0 > 0.0) {
            return Err(Error::param("sigma0", "must be > 0"));
        }
        if !(self.model_error.is_finite() && self.model_error >= 0.0) {
            return Err(Error::param("model_error", "must be >= 0"));
        }
        if !(self.kernel_floor_db.is_finite() && self.kernel_floor_db < 0.0) {
            return Err(Error::param(
                "kernel_floor_db",
                "must be a negative dB level",
            ));
        }
        if !(self.kappa.is_finite() && self.kappa >= 0.0) {
            return Err(Error::param("kappa", "must be >= 0"));
        }
        if self.tile == 0 || self.tile > 64 {
            return Err(Error::param("tile", "must be in 1..=64 cells"));
        }
        if self.max_dense_cells == 0 {
            return Err(Error::param("max_dense_cells", "must be > 0"));
        }
        Ok(())
    }
    /// Binary threshold η = Φ(κ) on p = P(x > μ0).
    pub fn eta(&self) -> f64 {
        normal_cdf(self.kappa)
    }
    /// Lowest mean kept by [`RrcsFilter::project_positive`] (1e-3·μ0).
    pub fn x_min(&self) -> f64 {
        1e-3 * self.mu0
    }
}

/// Standard normal CDF Φ.
pub fn normal_cdf(z: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2)
}

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
        if !(meta.n0.is_finite() && meta.n0 > 0.0) {
            return Err(Error::input(
                file,
                "metadata `n0` must be a positive number",
            ));
        }
        if !(meta.tw.is_finite() && meta.tw > 0.0) || meta.pulses == 0 {
            return Err(Error::input(
                file,
                "metadata `tw`/`pulses` must be positive",
            ));
        }
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
}

/// The interface of both EKF implementations.
pub trait RrcsFilter: Send {
    /// Cells.
    fn len(&self) -> usize;
    /// True for an empty grid.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Posterior means.
    fn mean(&self) -> &[f64];
    /// Posterior variances P_ii.
    fn variances(&self) -> Vec<f64>;
    /// Covariance P_ij if the filter keeps it (always for the dense filter).
    fn covariance(&self, i: usize, j: usize) -> Option<f64>;
    /// One EKF update with an observation linearised at the current mean.
    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()>;
    /// Reflect negative means (x_i → −x_i, row/column i of P negated) and keep means
    /// ≥ `x_min`; returns the cells reflected.
    fn project_positive(&mut self, x_min: f64) -> usize;
    /// Name (`dense`, `scalable`).
    fn name(&self) -> &'static str;
}

/// Build the filter of `params.variant` for `cells` cells in a `rows` × `cols` grid.
pub fn new_filter(params: &EkfParams, rows: usize, cols: usize) -> Result<Box<dyn RrcsFilter>> {
    params.check()?;
    Ok(match params.variant {
        EkfVariant::Dense => Box::new(DenseEkf::new(rows * cols, params)?),
        EkfVariant::Scalable => Box::new(TiledEkf::new(rows, cols, params.tile, params)?),
    })
}

// ------------------------------------------------------------------ dense linear algebra

/// In-place lower Cholesky factor of the symmetric m × m matrix `a` (row-major; the upper
/// triangle is zeroed).
pub fn cholesky(a: &mut [f64], m: usize) -> Result<()> {
    if cholesky_in_place(a, m) {
        Ok(())
    } else {
        Err(Error::param(
            "ekf",
            "innovation covariance S is not positive definite (numerical breakdown)",
        ))
    }
}

/// Cholesky factorisation in place (lower triangle, upper zeroed); false when the matrix is
/// not numerically positive definite (then `a` is partly overwritten).
fn cholesky_in_place(a: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if !(d.is_finite() && d > 0.0) {
            return false;
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        let (head, tail) = a.split_at_mut((j + 1) * m);
        let rj = &head[j * m..j * m + j];
        for i in (j + 1)..m {
            let ri = &mut tail[(i - j - 1) * m..(i - j) * m];
            let mut s = ri[j];
            for k in 0..j {
                s -= ri[k] * rj[k];
            }
            ri[j] = s / d;
        }
        for k in (j + 1)..m {
            head[j * m + k] = 0.0;
        }
    }
    true
}

/// Solve L·X = B in place for B (m × w, row-major), L lower m × m; columns in parallel
/// chunks of 256.
fn forward_solve(l: &[f64], m: usize, b: &mut [f64], w: usize) {
    if w == 0 || m == 0 {
        return;
    }
    const CH: usize = 256;
    let chunks = w.div_ceil(CH);
    // transpose-free: process column chunks independently (copy out, solve, copy back)
    let solved: Vec<Vec<f64>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let c0 = c * CH;
            let cw = CH.min(w - c0);
            let mut x = vec![0.0; m * cw];
            for i in 0..m {
                x[i * cw..(i + 1) * cw].copy_from_slice(&b[i * w + c0..i * w + c0 + cw]);
            }
            for i in 0..m {
                let (done, rest) = x.split_at_mut(i * cw);
                let xi = &mut rest[..cw];
                for k in 0..i {
                    let lik = l[i * m + k];
                    if lik != 0.0 {
                        let xk = &done[k * cw..(k + 1) * cw];
                        for (a, b) in xi.iter_mut().zip(xk) {
                            *a -= lik * b;
                        }
                    }
                }
                let inv = 1.0 / l[i * m + i];
                xi.iter_mut().for_each(|v| *v *= inv);
            }
            x
        })
        .collect();
    for (c, x) in solved.into_iter().enumerate() {
        let c0 = c * CH;
        let cw = CH.min(w - c0);
        for i in 0..m {
            b[i * w + c0..i * w + c0 + cw].copy_from_slice(&x[i * cw..(i + 1) * cw]);
        }
    }
}

/// Solve L·y = v (vector).
fn forward_solve_vec(l: &[f64], m: usize, v: &mut [f64]) {
    for i in 0..m {
        let mut s = v[i];
        for k in 0..i {
            s -= l[i * m + k] * v[k];
        }
        v[i] = s / l[i * m + i];
    }
}

/// Solve Lᵀ·y = v (vector).
fn backward_solve_vec(l: &[f64], m: usize, v: &mut [f64]) {
    for i in (0..m).rev() {
        let mut s = v[i];
        for k in (i + 1)..m {
            s -= l[k * m + i] * v[k];
        }
        v[i] = s / l[i * m + i];
    }
}

/// L⁻¹ of a lower-triangular m × m factor (row-major).
fn lower_inverse(l: &[f64], m: usize) -> Vec<f64> {
    let mut inv = vec![0.0; m * m];
    for a in 0..m {
        inv[a * m + a] = 1.0;
    }
    forward_solve(l, m, &mut inv, m);
    inv
}

/// A⁻¹ = L⁻ᵀ·L⁻¹ from the Cholesky factor L of A (m × m, row-major).
fn inverse_from_cholesky(l: &[f64], m: usize) -> Vec<f64> {
    let linv = lower_inverse(l, m);
    let li = ArrayView2::from_shape((m, m), &linv).expect("shape");
    let mut out = ndarray::Array2::<f64>::zeros((m, m));
    general_mat_mul(1.0, &li.t(), &li, 0.0, &mut out);
    out.into_raw_vec_and_offset().0
}

/// M·Y for M (r × r) and Y (r × n), row-major; columns in parallel blocks of 256.
fn mat_times_rows(mm: &[f64], r: usize, y: &[f64], n: usize) -> Vec<f64> {
    let mut z = vec![0.0; r * n];
    let yv = ArrayView2::from_shape((r, n), y).expect("shape");
    let mv = ArrayView2::from_shape((r, r), mm).expect("shape");
    let cols: Vec<(usize, Vec<f64>)> = (0..n.div_ceil(256))
        .into_par_iter()
        .map(|c| {
            let c0 = c * 256;
            let cw = 256.min(n - c0);
            let mut out = ndarray::Array2::<f64>::zeros((r, cw));
            general_mat_mul(1.0, &mv, &yv.slice(s![.., c0..c0 + cw]), 0.0, &mut out);
            (c0, out.into_raw_vec_and_offset().0)
        })
        .collect();
    for (c0, blk) in cols {
        let cw = blk.len() / r.max(1);
        for a in 0..r {
            z[a * n + c0..a * n + c0 + cw].copy_from_slice(&blk[a * cw..(a + 1) * cw]);
        }
    }
    z
}

const BLOCK: usize = 64;

/// P −= Aᵀ·B on the upper triangle (A, B: r × n row-major), then mirror: P stays exactly
/// symmetric. Row blocks of 64 in parallel.
fn sym_downdate(p: &mut [f64], n: usize, a: &[f64], b: &[f64], r: usize) {
    if r == 0 || n == 0 {
        return;
    }
    let av = ArrayView2::from_shape((r, n), a).expect("shape");
    let bv = ArrayView2::from_shape((r, n), b).expect("shape");
    p.par_chunks_mut(BLOCK * n)
        .enumerate()
        .for_each(|(bi, chunk)| {
            let i0 = bi * BLOCK;
            let rows = chunk.len() / n;
            let mut pv = ArrayViewMut2::from_shape((rows, n), chunk).expect("shape");
            let at = av.slice(s![.., i0..i0 + rows]);
            let bj = bv.slice(s![.., i0..]);
            let mut target = pv.slice_mut(s![.., i0..]);
            general_mat_mul(-1.0, &at.t(), &bj, 1.0, &mut target);
        });
    mirror_upper(p, n);
}

/// Copy the upper triangle onto the lower one (blocked transpose).
fn mirror_upper(p: &mut [f64], n: usize) {
    const T: usize = 32;
    let mut bi = 0;
    while bi < n {
        let mut bj = 0;
        while bj <= bi {
            for i in bi..(bi + T).min(n) {
                for j in bj..(bj + T).min(i) {
                    p[i * n + j] = p[j * n + i];
                }
            }
            bj += T;
        }
        bi += T;
    }
}

// ------------------------------------------------------------------ dense EKF

/// Exact EKF with the full covariance (see the module docs).
#[derive(Debug, Clone)]
pub struct DenseEkf {
    n: usize,
    x: Vec<f64>,
    p: Vec<f64>,
}

/// The active set of an observation: sorted unique cells, and H as CSR over local indices.
struct Active {
    cells: Vec<u32>,
    local: Vec<u32>,
}

fn active_set(obs: &Observation, n: usize) -> Active {
    let mut cells = obs.cell.clone();
    cells.sort_unstable();
    cells.dedup();
    let mut map = vec![u32::MAX; n];
    for (a, &c) in cells.iter().enumerate() {
        map[c as usize] = a as u32;
    }
    let local = obs.cell.iter().map(|&c| map[c as usize]).collect();
    Active { cells, local }
}

impl DenseEkf {
    /// Prior N(μ0, σ0²·I) over `n` cells.
    pub fn new(n: usize, params: &EkfParams) -> Result<DenseEkf> {
        params.check()?;
        if n > params.max_dense_cells {
            return Err(Error::param(
                "ekf",
                format!(
                    "dense EKF over {n} cells needs {:.1} GB of covariance (limit {} cells); use the scalable EKF or a coarser grid",
                    (n * n * 8) as f64 / 1e9,
                    params.max_dense_cells
                ),
            ));
        }
        let mut p = vec![0.0; n * n];
        let v = params.sigma0 * params.sigma0;
        for i in 0..n {
            p[i * n + i] = v;
        }
        Ok(DenseEkf {
            n,
            x: vec![params.mu0; n],
            p,
        })
    }
    /// From an explicit mean and covariance (row-major n × n, symmetric).
    pub fn from_parts(x: Vec<f64>, p: Vec<f64>) -> Result<DenseEkf> {
        let n = x.len();
        if p.len() != n * n {
            return Err(Error::param("ekf", "covariance must be n × n"));
        }
        Ok(DenseEkf { n, x, p })
    }
    /// The covariance (row-major n × n).
    pub fn covariance_matrix(&self) -> &[f64] {
        &self.p
    }

    /// Uᵀ = H·P (m × n, from the sparse rows of H and the rows of P).
    fn ut(&self, obs: &Observation, lin: &Linearized) -> Vec<f64> {
        let n = self.n;
        let m = obs.rows();
        let mut ut = vec![0.0; m * n];
        ut.par_chunks_mut(n).enumerate().for_each(|(j, row)| {
            for e in obs.ptr[j]..obs.ptr[j + 1] {
                let c = obs.cell[e] as usize;
                let h = lin.hval[e];
                for (u, p) in row.iter_mut().zip(&self.p[c * n..(c + 1) * n]) {
                    *u += h * p;
                }
            }
        });
        ut
    }

    /// S = H·Uᵀᵀ... = Uᵀ·Hᵀ + R from Uᵀ (symmetrised).
    fn s_from_ut(obs: &Observation, lin: &Linearized, ut: &[f64], n: usize) -> Vec<f64> {
        let m = obs.rows();
        let mut s = vec![0.0; m * m];
        s.par_chunks_mut(m).enumerate().for_each(|(j, srow)| {
            let uj = &ut[j * n..(j + 1) * n];
            for (k, sk) in srow.iter_mut().enumerate() {
                let mut v = 0.0;
                for e in obs.ptr[k]..obs.ptr[k + 1] {
                    v += lin.hval[e] * uj[obs.cell[e] as usize];
                }
                *sk = v;
            }
        });
        symmetrise_add_r(&mut s, m, &lin.r);
        s
    }

    /// The m > na update without S (see the module docs): with `y` = Y = P[A, :],
    /// P_AA = L·Lᵀ, G = H_Aᵀ·R⁻¹·H_A, b = H_Aᵀ·R⁻¹·ν, Q = Lᵀ·G·L and
    /// C = I + Q = L_C·L_Cᵀ:
    ///   x += Yᵀ·L⁻ᵀ·C⁻¹·Lᵀ·b,   P −= Yᵀ·M·Y with M = L⁻ᵀ·(I − C⁻¹)·L⁻¹,
    /// which equals the S form by the push-through identity
    /// H_Aᵀ·S⁻¹·H_A = G·(I + P_AA·G)⁻¹ = L⁻ᵀ·Q·(I + Q)⁻¹·L⁻¹. Returns false, leaving the
    /// state untouched, when P_AA or C is not numerically positive definite or some R_k ≤ 0.
    fn update_push_through(
        &mut self,
        obs: &Observation,
        lin: &Linearized,
        act: &Active,
        y: &[f64],
    ) -> bool {
        let n = self.n;
        let m = obs.rows();
        let na = act.cells.len();
        if lin.r[..m].iter().any(|r| !(*r > 0.0 && r.is_finite())) {
            return false;
        }
        let mut l = vec![0.0; na * na];
        for a in 0..na {
            for b in 0..na {
                l[a * na + b] = y[a * n + act.cells[b] as usize];
            }
        }
        symmetrise(&mut l, na);
        if !cholesky_in_place(&mut l, na) {
            return false;
        }
        // G and b from the sparse rows of H_A
        let mut g = vec![0.0; na * na];
        let mut bvec = vec![0.0; na];
        for j in 0..m {
            let (e0, e1) = (obs.ptr[j], obs.ptr[j + 1]);
            let ir = 1.0 / lin.r[j];
            for e in e0..e1 {
                let a = act.local[e] as usize;
                let ha = lin.hval[e] * ir;
                bvec[a] += ha * lin.nu[j];
                for f in e0..e1 {
                    g[a * na + act.local[f] as usize] += ha * lin.hval[f];
                }
            }
        }
        // Q = Lᵀ·G·L, C = I + Q
        let lv = ArrayView2::from_shape((na, na), &l).expect("shape");
        let gv = ArrayView2::from_shape((na, na), &g).expect("shape");
        let mut gl = ndarray::Array2::<f64>::zeros((na, na));
        general_mat_mul(1.0, &gv, &lv, 0.0, &mut gl);
        let mut c = ndarray::Array2::<f64>::eye(na);
        general_mat_mul(1.0, &lv.t(), &gl, 1.0, &mut c);
        let mut c = c.into_raw_vec_and_offset().0;
        symmetrise(&mut c, na);
        if !cholesky_in_place(&mut c, na) {
            return false;
        }
        // C⁻¹ = L_C⁻ᵀ·L_C⁻¹ and L⁻¹
        let cinv = inverse_from_cholesky(&c, na);
        let linv = lower_inverse(&l, na);
        // w = L⁻ᵀ·C⁻¹·Lᵀ·b, dx = Yᵀ·w
        let ltb: Vec<f64> = (0..na)
            .map(|a| (a..na).map(|k| l[k * na + a] * bvec[k]).sum())
            .collect();
        let u: Vec<f64> = (0..na)
            .map(|a| (0..na).map(|k| cinv[a * na + k] * ltb[k]).sum())
            .collect();
        let w: Vec<f64> = (0..na)
            .map(|a| (a..na).map(|k| linv[k * na + a] * u[k]).sum())
            .collect();
        let dx: Vec<f64> = (0..n)
            .into_par_iter()
            .map(|i| (0..na).map(|a| y[a * n + i] * w[a]).sum())
            .collect();
        for (x, d) in self.x.iter_mut().zip(dx) {
            *x += d;
        }
        // M = L⁻ᵀ·(I − C⁻¹)·L⁻¹ (= H_Aᵀ·S⁻¹·H_A), Z = M·Y, P −= Yᵀ·Z
        let mut t = ndarray::Array2::<f64>::eye(na);
        {
            let ci = ArrayView2::from_shape((na, na), &cinv).expect("shape");
            t -= &ci;
        }
        let li = ArrayView2::from_shape((na, na), &linv).expect("shape");
        let mut tl = ndarray::Array2::<f64>::zeros((na, na));
        general_mat_mul(1.0, &t, &li, 0.0, &mut tl);
        let mut mm = ndarray::Array2::<f64>::zeros((na, na));
        general_mat_mul(1.0, &li.t(), &tl, 0.0, &mut mm);
        let mut mm = mm.into_raw_vec_and_offset().0;
        symmetrise(&mut mm, na);
        let z = mat_times_rows(&mm, na, y, n);
        sym_downdate(&mut self.p, n, y, &z, na);
        true
    }

    /// The Kalman gain K = P·Hᵀ·S⁻¹ (n × m, row-major) of an observation at the current
    /// state, without updating (for checks).
    pub fn gain(&self, obs: &Observation, lin: &Linearized) -> Result<Vec<f64>> {
        let n = self.n;
        let m = obs.rows();
        let ut = self.ut(obs, lin);
        let mut s = Self::s_from_ut(obs, lin, &ut, n);
        cholesky(&mut s, m)?;
        let mut k = vec![0.0; n * m];
        let mut col = vec![0.0; m];
        for i in 0..n {
            for j in 0..m {
                col[j] = ut[j * n + i];
            }
            forward_solve_vec(&s, m, &mut col);
            backward_solve_vec(&s, m, &mut col);
            k[i * m..(i + 1) * m].copy_from_slice(&col);
        }
        Ok(k)
    }
}

/// Replace the m × m matrix `s` by (s + sᵀ)/2.
fn symmetrise(s: &mut [f64], m: usize) {
    for i in 0..m {
        for j in 0..i {
            let v = 0.5 * (s[i * m + j] + s[j * m + i]);
            s[i * m + j] = v;
            s[j * m + i] = v;
        }
    }
}

/// Symmetrise `s` and add the diagonal `r`.
fn symmetrise_add_r(s: &mut [f64], m: usize, r: &[f64]) {
    symmetrise(s, m);
    for i in 0..m {
        s[i * m + i] += r[i];
    }
}

impl RrcsFilter for DenseEkf {
    fn len(&self) -> usize {
        self.n
    }
    fn mean(&self) -> &[f64] {
        &self.x
    }
    fn variances(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.p[i * self.n + i]).collect()
    }
    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        (i < self.n && j < self.n).then(|| self.p[i * self.n + j])
    }
    fn name(&self) -> &'static str {
        "dense"
    }

    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()> {
        let n = self.n;
        let m = obs.rows();
        if m == 0 {
            return Ok(());
        }
        let act = active_set(obs, n);
        let na = act.cells.len();
        if m <= na {
            // W form: rank m
            let mut wt = self.ut(obs, lin);
            let mut s = Self::s_from_ut(obs, lin, &wt, n);
            cholesky(&mut s, m)?;
            forward_solve(&s, m, &mut wt, n);
            let mut w = lin.nu.clone();
            forward_solve_vec(&s, m, &mut w);
            let dx: Vec<f64> = (0..n)
                .into_par_iter()
                .map(|i| (0..m).map(|j| wt[j * n + i] * w[j]).sum())
                .collect();
            for (x, d) in self.x.iter_mut().zip(dx) {
                *x += d;
            }
            sym_downdate(&mut self.p, n, &wt, &wt, m);
        } else {
            // rank-na form: Y = P[A, :]
            let mut y = vec![0.0; na * n];
            y.par_chunks_mut(n).enumerate().for_each(|(a, row)| {
                let c = act.cells[a] as usize;
                row.copy_from_slice(&self.p[c * n..(c + 1) * n]);
            });
            if self.update_push_through(obs, lin, &act, &y) {
                return Ok(());
            }
            // through S (P_AA or C not numerically positive definite)
            // T = H_A · P_AA (m × na)
            let mut t = vec![0.0; m * na];
            t.par_chunks_mut(na).enumerate().for_each(|(j, row)| {
                for e in obs.ptr[j]..obs.ptr[j + 1] {
                    let a = act.local[e] as usize;
                    let h = lin.hval[e];
                    let ya = &y[a * n..(a + 1) * n];
                    for (b, tv) in row.iter_mut().enumerate() {
                        *tv += h * ya[act.cells[b] as usize];
                    }
                }
            });
            let mut s = vec![0.0; m * m];
            s.par_chunks_mut(m).enumerate().for_each(|(j, srow)| {
                let tj = &t[j * na..(j + 1) * na];
                for (k, sk) in srow.iter_mut().enumerate() {
                    let mut v = 0.0;
                    for e in obs.ptr[k]..obs.ptr[k + 1] {
                        v += lin.hval[e] * tj[act.local[e] as usize];
                    }
                    *sk = v;
                }
            });
            symmetrise_add_r(&mut s, m, &lin.r);
            cholesky(&mut s, m)?;
            // V = L⁻¹ H_A (m × na)
            let mut v = vec![0.0; m * na];
            for j in 0..m {
                for e in obs.ptr[j]..obs.ptr[j + 1] {
                    v[j * na + act.local[e] as usize] += lin.hval[e];
                }
            }
            forward_solve(&s, m, &mut v, na);
            let mut q = lin.nu.clone();
            forward_solve_vec(&s, m, &mut q);
            // g = Vᵀ q (na)
            let mut g = vec![0.0; na];
            for j in 0..m {
                for (gb, vb) in g.iter_mut().zip(&v[j * na..(j + 1) * na]) {
                    *gb += vb * q[j];
                }
            }
            // M = Vᵀ V (na × na)
            let mut mm = vec![0.0; na * na];
            {
                let vv = ArrayView2::from_shape((m, na), &v).expect("shape");
                let mut mv = ArrayViewMut2::from_shape((na, na), &mut mm).expect("shape");
                general_mat_mul(1.0, &vv.t(), &vv, 0.0, &mut mv);
            }
            // Z = M Y (na × n)
            let z = mat_times_rows(&mm, na, &y, n);
            let dx: Vec<f64> = (0..n)
                .into_par_iter()
                .map(|i| (0..na).map(|a| y[a * n + i] * g[a]).sum())
                .collect();
            for (x, d) in self.x.iter_mut().zip(dx) {
                *x += d;
            }
            sym_downdate(&mut self.p, n, &y, &z, na);
        }
        Ok(())
    }

    fn project_positive(&mut self, x_min: f64) -> usize {
        let n = self.n;
        let mut flipped = 0;
        for i in 0..n {
            if self.x[i] < 0.0 {
                self.x[i] = -self.x[i];
                for j in 0..n {
                    self.p[i * n + j] = -self.p[i * n + j];
                    self.p[j * n + i] = -self.p[j * n + i];
                }
                flipped += 1;
            }
            if self.x[i] < x_min {
                self.x[i] = x_min;
            }
        }
        flipped
    }
}

// ------------------------------------------------------------------ tiled (scalable) EKF

/// Scalable EKF: covariance block-diagonal over square tiles (see the module docs).
#[derive(Debug, Clone)]
pub struct TiledEkf {
    x: Vec<f64>,
    /// Tile of each cell.
    cell_tile: Vec<u32>,
    /// Index of each cell inside its tile.
    cell_local: Vec<u16>,
    /// Cells of each tile (row-major order).
    tile_cells: Vec<Vec<u32>>,
    /// Covariance of each tile (|T| × |T| row-major).
    tile_p: Vec<Vec<f64>>,
    /// Scratch: offset of each tile's g vector in `gbuf` for the current row (u32::MAX if
    /// the row does not touch it).
    slot: Vec<u32>,
    /// Scratch: g vectors of the touched tiles, concatenated.
    gbuf: Vec<f64>,
    /// Scratch: tiles the current row touches, in order of first touch.
    touched: Vec<u32>,
    /// Tiles whose means changed since the last `project_positive` (`None`: all cells).
    dirty: Option<Vec<u32>>,
    /// Membership flags of `dirty`.
    dirty_mark: Vec<bool>,
}

impl TiledEkf {
    /// Prior N(μ0, σ0²·I) on a `rows` × `cols` grid with `tile` × `tile` tiles.
    pub fn new(rows: usize, cols: usize, tile: usize, params: &EkfParams) -> Result<TiledEkf> {
        params.check()?;
        if tile == 0 || tile * tile > u16::MAX as usize {
            return Err(Error::param("tile", "must be in 1..=255"));
        }
        let n = rows * cols;
        let (tr, tc) = (rows.div_ceil(tile), cols.div_ceil(tile));
        let mut cell_tile = vec![0u32; n];
        let mut cell_local = vec![0u16; n];
        let mut tile_cells = vec![Vec::new(); tr * tc];
        for r in 0..rows {
            for c in 0..cols {
                let t = (r / tile) * tc + c / tile;
                let i = r * cols + c;
                cell_tile[i] = t as u32;
                cell_local[i] = tile_cells[t].len() as u16;
                tile_cells[t].push(i as u32);
            }
        }
        let v = params.sigma0 * params.sigma0;
        let tile_p = tile_cells
            .iter()
            .map(|cs| {
                let k = cs.len();
                let mut p = vec![0.0; k * k];
                for a in 0..k {
                    p[a * k + a] = v;
                }
                p
            })
            .collect();
        Ok(TiledEkf {
            x: vec![params.mu0; n],
            cell_tile,
            cell_local,
            tile_cells,
            slot: vec![u32::MAX; tr * tc],
            dirty: None,
            dirty_mark: vec![false; tr * tc],
            tile_p,
            gbuf: Vec::new(),
            touched: Vec::new(),
        })
    }
    /// Number of tiles.
    pub fn tiles(&self) -> usize {
        self.tile_cells.len()
    }
    /// Bytes held by the covariance blocks.
    pub fn covariance_bytes(&self) -> usize {
        self.tile_p.iter().map(|p| p.len() * 8).sum()
    }
}

impl RrcsFilter for TiledEkf {
    fn len(&self) -> usize {
        self.x.len()
    }
    fn mean(&self) -> &[f64] {
        &self.x
    }
    fn variances(&self) -> Vec<f64> {
        (0..self.x.len())
            .map(|i| {
                let t = self.cell_tile[i] as usize;
                let k = self.tile_cells[t].len();
                let a = self.cell_local[i] as usize;
                self.tile_p[t][a * k + a]
            })
            .collect()
    }
    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        if i >= self.x.len() || j >= self.x.len() || self.cell_tile[i] != self.cell_tile[j] {
            return None;
        }
        let t = self.cell_tile[i] as usize;
        let k = self.tile_cells[t].len();
        Some(self.tile_p[t][self.cell_local[i] as usize * k + self.cell_local[j] as usize])
    }
    fn name(&self) -> &'static str {
        "scalable"
    }

    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()> {
        for j in 0..obs.rows() {
            let (e0, e1) = (obs.ptr[j], obs.ptr[j + 1]);
            // g_T = P_T h_T for each touched tile (tiles in order of first touch)
            self.gbuf.clear();
            self.touched.clear();
            let mut nu = lin.nu[j];
            for e in e0..e1 {
                let c = obs.cell[e] as usize;
                let h = lin.hval[e];
                nu -= h * (self.x[c] - lin.x0[e]);
                let t = self.cell_tile[c] as usize;
                let k = self.tile_cells[t].len();
                let off = if self.slot[t] == u32::MAX {
                    let off = self.gbuf.len();
                    self.gbuf.resize(off + k, 0.0);
                    self.slot[t] = off as u32;
                    self.touched.push(t as u32);
                    off
                } else {
                    self.slot[t] as usize
                };
                let l = self.cell_local[c] as usize;
                let p = &self.tile_p[t][l * k..(l + 1) * k];
                for (gi, pv) in self.gbuf[off..off + k].iter_mut().zip(p) {
                    *gi += h * pv;
                }
            }
            // s = Σ_T h_T·g_T + R
            let mut s = lin.r[j];
            for e in e0..e1 {
                let c = obs.cell[e] as usize;
                let off = self.slot[self.cell_tile[c] as usize] as usize;
                s += lin.hval[e] * self.gbuf[off + self.cell_local[c] as usize];
            }
            if !(s.is_finite() && s > 0.0) {
                for &t in &self.touched {
                    self.slot[t as usize] = u32::MAX;
                }
                return Err(Error::param(
                    "ekf",
                    "innovation variance is not positive (numerical breakdown)",
                ));
            }
            let inv = 1.0 / s;
            for &t in &self.touched {
                let t = t as usize;
                let off = self.slot[t] as usize;
                self.slot[t] = u32::MAX;
                if let Some(d) = self.dirty.as_mut() {
                    if !self.dirty_mark[t] {
                        self.dirty_mark[t] = true;
                        d.push(t as u32);
                    }
                }
                let cells = &self.tile_cells[t];
                let k = cells.len();
                let gv = &self.gbuf[off..off + k];
                for (a, &c) in cells.iter().enumerate() {
                    self.x[c as usize] += gv[a] * nu * inv;
                }
                let p = &mut self.tile_p[t];
                for a in 0..k {
                    let ga = gv[a] * inv;
                    for (pv, gb) in p[a * k..(a + 1) * k].iter_mut().zip(gv) {
                        *pv -= ga * gb;
                    }
                }
            }
        }
        Ok(())
    }

    fn project_positive(&mut self, x_min: f64) -> usize {
        // only the cells of tiles updated since the last call can violate the bounds
        let cells: Vec<u32> = match self.dirty.replace(Vec::new()) {
            None => (0..self.x.len() as u32).collect(),
            Some(tiles) => {
                let mut cs = Vec::new();
                for t in tiles {
                    self.dirty_mark[t as usize] = false;
                    cs.extend_from_slice(&self.tile_cells[t as usize]);
                }
                cs
            }
        };
        let mut flipped = 0;
        for i in cells {
            let i = i as usize;
            if self.x[i] < 0.0 {
                self.x[i] = -self.x[i];
                let t = self.cell_tile[i] as usize;
                let k = self.tile_cells[t].len();
                let a = self.cell_local[i] as usize;
                let p = &mut self.tile_p[t];
                for b in 0..k {
                    p[a * k + b] = -p[a * k + b];
                    p[b * k + a] = -p[b * k + a];
                }
                flipped += 1;
            }
            if self.x[i] < x_min {
                self.x[i] = x_min;
            }
        }
        flipped
    }
}

// ------------------------------------------------------------------ the mapper

/// Work statistics of an EKF run.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct EkfStats {
    /// (pose, direction) updates.
    pub updates: u64,
    /// Bin rows processed.
    pub rows: u64,
    /// Nonzeros of H processed.
    pub entries: u64,
    /// Means reflected by the positivity step.
    pub reflected: u64,
    /// Time building observations, s (wall).
    pub build_seconds: f64,
    /// Time in the filter updates, s (wall).
    pub update_seconds: f64,
    /// Total wall time, s.
    pub seconds: f64,
}

/// Run the filter over one run: every pose, every direction, in order; `progress(done,
/// total)` counts poses.
pub fn ekf_run(
    model: &ObservationModel,
    energy: &EnergyMatrix,
    kernel: &[f64],
    params: &EkfParams,
    noise: &NoiseModel,
    filter: &mut dyn RrcsFilter,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<EkfStats> {
    params.check()?;
    let n = model.spec.len();
    if filter.len() != n {
        return Err(Error::param("ekf", "filter and grid sizes differ"));
    }
    if energy.positions != model.poses.len() || energy.directions() != model.directions() {
        return Err(Error::param(
            "ekf",
            "energy table and observation model disagree on poses/directions",
        ));
    }
    let kernel = truncate_kernel(kernel, params.kernel_floor_db);
    let t0 = Instant::now();
    let mut st = EkfStats::default();
    let np = model.poses.len();
    // the observations of pose p are built (in parallel over directions) while those of
    // pose p − 1 are applied, in order, on the calling thread
    let build = |p: usize| -> (Vec<Observation>, f64) {
        let tb = Instant::now();
        let geom = model.pose_geometry(p);
        let obs: Vec<Observation> = (0..model.directions())
            .into_par_iter()
            .map_init(
                || vec![0.0; n],
                |scratch, d| {
                    let beam = model.beam(&geom, d);
                    let prof = energy.profile(p, d);
                    let bins = prof.len().min(model.bins);
                    Observation::build(&beam, &prof[..bins], &kernel, model.min_bin, scratch)
                },
            )
            .collect();
        (obs, tb.elapsed().as_secs_f64())
    };
    let mut current = if np > 0 { Some(build(0)) } else { None };
    for p in 0..np {
        let (obs, build_s) = current.take().expect("built");
        st.build_seconds += build_s;
        let apply = |filter: &mut dyn RrcsFilter, st: &mut EkfStats| -> Result<()> {
            let tu = Instant::now();
            for o in &obs {
                let lin = Linearized::new(o, filter.mean(), noise);
                filter.update(o, &lin)?;
                st.reflected += filter.project_positive(params.x_min()) as u64;
                st.updates += 1;
                st.rows += o.rows() as u64;
                st.entries += o.cell.len() as u64;
            }
            st.update_seconds += tu.elapsed().as_secs_f64();
            Ok(())
        };
        let (applied, next) = rayon::join(
            || apply(&mut *filter, &mut st),
            || (p + 1 < np).then(|| build(p + 1)),
        );
        applied?;
        current = next;
        progress(p + 1, np);
    }
    st.seconds = t0.elapsed().as_secs_f64();
    Ok(st)
}

/// The EKF map: posterior mean and standard deviation per cell, soft and binary maps.
#[derive(Debug, Clone, PartialEq)]
pub struct EkfMap {
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Posterior mean RRCS, m.
    pub mean: Vec<f64>,
    /// Posterior standard deviation, m.
    pub std: Vec<f64>,
    /// Prior mean μ0.
    pub mu0: f64,
    /// κ of the binary rule.
    pub kappa: f64,
}

impl EkfMap {
    /// Snapshot of a filter.
    pub fn from_filter(f: &dyn RrcsFilter, rows: usize, cols: usize, params: &EkfParams) -> Self {
        EkfMap {
            rows,
            cols,
            mean: f.mean().to_vec(),
            std: f.variances().iter().map(|v| v.max(0.0).sqrt()).collect(),
            mu0: params.mu0,
            kappa: params.kappa,
        }
    }
    /// p_i = Φ((x̂_i − μ0)/σ̂_i).
    pub fn probs(&self) -> Vec<f64> {
        self.mean
            .iter()
            .zip(&self.std)
            .map(|(&m, &s)| {
                if s > 0.0 {
                    normal_cdf((m - self.mu0) / s)
                } else if m > self.mu0 {
                    1.0
                } else {
                    0.0
                }
            })
            .collect()
    }
    /// Binary map: x̂ − κ·σ̂ > μ0.
    pub fn binary(&self) -> Vec<bool> {
        self.mean
            .iter()
            .zip(&self.std)
            .map(|(&m, &s)| m - self.kappa * s > self.mu0)
            .collect()
    }
}

// ------------------------------------------------------------------ the `map --method ekf` job

/// EKF section of `metrics.json`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EkfReport {
    /// Parameters used.
    pub params: EkfParams,
    /// Binary threshold η = Φ(κ) on p = P(x > μ0).
    pub eta: f64,
    /// Kernel bins kept each side of the peak.
    pub kernel_half_width: usize,
    /// Work statistics per run (the fused filter's).
    pub stats: Vec<EkfStats>,
    /// Peak covariance storage, bytes.
    pub covariance_bytes: usize,
}

/// Grey of a mean RRCS: white at ≤ μ0/10 (−20 dB re μ0), black at ≥ 1000·μ0 (+60 dB),
/// linear in dB between.
pub fn mean_grey(x: f64, mu0: f64) -> u8 {
    let db = 20.0 * (x.max(1e-30) / mu0).log10();
    let t = ((db + 20.0) / 80.0).clamp(0.0, 1.0);
    (254.0 * (1.0 - t)).round() as u8
}

/// Grey of a posterior standard deviation: black at σ0 (no information), white at 0.
pub fn std_grey(s: f64, sigma0: f64) -> u8 {
    (254.0 * (1.0 - (s / sigma0).clamp(0.0, 1.0))).round() as u8
}

/// `pradar map --method ekf`: the runs are filtered in order by one filter (fusion = the
/// same filter continued over the next run); the fusion table snapshots the map after each
/// run; with several runs each run is also mapped alone. Writes `ekf.*` (soft map p),
/// `ekf_binary.*`, `ekf_mean.*` ([`mean_grey`]), `ekf_std.*` ([`std_grey`]),
/// `ekf_rrcs.csv` (row, col, x_m, y_m, mean_m, std_m, p, occupied), `reference.*` and
/// `metrics.json`.
pub fn run_map_ekf(
    opts: &crate::mapping::job::MapOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<crate::mapping::job::MapReport> {
    use crate::mapping::job::{
        load_runs, runs_region, score_binary, window_kernel, write_reference, FusionRow, MapReport,
        RunSummary,
    };
    use crate::mapping::output::{self, soft_grey, GREY_FREE, GREY_OCCUPIED};
    let params = opts.ekf;
    params.check()?;
    let (loaded, reference) = load_runs(opts)?;
    let spec = reference.spec;
    let region = runs_region(&loaded, &reference);
    let mut kernels = Vec::new();
    let mut noises = Vec::new();
    for l in &loaded {
        kernels.push(window_kernel(&l.campaign)?);
        noises.push(NoiseModel::new(
            &l.energy.meta,
            params.model_error,
            &l.energy_path,
        )?);
    }
    let total: usize = loaded.iter().map(|l| l.model.poses.len()).sum();
    let mut filter = new_filter(&params, spec.rows, spec.cols)?;
    let mut done = 0;
    let mut stats = Vec::new();
    let mut fusion = Vec::new();
    let mut alone = Vec::new();
    for (i, l) in loaded.iter().enumerate() {
        let base = done;
        let st = ekf_run(
            &l.model,
            &l.energy,
            &kernels[i],
            &params,
            &noises[i],
            filter.as_mut(),
            &|d, _| progress(base + d, total),
        )?;
        done += l.model.poses.len();
        stats.push(st);
        let snap = EkfMap::from_filter(filter.as_ref(), spec.rows, spec.cols, &params);
        let m = score_binary(&snap.binary(), &reference, &region);
        fusion.push(FusionRow {
            runs: i + 1,
            metrics: m,
        });
        if loaded.len() == 1 {
            alone.push(m);
        }
    }
    if loaded.len() > 1 {
        for (i, l) in loaded.iter().enumerate() {
            let mut f = new_filter(&params, spec.rows, spec.cols)?;
            ekf_run(
                &l.model,
                &l.energy,
                &kernels[i],
                &params,
                &noises[i],
                f.as_mut(),
                &|_, _| {},
            )?;
            let snap = EkfMap::from_filter(f.as_ref(), spec.rows, spec.cols, &params);
            alone.push(score_binary(&snap.binary(), &reference, &region));
        }
    }
    let map = EkfMap::from_filter(filter.as_ref(), spec.rows, spec.cols, &params);
    let bin = map.binary();
    let metrics = score_binary(&bin, &reference, &region);
    let probs = map.probs();
    let eta = params.eta();
    // files
    let out = &opts.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let soft: Vec<u8> = probs.iter().map(|&p| soft_grey(p)).collect();
    output::write_map_files(out, "ekf", &spec, &soft, eta, 1.0 - eta)?;
    let bgrey: Vec<u8> = bin
        .iter()
        .map(|&o| if o { GREY_OCCUPIED } else { GREY_FREE })
        .collect();
    output::write_map_files(out, "ekf_binary", &spec, &bgrey, 0.5, 0.45)?;
    let mg: Vec<u8> = map.mean.iter().map(|&x| mean_grey(x, params.mu0)).collect();
    output::write_map_files(out, "ekf_mean", &spec, &mg, 0.65, 0.196)?;
    let sg: Vec<u8> = map
        .std
        .iter()
        .map(|&s| std_grey(s, params.sigma0))
        .collect();
    output::write_map_files(out, "ekf_std", &spec, &sg, 0.65, 0.196)?;
    let mut csv = String::from("row,col,x_m,y_m,mean_m,std_m,p,occupied\n");
    for r in 0..spec.rows {
        for c in 0..spec.cols {
            let i = r * spec.cols + c;
            let ctr = spec.center(r, c);
            csv.push_str(&format!(
                "{r},{c},{:.4},{:.4},{:.6e},{:.6e},{:.6},{}\n",
                ctr.x, ctr.y, map.mean[i], map.std[i], probs[i], bin[i] as u8
            ));
        }
    }
    crate::io::write_bytes(&out.join("ekf_rrcs.csv"), csv.as_bytes())?;
    write_reference(out, &reference)?;
    let runs = loaded
        .iter()
        .zip(&alone)
        .map(|(l, m)| RunSummary {
            campaign: l.campaign.path.display().to_string(),
            energy: l.energy_path.display().to_string(),
            threshold: l.detector.threshold,
            stats: Default::default(),
            metrics: *m,
        })
        .collect();
    let cov_bytes = match params.variant {
        EkfVariant::Dense => spec.len() * spec.len() * 8,
        EkfVariant::Scalable => {
            let t = params.tile;
            spec.rows.div_ceil(t) * spec.cols.div_ceil(t) * t * t * t * t * 8
        }
    };
    let report = MapReport {
        method: "ekf".into(),
        rows: spec.rows,
        cols: spec.cols,
        cell_m: spec.cell_m,
        eta,
        observable_cells: region.iter().filter(|&&v| v).count(),
        metrics,
        runs,
        fusion,
        ekf: Some(EkfReport {
            params,
            eta,
            kernel_half_width: truncate_kernel(&kernels[0], params.kernel_floor_db).len() - 1,
            stats,
            covariance_bytes: cov_bytes,
        }),
        pose_noise: opts.pose_noise,
        binary: bin,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::param("metrics", e.to_string()))?;
    crate::io::write_bytes(&out.join("metrics.json"), json.as_bytes())?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves() {
        let a = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let mut l = a.to_vec();
        cholesky(&mut l, 3).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let v: f64 = (0..3).map(|k| l[i * 3 + k] * l[j * 3 + k]).sum();
                assert!((v - a[i * 3 + j]).abs() < 1e-12);
            }
        }
        let mut bad = vec![1.0, 2.0, 2.0, 1.0];
        assert!(cholesky(&mut bad, 2).is_err());
    }

    #[test]
    fn downdate_is_symmetric_and_right() {
        let n = 70;
        let r = 3;
        let a: Vec<f64> = (0..r * n)
            .map(|i| ((i * 37 % 101) as f64) / 101.0)
            .collect();
        let mut p = vec![0.0; n * n];
        for i in 0..n {
            p[i * n + i] = 10.0;
        }
        let p0 = p.clone();
        sym_downdate(&mut p, n, &a, &a, r);
        for i in 0..n {
            for j in 0..n {
                let v: f64 = (0..r).map(|k| a[k * n + i] * a[k * n + j]).sum();
                assert!((p[i * n + j] - (p0[i * n + j] - v)).abs() < 1e-12);
                assert_eq!(p[i * n + j], p[j * n + i]);
            }
        }
    }

    #[test]
    fn params_are_checked() {
        assert!(EkfParams::default().check().is_ok());
        for bad in [
            EkfParams {
                mu0: 0.0,
                ..Default::default()
            },
            EkfParams {
                sigma0: -1.0,
                ..Default::default()
            },
            EkfParams {
                tile: 0,
                ..Default::default()
            },
            EkfParams {
                model_error: f64::NAN,
                ..Default::default()
            },
        ] {
            assert!(bad.check().is_err());
        }
        assert!((EkfParams::default().eta() - 0.97725).abs() < 1e-4);
        assert!(EkfVariant::parse("dense").is_ok() && EkfVariant::parse("x").is_err());
    }

    #[test]
    fn kernel_is_truncated_at_the_floor() {
        let k = [1.0, 0.5, 0.01, 0.0005, 0.0001];
        assert_eq!(truncate_kernel(&k, -30.0), vec![1.0, 0.5, 0.01]);
    }

    #[test]
    fn tiled_with_one_tile_equals_dense_on_a_random_problem() {
        // 5 × 6 grid, one tile covering it; 8 rows, random coefficients
        let (rows, cols) = (5, 6);
        let n = rows * cols;
        let params = EkfParams {
            tile: 6,
            ..Default::default()
        };
        let mut dense = DenseEkf::new(n, &params).unwrap();
        let mut tiled = TiledEkf::new(rows, cols, 6, &params).unwrap();
        let noise = NoiseModel {
            n0: 1e-6,
            tw: 1.2,
            pulses: 1.0,
            model_error: 0.3,
        };
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..3 {
            let mut o = Observation {
                ptr: vec![0],
                ..Default::default()
            };
            for j in 0..8 {
                let mut cells: Vec<u32> = (0..n as u32).filter(|_| rnd() < 0.3).collect();
                cells.sort_unstable();
                for c in cells {
                    o.cell.push(c);
                    o.coef.push(1e-3 * (0.1 + rnd()));
                }
                o.bin.push(j);
                o.z.push(1e-5 * rnd());
                o.ptr.push(o.cell.len());
            }
            let l1 = Linearized::new(&o, dense.mean(), &noise);
            let l2 = Linearized::new(&o, tiled.mean(), &noise);
            dense.update(&o, &l1).unwrap();
            tiled.update(&o, &l2).unwrap();
        }
        for i in 0..n {
            assert!((dense.mean()[i] - tiled.mean()[i]).abs() < 1e-9 * 0.1);
            for j in 0..n {
                let (a, b) = (
                    dense.covariance(i, j).unwrap(),
                    tiled.covariance(i, j).unwrap(),
                );
                assert!((a - b).abs() < 1e-9 * 0.01, "{i},{j}: {a} vs {b}");
            }
        }
    }
}
