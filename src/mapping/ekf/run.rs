//! Running the EKF over a run ([`ekf_run`]) and reading the result ([`EkfMap`]).
//!
//! Takes an [`ObservationModel`], the run's [`EnergyMatrix`], the window kernel, checked
//! [`EkfValid`] parameters, the run's [`NoiseModel`] and a filter; gives the filter updated
//! by every (pose, direction) in order and [`EkfStats`]. The observations of pose p are
//! built in parallel over directions (beam, kernel convolution) while those of pose p − 1
//! are applied, in direction order, on the calling thread, so the result does not depend on
//! the number of threads.
//!
//! [`EkfMap`]: posterior mean x̂_i and standard deviation σ̂_i per cell, the soft map
//! p_i = Φ((x̂_i − μ0)/σ̂_i) and the binary map x̂_i − κ·σ̂_i > μ0 (p_i > η = Φ(κ)); cells
//! never illuminated stay at the prior and read as free. Grey coding of the mean and the
//! standard deviation maps: [`mean_grey`], [`std_grey`].

use super::{
    normal_cdf, truncate_kernel, EkfParams, EkfValid, Linearized, NoiseModel, Observation,
    RrcsFilter,
};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::mapping::grid::ObservationModel;
use rayon::prelude::*;
use std::time::Instant;

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
    params: &EkfValid,
    noise: &NoiseModel,
    filter: &mut dyn RrcsFilter,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<EkfStats> {
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
    pub fn from_filter(f: &dyn RrcsFilter, rows: usize, cols: usize, params: &EkfValid) -> Self {
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
