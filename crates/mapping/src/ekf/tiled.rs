//! The scalable EKF ([`TiledEkf`]): the covariance is kept block-diagonal over square
//! tiles of `tile` × `tile` cells (4 × 4 by default).
//!
//! The covariances among neighbouring cells (the ones a range ring couples most strongly
//! and that shape a wall's outline) are kept, the cross-tile ones are dropped. The bins of
//! an observation are processed one at a time as scalar measurements of the same
//! linearisation (frozen at x⁻: innovation ν'_k = z_k − h_k(x⁻) − H_k·(x − x⁻)), which for a
//! full covariance is exactly the batch update of [`crate::ekf::DenseEkf`] (R is
//! diagonal). Per bin k, for every tile T it touches: g_T = P_T·H_{k,T}ᵀ and
//! a_T = H_{k,T}·g_T (the tile's share of H·P·Hᵀ); s = Σ_T a_T + R_k.
//!
//! **Why not the plain update**: x_T += g_T·ν'/s,
//! P_T −= g_T·g_Tᵀ/s, the cross-tile terms −g_T·g_Uᵀ/s dropped. From a block-diagonal
//! prior this is the exact marginal of one bin's update; but the next bin of the same ring
//! (the kernel's neighbouring bins, the neighbouring directions' side lobes) meets tiles
//! whose errors are correlated through the dropped terms, and treats the other tiles'
//! contribution n_T = Σ_{U≠T} H_{k,U}·(x_U − x̂_U) as fresh noise again: the same nuisance
//! is counted once per bin, and each tile's variance shrinks as if it alone explained the
//! ring: the filter is overconfident (NEES measured in `docs/mapping.md`).
//!
//! **Why not a bound.** From a block-diagonal prior B, one bin's exact posterior is
//! B − g·gᵀ/s with g = B·Hᵀ. If the bin touches two tiles there is a direction v mixing
//! them with g·v = 0, along which the posterior keeps the prior's variance; a block-diagonal
//! Q ≥ B − g·gᵀ/s must keep it too, which forces Q_T = P_T: the tightest block-diagonal
//! upper bound of the update is no update. So a tiled filter that learns from range rings
//! is an approximation whose consistency has to be measured (NEES), not proven. The
//! covariance intersection over the touched tiles that keeps the inflated blocks
//! (P_T/ω_T, Σω_T = 1, then the update; Julier & Uhlmann 1997) is a bound for one bin, but
//! a weak bin inflates every tile it touches by 1/ω_T: the variances overflowed in every
//! run, with ω_T = 1/m and with ω_T ∝ a_T.
//!
//! **Information split** (what the filter does; Walter, Eustice & Leonard 2007 on
//! the overconfidence of filters that drop correlations). Each touched tile sees the bin
//! as a measurement of its own contribution, y_T = z_k − Σ_{U≠T} h_U(x̂_U) = H_{k,T}·x_T +
//! n_T + v, of noise variance s − a_T; the m tiles get m copies of one measurement, whose
//! errors share v and the nuisances and are correlated with the tiles' own errors in ways
//! the filter no longer knows. Counting the copies as independent with their variances
//! divided by ω_T, Σ_T ω_T = 1, bounds the stacked copies' noise covariance whatever their
//! correlation (the CI bound on the copies, not on the tiles' priors): the bin's
//! information is counted once over its tiles. The weights are the tiles' shares,
//! ω_T = a_T/Σ_U a_U: a tile that carries the bin (the main lobe's cells) keeps nearly all
//! of it, a tile the bin touches through a side lobe little. Per tile
//!   s_T = a_T + (s − a_T)/ω_T,   x_T += g_T·ν'/s_T,   P_T −= g_T·g_Tᵀ/s_T,
//! so each tile's reported variance covers its own (suboptimal) gain's error for one bin.
//! With one tile (ω = 1) it is the exact update, so one tile covering the grid still equals
//! the dense filter (tested). What it does not bound: the correlation of a tile's prior
//! error with the nuisance, built by earlier bins; over a campaign it is an approximation,
//! whose NEES against the dense filter's and the alternatives measured are in
//! `docs/mapping.md`. A bin that touches one tile is the exact update.
//!
//! Cost per bin: Σ_T (|T|·nnz_T + |T|²) as before; the a_T are summed in the pass that sums
//! s, so a campaign costs O(nnz(H)·tile²) and memory O(n·tile²) (runtime against the plain
//! update: `docs/mapping.md`).

use super::{EkfValid, Linearized, NoiseModel, Observation, RrcsFilter};
use crate::error::{Error, Result};

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
    /// Scratch: index in `touched` of each tile the current row touches (u32::MAX if it
    /// does not touch it).
    slot: Vec<u32>,
    /// Scratch: g vectors of the touched tiles, concatenated (tile `touched[q]` at
    /// `goff[q]`).
    gbuf: Vec<f64>,
    /// Scratch: offset of each touched tile's g vector in `gbuf`.
    goff: Vec<usize>,
    /// Scratch: a_T = h_T·g_T of each touched tile.
    abuf: Vec<f64>,
    /// Scratch: tiles the current row touches, in order of first touch.
    touched: Vec<u32>,
    /// Tiles whose means changed since the last `project_positive` (`None`: all cells).
    dirty: Option<Vec<u32>>,
    /// Membership flags of `dirty`.
    dirty_mark: Vec<bool>,
}

impl TiledEkf {
    /// Prior N(μ0, σ0²·I) on a `rows` × `cols` grid with `tile` × `tile` tiles.
    pub fn new(rows: usize, cols: usize, tile: usize, params: &EkfValid) -> Result<TiledEkf> {
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
            goff: Vec::new(),
            abuf: Vec::new(),
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
    fn linearize_second_order(&self, obs: &Observation, noise: &NoiseModel) -> Linearized {
        Linearized::second_order(obs, &self.x, noise, &|i| self.cell_tile[i], &|i, j| {
            let t = self.cell_tile[i] as usize;
            let k = self.tile_cells[t].len();
            self.tile_p[t][self.cell_local[i] as usize * k + self.cell_local[j] as usize]
        })
    }

    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()> {
        for j in 0..obs.rows() {
            let (e0, e1) = (obs.ptr[j], obs.ptr[j + 1]);
            // g_T = P_T h_Tᵀ for each touched tile (tiles in order of first touch)
            self.gbuf.clear();
            self.goff.clear();
            self.touched.clear();
            let mut nu = lin.nu[j];
            for e in e0..e1 {
                let c = obs.cell[e] as usize;
                let h = lin.hval[e];
                nu -= h * (self.x[c] - lin.x0[e]);
                let t = self.cell_tile[c] as usize;
                let k = self.tile_cells[t].len();
                let q = if self.slot[t] == u32::MAX {
                    let q = self.touched.len();
                    self.slot[t] = q as u32;
                    self.touched.push(t as u32);
                    self.goff.push(self.gbuf.len());
                    self.gbuf.resize(self.gbuf.len() + k, 0.0);
                    q
                } else {
                    self.slot[t] as usize
                };
                let off = self.goff[q];
                let l = self.cell_local[c] as usize;
                let p = &self.tile_p[t][l * k..(l + 1) * k];
                for (gi, pv) in self.gbuf[off..off + k].iter_mut().zip(p) {
                    *gi += h * pv;
                }
            }
            // s = H·P·Hᵀ + R (summed entry by entry) and, for the split over several tiles,
            // a_T = h_T·g_T (the tile's share of H·P·Hᵀ)
            let split = self.touched.len() > 1;
            self.abuf.clear();
            self.abuf.resize(self.touched.len(), 0.0);
            let mut s = lin.r[j];
            for e in e0..e1 {
                let c = obs.cell[e] as usize;
                let q = self.slot[self.cell_tile[c] as usize] as usize;
                let v = lin.hval[e] * self.gbuf[self.goff[q] + self.cell_local[c] as usize];
                s += v;
                if split {
                    self.abuf[q] += v;
                }
            }
            for &t in &self.touched {
                self.slot[t as usize] = u32::MAX;
            }
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::param(
                    "ekf",
                    "innovation variance is not positive (numerical breakdown)",
                ));
            }
            let hph: f64 = if split { self.abuf.iter().sum() } else { 0.0 };
            for (q, &t) in self.touched.iter().enumerate() {
                let t = t as usize;
                // the tile's innovation variance: s for a single tile; with the split,
                // a_T + (s − a_T)/ω_T, ω_T = a_T / Σ a (module docs)
                let a = self.abuf[q];
                let st = if split {
                    if a.is_nan() || a <= 0.0 {
                        // g_T = 0: the row says nothing about this tile
                        continue;
                    }
                    a + (s - a) * (hph / a)
                } else {
                    s
                };
                let inv = 1.0 / st;
                if let Some(d) = self.dirty.as_mut() {
                    if !self.dirty_mark[t] {
                        self.dirty_mark[t] = true;
                        d.push(t as u32);
                    }
                }
                let cells = &self.tile_cells[t];
                let k = cells.len();
                let off = self.goff[q];
                let gv = &self.gbuf[off..off + k];
                for (b, &c) in cells.iter().enumerate() {
                    self.x[c as usize] += gv[b] * nu * inv;
                }
                let p = &mut self.tile_p[t];
                for b in 0..k {
                    let gb = gv[b] * inv;
                    for (pv, gc) in p[b * k..(b + 1) * k].iter_mut().zip(gv) {
                        *pv -= gb * gc;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::{DenseEkf, EkfParams, NoiseModel};
    use crate::params::ParamGuard;

    /// One bin over two cells in two 1 × 1 tiles (a_1 = h_1²·P_1, a_2 = h_2²·P_2): the
    /// exact marginal of each cell is P_i − a_i·P_i/s; the split gives P_i − a_i·P_i/s_i
    /// with s_i = a_i + (s − a_i)·(a_1 + a_2)/a_i, a larger variance, and the mean moved by
    /// the same factor less.
    #[test]
    fn split_divides_a_bin_over_its_tiles() {
        let p = EkfParams {
            tile: 1,
            ..Default::default()
        };
        let split_p = p.check().unwrap();
        let obs = Observation {
            bin: vec![0],
            z: vec![0.0],
            ptr: vec![0, 2],
            cell: vec![0, 1],
            coef: vec![1.0, 1.0],
        };
        let (h, r, nu) = ([2.0, 0.5], 0.3, 0.7);
        let lin = Linearized {
            h: vec![0.0],
            nu: vec![nu],
            r: vec![r],
            hval: h.to_vec(),
            x0: vec![p.mu0, p.mu0],
        };
        let mut split = TiledEkf::new(1, 2, 1, &split_p).unwrap();
        split.update(&obs, &lin).unwrap();
        let v0 = p.sigma0 * p.sigma0;
        let a = [h[0] * h[0] * v0, h[1] * h[1] * v0];
        let s = a[0] + a[1] + r;
        for i in 0..2 {
            let si = a[i] + (s - a[i]) * (a[0] + a[1]) / a[i];
            let g = v0 * h[i];
            assert!((split.variances()[i] - (v0 - g * g / si)).abs() < 1e-15);
            assert!(split.variances()[i] > v0 - g * g / s);
            assert!((split.mean()[i] - (p.mu0 + g * nu / si)).abs() < 1e-15);
        }
    }

    #[test]
    fn tiled_with_one_tile_equals_dense_on_a_random_problem() {
        // 5 × 6 grid, one tile covering it; 8 rows, random coefficients
        let (rows, cols) = (5, 6);
        let n = rows * cols;
        let params = EkfParams {
            tile: 6,
            ..Default::default()
        }
        .check()
        .unwrap();
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
