//! Dense linear algebra of [`crate::ekf::DenseEkf`] on row-major `f64` slices.
//!
//! Takes symmetric or lower-triangular m × m matrices and right-hand sides stored
//! row-major (the covariance's layout); gives Cholesky factors, triangular solves, inverses
//! and the symmetric rank-r downdate P −= Aᵀ·B.
//!
//! * Factorisations and solves are nalgebra's ([`nalgebra::Cholesky`], the triangular
//!   solves of [`nalgebra::Matrix`]). A row-major m × m slice read as a column-major
//!   matrix is its transpose, so a lower factor L stored row-major is the upper factor
//!   U = Lᵀ to nalgebra: L·y = v is solved as Uᵀ·y = v and Lᵀ·y = v as U·y = v, in place,
//!   without copying L. A block of right-hand sides (m × w, row-major) is copied to a
//!   column-major matrix per chunk of 256 columns, the chunks solved in parallel.
//! * A factorisation is accepted only when every pivot is finite and > 0 (nalgebra stops at
//!   a zero or negative pivot; the extra test also rejects an infinite one).
//! * The products (M·Y, P −= Aᵀ·B) are `ndarray`'s `general_mat_mul` (matrixmultiply) over
//!   fixed blocks in parallel: the downdate is done on the upper triangle in blocks of 64
//!   rows and mirrored, so P stays exactly symmetric and the result does not depend on the
//!   number of threads (nalgebra has no parallel blocked symmetric downdate).

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DMatrixView, DVectorViewMut};
use ndarray::linalg::general_mat_mul;
use ndarray::{s, ArrayView2, ArrayViewMut2};
use rayon::prelude::*;

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
/// not numerically positive definite (then `a` may be left unchanged or overwritten).
pub(crate) fn cholesky_in_place(a: &mut [f64], m: usize) -> bool {
    let Some(ch) = nalgebra::Cholesky::new(DMatrix::from_row_slice(m, m, a)) else {
        return false;
    };
    let l = ch.unpack();
    if (0..m).any(|i| !(l[(i, i)].is_finite() && l[(i, i)] > 0.0)) {
        return false;
    }
    for i in 0..m {
        for j in 0..m {
            a[i * m + j] = l[(i, j)];
        }
    }
    true
}

/// Solve L·X = B in place for B (m × w, row-major), L lower m × m; columns in parallel
/// chunks of 256.
pub(crate) fn forward_solve(l: &[f64], m: usize, b: &mut [f64], w: usize) {
    if w == 0 || m == 0 {
        return;
    }
    const CH: usize = 256;
    let u = DMatrixView::from_slice(l, m, m);
    let solved: Vec<DMatrix<f64>> = (0..w.div_ceil(CH))
        .into_par_iter()
        .map(|c| {
            let c0 = c * CH;
            let cw = CH.min(w - c0);
            let mut x = DMatrix::from_fn(m, cw, |i, j| b[i * w + c0 + j]);
            u.tr_solve_upper_triangular_mut(&mut x);
            x
        })
        .collect();
    for (c, x) in solved.into_iter().enumerate() {
        let c0 = c * CH;
        for i in 0..m {
            for j in 0..x.ncols() {
                b[i * w + c0 + j] = x[(i, j)];
            }
        }
    }
}

/// Solve L·y = v (vector).
pub(crate) fn forward_solve_vec(l: &[f64], m: usize, v: &mut [f64]) {
    let u = DMatrixView::from_slice(&l[..m * m], m, m);
    u.tr_solve_upper_triangular_mut(&mut DVectorViewMut::from_slice(&mut v[..m], m));
}

/// Solve Lᵀ·y = v (vector).
pub(crate) fn backward_solve_vec(l: &[f64], m: usize, v: &mut [f64]) {
    let u = DMatrixView::from_slice(&l[..m * m], m, m);
    u.solve_upper_triangular_mut(&mut DVectorViewMut::from_slice(&mut v[..m], m));
}

/// L⁻¹ of a lower-triangular m × m factor (row-major).
pub(crate) fn lower_inverse(l: &[f64], m: usize) -> Vec<f64> {
    // (L⁻¹)ᵀ = U⁻¹ solves U·X = I; its column-major storage is L⁻¹ row-major
    let u = DMatrixView::from_slice(&l[..m * m], m, m);
    let mut x = DMatrix::<f64>::identity(m, m);
    u.solve_upper_triangular_mut(&mut x);
    // U⁻¹ is upper: in row-major order L⁻¹ = (U⁻¹)ᵀ is lower, stored as U⁻¹ column-major
    x.as_slice().to_vec()
}

/// A⁻¹ = L⁻ᵀ·L⁻¹ from the Cholesky factor L of A (m × m, row-major).
pub(crate) fn inverse_from_cholesky(l: &[f64], m: usize) -> Vec<f64> {
    let linv = lower_inverse(l, m);
    // row-major L⁻¹ read column-major is L⁻ᵀ; A⁻¹ = L⁻ᵀ·L⁻¹ is symmetric, so its
    // column-major storage is its row-major storage
    let lt = DMatrixView::from_slice(&linv, m, m);
    let mut out = DMatrix::<f64>::zeros(m, m);
    out.gemm(1.0, &lt, &lt.transpose(), 0.0);
    out.as_slice().to_vec()
}

/// M·Y for M (r × r) and Y (r × n), row-major; columns in parallel blocks of 256.
pub(crate) fn mat_times_rows(mm: &[f64], r: usize, y: &[f64], n: usize) -> Vec<f64> {
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
pub(crate) fn sym_downdate(p: &mut [f64], n: usize, a: &[f64], b: &[f64], r: usize) {
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
pub(crate) fn mirror_upper(p: &mut [f64], n: usize) {
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

/// Replace the m × m matrix `s` by (s + sᵀ)/2.
pub(crate) fn symmetrise(s: &mut [f64], m: usize) {
    for i in 0..m {
        for j in 0..i {
            let v = 0.5 * (s[i * m + j] + s[j * m + i]);
            s[i * m + j] = v;
            s[j * m + i] = v;
        }
    }
}

/// Symmetrise `s` and add the diagonal `r`.
pub(crate) fn symmetrise_add_r(s: &mut [f64], m: usize, r: &[f64]) {
    symmetrise(s, m);
    for i in 0..m {
        s[i * m + i] += r[i];
    }
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
    fn nalgebra_solves_agree_with_the_definitions() {
        let m = 5;
        // A = B·Bᵀ + m·I, symmetric positive definite
        let b: Vec<f64> = (0..m * m).map(|i| ((i * 7 % 11) as f64) / 11.0).collect();
        let mut a = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                a[i * m + j] = (0..m).map(|k| b[i * m + k] * b[j * m + k]).sum::<f64>()
                    + if i == j { m as f64 } else { 0.0 };
            }
        }
        let mut l = a.clone();
        assert!(cholesky_in_place(&mut l, m));
        let v: Vec<f64> = (0..m).map(|i| 1.0 + i as f64).collect();
        // L·y = v, then Lᵀ·x = y: x = A⁻¹·v
        let mut x = v.clone();
        forward_solve_vec(&l, m, &mut x);
        backward_solve_vec(&l, m, &mut x);
        let inv = inverse_from_cholesky(&l, m);
        let linv = lower_inverse(&l, m);
        for i in 0..m {
            let ax: f64 = (0..m).map(|k| a[i * m + k] * x[k]).sum();
            assert!((ax - v[i]).abs() < 1e-12, "{ax} vs {}", v[i]);
            for j in 0..m {
                let ai: f64 = (0..m).map(|k| a[i * m + k] * inv[k * m + j]).sum();
                let li: f64 = (0..m).map(|k| l[i * m + k] * linv[k * m + j]).sum();
                let id = if i == j { 1.0 } else { 0.0 };
                assert!((ai - id).abs() < 1e-12 && (li - id).abs() < 1e-12);
            }
        }
        // L·X = B for a block of right-hand sides (m × 300, over two chunks)
        let w = 300;
        let rhs: Vec<f64> = (0..m * w).map(|i| (i % 13) as f64 - 6.0).collect();
        let mut xs = rhs.clone();
        forward_solve(&l, m, &mut xs, w);
        for i in 0..m {
            for c in 0..w {
                let lx: f64 = (0..m).map(|k| l[i * m + k] * xs[k * w + c]).sum();
                assert!((lx - rhs[i * w + c]).abs() < 1e-12);
            }
        }
    }
}
