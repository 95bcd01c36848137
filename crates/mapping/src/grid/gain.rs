//! The mapper's one-way gain model: the array's pattern at the band centre f_c tabulated
//! on a 0.05° grid in the array frame (one table for mechanical steering, turned to each
//! beam θ_s; one table per direction for electronic steering), linearly interpolated, with
//! each direction's peak gain G_max and the device-frame bearing intervals where the
//! two-way weight (G/G_max)² reaches the floor (widened by one table step, split at ±π).

use crate::campaign::manifest::{Manifest, Steering};
use crate::error::{Error, Result};
use crate::memo::Memo;
use crate::pattern::ArrayPattern;
use crate::units::wrap_rad;
use rayon::prelude::*;
use std::f64::consts::PI;

const STEP_DEG: f64 = 0.05;

/// One-way gain tables of the mapper's pattern model (band centre).
#[derive(Debug, Clone)]
pub(super) struct GainModel {
    /// Mechanical: one table; electronic: one per direction. Array-frame angle −90..90°.
    pub(super) tables: Vec<Vec<f64>>,
    pub(super) mechanical: bool,
    /// Steering angles, rad (device frame).
    pub(super) theta_s: Vec<f64>,
    /// Peak gain per direction.
    pub(super) gmax: Vec<f64>,
    /// The largest of them (the broadside gain when a direction points at 0°).
    pub(super) g0: f64,
    /// Per direction: device-frame angle intervals (rad, within (−π, π]) where w ≥ floor.
    pub(super) intervals: Vec<Vec<(f64, f64)>>,
    /// The inputs the tables were made from (array, band, directions, floor) as text:
    /// the key of [`GAIN_MEMO`] and of the scoring region's memo.
    pub(super) source: String,
}

/// Gain models already made in this process ([`crate::memo`]).
static GAIN_MEMO: Memo<GainModel> = Memo::new();

fn lookup(table: &[f64], deg: f64) -> f64 {
    if !(-90.0..=90.0).contains(&deg) {
        return 0.0;
    }
    let x = (deg + 90.0) / STEP_DEG;
    let i = (x.floor() as usize).min(table.len() - 2);
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

impl GainModel {
    pub(super) fn new(m: &Manifest, floor: f64) -> Result<GainModel> {
        let source = format!("{:?} {:?} {:?} {:?}", m.array, m.band, m.directions, floor);
        GAIN_MEMO.get_or(source.clone(), || GainModel::make(m, floor, source))
    }

    /// [`GainModel::new`] without the memo.
    fn make(m: &Manifest, floor: f64, source: String) -> Result<GainModel> {
        let pat = ArrayPattern::new(m.array, m.band.center_hz())?;
        let fc = m.band.center_hz();
        let n_ang = (180.0 / STEP_DEG).round() as usize + 1;
        let angles: Vec<f64> = m
            .directions
            .angles_deg()
            .iter()
            .map(|a| a.to_radians())
            .collect();
        let mechanical = m.array.steering == Steering::Mechanical;
        let make = |theta_s: f64| -> Vec<f64> {
            (0..n_ang)
                .into_par_iter()
                .map(|i| {
                    let th = (-90.0 + i as f64 * STEP_DEG).to_radians();
                    pat.field_dir(th, 0.0, theta_s, fc).norm_sqr()
                })
                .collect()
        };
        let tables: Vec<Vec<f64>> = if mechanical {
            vec![make(0.0)]
        } else {
            angles.iter().map(|&a| make(a)).collect()
        };
        let floor_amp = floor.sqrt();
        let mut gmax = Vec::new();
        let mut intervals = Vec::new();
        for (d, &ts) in angles.iter().enumerate() {
            let t = if mechanical { &tables[0] } else { &tables[d] };
            let g = t.iter().cloned().fold(0.0f64, f64::max);
            if g <= 0.0 {
                return Err(Error::param("array", "pattern has no gain"));
            }
            gmax.push(g);
            // runs of table samples above the floor, widened by one step
            let mut iv = Vec::new();
            let mut i = 0;
            while i < n_ang {
                if t[i] >= floor_amp * g {
                    let s = i;
                    while i + 1 < n_ang && t[i + 1] >= floor_amp * g {
                        i += 1;
                    }
                    let lo = (-90.0 + (s as f64 - 1.0) * STEP_DEG).to_radians();
                    let hi = (-90.0 + (i as f64 + 1.0) * STEP_DEG).to_radians();
                    let (lo, hi) = if mechanical {
                        (lo + ts, hi + ts)
                    } else {
                        (lo, hi)
                    };
                    // split at ±π
                    let (wl, wh) = (wrap_rad(lo), wrap_rad(hi));
                    if hi - lo >= 2.0 * PI {
                        iv.push((-PI, PI));
                    } else if wl <= wh {
                        iv.push((wl, wh));
                    } else {
                        iv.push((wl, PI));
                        iv.push((-PI, wh));
                    }
                }
                i += 1;
            }
            intervals.push(iv);
        }
        Ok(GainModel {
            tables,
            mechanical,
            theta_s: angles,
            g0: gmax.iter().cloned().fold(0.0f64, f64::max),
            gmax,
            intervals,
            source,
        })
    }

    /// One-way gain of direction `d` towards device-frame bearing `theta_rel` (rad).
    #[inline]
    pub(super) fn gain(&self, d: usize, theta_rel: f64) -> f64 {
        if self.mechanical {
            lookup(
                &self.tables[0],
                wrap_rad(theta_rel - self.theta_s[d]).to_degrees(),
            )
        } else {
            lookup(&self.tables[d], theta_rel.to_degrees())
        }
    }
}
