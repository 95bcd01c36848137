//! Map grid and the shared observation model (DESIGN §2 "Mapping").
//!
//! Takes the campaign's poses, directions, array and band, the energy table's bin layout and
//! a [`GridSpec`] (by default 0.1 m cells over the layout's bounding box plus 0.5 m, the same
//! raster as the reference map); gives, for every (pose, direction), the sparse list of
//! illuminated cells grouped by range bin ([`Beam`], CSR arrays: the cells of bin k are
//! contiguous), and the boresight ray of the classic baseline ([`RayCell`]).
//!
//! Equations and choices:
//! * one-way gain G(θ) of the array at the band centre f_c (the mapper's model, deliberately
//!   simpler than the simulator's frequency-dependent pattern), tabulated on a 0.05° grid in
//!   the array frame; mechanical steering turns that pattern to the beam θ_s, electronic
//!   steering uses one table per direction;
//! * two-way pattern weight w_i = (G(θ_i)/G_max)², G_max the peak of that direction's
//!   pattern; a cell is illuminated when w_i ≥ `lobe_floor_db` (−40 dB by default: main and
//!   side lobes) and belongs to the main lobe when w_i ≥ `main_lobe_db` (−3 dB two-way);
//! * share s_{k,i} of cell i in bin k: the cell is sub-sampled on an S × S grid (S =
//!   `subsamples`, 4 by default: 2.5 cm spacing for 0.1 m cells, about one bin of range) and
//!   the round-trip delays of the sub-points are histogrammed into bins
//!   k = round(2r/(c·T_b)); sub-points outside [min_bin, bins) are dropped (gated or beyond
//!   the last bin);
//! * radar-equation coefficient c_{k,i} = G(θ_i)²·λ_c²/((4π)³·d_i⁴)·s_{k,i} (d_i the range of
//!   the cell centre), so a cell of RRCS x_i adds c_{k,i}·x_i² to the energy of bin k
//!   (before the window kernel, which the EKF may fold in);
//! * cells are found per pose once (range, bearing, bin shares: [`PoseGeometry`]) and
//!   bucketed by bearing (0.05° buckets, counting sort); a direction's beam then visits only
//!   the buckets inside its lobes above the floor, so the cost is proportional to the
//!   illuminated cells.
//!
//! What a scan can see (the occluder of each beam, the visibility of each cell) is
//! [`visibility`]; [`ObservationModel::beam_seen`] restricts a beam to it. Beams are built
//! on demand per pose and reused for every bin of a mapper;
//! [`ObservationModel::beams`] builds one pose's beams in parallel.

use crate::campaign::manifest::{Manifest, Pose};
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use crate::reference::GridSpec;
use crate::units::{wrap_rad, C0};
use rayon::prelude::*;

mod gain;
pub mod visibility;
use gain::GainModel;
use std::f64::consts::PI;
pub use visibility::{Occlusion, Polygon, ScanEchoes, SilentBound, Visibility};

/// The cell sides [`GridParams::check`] accepts, m (`--cell-m`).
pub const CELL_M_RANGE: std::ops::RangeInclusive<f64> = 0.005..=10.0;

/// Grid and observation-model parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridParams {
    /// Cell side, m (0.1).
    pub cell_m: f64,
    /// Margin around the layout's bounding box, m (0.5).
    pub margin_m: f64,
    /// Lowest two-way pattern weight kept in a beam, dB (−40).
    pub lobe_floor_db: f64,
    /// Two-way weight above which a cell is in the main lobe, dB (−3).
    pub main_lobe_db: f64,
    /// Sub-samples per cell side for the bin shares (4).
    pub subsamples: usize,
}

impl Default for GridParams {
    fn default() -> Self {
        GridParams {
            cell_m: 0.1,
            margin_m: 0.5,
            lobe_floor_db: -40.0,
            main_lobe_db: -3.0,
            subsamples: 4,
        }
    }
}

/// Grid parameters that passed [`ParamGuard::check`].
pub type GridValid = Valid<GridParams>;

impl ParamGuard for GridParams {
    type Checked = GridValid;

    /// Cell side in [0.005, 10] m, margin ≥ 0, lobe floor < 0 dB, main-lobe level in
    /// [lobe floor, 0) dB, sub-samples in 1..=16.
    fn check(&self) -> Result<GridValid> {
        if !(self.cell_m.is_finite() && CELL_M_RANGE.contains(&self.cell_m)) {
            return Err(Error::param("cell_m", "must be in [0.005, 10] m"));
        }
        if !(self.margin_m.is_finite() && self.margin_m >= 0.0) {
            return Err(Error::param("margin_m", "must be >= 0"));
        }
        if !(self.lobe_floor_db.is_finite() && self.lobe_floor_db < 0.0) {
            return Err(Error::param("lobe_floor_db", "must be a negative dB level"));
        }
        if !(self.main_lobe_db.is_finite()
            && self.main_lobe_db < 0.0
            && self.main_lobe_db >= self.lobe_floor_db)
        {
            return Err(Error::param(
                "main_lobe_db",
                "must be negative and >= lobe_floor_db",
            ));
        }
        if self.subsamples == 0 || self.subsamples > 16 {
            return Err(Error::param("subsamples", "must be in 1..=16"));
        }
        Ok(Valid::new(*self))
    }
}

impl GridParams {
    /// Lowest kept two-way weight, linear.
    pub fn floor_weight(&self) -> f64 {
        10f64.powf(self.lobe_floor_db / 10.0)
    }
    /// Main-lobe two-way weight, linear.
    pub fn main_weight(&self) -> f64 {
        10f64.powf(self.main_lobe_db / 10.0)
    }
}

/// Bearing of the offset (`dx`, `dy`) from a pose of heading `heading` (rad) in the device
/// frame, rad in (−π, π].
fn device_bearing(dx: f64, dy: f64, heading: f64) -> f64 {
    wrap_rad(dy.atan2(dx) - heading)
}

/// Bearing buckets of [`PoseGeometry`] (0.05° each).
const BUCKETS: usize = 7200;

#[inline]
fn bucket_of(theta: f64) -> usize {
    (((theta + PI) / (2.0 * PI) * BUCKETS as f64) as usize).min(BUCKETS - 1)
}

/// Cells within range of one pose, bucketed by bearing (0.05° buckets, ascending; cells in
/// row-major order within a bucket), with their bin shares.
#[derive(Debug, Clone, Default)]
pub struct PoseGeometry {
    /// Cell indices (row-major).
    pub cell: Vec<u32>,
    /// `bucket[b]..bucket[b+1]` are the cells whose bearing falls in bucket b (len 7201).
    pub bucket: Vec<u32>,
    /// Bearing relative to the pose heading, rad in (−π, π].
    pub theta: Vec<f64>,
    /// Range of the cell centre, m.
    pub range: Vec<f64>,
    /// CSR pointer into `bin`/`share` per cell (len = cells + 1).
    pub ptr: Vec<u32>,
    /// Bin of each (cell, bin) pair.
    pub bin: Vec<u32>,
    /// Share of the cell's sub-samples in that bin.
    pub share: Vec<f32>,
}

/// One (pose, direction)'s illuminated cells, grouped by bin (CSR).
#[derive(Debug, Clone, Default)]
pub struct Beam {
    /// `ptr[k]..ptr[k+1]` are the entries of bin k (len = bins + 1).
    pub ptr: Vec<u32>,
    /// Cell index of each entry.
    pub cell: Vec<u32>,
    /// Two-way pattern weight w = (G/G_max)².
    pub weight: Vec<f32>,
    /// Share of the cell in the bin.
    pub share: Vec<f32>,
    /// Radar-equation coefficient c_{k,i} = G²λ²/((4π)³d⁴)·share.
    pub coef: Vec<f32>,
}

impl Beam {
    /// Entry range of bin `k`.
    #[inline]
    pub fn bin_range(&self, k: usize) -> std::ops::Range<usize> {
        self.ptr[k] as usize..self.ptr[k + 1] as usize
    }
    /// Number of (cell, bin) entries.
    pub fn len(&self) -> usize {
        self.cell.len()
    }
    /// True when no cell is illuminated.
    pub fn is_empty(&self) -> bool {
        self.cell.is_empty()
    }
}

/// A cell crossed by the boresight ray, with the bins the ray spends in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RayCell {
    /// Cell index.
    pub cell: u32,
    /// First bin of the ray inside the cell.
    pub bin_lo: u32,
    /// Last bin of the ray inside the cell.
    pub bin_hi: u32,
}

/// The shared observation model of one run (campaign + energy bin layout).
#[derive(Debug, Clone)]
pub struct ObservationModel {
    /// Grid geometry.
    pub spec: GridSpec,
    /// Parameters.
    pub params: GridValid,
    /// Poses of the run.
    pub poses: Vec<Pose>,
    /// Bins per profile.
    pub bins: usize,
    /// First usable bin (after the coupling gate and the kernel's half-width).
    pub min_bin: usize,
    /// Bin width, s.
    pub bin_width_s: f64,
    /// Wavelength at the band centre, m.
    pub lambda_m: f64,
    gain: GainModel,
}

impl ObservationModel {
    /// Build for a grid, a campaign manifest (poses, directions, array, band) and the energy
    /// bin layout (`bins` bins of `bin_width_ns`, usable from `min_bin`).
    pub fn new(
        spec: GridSpec,
        params: &GridValid,
        manifest: &Manifest,
        bins: usize,
        bin_width_ns: f64,
        min_bin: usize,
    ) -> Result<ObservationModel> {
        if !(bin_width_ns.is_finite() && bin_width_ns > 0.0) {
            return Err(Error::param("bin_width_ns", "must be > 0"));
        }
        if spec.len() >= u32::MAX as usize || bins >= u32::MAX as usize {
            return Err(Error::param("cell_m", "grid too large"));
        }
        let gain = GainModel::new(manifest, params.floor_weight())?;
        Ok(ObservationModel {
            spec,
            params: params.clone(),
            poses: manifest.poses.clone(),
            bins,
            min_bin: min_bin.min(bins),
            bin_width_s: bin_width_ns * 1e-9,
            lambda_m: C0 / manifest.band.center_hz(),
            gain,
        })
    }

    /// Number of directions.
    pub fn directions(&self) -> usize {
        self.gain.theta_s.len()
    }

    /// Boresight of direction `d` relative to the heading, rad.
    pub fn direction_rad(&self, d: usize) -> f64 {
        self.gain.theta_s[d]
    }

    /// Largest range covered by the bins, m.
    pub fn max_range_m(&self) -> f64 {
        crate::units::range_from_delay_s((self.bins as f64 - 0.5) * self.bin_width_s)
    }

    /// Everything the model's geometry and weights are made from, as text (its grid,
    /// parameters, poses, bins and the gain tables' inputs): two models with the same key
    /// give the same cells, bearings and weights (the scoring region's memo).
    pub(crate) fn memo_key(&self) -> String {
        format!(
            "{:?} {:?} {:?} {} {} {:?} {:?} {}",
            self.spec,
            self.params,
            self.poses,
            self.bins,
            self.min_bin,
            self.bin_width_s,
            self.lambda_m,
            self.gain.source
        )
    }

    /// Bearing of cell `cell`'s centre from pose `p` in the device frame (relative to the
    /// heading), rad: the bearing [`PoseGeometry::theta`] holds.
    pub fn cell_bearing_rad(&self, p: usize, cell: u32) -> f64 {
        let pose = self.poses[p];
        let c = cell as usize;
        let at = self.spec.center(c / self.spec.cols, c % self.spec.cols);
        device_bearing(
            at.x - pose.x_m,
            at.y - pose.y_m,
            pose.heading_deg.to_radians(),
        )
    }

    /// Two-way weight of direction `d` towards relative bearing `theta_rel` (rad).
    pub fn weight(&self, d: usize, theta_rel: f64) -> f64 {
        let g = self.gain.gain(d, theta_rel) / self.gain.gmax[d];
        g * g
    }

    /// Two-way weight of direction `d` towards relative bearing `theta_rel` (rad) against
    /// the array's peak gain over all directions (the broadside gain G0 of `simulate`'s
    /// truth powers): [`ObservationModel::weight`] times the direction's scan loss
    /// (G_max,d / G0)², 1 for mechanical steering. With electronic steering and no
    /// direction at 0° the peak is below the broadside gain, and the weight reads high by
    /// their ratio.
    pub fn broadside_weight(&self, d: usize, theta_rel: f64) -> f64 {
        let g = self.gain.gain(d, theta_rel) / self.gain.g0;
        g * g
    }

    #[inline]
    fn bin_of_range(&self, r: f64) -> f64 {
        (2.0 * r / (C0 * self.bin_width_s)).round()
    }

    /// The cells in range of pose `p` with bearings and bin shares.
    pub fn pose_geometry(&self, p: usize) -> PoseGeometry {
        let (items, flat) = self.cells_in_range(p);
        bucket_by_bearing(&items, &flat)
    }

    /// Every cell within the usable ranges of pose `p` that has a sub-sample in a usable
    /// bin, in row-major order, with its bin shares (concatenated in `flat`).
    fn cells_in_range(&self, p: usize) -> (Vec<CellItem>, Vec<(u32, f32)>) {
        let pose = self.poses[p];
        let spec = &self.spec;
        let rmax = self.max_range_m();
        let rmin = crate::units::range_from_delay_s(
            (self.min_bin as f64 - 0.5).max(0.0) * self.bin_width_s,
        );
        let heading = pose.heading_deg.to_radians();
        let s = self.params.subsamples;
        let half_diag = spec.cell_m * std::f64::consts::FRAC_1_SQRT_2;
        let mut items: Vec<CellItem> = Vec::new();
        let mut flat: Vec<(u32, f32)> = Vec::new();
        let (c_lo, c_hi) = col_span(spec, pose.x_m, rmax);
        let (r_lo, r_hi) = row_span(spec, pose.y_m, rmax);
        let mut sub = SubSampler {
            off: (0..s)
                .map(|a| ((a as f64 + 0.5) / s as f64 - 0.5) * spec.cell_m)
                .collect(),
            inv: 1.0 / (s * s) as f64,
            scale: 2.0 / (C0 * self.bin_width_s),
            ks: vec![0i64; s * s],
            counts: [0u32; 64],
            hist: Vec::with_capacity(16),
        };
        for row in r_lo..r_hi {
            for col in c_lo..c_hi {
                let c = spec.center(row, col);
                let (dx, dy) = (c.x - pose.x_m, c.y - pose.y_m);
                let r = dx.hypot(dy);
                if r + half_diag < rmin || r - half_diag > rmax || r < 1e-6 {
                    continue;
                }
                sub.bin_shares(dx, dy, r, self.min_bin, self.bins);
                if sub.hist.is_empty() {
                    continue;
                }
                sub.hist.sort_by_key(|e| e.0);
                let th = device_bearing(dx, dy, heading);
                items.push((
                    th,
                    (row * spec.cols + col) as u32,
                    r,
                    flat.len() as u32,
                    sub.hist.len() as u32,
                ));
                flat.extend_from_slice(&sub.hist);
            }
        }
        (items, flat)
    }

    /// The beam of direction `d` from a pose's geometry.
    pub fn beam(&self, geom: &PoseGeometry, d: usize) -> Beam {
        self.beam_seen(geom, d, None)
    }

    /// The beam of direction `d` restricted to what it can see: with `seen = (vis, last)`
    /// only the cells `vis` lets receive occupancy evidence and the bins ≤ `last` (the
    /// rows of later bins stay empty).
    pub fn beam_seen(
        &self,
        geom: &PoseGeometry,
        d: usize,
        seen: Option<(&Visibility, usize)>,
    ) -> Beam {
        let floor = self.params.floor_weight();
        let gmax = self.gain.gmax[d];
        let k_rad = self.lambda_m * self.lambda_m / (4.0 * PI).powi(3);
        // (bin, cell, w, share, coef)
        let mut counts = vec![0u32; self.bins + 1];
        let mut tmp: Vec<(u32, u32, f32, f32, f32)> = Vec::new();
        for &(lo, hi) in &self.gain.intervals[d] {
            let a = geom.bucket[bucket_of(lo)] as usize;
            let b = geom.bucket[bucket_of(hi) + 1] as usize;
            for i in a..b {
                if let Some((vis, _)) = seen {
                    if !vis.visible(geom.cell[i]) {
                        continue;
                    }
                }
                let g = self.gain.gain(d, geom.theta[i]);
                let w = (g / gmax) * (g / gmax);
                if w < floor {
                    continue;
                }
                let r = geom.range[i];
                let c0 = g * g * k_rad / (r * r * r * r);
                for j in geom.ptr[i] as usize..geom.ptr[i + 1] as usize {
                    let k = geom.bin[j];
                    if seen.is_some_and(|(_, last)| k as usize > last) {
                        continue;
                    }
                    let sh = geom.share[j];
                    counts[k as usize + 1] += 1;
                    tmp.push((k, geom.cell[i], w as f32, sh, (c0 * sh as f64) as f32));
                }
            }
        }
        for k in 0..self.bins {
            counts[k + 1] += counts[k];
        }
        let n = tmp.len();
        let mut beam = Beam {
            ptr: counts.clone(),
            cell: vec![0; n],
            weight: vec![0.0; n],
            share: vec![0.0; n],
            coef: vec![0.0; n],
        };
        let mut next = counts;
        for (k, c, w, s, co) in tmp {
            let at = next[k as usize] as usize;
            next[k as usize] += 1;
            beam.cell[at] = c;
            beam.weight[at] = w;
            beam.share[at] = s;
            beam.coef[at] = co;
        }
        beam
    }

    /// All beams of pose `p` (built in parallel over directions; deterministic).
    pub fn beams(&self, p: usize) -> Vec<Beam> {
        let g = self.pose_geometry(p);
        (0..self.directions())
            .into_par_iter()
            .map(|d| self.beam(&g, d))
            .collect()
    }

    /// The boresight ray of (pose `p`, direction `d`): the cells it crosses in range order,
    /// each with the bins the ray spends inside it (sampled every cell/8).
    pub fn boresight_ray(&self, p: usize, d: usize) -> Vec<RayCell> {
        let pose = self.poses[p];
        let th = pose.heading_deg.to_radians() + self.gain.theta_s[d];
        let (ux, uy) = (th.cos(), th.sin());
        let step = self.spec.cell_m / 8.0;
        let rmax = self.max_range_m();
        let mut out: Vec<RayCell> = Vec::new();
        let mut r = step;
        while r <= rmax {
            let k = self.bin_of_range(r);
            if k >= self.min_bin as f64 && k < self.bins as f64 {
                let k = k as u32;
                let pt = geo::Coord {
                    x: pose.x_m + r * ux,
                    y: pose.y_m + r * uy,
                };
                if let Some((row, col)) = self.spec.cell_of(pt) {
                    let cell = (row * self.spec.cols + col) as u32;
                    match out.last_mut() {
                        Some(last) if last.cell == cell => last.bin_hi = k,
                        _ => out.push(RayCell {
                            cell,
                            bin_lo: k,
                            bin_hi: k,
                        }),
                    }
                }
            }
            r += step;
        }
        out
    }

    /// Observable region: cells inside the main lobe (w ≥ `main_lobe_db`) of at least one
    /// (pose, direction) within the usable bins. Mapper-independent (no occlusion test).
    pub fn main_lobe_coverage(&self) -> Vec<bool> {
        let main = self.params.main_weight();
        let per_pose: Vec<Vec<u32>> = (0..self.poses.len())
            .into_par_iter()
            .map(|p| {
                let g = self.pose_geometry(p);
                let mut v = Vec::new();
                for (i, &th) in g.theta.iter().enumerate() {
                    if (0..self.directions()).any(|d| self.weight(d, th) >= main) {
                        v.push(g.cell[i]);
                    }
                }
                v
            })
            .collect();
        let mut cov = vec![false; self.spec.len()];
        for v in per_pose {
            for c in v {
                cov[c as usize] = true;
            }
        }
        cov
    }
}

/// A cell of [`ObservationModel::cells_in_range`]: (bearing, cell, range, start of its
/// bin shares in `flat`, their count).
type CellItem = (f64, u32, f64, u32, u32);

/// The sub-sampling of one cell into bins (buffers reused from cell to cell).
struct SubSampler {
    /// Sub-point offsets from the cell centre along one axis, m.
    off: Vec<f64>,
    /// Share of one sub-point, 1/S².
    inv: f64,
    /// Bins per metre of range, 2/(c·T_b).
    scale: f64,
    /// Bin of each sub-point.
    ks: Vec<i64>,
    /// Histogram of a narrow bin span.
    counts: [u32; 64],
    /// The cell's (bin, share) pairs in usable bins [min_bin, bins), unsorted.
    hist: Vec<(u32, f32)>,
}

impl SubSampler {
    /// Bin shares of the cell at offset (dx, dy), range r from the pose into `hist`:
    /// sub-point bins from exact ranges near the pose, first-order ranges beyond 2 m (error
    /// ≤ δ²/2r ≈ 1 mm for 0.1 m cells, against 2.5 cm bins).
    fn bin_shares(&mut self, dx: f64, dy: f64, r: f64, min_bin: usize, bins: usize) {
        let (ks, off, scale, inv) = (&mut self.ks, &self.off, self.scale, self.inv);
        self.hist.clear();
        let mut n = 0;
        if r > 2.0 {
            let (ux, uy) = (dx / r, dy / r);
            for &oa in off {
                let ra = r + ux * oa;
                for &ob in off {
                    ks[n] = ((ra + uy * ob) * scale).round() as i64;
                    n += 1;
                }
            }
        } else {
            for &oa in off {
                let x = dx + oa;
                for &ob in off {
                    let y = dy + ob;
                    ks[n] = ((x * x + y * y).sqrt() * scale).round() as i64;
                    n += 1;
                }
            }
        }
        let kmin = *ks[..n].iter().min().unwrap_or(&0);
        let kmax = *ks[..n].iter().max().unwrap_or(&0);
        let span = (kmax - kmin + 1) as usize;
        if span <= self.counts.len() {
            let counts = &mut self.counts;
            counts[..span].iter_mut().for_each(|c| *c = 0);
            for &k in &ks[..n] {
                counts[(k - kmin) as usize] += 1;
            }
            for (j, &cnt) in counts[..span].iter().enumerate() {
                let k = kmin + j as i64;
                if cnt > 0 && k >= min_bin as i64 && k < bins as i64 {
                    self.hist.push((k as u32, (cnt as f64 * inv) as f32));
                }
            }
        } else {
            for &k in &ks[..n] {
                if k < min_bin as i64 || k >= bins as i64 {
                    continue;
                }
                let k = k as u32;
                match self.hist.iter_mut().find(|e| e.0 == k) {
                    Some(e) => e.1 += inv as f32,
                    None => self.hist.push((k, inv as f32)),
                }
            }
        }
    }
}

/// Counting sort of the cells by bearing bucket (stable: row-major within a bucket) into a
/// [`PoseGeometry`].
fn bucket_by_bearing(items: &[CellItem], flat: &[(u32, f32)]) -> PoseGeometry {
    let mut bucket = vec![0u32; BUCKETS + 1];
    for it in items {
        bucket[bucket_of(it.0) + 1] += 1;
    }
    for b in 0..BUCKETS {
        bucket[b + 1] += bucket[b];
    }
    let mut order = vec![0u32; items.len()];
    let mut next = bucket.clone();
    for (i, it) in items.iter().enumerate() {
        let b = bucket_of(it.0);
        order[next[b] as usize] = i as u32;
        next[b] += 1;
    }
    let mut g = PoseGeometry {
        ptr: Vec::with_capacity(items.len() + 1),
        cell: Vec::with_capacity(items.len()),
        bucket,
        theta: Vec::with_capacity(items.len()),
        range: Vec::with_capacity(items.len()),
        bin: Vec::with_capacity(flat.len()),
        share: Vec::with_capacity(flat.len()),
    };
    g.ptr.push(0);
    for &o in &order {
        let (th, cell, r, start, n) = items[o as usize];
        g.cell.push(cell);
        g.theta.push(th);
        g.range.push(r);
        for &(k, sh) in &flat[start as usize..(start + n) as usize] {
            g.bin.push(k);
            g.share.push(sh);
        }
        g.ptr.push(g.bin.len() as u32);
    }
    g
}

fn col_span(spec: &GridSpec, x: f64, r: f64) -> (usize, usize) {
    let lo = ((x - r - spec.x0_m) / spec.cell_m).floor().max(0.0) as usize;
    let hi = (((x + r - spec.x0_m) / spec.cell_m).ceil() + 1.0).max(0.0) as usize;
    (lo.min(spec.cols), hi.min(spec.cols))
}

fn row_span(spec: &GridSpec, y: f64, r: f64) -> (usize, usize) {
    let lo = ((y - r - spec.y0_m) / spec.cell_m).floor().max(0.0) as usize;
    let hi = (((y + r - spec.y0_m) / spec.cell_m).ceil() + 1.0).max(0.0) as usize;
    (lo.min(spec.rows), hi.min(spec.rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_params_are_checked() {
        assert!(GridParams::default().check().is_ok());
        for (bad, field) in [
            (
                GridParams {
                    cell_m: 0.0,
                    ..Default::default()
                },
                "cell_m",
            ),
            (
                GridParams {
                    cell_m: f64::INFINITY,
                    ..Default::default()
                },
                "cell_m",
            ),
            (
                GridParams {
                    margin_m: -1.0,
                    ..Default::default()
                },
                "margin_m",
            ),
            (
                GridParams {
                    main_lobe_db: -50.0,
                    ..Default::default()
                },
                "main_lobe_db",
            ),
            (
                GridParams {
                    subsamples: 0,
                    ..Default::default()
                },
                "subsamples",
            ),
        ] {
            let e = bad.check().unwrap_err().to_string();
            assert!(
                e.contains(&format!("`{field}`")) && e.contains("must be"),
                "{e}"
            );
        }
    }

    #[test]
    fn wrap_is_in_range() {
        for a in [-7.0, -PI, -1.0, 0.0, PI, 4.0, 10.0] {
            let w = wrap_rad(a);
            assert!(w > -PI - 1e-12 && w <= PI + 1e-12, "{a} -> {w}");
            assert!(((w - a) / (2.0 * PI)).round() * 2.0 * PI - (w - a) < 1e-9);
        }
    }
}
