//! Binned sweep synthesis: the sum of [`super::synth`] regrouped by pattern-table cell, for
//! mechanical steering with the pattern at every frequency point (the default scene).
//!
//! Takes a pose's paths, the direction table and the band; gives the noise-free S21 of every
//! direction. It is the same sum as the per-path code, up to rounding:
//! * when the beam turns by whole table cells between directions (5° steps on the 0.05°
//!   table), a path's table cell and fraction are the same in every direction up to a shift:
//!   with x = (θ_rel − θ_ref + 90°)/step, j = ⌊x⌋, t = x − j, direction d reads cell
//!   i = j − o_d, o_d = (θ_d − θ_ref)/step, visible when 0 ≤ i ≤ n − 2;
//! * the interpolated field squared expands as
//!   F² = (1−t)²·F_i² + t(1−t)·2F_iF_{i+1} + t²·F_{i+1}², so
//!   S21_d(f) = Σ_j λF_i²·C0_j + 2λF_iF_{i+1}·C1_j + λF_{i+1}²·C2_j over occupied cells j, with
//!   C0_j(f) = Σ_{paths in j} (1−t)²·A·e^{−j2πfτ} (C1 with t(1−t), C2 with t²) computed once per
//!   pose for all directions; the work per direction is per occupied cell (about 2.3 paths
//!   per cell in the corridor), not per path, and reads each table row once;
//! * a path the per-path code culls in a direction (|F²λA| below 10⁻⁶·σ at five frequencies,
//!   the same test on the same table values) is subtracted again in that direction;
//! * frequencies go in blocks of [`BLOCK`] points: per block the cell sums are formed, then
//!   every occupied cell adds its three table rows to each direction that sees it (the
//!   table is stored block by block, so those rows are contiguous and stay in cache);
//!   groups of four blocks run in parallel, their phases starting from
//!   e^{−j2π·frac(frac(f₀τ) + k·frac(Δf·τ))} at the group's first point k and advancing by a
//!   constant step. Each group is summed by one
//!   thread in a fixed order, so the bytes do not depend on the thread count.
//!
//! The order of the additions differs from the per-path code, so values differ from it by
//! rounding: sums agree to about 1e-11 of the largest value (a group's starting phase is
//! frac(f₀τ) + k·frac(Δfτ), as exact as the per-path recurrence; f·τ itself is thousands of
//! cycles, so either carries about 1e-12 rad). Directions more than 180° apart, or not
//! whole table cells apart, use the per-path code.

use super::paths::Path1;
use crate::pattern::PatternTable;
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Frequency points per block: a block's table rows and cell sums stay in cache while every
/// direction reads them.
pub const BLOCK: usize = 8;

/// Blocks per parallel task (the phases advance by recurrence within a task).
const TASK_BLOCKS: usize = 4;

/// Points at which a path's size is tested against the cull level (as the per-path code).
fn cull_points(nf: usize) -> [usize; 5] {
    [0, nf / 4, nf / 2, 3 * nf / 4, nf - 1]
}

/// The pattern products of a direction table and the directions' cell offsets.
pub(super) struct BinnedTables {
    n_ang: usize,
    nf: usize,
    step_deg: f64,
    /// Per block of points, per angle i: re λF_i², im λF_i², re 2λF_iF_{i+1}, im 2λF_iF_{i+1}
    /// (zero for the last angle and past the last point), `BLOCK` points each.
    tab: Vec<f64>,
    /// F at the cull points per angle.
    cull_f: Vec<[Complex64; 5]>,
    /// λ at the cull points.
    cull_lambda: [f64; 5],
    /// θ_ref, rad.
    ref_rad: f64,
    /// o_d per direction, cells.
    offsets: Vec<isize>,
    /// Band start and step, Hz.
    f0_hz: f64,
    df_hz: f64,
}

/// One path placed on the table grid.
#[derive(Clone, Copy)]
struct Entry {
    j: isize,
    t: f64,
    amp: Complex64,
    /// frac(f₀·τ) and frac(Δf·τ), cycles.
    f0_cycles: f64,
    df_cycles: f64,
    /// e^{−j2π·frac(Δf·τ)}: the phase step from one point to the next.
    step: Complex64,
}

impl Entry {
    /// The weights of F_i², 2F_iF_{i+1}, F_{i+1}².
    fn weights(&self) -> [f64; 3] {
        let (t, u) = (self.t, 1.0 - self.t);
        [u * u, t * u, t * t]
    }

    /// The phase at point `k`: the per-path code's f₀·τ + k·Δf·τ, each part reduced to its
    /// fraction first (f·τ itself is thousands of cycles).
    fn phase_at(&self, k: usize) -> Complex64 {
        Complex64::from_polar(
            1.0,
            -2.0 * PI * (self.f0_cycles + k as f64 * self.df_cycles).fract(),
        )
    }
}

impl BinnedTables {
    /// Products of `table` (one knot per point of the band f0 + k·df with wavelengths
    /// `lambdas`) for the directions `angles_deg`; None when the directions are not whole
    /// table cells apart or span more than 180°.
    pub(super) fn new(
        table: &PatternTable,
        lambdas: &[f64],
        f0_hz: f64,
        df_hz: f64,
        angles_deg: &[f64],
    ) -> Option<BinnedTables> {
        let nf = lambdas.len();
        if table.knots() != nf || nf < 2 || angles_deg.is_empty() {
            return None;
        }
        let step = table.step_deg();
        let a0 = angles_deg[0];
        let lo = angles_deg.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = angles_deg.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let ref_deg = a0 + (((lo + hi) / 2.0 - a0) / step).round() * step;
        let mut offsets = Vec::with_capacity(angles_deg.len());
        for &a in angles_deg {
            let o = (a - ref_deg) / step;
            if (o - o.round()).abs() > 1e-9 || (a - ref_deg).abs() > 90.0 + 1e-9 {
                return None;
            }
            offsets.push(o.round() as isize);
        }
        let n_ang = table.angles();
        let nb = nf.div_ceil(BLOCK);
        let mut tab = vec![0.0; nb * n_ang * 4 * BLOCK];
        for i in 0..n_ang {
            let r0 = table.knots_at(i);
            let r1 = (i + 1 < n_ang).then(|| table.knots_at(i + 1));
            for k in 0..nf {
                let at = ((k / BLOCK * n_ang + i) * 4) * BLOCK + k % BLOCK;
                let v = r0[k] * r0[k] * lambdas[k];
                tab[at] = v.re;
                tab[at + BLOCK] = v.im;
                if let Some(r1) = r1 {
                    let w = r0[k] * r1[k] * (2.0 * lambdas[k]);
                    tab[at + 2 * BLOCK] = w.re;
                    tab[at + 3 * BLOCK] = w.im;
                }
            }
        }
        let ks = cull_points(nf);
        let cull_f = (0..n_ang)
            .map(|i| ks.map(|k| table.knots_at(i)[k]))
            .collect();
        Some(BinnedTables {
            n_ang,
            nf,
            step_deg: step,
            tab,
            cull_f,
            cull_lambda: ks.map(|k| lambdas[k]),
            ref_rad: ref_deg.to_radians(),
            offsets,
            f0_hz,
            df_hz,
        })
    }

    /// Directions.
    pub(super) fn directions(&self) -> usize {
        self.offsets.len()
    }

    /// The heading-frame cells j a direction with offset `o` sees: table cells
    /// i = j − o from 0 to n − 2.
    fn seen(&self, o: isize) -> std::ops::RangeInclusive<isize> {
        o..=o + self.n_ang as isize - 2
    }

    /// The table cell of entry `e` in direction `d`, None when not visible there.
    fn cell(&self, e: &Entry, d: usize) -> Option<usize> {
        let o = self.offsets[d];
        self.seen(o).contains(&e.j).then(|| (e.j - o) as usize)
    }

    /// Whether the per-path code culls entry `e` in direction `d` (cell `i`).
    fn culled(&self, e: &Entry, i: usize, cull: f64) -> bool {
        let (a, b) = (&self.cull_f[i], &self.cull_f[i + 1]);
        let est = (0..5)
            .map(|k| {
                (a[k] * (1.0 - e.t) + b[k] * e.t).norm_sqr() * self.cull_lambda[k] * e.amp.norm()
            })
            .fold(0.0, f64::max);
        est < 0.1 * cull
    }

    /// The noise-free S21 of every direction (`[direction][point]`, without coupling) of a
    /// pose with heading `heading` (rad) and paths `paths`; `cull` as the per-path code.
    pub(super) fn position(&self, heading: f64, paths: &[Path1], cull: f64) -> Vec<Complex64> {
        let (nd, nf) = (self.directions(), self.nf);
        let o_lo = *self.offsets.iter().min().expect("directions");
        let o_hi = *self.offsets.iter().max().expect("directions");
        let any = *self.seen(o_lo).start()..=*self.seen(o_hi).end();
        let mut entries: Vec<Entry> = paths
            .iter()
            .filter_map(|p| {
                let rel = crate::units::wrap_rad(p.theta - heading - self.ref_rad);
                let x = (rel.to_degrees() + 90.0) / self.step_deg;
                let jf = x.floor();
                let j = jf as isize;
                let df_cycles = (self.df_hz * p.tau_s).fract();
                any.contains(&j).then(|| Entry {
                    j,
                    t: x - jf,
                    amp: p.amp,
                    f0_cycles: (self.f0_hz * p.tau_s).fract(),
                    df_cycles,
                    step: Complex64::from_polar(1.0, -2.0 * PI * df_cycles),
                })
            })
            .collect();
        entries.sort_by_key(|e| e.j); // stable: paths keep their order within a cell
        let mut cells: Vec<(isize, usize, usize)> = Vec::new();
        for (n, e) in entries.iter().enumerate() {
            match cells.last_mut() {
                Some(c) if c.0 == e.j => c.2 = n + 1,
                _ => cells.push((e.j, n, n + 1)),
            }
        }
        let culled: Vec<Vec<usize>> = (0..nd)
            .into_par_iter()
            .map(|d| {
                (entries.iter().enumerate())
                    .filter(|(_, e)| self.cell(e, d).is_some_and(|i| self.culled(e, i, cull)))
                    .map(|(n, _)| n)
                    .collect()
            })
            .collect();
        // the cells each direction sees: a contiguous run of the sorted cells
        let ranges: Vec<(usize, usize)> = (self.offsets.iter())
            .map(|&o| {
                let seen = self.seen(o);
                let lo = cells.partition_point(|c| c.0 < *seen.start());
                let hi = cells.partition_point(|c| c.0 <= *seen.end());
                (lo, hi)
            })
            .collect();
        let nb = nf.div_ceil(BLOCK);
        let tasks: Vec<Vec<Complex64>> = (0..nb.div_ceil(TASK_BLOCKS))
            .into_par_iter()
            .map(|g| {
                let bs = g * TASK_BLOCKS..((g + 1) * TASK_BLOCKS).min(nb);
                self.task(bs, &entries, &cells, &ranges, &culled)
            })
            .collect();
        // each task gives [block][direction][BLOCK]
        let mut out = vec![Complex64::new(0.0, 0.0); nd * nf];
        for (g, v) in tasks.iter().enumerate() {
            for (n, blk) in v.chunks(nd * BLOCK).enumerate() {
                let k0 = (g * TASK_BLOCKS + n) * BLOCK;
                let len = BLOCK.min(nf - k0);
                for d in 0..nd {
                    out[d * nf + k0..d * nf + k0 + len]
                        .copy_from_slice(&blk[d * BLOCK..d * BLOCK + len]);
                }
            }
        }
        out
    }

    /// The blocks `bs` of points: `[block][direction][BLOCK]`. The phases start at the first
    /// point of the first block and advance by recurrence.
    fn task(
        &self,
        bs: std::ops::Range<usize>,
        entries: &[Entry],
        cells: &[(isize, usize, usize)],
        ranges: &[(usize, usize)],
        culled: &[Vec<usize>],
    ) -> Vec<Complex64> {
        let (nd, n_ang) = (self.directions(), self.n_ang);
        let mut ph: Vec<Complex64> = (entries.iter())
            .map(|e| e.phase_at(bs.start * BLOCK))
            .collect();
        let mut out = Vec::with_capacity(bs.len() * nd * BLOCK);
        let mut c = vec![[0.0f64; 6 * BLOCK]; cells.len()];
        let mut acc = vec![[0.0f64; 2 * BLOCK]; nd];
        for b in bs {
            let start = ph.clone();
            // per cell: C0, C1, C2 as (re, im) rows of BLOCK
            for (cc, &(_, a, z)) in c.iter_mut().zip(cells) {
                *cc = [0.0; 6 * BLOCK];
                for (e, p) in entries[a..z].iter().zip(&mut ph[a..z]) {
                    spread(cc, e.weights(), &phasors(e.amp, p, e.step));
                }
            }
            for a in acc.iter_mut() {
                *a = [0.0; 2 * BLOCK];
            }
            let tab = &self.tab[b * n_ang * 4 * BLOCK..(b + 1) * n_ang * 4 * BLOCK];
            add_cells(&mut acc, tab, &c, cells, &self.offsets, ranges);
            for (d, a) in acc.iter_mut().enumerate() {
                for &n in &culled[d] {
                    let e = &entries[n];
                    let i = self.cell(e, d).expect("culled entries are visible");
                    let (mut p, mut cc) = (start[n], [0.0f64; 6 * BLOCK]);
                    spread(&mut cc, e.weights(), &phasors(e.amp, &mut p, e.step));
                    add_cell(a, &tab[i * 4 * BLOCK..][..6 * BLOCK], &cc, -1.0);
                }
                out.extend((0..BLOCK).map(|k| Complex64::new(a[k], a[BLOCK + k])));
            }
        }
        out
    }
}

/// A·e^{−j2πfτ} over a block's points (re then im), advancing the phase `ph` by `step`.
fn phasors(amp: Complex64, ph: &mut Complex64, step: Complex64) -> [f64; 2 * BLOCK] {
    let mut h = [0.0; 2 * BLOCK];
    for k in 0..BLOCK {
        let v = amp * *ph;
        h[k] = v.re;
        h[BLOCK + k] = v.im;
        *ph *= step;
    }
    h
}

/// `c += (w₀·h, w₁·h, w₂·h)`: a path's phasors `h` (re then im) added to its cell's sums
/// C0, C1, C2 with its weights.
fn spread(c: &mut [f64; 6 * BLOCK], w: [f64; 3], h: &[f64; 2 * BLOCK]) {
    for (m, wm) in w.into_iter().enumerate() {
        for k in 0..BLOCK {
            c[2 * m * BLOCK + k] += wm * h[k];
            c[(2 * m + 1) * BLOCK + k] += wm * h[BLOCK + k];
        }
    }
}

/// Every cell's rows added to every direction that sees it (`acc[d]`; direction d sees the
/// cells `ranges[d]`), with 256-bit vectors where the CPU has AVX2: the same additions in the
/// same order (no fused multiply-add), so the bytes are the same on every x86-64.
fn add_cells(
    acc: &mut [[f64; 2 * BLOCK]],
    tab: &[f64],
    c: &[[f64; 6 * BLOCK]],
    cells: &[(isize, usize, usize)],
    offsets: &[isize],
    ranges: &[(usize, usize)],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above)
        unsafe { add_cells_avx2(acc, tab, c, cells, offsets, ranges) };
        return;
    }
    add_cells_generic(acc, tab, c, cells, offsets, ranges);
}

/// [`add_cells_generic`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_cells_avx2(
    acc: &mut [[f64; 2 * BLOCK]],
    tab: &[f64],
    c: &[[f64; 6 * BLOCK]],
    cells: &[(isize, usize, usize)],
    offsets: &[isize],
    ranges: &[(usize, usize)],
) {
    add_cells_generic(acc, tab, c, cells, offsets, ranges);
}

/// Cells a chunk at a time (their sums stay in L1 while every direction reads them); within
/// a direction the cells are added in order.
#[inline(always)]
fn add_cells_generic(
    acc: &mut [[f64; 2 * BLOCK]],
    tab: &[f64],
    c: &[[f64; 6 * BLOCK]],
    cells: &[(isize, usize, usize)],
    offsets: &[isize],
    ranges: &[(usize, usize)],
) {
    const CHUNK: usize = 64;
    for start in (0..cells.len()).step_by(CHUNK) {
        let end = (start + CHUNK).min(cells.len());
        for ((a, &o), &(lo, hi)) in acc.iter_mut().zip(offsets).zip(ranges) {
            let (lo, hi) = (lo.max(start), hi.min(end));
            if lo >= hi {
                continue;
            }
            let mut local = *a;
            for (cc, cell) in c[lo..hi].iter().zip(&cells[lo..hi]) {
                let i = (cell.0 - o) as usize;
                add_cell(&mut local, &tab[i * 4 * BLOCK..][..6 * BLOCK], cc, 1.0);
            }
            *a = local;
        }
    }
}

/// `acc += sign · (λF_i²·C0 + 2λF_iF_{i+1}·C1 + λF_{i+1}²·C2)` over a block: `t` holds the
/// table rows of cell i and the first two of cell i + 1, `c` the cell's sums.
#[inline(always)]
fn add_cell(acc: &mut [f64; 2 * BLOCK], t: &[f64], c: &[f64; 6 * BLOCK], sign: f64) {
    let t: &[f64; 6 * BLOCK] = t.try_into().expect("six rows");
    // rows of t: q re, q im, p re, p im, q' re, q' im; rows of c: C0 re, im, C1, C2
    for k in 0..BLOCK {
        let (b0, b1, b2, b3, b4, b5) = (
            k,
            BLOCK + k,
            2 * BLOCK + k,
            3 * BLOCK + k,
            4 * BLOCK + k,
            5 * BLOCK + k,
        );
        let re = t[b0] * c[b0] - t[b1] * c[b1] + t[b2] * c[b2] - t[b3] * c[b3] + t[b4] * c[b4]
            - t[b5] * c[b5];
        let im = t[b0] * c[b1]
            + t[b1] * c[b0]
            + t[b2] * c[b3]
            + t[b3] * c[b2]
            + t[b4] * c[b5]
            + t[b5] * c[b4];
        acc[k] += sign * re;
        acc[BLOCK + k] += sign * im;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::manifest::{ArrayConfig, Band, Steering, C0};
    use crate::pattern::{ArrayPattern, TABLE_STEP_DEG};
    use crate::scene::ScattererKind;
    use crate::synth::synth_sweep;
    use geo::Coord;
    use rand::{Rng, SeedableRng};

    /// `n` paths all around the pose (some far below the cull level, some exactly on table
    /// grid angles), delays 2–60 ns.
    fn paths(n: usize, seed: u64) -> Vec<Path1> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let theta = if i % 17 == 0 {
                    (-180.0 + 0.05 * rng.gen_range(0..7200) as f64).to_radians()
                } else {
                    rng.gen_range(-PI..PI)
                };
                let size = if i % 5 == 0 { 1e-12 } else { 1e-4 };
                Path1 {
                    tau_s: rng.gen_range(2e-9..60e-9),
                    theta,
                    amp: Complex64::from_polar(
                        size * rng.gen_range(0.1..1.0),
                        rng.gen_range(-PI..PI),
                    ),
                    scatterer: i,
                    kind: ScattererKind::Diffuse,
                    wall: None,
                    pos: Coord { x: 0.0, y: 0.0 },
                }
            })
            .collect()
    }

    /// The band (57.5–63.5 GHz, `points`), a mechanically steered array's pattern table
    /// at every point and the wavelengths.
    fn setup(
        points: usize,
        elements: usize,
        one_bit: bool,
    ) -> (Band, ArrayPattern, PatternTable, Vec<f64>) {
        let band = Band {
            start_hz: 57.5e9,
            stop_hz: 63.5e9,
            points,
        };
        let cfg = ArrayConfig {
            elements,
            one_bit,
            element_q: 1.0,
            steering: Steering::Mechanical,
        };
        let pattern = ArrayPattern::new(cfg, band.center_hz()).unwrap();
        let table = pattern.table(0.0, &band, band.points, TABLE_STEP_DEG);
        let lambdas: Vec<f64> = (0..band.points).map(|k| C0 / band.freq(k)).collect();
        (band, pattern, table, lambdas)
    }

    #[test]
    fn binned_sum_is_the_per_path_sum() {
        let (band, _, table, lambdas) = setup(101, 100, true);
        let angles: Vec<f64> = (0..37).map(|d| -90.0 + 5.0 * d as f64).collect();
        let b = BinnedTables::new(&table, &lambdas, band.start_hz, band.step_hz(), &angles)
            .expect("5° steps are whole cells");
        let ps = paths(600, 7);
        let cull = 1e-10;
        let heading = 0.3;
        let got = b.position(heading, &ps, cull);
        for (d, a) in angles.iter().enumerate() {
            let mut want = vec![Complex64::new(0.0, 0.0); band.points];
            let th = a.to_radians();
            synth_sweep(
                &ps,
                &table,
                heading,
                th,
                Steering::Mechanical,
                &band,
                cull,
                &mut want,
            );
            let scale = want.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert!(scale > 0.0);
            let g = &got[d * band.points..(d + 1) * band.points];
            for (k, (g, w)) in g.iter().zip(&want).enumerate() {
                assert!(
                    (g - w).norm() <= 1e-11 * scale,
                    "direction {d} point {k}: {g} vs {w}"
                );
            }
        }
        // the tiny paths are culled, and keeping them would move the sums well past rounding:
        // the comparison above sees the cull
        let d0 = 18;
        let mut kept = vec![Complex64::new(0.0, 0.0); band.points];
        synth_sweep(
            &ps,
            &table,
            heading,
            0.0,
            Steering::Mechanical,
            &band,
            0.0,
            &mut kept,
        );
        let g = &got[d0 * band.points..(d0 + 1) * band.points];
        let scale = kept.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let diff = (g.iter().zip(&kept))
            .map(|(g, w)| (g - w).norm())
            .fold(0.0, f64::max);
        assert!(diff > 1e-10 * scale, "cull effect {diff:e} of {scale:e}");
    }

    #[test]
    fn directions_off_the_table_grid_fall_back() {
        let (band, pattern, table, lambdas) = setup(11, 16, false);
        let new = |a: &[f64]| BinnedTables::new(&table, &lambdas, band.start_hz, band.step_hz(), a);
        assert!(new(&[-90.0, 0.0, 90.0]).is_some());
        assert!(new(&[0.0, 0.025]).is_none(), "half a cell apart");
        assert!(new(&[-100.0, 90.0]).is_none(), "more than 180° apart");
        // knots fewer than points: interpolated in frequency, not for the binned sum
        let coarse = pattern.table(0.0, &band, 5, TABLE_STEP_DEG);
        assert!(
            BinnedTables::new(&coarse, &lambdas, band.start_hz, band.step_hz(), &[0.0]).is_none()
        );
    }
}
