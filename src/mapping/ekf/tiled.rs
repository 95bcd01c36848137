//! The scalable EKF ([`TiledEkf`]): the covariance is kept block-diagonal over square
//! tiles of `tile` × `tile` cells (4 × 4 by default).
//!
//! The covariances among neighbouring cells (the ones a range ring couples most strongly
//! and that shape a wall's outline) are kept, the cross-tile ones are dropped. The bins of
//! an observation are processed one at a time as scalar measurements of the same
//! linearisation (frozen at x⁻: innovation ν'_k = z_k − h_k(x⁻) − H_k·(x − x⁻)), which for a
//! full covariance is exactly the batch update of [`crate::mapping::ekf::DenseEkf`] (R is
//! diagonal); per bin: g_T = P_T·H_{k,T}ᵀ for every tile T the bin touches,
//! s = Σ_T H_{k,T}·g_T + R_k, x_T += g_T·ν'_k/s, P_T −= g_T·g_Tᵀ/s, and the cross-tile terms
//! g_T·g_T'ᵀ/s are dropped. The cost per bin is Σ_T (|T|·nnz + |T|²), so a campaign costs
//! O(nnz(H)·tile²) and memory O(n·tile²). With one tile covering the grid it equals the
//! dense filter (tested). Dropping cross-tile covariances makes the filter somewhat
//! overconfident about cells coupled through a range ring but in different tiles.

use super::{EkfValid, Linearized, Observation, RrcsFilter};
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

    fn project_positive(&mut self, x_min: f64, reflect: bool) -> usize {
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
            if reflect && self.x[i] < 0.0 {
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
    use crate::mapping::ekf::{DenseEkf, EkfParams, NoiseModel};
    use crate::params::ParamGuard;

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
