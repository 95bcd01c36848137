//! The exact EKF ([`DenseEkf`]): the full n × n covariance (row-major, 8n² bytes; refused
//! above `max_dense_cells`).
//!
//! Only the na illuminated cells A have nonzero columns of H (m rows = bins), so with
//! Y = P[A, :] an update is a rank-r downdate, r = min(m, na):
//! * m ≤ na: Uᵀ = H_A·Y, S = Uᵀ[:, A]·H_Aᵀ + R = L·Lᵀ, Wᵀ = L⁻¹Uᵀ, x += Wᵀᵀ·L⁻¹ν,
//!   P −= W·Wᵀ;
//! * m > na: M = H_Aᵀ·S⁻¹·H_A (na × na) without forming the m × m matrix S, by the
//!   push-through identity H_Aᵀ(H_A P_AA H_Aᵀ + R)⁻¹H_A = G(I + P_AA G)⁻¹,
//!   G = H_Aᵀ R⁻¹ H_A (R diagonal), in the symmetric form P_AA = L·Lᵀ, C = I + Lᵀ·G·L
//!   (eigenvalues ≥ 1), M = L⁻ᵀ·(I − C⁻¹)·L⁻¹; the gain applied to ν is
//!   Yᵀ·L⁻ᵀ·C⁻¹·Lᵀ·H_Aᵀ R⁻¹ ν; then P −= Yᵀ·(M·Y). Cost O(nnz + na³) instead of
//!   O(m³ + m²·na). If P_AA or C is not numerically positive definite the update goes
//!   through S: S = H_A·P_AA·H_Aᵀ + R, V = L⁻¹H_A, M = VᵀV, x += Yᵀ·Vᵀ·L⁻¹ν,
//!   P −= Yᵀ·(M·Y).
//!
//! All bins of an observation are processed together (one batch per (pose, direction)).
//! The downdate keeps P exactly symmetric ([`super::linalg`]; the symmetric form P − W·Wᵀ
//! rather than the Joseph form, whose cost is n³ per update); S is symmetrised before its
//! Cholesky factorisation.

use super::linalg::{
    backward_solve_vec, cholesky, cholesky_in_place, forward_solve, forward_solve_vec,
    inverse_from_cholesky, lower_inverse, mat_times_rows, sym_downdate, symmetrise,
    symmetrise_add_r,
};
use super::{EkfValid, Linearized, NoiseModel, Observation, RrcsFilter};
use crate::error::{Error, Result};
use ndarray::linalg::general_mat_mul;
use ndarray::{ArrayView2, ArrayViewMut2};
use rayon::prelude::*;

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
    pub fn new(n: usize, params: &EkfValid) -> Result<DenseEkf> {
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

    /// The m ≤ na update (rank m): Uᵀ = H·P, S = Uᵀ·Hᵀ + R = L·Lᵀ, Wᵀ = L⁻¹·Uᵀ,
    /// x += W·L⁻¹·ν, P −= W·Wᵀ.
    fn update_rank_m(&mut self, obs: &Observation, lin: &Linearized) -> Result<()> {
        let n = self.n;
        let m = obs.rows();
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
        Ok(())
    }

    /// Y = P[A, :] (na × n), the rows of the active cells.
    fn active_rows(&self, act: &Active) -> Vec<f64> {
        let n = self.n;
        let na = act.cells.len();
        let mut y = vec![0.0; na * n];
        y.par_chunks_mut(n).enumerate().for_each(|(a, row)| {
            let c = act.cells[a] as usize;
            row.copy_from_slice(&self.p[c * n..(c + 1) * n]);
        });
        y
    }

    /// The m > na update through S, when P_AA or C is not numerically positive definite:
    /// S = H_A·P_AA·H_Aᵀ + R = L·Lᵀ, V = L⁻¹·H_A, M = Vᵀ·V, x += Yᵀ·Vᵀ·L⁻¹·ν,
    /// P −= Yᵀ·(M·Y).
    fn update_through_s(
        &mut self,
        obs: &Observation,
        lin: &Linearized,
        act: &Active,
        y: &[f64],
    ) -> Result<()> {
        let n = self.n;
        let m = obs.rows();
        let na = act.cells.len();
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
        let z = mat_times_rows(&mm, na, y, n);
        let dx: Vec<f64> = (0..n)
            .into_par_iter()
            .map(|i| (0..na).map(|a| y[a * n + i] * g[a]).sum())
            .collect();
        for (x, d) in self.x.iter_mut().zip(dx) {
            *x += d;
        }
        sym_downdate(&mut self.p, n, y, &z, na);
        Ok(())
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
    fn linearize_second_order(&self, obs: &Observation, noise: &NoiseModel) -> Linearized {
        let n = self.n;
        Linearized::second_order(obs, &self.x, noise, &|_| 0, &|i, j| self.p[i * n + j])
    }

    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()> {
        let m = obs.rows();
        if m == 0 {
            return Ok(());
        }
        let act = active_set(obs, self.n);
        if m <= act.cells.len() {
            return self.update_rank_m(obs, lin);
        }
        let y = self.active_rows(&act);
        if self.update_push_through(obs, lin, &act, &y) {
            return Ok(());
        }
        self.update_through_s(obs, lin, &act, &y)
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
