//! Running the EKF over a run ([`ekf_run`]) and reading the result ([`EkfMap`]).
//!
//! Takes an [`ObservationModel`], the run's [`EnergyMatrix`], the window kernel, checked
//! [`EkfValid`] parameters, the run's [`NoiseModel`], optionally what it can see
//! ([`Sight`]) and a filter; gives the filter updated
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
use crate::energy::{EnergyMatrix, EnergySource};
use crate::error::{Error, Result};
use crate::grid::{ObservationModel, Occlusion, PoseGeometry, ScanEchoes, Visibility};
use crate::og::Detector;
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
    /// Free-space observations (cells observed as RRCS ≈ 0, summed over updates).
    pub free_cells: u64,
    /// Detections whose rows were not observed: more than the guard beyond the occluder of
    /// their beam, or before it (the occluder's own rows are always kept).
    pub withheld: u64,
    /// Time building observations, s (wall).
    pub build_seconds: f64,
    /// Time in the filter updates, s (wall).
    pub update_seconds: f64,
    /// Total wall time, s.
    pub seconds: f64,
}

/// Run the filter over one run: every pose, every direction, in order; `progress(done,
/// total)` counts poses.
#[allow(clippy::too_many_arguments)]
pub fn ekf_run(
    model: &ObservationModel,
    src: &dyn EnergySource,
    kernel: &[f64],
    params: &EkfValid,
    noise: &NoiseModel,
    sight: Option<Sight<'_>>,
    filter: &mut dyn RrcsFilter,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<EkfStats> {
    ekf_run_with_arcs(
        model, src, kernel, params, noise, sight, filter, None, progress,
    )
}

/// [`ekf_run`] that also records, with a sight model and `arcs`, the range ring (main and
/// side lobes) of every detected echo ([`EchoArcs`]).
#[allow(clippy::too_many_arguments)]
pub fn ekf_run_with_arcs(
    model: &ObservationModel,
    src: &dyn EnergySource,
    kernel: &[f64],
    params: &EkfValid,
    noise: &NoiseModel,
    sight: Option<Sight<'_>>,
    filter: &mut dyn RrcsFilter,
    mut arcs: Option<&mut EchoArcs>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<EkfStats> {
    let n = model.spec.len();
    if filter.len() != n {
        return Err(Error::param("ekf", "filter and grid sizes differ"));
    }
    let head = src.header();
    if head.positions != model.poses.len() || head.directions() != model.directions() {
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
    // with a sight model, the occluders of pose p are confirmed against the binary map of
    // the filter before pose p − 1 was applied (the state the observations are built from)
    // (the energies are loaded one pose at a time: a table read from its file is never
    // held whole)
    let builder = Builder {
        model,
        src,
        kernel: &kernel,
        noise,
        sight,
    };
    // the filter's binary map (EkfMap's rule)
    let snapshot = |f: &dyn RrcsFilter| -> Option<Vec<bool>> {
        sight.map(|_| EkfMap::from_filter(f, model.spec.rows, model.spec.cols, params).binary())
    };
    let second_order = params.update == super::EkfUpdate::SecondOrder;
    let mut current = if np > 0 {
        Some(builder.build(0, snapshot(&*filter)))
    } else {
        None
    };
    for p in 0..np {
        let (obs, build_s, withheld, pose_arcs) = current.take().expect("built")?;
        if let Some(a) = arcs.as_deref_mut() {
            for arc in pose_arcs {
                a.push(p as u32, &arc);
            }
        }
        st.build_seconds += build_s;
        st.withheld += withheld;
        let occupied = if p + 1 < np { snapshot(&*filter) } else { None };
        let (applied, next) = rayon::join(
            || apply_pose(&mut *filter, &mut st, &obs, second_order, noise, params),
            || (p + 1 < np).then(|| builder.build(p + 1, occupied)),
        );
        applied?;
        current = next;
        progress(p + 1, np);
    }
    st.seconds = t0.elapsed().as_secs_f64();
    Ok(st)
}

/// A pose's observations with their free-space evidence, build time, withheld rows, echo
/// arcs.
type Built = (
    Vec<(Observation, Option<FreeSpace>)>,
    f64,
    u64,
    Vec<Vec<(u32, f32)>>,
);

/// One direction's observation with its free-space evidence, withheld rows, echo arcs.
type Dir = (Observation, Option<FreeSpace>, u64, Vec<Vec<(u32, f32)>>);

/// A pose's echoes, the visibility of its cells and the occlusion guard (bins), with a
/// sight model.
type Seen = (ScanEchoes, Visibility, usize);

/// What building a pose's observations takes: the observation model, the energies, the
/// truncated kernel, the noise model and what the run can see.
struct Builder<'a, 's> {
    /// The observation model.
    model: &'a ObservationModel,
    /// The run's energies (loaded one pose at a time).
    src: &'a dyn EnergySource,
    /// The window kernel, truncated at the parameters' floor.
    kernel: &'a [f64],
    /// The run's noise model.
    noise: &'a NoiseModel,
    /// What the run can see.
    sight: Option<Sight<'s>>,
}

impl Builder<'_, '_> {
    /// Takes a pose and, with a sight model, the filter's binary map its occluders are
    /// confirmed against; gives the pose's observations (built in parallel over
    /// directions, collected in direction order), with their build time, withheld rows
    /// and echo arcs.
    fn build(&self, p: usize, occupied: Option<Vec<bool>>) -> Result<Built> {
        let (model, sight) = (self.model, self.sight);
        let n = model.spec.len();
        let tb = Instant::now();
        let part = self.src.load(p, p + 1)?;
        let energy: &EnergyMatrix = &part;
        let geom = model.pose_geometry(p);
        let seen = sight.map(|s| {
            let dets = s.detector.detect_pose(energy, p);
            let echoes = s
                .occlusion
                .echoes(model, energy, p, dets, occupied.as_deref());
            let vis = s.occlusion.visibility(model, &geom, &echoes);
            (echoes, vis, s.occlusion.guard_bins())
        });
        let obs: Vec<Dir> = (0..model.directions())
            .into_par_iter()
            .map_init(
                || vec![0.0; n],
                |scratch, d| self.direction(energy, &geom, seen.as_ref(), p, d, scratch),
            )
            .collect();
        let withheld = obs.iter().map(|o| o.2).sum();
        let mut arcs = Vec::new();
        let obs = obs
            .into_iter()
            .map(|o| {
                arcs.extend(o.3);
                (o.0, o.1)
            })
            .collect();
        Ok((obs, tb.elapsed().as_secs_f64(), withheld, arcs))
    }

    /// Takes the pose's energies, geometry and (with a sight model) what it sees, the
    /// pose, a direction and a scratch buffer; gives the direction's observation (its
    /// bins up to the occluder plus the guard, less the rows around detections before
    /// the occluder), free-space evidence, withheld rows and echo arcs.
    fn direction(
        &self,
        energy: &EnergyMatrix,
        geom: &PoseGeometry,
        seen: Option<&Seen>,
        p: usize,
        d: usize,
        scratch: &mut [f64],
    ) -> Dir {
        let (model, kernel, noise, sight) = (self.model, self.kernel, self.noise, self.sight);
        if !energy.has(p, d) {
            // no sweep: no rows, no evidence
            let none = Observation {
                ptr: vec![0],
                ..Default::default()
            };
            return (none, None, 0, Vec::new());
        }
        let prof = energy.profile(p, d);
        let mut bins = prof.len().min(model.bins);
        let mut withheld = 0;
        let beam = match seen {
            Some((echoes, vis, guard)) => {
                let last = echoes.last_observed(d, *guard, bins);
                withheld = (last + 1..bins).filter(|&k| echoes.det[d][k]).count() as u64;
                bins = bins.min(last + 1);
                model.beam_seen(geom, d, Some((vis, last)))
            }
            None => model.beam(geom, d),
        };
        let mut o = Observation::build(&beam, &prof[..bins], kernel, model.min_bin, scratch);
        let mut free = None;
        if let (Some((echoes, _, _)), Some(s)) = (seen, sight) {
            let first = echoes.occluder[d].unwrap_or(bins);
            let j = kernel.len().saturating_sub(1);
            free = free_space(&o, &echoes.det[d], first, j, s.detector.threshold, noise);
        }
        if let Some((echoes, _, _)) = seen {
            // the rows around a detection before the occluder (leakage of a strong
            // echo at another bearing, withheld by the OG too) are not observed:
            // no cell of this beam explains them; with no occluder every detection
            // is explained by a side lobe
            let first = echoes.occluder[d].unwrap_or(bins);
            let j = kernel.len().saturating_sub(1);
            let det = &echoes.det[d];
            let early: Vec<usize> = (0..first.min(det.len())).filter(|&k| det[k]).collect();
            withheld += early.len() as u64;
            if !early.is_empty() {
                o.retain_rows(|b| {
                    let b = b as usize;
                    b.abs_diff(first) <= j || !early.iter().any(|&k| b.abs_diff(k) <= j)
                });
            }
        }
        let arcs = match seen {
            Some((echoes, _, _)) => echo_arcs(&o, &echoes.det[d]),
            None => Vec::new(),
        };
        (o, free, withheld, arcs)
    }
}

/// Takes the filter, the run's statistics, a pose's observations (with their free-space
/// evidence), the linearisation order, the noise model and the parameters; applies the
/// observations to the filter in order, each followed by the positivity step and its
/// free-space evidence, and counts them in the statistics.
fn apply_pose(
    filter: &mut dyn RrcsFilter,
    st: &mut EkfStats,
    obs: &[(Observation, Option<FreeSpace>)],
    second_order: bool,
    noise: &NoiseModel,
    params: &EkfValid,
) -> Result<()> {
    let tu = Instant::now();
    for (o, free) in obs {
        let lin = if second_order {
            filter.linearize_second_order(o, noise)
        } else {
            Linearized::new(o, filter.mean(), noise)
        };
        filter.update(o, &lin)?;
        st.reflected += filter.project_positive(params.x_min()) as u64;
        if let Some((f, r)) = free {
            let lin = Linearized::direct(f, filter.mean(), r);
            filter.update(f, &lin)?;
            st.reflected += filter.project_positive(params.x_min()) as u64;
            st.free_cells += f.rows() as u64;
        }
        st.updates += 1;
        st.rows += o.rows() as u64;
        st.entries += o.cell.len() as u64;
    }
    st.update_seconds += tu.elapsed().as_secs_f64();
    Ok(())
}

/// Free-space evidence: direct observations of cells (z = 0) and their variances.
type FreeSpace = (Observation, Vec<f64>);

/// The free-space evidence of one observation (module docs of [`super`]): for each row
/// (bin k) that is below the detector's threshold, at least the kernel's half-width `j`
/// bins from every detection and ending before the occluder's kernel reach (k + j <
/// `first`), the cells whose largest coefficient in the observation is in that row and is
/// within −3 dB of the row's largest (the main lobe at that range): each observed directly
/// as RRCS 0 with variance x_max²/3, x_max² = (threshold − N0·TW)/c̃ the RRCS that alone
/// would lift the bin to the threshold (a uniform belief on [−x_max, x_max]). `None` when no
/// cell qualifies.
fn free_space(
    o: &Observation,
    det: &[bool],
    first: usize,
    j: usize,
    threshold: f64,
    noise: &NoiseModel,
) -> Option<FreeSpace> {
    let excess = threshold - noise.mean();
    if excess.is_nan() || excess <= 0.0 {
        return None;
    }
    // each cell's largest coefficient and its row
    let mut best: std::collections::HashMap<u32, (f64, usize)> = Default::default();
    let mut row_max = vec![0.0f64; o.rows()];
    for (r, m) in row_max.iter_mut().enumerate() {
        for e in o.ptr[r]..o.ptr[r + 1] {
            let (c, v) = (o.cell[e], o.coef[e]);
            *m = m.max(v);
            let b = best.entry(c).or_insert((0.0, r));
            if v > b.0 {
                *b = (v, r);
            }
        }
    }
    let free_row: Vec<bool> = (0..o.rows())
        .map(|r| {
            let k = o.bin[r] as usize;
            k + j < first
                && o.z[r] < threshold
                && (k.saturating_sub(j)..=(k + j).min(det.len().saturating_sub(1)))
                    .all(|b| !det.get(b).copied().unwrap_or(false))
        })
        .collect();
    let mut cells: Vec<(u32, f64)> = best
        .into_iter()
        .filter(|(_, (v, r))| free_row[*r] && *v >= 0.5 * row_max[*r] && *v > 0.0)
        .map(|(c, (v, _))| (c, excess / v / 3.0))
        .collect();
    if cells.is_empty() {
        return None;
    }
    cells.sort_by_key(|c| c.0);
    let f = Observation {
        bin: vec![0; cells.len()],
        z: vec![0.0; cells.len()],
        ptr: (0..=cells.len()).collect(),
        cell: cells.iter().map(|c| c.0).collect(),
        coef: vec![1.0; cells.len()],
    };
    Some((f, cells.into_iter().map(|c| c.1).collect()))
}

/// The range rings of one observation's echoes: for each kept row whose bin holds a
/// detection, every cell with a coefficient in that row (main and side lobes down to the
/// observation model's floor), with its coefficient c̃.
fn echo_arcs(o: &Observation, det: &[bool]) -> Vec<Vec<(u32, f32)>> {
    (0..o.rows())
        .filter(|&r| det.get(o.bin[r] as usize).copied().unwrap_or(false))
        .map(|r| {
            (o.ptr[r]..o.ptr[r + 1])
                .filter(|&e| o.coef[e] > 0.0)
                .map(|e| (o.cell[e], o.coef[e] as f32))
                .collect::<Vec<_>>()
        })
        .filter(|arc| !arc.is_empty())
        .collect()
}

/// The range rings (arcs) of the echoes a run observed (one per detected bin of a kept row,
/// [`ekf_run_with_arcs`]), for the arc-explanation step ([`EkfMap::explain`]): compressed rows
/// of (cell, c̃) and the pose of each arc.
#[derive(Debug, Clone, Default)]
pub struct EchoArcs {
    /// Row pointers into `cell`/`coef`, one row per arc.
    pub ptr: Vec<usize>,
    /// Cells of the arcs.
    pub cell: Vec<u32>,
    /// Their coefficients c̃ in the echo's bin.
    pub coef: Vec<f32>,
    /// Pose of each arc.
    pub pose: Vec<u32>,
}

impl EchoArcs {
    /// Append one arc seen from pose `pose`.
    pub fn push(&mut self, pose: u32, arc: &[(u32, f32)]) {
        if self.ptr.is_empty() {
            self.ptr.push(0);
        }
        for &(c, v) in arc {
            self.cell.push(c);
            self.coef.push(v);
        }
        self.ptr.push(self.cell.len());
        self.pose.push(pose);
    }
    /// Number of arcs.
    pub fn len(&self) -> usize {
        self.pose.len()
    }
    /// True without arcs.
    pub fn is_empty(&self) -> bool {
        self.pose.is_empty()
    }
}

/// What the EKF can see (`map --method ekf` always gives it): the run's detector and its
/// occlusion model ([`crate::grid::visibility`]). With it, an observation keeps
/// only the bins up to its beam's occluder plus the guard, less the rows around weaker
/// detections before the occluder, and only the cells visible from the pose; without it,
/// every bin and every illuminated cell (the filter's unit tests).
#[derive(Debug, Clone, Copy)]
pub struct Sight<'a> {
    /// Detector of the run.
    pub detector: &'a Detector,
    /// Occlusion model of the run.
    pub occlusion: &'a Occlusion,
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
    /// Echo arcs through each cell ([`EkfMap::explain`]; zeros before it).
    pub arcs: Vec<u32>,
    /// Distinct poses of those arcs.
    pub arc_poses: Vec<u32>,
    /// The cell's largest share c̃·x'² of an arc relative to the arc's strongest cell (0 on
    /// no arc).
    pub arc_share: Vec<f64>,
    /// Echo arcs the cell explains (share ≥ γ of the arc's strongest).
    pub explained_arcs: Vec<u32>,
    /// Distinct poses of the arcs the cell explains ([`EkfMap::explain`]'s `min_poses`).
    pub explained_poses: Vec<u32>,
    /// Cells on at least one echo arc none of which they explain ([`EkfMap::explain`] with
    /// γ > 0): never decided occupied.
    pub unexplained: Vec<bool>,
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
            arcs: vec![0; rows * cols],
            arc_poses: vec![0; rows * cols],
            arc_share: vec![0.0; rows * cols],
            explained_arcs: vec![0; rows * cols],
            explained_poses: vec![0; rows * cols],
            unexplained: vec![false; rows * cols],
        }
    }

    /// The arc-explanation step (module docs of [`super`]): with x'_i = max(x̂_i, 0), the
    /// energy of an echo's range ring (every cell with a coefficient c̃ in the echo's bin,
    /// [`EchoArcs`]) is explained by its cells in proportion to c̃_i·x'_i²; a cell explains
    /// the echo when its share is at least `gamma` times the ring's largest. With `gamma` > 0
    /// and at least one run's rings given, a cell that explains no echo (including a cell on
    /// no echo's ring: raised by bins without a detection only) is marked unexplained and
    /// never decided occupied. Also counts the rings and their distinct poses per cell, the
    /// rings it explains and their distinct poses, and keeps each cell's largest relative
    /// share.
    pub fn explain(&mut self, arcs: &[EchoArcs], gamma: f64) {
        let n = self.mean.len();
        let x: Vec<f64> = self.mean.iter().map(|&m| m.max(0.0)).collect();
        // the (run, pose) each count saw last per cell: a pose's arcs are consecutive in a
        // run, so a new pair is a new distinct pose (1 to add), a repeat is not (0)
        let mut last_arc = vec![(usize::MAX, u32::MAX); n];
        let mut last_explained = vec![(usize::MAX, u32::MAX); n];
        let new_pose = |last: &mut [(usize, u32)], c: usize, key: (usize, u32)| -> u32 {
            u32::from(std::mem::replace(&mut last[c], key) != key)
        };
        for (ri, run) in arcs.iter().enumerate() {
            for a in 0..run.len() {
                let key = (ri, run.pose[a]);
                let es = run.ptr[a]..run.ptr[a + 1];
                let share = |e: usize| run.coef[e] as f64 * x[run.cell[e] as usize].powi(2);
                let max = es.clone().map(share).fold(0.0f64, f64::max);
                for e in es {
                    let c = run.cell[e] as usize;
                    self.arcs[c] += 1;
                    self.arc_poses[c] += new_pose(&mut last_arc, c, key);
                    let rel = if max > 0.0 { share(e) / max } else { 1.0 };
                    self.arc_share[c] = self.arc_share[c].max(rel);
                    if share(e) >= gamma * max {
                        self.explained_arcs[c] += 1;
                        self.explained_poses[c] += new_pose(&mut last_explained, c, key);
                    }
                }
            }
        }
        if gamma > 0.0 && !arcs.is_empty() {
            for (u, &e) in self.unexplained.iter_mut().zip(&self.explained_poses) {
                *u = e < 1;
            }
        }
    }

    /// p_i = Φ((x̂_i − μ0)/σ̂_i); at most η = Φ(κ) for an unexplained cell
    /// ([`EkfMap::explain`]).
    pub fn probs(&self) -> Vec<f64> {
        self.mean
            .iter()
            .zip(&self.std)
            .zip(&self.unexplained)
            .map(|((&m, &s), &u)| {
                if u {
                    // not decided occupied: capped at the binary threshold
                    normal_cdf(self.kappa).min(if s > 0.0 {
                        normal_cdf((m - self.mu0) / s)
                    } else {
                        0.0
                    })
                } else if s > 0.0 {
                    normal_cdf((m - self.mu0) / s)
                } else if m > self.mu0 {
                    1.0
                } else {
                    0.0
                }
            })
            .collect()
    }
    /// Binary map: x̂ − κ·σ̂ > μ0 and not unexplained ([`EkfMap::explain`]).
    pub fn binary(&self) -> Vec<bool> {
        self.mean
            .iter()
            .zip(&self.std)
            .zip(&self.unexplained)
            .map(|((&m, &s), &u)| !u && m - self.kappa * s > self.mu0)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamGuard;

    /// The arc explanation: one ring over cells 0–2 (equal c̃) seen from pose 0 and a second
    /// over cells 0–1 from pose 1; cell 3 on no ring. Cell 0 (x̂ 1 m) explains both rings;
    /// cell 1 (x̂ 0.04 m: share 1.6e-3 < γ = 2.24e-3) and cell 2 (x̂ 0.05 m: share 2.5e-3 ≥ γ)
    /// and cell 3 are occupied by the κ rule alone; with the step cell 1 (explains nothing)
    /// and cell 3 (on no ring) are cleared, cell 2 stays; γ = 0 clears nothing.
    #[test]
    fn arc_explanation_clears_cells_that_explain_no_echo() {
        let params = EkfParams::default().check().unwrap();
        let mut arcs = EchoArcs::default();
        arcs.push(0, &[(0, 1.0), (1, 1.0), (2, 1.0)]);
        arcs.push(1, &[(0, 2.0), (1, 2.0)]);
        assert_eq!(arcs.len(), 2);
        let map = EkfMap {
            rows: 1,
            cols: 4,
            mean: vec![1.0, 0.04, 0.05, 0.5],
            std: vec![1e-3; 4],
            mu0: params.mu0,
            kappa: params.kappa,
            arcs: vec![0; 4],
            arc_poses: vec![0; 4],
            arc_share: vec![0.0; 4],
            explained_arcs: vec![0; 4],
            explained_poses: vec![0; 4],
            unexplained: vec![false; 4],
        };
        assert_eq!(map.binary(), vec![true; 4]);
        let mut off = map.clone();
        off.explain(std::slice::from_ref(&arcs), 0.0);
        assert_eq!(off.binary(), vec![true; 4]);
        assert_eq!(off.arcs, vec![2, 2, 1, 0]);
        assert_eq!(off.arc_poses, vec![2, 2, 1, 0]);
        let mut on = map.clone();
        on.explain(std::slice::from_ref(&arcs), params.arc_explain);
        assert_eq!(on.binary(), vec![true, false, true, false]);
        assert_eq!(on.explained_arcs, vec![2, 0, 1, 0]);
        assert_eq!(on.explained_poses, vec![2, 0, 1, 0]);
        assert!((on.arc_share[1] - 0.04f64.powi(2)).abs() < 1e-12);
        // an unexplained cell's soft value is capped at η
        assert!(on.probs()[1] <= params.eta() && on.probs()[0] > params.eta());
        // without rings (no sight model) nothing is judged
        let mut none = map;
        none.explain(&[], params.arc_explain);
        assert_eq!(none.binary(), vec![true; 4]);
    }

    /// Five rows (bins 10..=14) over three cells; threshold 1.0, noise mean 0.2 (excess
    /// 0.8), kernel half-width 1, occluder at bin 14. Row 10: cells 0 (c̃ 0.4) and 1 (0.1);
    /// row 11: cell 1 (0.3), cell 2 (0.2); row 12: cell 2 (0.5), energy above the threshold;
    /// rows 13–14: cell 0 (0.01). Free rows: 10 only (11 is within one bin of the echo at 12,
    /// 12 is above the threshold, 13 reaches the occluder). Cell 0's largest coefficient is
    /// in row 10 and is the row's largest: observed, variance 0.8/0.4/3. Cell 1's largest is
    /// in row 11 (not free); cell 2's in row 12: neither observed.
    #[test]
    fn free_space_observes_main_lobe_cells_of_quiet_bins_only() {
        let o = Observation {
            bin: vec![10, 11, 12, 13, 14],
            z: vec![0.3, 0.4, 2.0, 0.2, 0.2],
            ptr: vec![0, 2, 4, 5, 6, 7],
            cell: vec![0, 1, 1, 2, 2, 0, 0],
            coef: vec![0.4, 0.1, 0.3, 0.2, 0.5, 0.01, 0.01],
        };
        let mut det = vec![false; 20];
        det[12] = true;
        let noise = NoiseModel {
            n0: 0.2,
            tw: 1.0,
            pulses: 1.0,
            model_error: 0.5,
        };
        let (f, r) = free_space(&o, &det, 14, 1, 1.0, &noise).unwrap();
        assert_eq!(f.cell, vec![0]);
        assert_eq!(f.z, vec![0.0]);
        assert!((r[0] - 0.8 / 0.4 / 3.0).abs() < 1e-12);
        // the direct measurement pulls the cell's mean toward 0 by the Kalman gain
        let params = EkfParams::default().check().unwrap();
        let mut filter = super::super::DenseEkf::new(3, &params).unwrap();
        let lin = Linearized::direct(&f, filter.mean(), &r);
        filter.update(&f, &lin).unwrap();
        let p0 = params.sigma0 * params.sigma0;
        let want = params.mu0 - p0 / (p0 + r[0]) * params.mu0;
        assert!(
            (filter.mean()[0] - want).abs() < 1e-12,
            "{}",
            filter.mean()[0]
        );
        assert!((filter.variances()[0] - p0 * r[0] / (p0 + r[0])).abs() < 1e-12);
        // a threshold at the noise mean gives no evidence
        assert!(free_space(&o, &det, 14, 1, 0.2, &noise).is_none());
    }
}
