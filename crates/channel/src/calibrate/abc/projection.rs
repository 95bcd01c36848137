//! The semi-automatic projection of ABC's raw summaries (Fearnhead & Prangle 2012): each
//! raw summary standardised by its median and MAD, the ln parameters regressed on them by
//! ridge least squares, each projection scaled by its MAD; the distance of the sampler
//! ([`apmc`](super::apmc)) is the scaled Euclidean distance of the projections. Takes the
//! particles' raw summaries and ln parameters; gives the fitted [`Projection`], the penalty
//! per parameter ([`choose_ridge`]) and its held-out R².
//!
//! The R² of the projection that the trace (`PRADAR_ABC_TRACE=1`) prints per generation and
//! [`Posterior::heldout_r2`](super::Posterior::heldout_r2) records is held out: 5-fold
//! cross-validated, the same ridge fit (its own median/MAD standardisation) refitted on
//! four folds and scored on the fifth, folds by position in the population (particle i in
//! fold i mod 5), so it is deterministic too; R² = 1 − Σ(x − x̂)²/Σ(x − x̄)² over all
//! held-out predictions, which is ≤ 0 when the statistics predict nothing (the in-sample R²
//! of the fit is positive even then).
//!
//! The projection's ridge penalty ([`Ridge`](super::Ridge)): `Fixed` is λ = 1e-3·n on every
//! slope (only there to keep collinear statistics solvable). `Cv` chooses it per parameter
//! from the data at every refit: λ_k = c_k·n_train with c_k the entry of
//! [`RIDGE_GRID`](super::RIDGE_GRID) (1e-3 … 1e3, half decades) minimising the same 5-fold
//! held-out squared error Σ_i (x_ik − x̂_ik^(−fold(i)))², ties to the smaller penalty. Why:
//! with 87 raw statistics fitted on 100–200 particles the fixed penalty overfits (held-out
//! R² < 0 for most parameters in the corridor), and the amount of shrinkage that predicts
//! best differs per parameter and per generation (the population narrows), which
//! cross-validation measures and a constant cannot; a log grid spans the least-squares fit
//! to the near-marginal-correlation projection (λ ≫ eigenvalues of ZᵀZ, where β ∝ Zᵀx). The
//! distance divides each projection by its MAD, so the penalty changes the projection's
//! direction, not its weight. `CvDrop` also leaves out of the distance a parameter whose
//! projection's held-out R² is ≤ 0 at its best penalty: its projection is noise around the
//! mean, and in the distance it only adds that noise to every particle's ρ. The held-out R²
//! recorded is the one at the chosen penalty (the minimum over 13 grid entries, so slightly
//! optimistic). The fold assignment is by position, the grid fixed: still deterministic.
//! `Cv` is the default: `Fixed`'s intervals are narrower but cover d_c and the rays per
//! cluster in only 16 of 20 corridor environments, `Cv`'s every quantity in ≥ 18 of 20
//! (docs/calibrate.md, "The ridge default").

use super::{Ridge, FIXED_RIDGE, RIDGE_GRID};
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// The semi-automatic summaries: raw summaries standardised (median, MAD over the prior
/// generation), then projected by the least-squares fit of the ln parameters on them,
/// scaled by each projection's MAD over the prior generation.
#[derive(Debug, Clone)]
pub(super) struct Projection {
    centre: Vec<f64>,
    scale: Vec<f64>,
    beta: DMatrix<f64>,
    mad: Vec<f64>,
    /// Whether parameter k's projection enters the distance ([`Ridge::CvDrop`]).
    pub(super) used: Vec<bool>,
}

/// Median and MAD (scaled by 1.4826 to a Gaussian σ) of a column; a MAD of 0 falls back
/// to the standard deviation, then to 1.
pub(crate) fn median_mad(col: &[f64]) -> (f64, f64) {
    let mut v: Vec<f64> = col.iter().copied().filter(|x| x.is_finite()).collect();
    // sorted in place: the mean below sums in that order
    v.sort_by(f64::total_cmp);
    let m = crate::stats::sorted::median(&v).unwrap_or(0.0);
    let dev: Vec<f64> = v.iter().map(|x| (x - m).abs()).collect();
    let mad = 1.4826 * crate::stats::median(&dev).unwrap_or(0.0);
    if mad > 1e-12 {
        return (m, mad);
    }
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    (m, if sd > 1e-12 { sd } else { 1.0 })
}

/// XᵀX and XᵀΘ of a design X and the parameters Θ, and n (the rows): what every ridge
/// penalty's solve shares.
struct NormalEquations {
    xtx: DMatrix<f64>,
    xty: DMatrix<f64>,
    n: usize,
}

impl NormalEquations {
    fn new(x: &DMatrix<f64>, theta: &[Vec<f64>]) -> NormalEquations {
        let n = x.nrows();
        let p = theta.first().map_or(0, Vec::len);
        NormalEquations {
            xtx: x.transpose() * x,
            xty: x.transpose() * DMatrix::from_fn(n, p, |i, k| theta[i][k]),
            n,
        }
    }
}

impl Projection {
    /// Median/MAD of each raw summary over `features`.
    fn standardisation(features: &[Vec<f64>]) -> Projection {
        let m = features[0].len();
        let (centre, scale): (Vec<f64>, Vec<f64>) = (0..m)
            .map(|j| median_mad(&features.iter().map(|f| f[j]).collect::<Vec<_>>()))
            .unzip();
        Projection {
            centre,
            scale,
            beta: DMatrix::zeros(m + 1, 0),
            mad: Vec::new(),
            used: Vec::new(),
        }
    }

    /// The design matrix [1, z] of `features` under this standardisation.
    fn design(&self, features: &[Vec<f64>]) -> DMatrix<f64> {
        let m = self.centre.len();
        let z: Vec<Vec<f64>> = features.iter().map(|f| self.standard(f)).collect();
        DMatrix::from_fn(features.len(), m + 1, |i, j| {
            if j == 0 {
                1.0
            } else {
                z[i][j - 1]
            }
        })
    }

    /// Ridge slopes of `theta` on the design `x`, column k with penalty c_k·n on the
    /// slopes (not the intercept).
    fn ridge(x: &DMatrix<f64>, theta: &[Vec<f64>], c: &[f64]) -> Result<DMatrix<f64>> {
        Projection::ridge_solve(&NormalEquations::new(x, theta), c)
    }

    /// [`Projection::ridge`] from the normal equations (made once for every penalty).
    fn ridge_solve(ne: &NormalEquations, c: &[f64]) -> Result<DMatrix<f64>> {
        let (xtx, xty, n) = (&ne.xtx, &ne.xty, ne.n);
        let m1 = xtx.ncols();
        let p = c.len();
        let mut beta = DMatrix::zeros(m1, p);
        // parameters in a row sharing a penalty share the factorisation
        let mut last: Option<(f64, nalgebra::linalg::Cholesky<f64, nalgebra::Dyn>)> = None;
        for (k, ck) in c.iter().enumerate() {
            if last.as_ref().is_none_or(|(cl, _)| cl != ck) {
                let mut a = xtx.clone();
                for j in 1..m1 {
                    a[(j, j)] += ck * n as f64;
                }
                let chol = a.cholesky().ok_or_else(|| {
                    Error::param("calibrate", "the summaries' regression is singular")
                })?;
                last = Some((*ck, chol));
            }
            let (_, chol) = last.as_ref().expect("factorised above");
            beta.set_column(k, &chol.solve(&xty.column(k).into_owned()));
        }
        Ok(beta)
    }

    /// The projection fitted on `features`/`theta` with relative penalties `c` (one per
    /// parameter).
    pub(super) fn fit_with(
        features: &[Vec<f64>],
        theta: &[Vec<f64>],
        c: &[f64],
    ) -> Result<Projection> {
        let mut proj = Projection::standardisation(features);
        let x = proj.design(features);
        proj.beta = Projection::ridge(&x, theta, c)?;
        let s: Vec<Vec<f64>> = features.iter().map(|f| proj.project(f)).collect();
        proj.mad = (0..c.len())
            .map(|k| median_mad(&s.iter().map(|v| v[k]).collect::<Vec<_>>()).1)
            .collect();
        proj.used = vec![true; c.len()];
        Ok(proj)
    }

    /// The projection with the fixed penalty 1e-3·n.
    #[cfg(test)]
    fn fit(features: &[Vec<f64>], theta: &[Vec<f64>]) -> Result<Projection> {
        Projection::fit_with(features, theta, &vec![FIXED_RIDGE; theta[0].len()])
    }

    /// Standardised raw summaries (a non-finite one at its centre).
    fn standard(&self, f: &[f64]) -> Vec<f64> {
        f.iter()
            .zip(self.centre.iter().zip(&self.scale))
            .map(|(v, (c, s))| {
                if v.is_finite() {
                    ((v - c) / s).clamp(-50.0, 50.0)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The projected summaries (one per parameter).
    pub(super) fn project(&self, f: &[f64]) -> Vec<f64> {
        let z = self.standard(f);
        let zr = DVector::from_iterator(z.len() + 1, std::iter::once(1.0).chain(z));
        (self.beta.transpose() * zr).iter().copied().collect()
    }

    /// Scaled Euclidean distance of projected summaries (those [`Projection::used`]).
    pub(super) fn distance(&self, s: &[f64], obs: &[f64]) -> f64 {
        s.iter()
            .zip(obs)
            .zip(self.mad.iter().zip(&self.used))
            .filter(|(_, (_, u))| **u)
            .map(|((a, b), (m, _))| ((a - b) / m).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// Folds of the cross-validated R² of the projection.
pub(super) const FOLDS: usize = 5;

/// R² = 1 − Σ(x − x̂)²/Σ(x − x̄)² from the residual and total sums of squares.
fn r2(res: f64, tot: f64) -> f64 {
    1.0 - res / tot.max(1e-300)
}

/// R² per parameter of predictions `pred` of `theta`.
#[cfg(test)]
fn r_squared(theta: &[Vec<f64>], pred: &[Vec<f64>]) -> Vec<f64> {
    total_ss(theta)
        .into_iter()
        .enumerate()
        .map(|(k, tot)| {
            let res: f64 = theta
                .iter()
                .zip(pred)
                .map(|(t, p)| (t[k] - p[k]).powi(2))
                .sum();
            r2(res, tot)
        })
        .collect()
}

/// In-sample R² per parameter of the projection fitted on all of `features`/`theta`.
#[cfg(test)]
pub(super) fn insample_r2(features: &[Vec<f64>], theta: &[Vec<f64>]) -> Vec<f64> {
    let proj = Projection::fit(features, theta).expect("ridge fit");
    let pred: Vec<Vec<f64>> = features.iter().map(|f| proj.project(f)).collect();
    r_squared(theta, &pred)
}

/// Cross-validated squared errors of the projection: `k`-fold, row i in fold i mod k,
/// each fold predicted by the projection (standardisation and ridge fit) fitted on the
/// other folds, for every relative penalty of `grid`. Returns per grid entry and
/// parameter the sum of squared held-out errors (+∞ for a penalty whose fit fails on some
/// fold); None when there are fewer than 2k rows.
fn cv_errors(
    features: &[Vec<f64>],
    theta: &[Vec<f64>],
    k: usize,
    grid: &[f64],
) -> Option<Vec<Vec<f64>>> {
    let (n, p) = (theta.len(), theta.first().map_or(0, Vec::len));
    if n < 2 * k || p == 0 {
        return None;
    }
    let mut sse = vec![vec![0.0; p]; grid.len()];
    for fold in 0..k {
        let train: Vec<usize> = (0..n).filter(|i| i % k != fold).collect();
        let tf: Vec<Vec<f64>> = train.iter().map(|&i| features[i].clone()).collect();
        let tt: Vec<Vec<f64>> = train.iter().map(|&i| theta[i].clone()).collect();
        let proj = Projection::standardisation(&tf);
        let ne = NormalEquations::new(&proj.design(&tf), &tt);
        let test: Vec<usize> = (fold..n).step_by(k).collect();
        let xt = proj.design(
            &test
                .iter()
                .map(|&i| features[i].clone())
                .collect::<Vec<_>>(),
        );
        for (g, c) in grid.iter().enumerate() {
            // a penalty whose fit fails on some fold (collinear statistics at a small
            // penalty) is out of the choice: +∞, the other penalties still compete
            let Ok(beta) = Projection::ridge_solve(&ne, &vec![*c; p]) else {
                sse[g].iter_mut().for_each(|e| *e = f64::INFINITY);
                continue;
            };
            let pred = &xt * &beta;
            for (r, &i) in test.iter().enumerate() {
                for kk in 0..p {
                    sse[g][kk] += (theta[i][kk] - pred[(r, kk)]).powi(2);
                }
            }
        }
    }
    Some(sse)
}

/// Σ(x − x̄)² per parameter.
fn total_ss(theta: &[Vec<f64>]) -> Vec<f64> {
    let n = theta.len() as f64;
    (0..theta.first().map_or(0, Vec::len))
        .map(|k| {
            let m = theta.iter().map(|t| t[k]).sum::<f64>() / n;
            theta.iter().map(|t| (t[k] - m).powi(2)).sum::<f64>()
        })
        .collect()
}

/// Held-out R² per parameter of the projection with relative penalty `c`: `k`-fold
/// cross-validation ([`cv_errors`]). NaN for a parameter when a fold's fit fails or there
/// are fewer than 2k rows.
#[cfg(test)]
pub(super) fn heldout_r2(features: &[Vec<f64>], theta: &[Vec<f64>], k: usize, c: f64) -> Vec<f64> {
    let p = theta.first().map_or(0, Vec::len);
    match cv_errors(features, theta, k, &[c]) {
        None => vec![f64::NAN; p],
        Some(sse) => sse[0]
            .iter()
            .zip(total_ss(theta))
            .map(|(e, t)| match e.is_finite() {
                true => r2(*e, t),
                false => f64::NAN,
            })
            .collect(),
    }
}

/// The relative penalty per parameter and its held-out R², for `ridge`: fixed (1e-3 and
/// its cross-validated R²), or the entry of [`RIDGE_GRID`] with the smallest
/// cross-validated squared error (ties to the smaller penalty; the R² at it is then the
/// minimum over the grid, optimistic by the selection). Fixed penalty and NaN R² when the
/// cross-validation cannot run.
pub(super) fn choose_ridge(
    features: &[Vec<f64>],
    theta: &[Vec<f64>],
    ridge: Ridge,
) -> (Vec<f64>, Vec<f64>) {
    let p = theta.first().map_or(0, Vec::len);
    let grid: &[f64] = match ridge {
        Ridge::Fixed => &[FIXED_RIDGE],
        Ridge::Cv | Ridge::CvDrop => &RIDGE_GRID,
    };
    let Some(sse) = cv_errors(features, theta, FOLDS, grid) else {
        return (vec![FIXED_RIDGE; p], vec![f64::NAN; p]);
    };
    let tot = total_ss(theta);
    (0..p)
        .map(|k| {
            let mut best = 0;
            for g in 1..grid.len() {
                if sse[g][k] < sse[best][k] {
                    best = g;
                }
            }
            match sse[best][k].is_finite() {
                true => (grid[best], r2(sse[best][k], tot[k])),
                // no penalty of the grid could be fitted on every fold
                false => (FIXED_RIDGE, f64::NAN),
            }
        })
        .unzip()
}
