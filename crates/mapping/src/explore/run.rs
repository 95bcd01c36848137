//! The grid run of `pradar explore` ([`crate::explore`]: its parameters, result types and
//! energy model): every (configuration, seed) job made (physics sweeps
//! and the energy stage, or `synth`), mapped by every mapper and scored; the jobs run in
//! parallel (rayon), each depending only on its configuration and seed, so the rows are
//! the same bytes with any thread count. The cheapest job is run first, timed, and the
//! grid refused when its estimate is above `max_minutes` (module docs of [`crate::explore`]).

use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::error::{Error, Result};
use crate::explore::{
    Config, DataKind, EnergyModelValid, ExploreOutput, ExploreRow, ExploreValid, ScanShape, Scores,
    Timing, PAPER_ELEMENTS, PAPER_PULSES, PAPER_STEP_DEG,
};
use crate::job::{run_map, MapOptions, MapRun, PoseNoise};
use crate::model::file::ModelConfig;
use crate::model::{synth, SynthParams};
use crate::params::ParamGuard;
use crate::progress::Bars as Progress;
use crate::simulate::{has_scene, simulate, write_campaign};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One job: a configuration at a seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Job {
    /// The configuration.
    pub config: Config,
    /// The seed.
    pub seed: u64,
    /// Directions of a scan.
    pub directions: usize,
    /// Samples (frequency points) per pulse.
    pub samples: usize,
}

/// A pulse's share of a direction's work beside the sweep's own synthesis (measured on the
/// corridor: 8 pulses cost ~20 % more than 1 in the simulator and the energy stage,
/// docs/explore.md).
const PULSE_SHARE: f64 = 0.025;
/// A mapper's share of a direction's work (measured: the OG takes ~5 % of the simulator's
/// time per direction on the corridor).
const MAPPER_SHARE: f64 = 0.05;

impl Job {
    /// The job's work for the time estimate, in sweep samples: directions × samples ×
    /// (1 + pulses × [`PULSE_SHARE`] + mappers × [`MAPPER_SHARE`]).
    pub fn work(&self, mappers: usize) -> f64 {
        let ds = (self.directions * self.samples) as f64;
        ds * (1.0 + PULSE_SHARE * self.config.pulses as f64 + MAPPER_SHARE * mappers as f64)
    }
}

/// The campaign changed to a configuration at a seed (manifest seed + seed).
pub fn configured(base: &Campaign, cfg: &Config, seed: u64) -> Result<Campaign> {
    let mut c = base.clone();
    c.set_elements(cfg.elements)?;
    let m = &mut c.manifest;
    m.seed = m.seed.wrapping_add(seed);
    m.pulses = cfg.pulses;
    m.directions.step_deg = cfg.step_deg;
    m.directions.check().map_err(|_| {
        Error::param(
            "--step-deg",
            format!(
                "{}° does not divide the campaign's sector {}° to {}° (or gives too many directions)",
                cfg.step_deg, m.directions.start_deg, m.directions.stop_deg
            ),
        )
    })?;
    let df = m.band.step_hz();
    let b = cfg.bandwidth_ghz * 1e9;
    let fc = m.band.center_hz();
    let steps = (b / df).round().max(1.0) as usize;
    m.band.start_hz = fc - 0.5 * b;
    m.band.stop_hz = fc + 0.5 * b;
    m.band.points = steps + 1;
    m.band.check().map_err(|_| {
        Error::param(
            "--bandwidth-ghz",
            format!(
                "{} GHz at the campaign's {} MHz step gives {} frequency points (8 to the largest sweep)",
                cfg.bandwidth_ghz,
                df / 1e6,
                m.band.points
            ),
        )
    })?;
    m.noise.tx_power_dbm = cfg.tx_power_dbm;
    Ok(c)
}

/// The configurations of the grid (N, then pulses, step, bandwidth, power), the campaign's
/// band and power where the lists are empty; the paper's setting appended when absent.
fn grid(base: &Campaign, p: &ExploreValid) -> (Vec<Config>, Config) {
    let m = &base.manifest;
    let b0 = m.band.bandwidth_hz() / 1e9;
    let bws = if p.bandwidth_ghz.is_empty() {
        vec![b0]
    } else {
        p.bandwidth_ghz.clone()
    };
    let txs = if p.tx_power_dbm.is_empty() {
        vec![m.noise.tx_power_dbm]
    } else {
        p.tx_power_dbm.clone()
    };
    let mut configs = Vec::new();
    for &elements in &p.elements {
        for &pulses in &p.pulses {
            for &step_deg in &p.step_deg {
                for &bandwidth_ghz in &bws {
                    for &tx_power_dbm in &txs {
                        configs.push(Config {
                            elements,
                            pulses,
                            step_deg,
                            bandwidth_ghz,
                            tx_power_dbm,
                        });
                    }
                }
            }
        }
    }
    let paper = Config {
        elements: PAPER_ELEMENTS,
        pulses: PAPER_PULSES,
        step_deg: PAPER_STEP_DEG,
        bandwidth_ghz: b0,
        tx_power_dbm: m.noise.tx_power_dbm,
    };
    if !configs.contains(&paper) {
        configs.push(paper);
    }
    (configs, paper)
}

/// The data every job draws from.
enum Source {
    Sweeps,
    Model(Box<ModelConfig>),
}

/// Inputs of [`explore`].
#[derive(Debug, Clone)]
pub struct ExploreInputs {
    /// Campaign manifest (needs a `[scene]` for physics sweeps).
    pub campaign: PathBuf,
    /// Physics sweeps or a model file.
    pub data: DataKind,
    /// Keep every job's data and maps in `out/work/` (else removed after the job).
    pub keep_work: bool,
}

/// Run the grid: the jobs (each configuration at each seed), rows and timings in grid
/// order. Refused before the grid runs (after the probe job) when the estimate is above
/// `params.max_minutes`.
pub fn run_grid(
    inputs: &ExploreInputs,
    params: &ExploreValid,
    model: &EnergyModelValid,
    out: &Path,
    progress: Progress,
) -> Result<ExploreOutput> {
    let base = Campaign::load(&inputs.campaign)?;
    let (source, data) = source_of(inputs, &base)?;
    let (configs, paper) = grid(&base, params);
    let jobs = jobs_of(&base, &configs, params)?;
    let work_dir = out.join("work");
    let nm = params.mappers.len();
    let (probe, probe_done, probe_s) =
        run_probe(&base, &source, &jobs, params, &work_dir, inputs.keep_work)?;
    let total_work: f64 = jobs.iter().map(|j| j.work(nm)).sum();
    let threads = rayon::current_num_threads().max(1) as f64;
    let estimate_minutes = probe_s * total_work / jobs[probe].work(nm) / threads / 60.0;
    if estimate_minutes > params.max_minutes {
        return Err(Error::param(
            "--max-minutes",
            format!(
                "the grid ({} configurations × {} seeds × {} mapper(s)) is estimated at {estimate_minutes:.1} min on {threads} thread(s) (the cheapest job took {probe_s:.1} s), above --max-minutes {}; shrink the grid or raise --max-minutes",
                configs.len(),
                params.seeds.len(),
                nm,
                params.max_minutes
            ),
        ));
    }
    let grid_run = GridRun {
        base: &base,
        source: &source,
        jobs: &jobs,
        params,
        work_dir: &work_dir,
        keep: inputs.keep_work,
    };
    let by_job = grid_run.run_rest(probe, probe_done, threads, progress)?;
    let rows = rows_of(&configs, &jobs, &by_job, params, model);
    let mut timings = Vec::new();
    for r in by_job.into_iter().flatten() {
        timings.push(r.timing);
    }
    let m = &base.manifest;
    Ok(ExploreOutput {
        campaign: inputs.campaign.clone(),
        data,
        configs,
        paper,
        rows,
        timings,
        estimate_minutes,
        slice: (
            if params.step_deg.contains(&PAPER_STEP_DEG) {
                PAPER_STEP_DEG
            } else {
                params.step_deg[0]
            },
            paper.bandwidth_ghz,
            if params.tx_power_dbm.is_empty() {
                m.noise.tx_power_dbm
            } else {
                params.tx_power_dbm[0]
            },
        ),
    })
}

/// Takes the inputs and their campaign; gives the data every job draws from and how the
/// page names it (physics sweeps need the campaign's `[scene]`; a model must be
/// estimable).
fn source_of(inputs: &ExploreInputs, base: &Campaign) -> Result<(Source, String)> {
    Ok(match &inputs.data {
        DataKind::Sweeps => {
            if !has_scene(base)? {
                return Err(Error::input(
                    &inputs.campaign,
                    "physics sweeps need a [scene] section (or use --data model --model M)",
                ));
            }
            (Source::Sweeps, "physics sweeps".to_string())
        }
        DataKind::Model(m) => {
            let mc = ModelConfig::load(m)?
                .require_estimable(&Default::default())
                .map_err(|e| Error::input(m, e.to_string()))?;
            (
                Source::Model(Box::new(mc)),
                format!("synth of {}", m.display()),
            )
        }
    })
}

/// Takes the campaign, the grid's configurations and the parameters; gives the jobs,
/// each configuration at each seed (in that order), with its scan's directions and
/// samples.
fn jobs_of(base: &Campaign, configs: &[Config], params: &ExploreValid) -> Result<Vec<Job>> {
    let mut jobs = Vec::new();
    for cfg in configs {
        let c = configured(base, cfg, 0)?;
        for &seed in &params.seeds {
            jobs.push(Job {
                config: *cfg,
                seed,
                directions: c.manifest.directions.count(),
                samples: c.manifest.band.points,
            });
        }
    }
    Ok(jobs)
}

/// The probe: takes what the jobs need; gives the cheapest job's index, its result and
/// its time (s), run first on one thread, so its time is one core's whatever the stages'
/// own parallelism.
fn run_probe(
    base: &Campaign,
    source: &Source,
    jobs: &[Job],
    params: &ExploreValid,
    work_dir: &Path,
    keep: bool,
) -> Result<(usize, JobResult, f64)> {
    let nm = params.mappers.len();
    // the probe: the cheapest job, run and timed first
    let probe = (0..jobs.len())
        .min_by(|&a, &b| jobs[a].work(nm).total_cmp(&jobs[b].work(nm)))
        .expect("at least one job");
    // on one thread, so its time is one core's whatever the stages' own parallelism
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| Error::param("threads", e.to_string()))?;
    let t = Instant::now();
    let probe_done = one.install(|| run_job(base, source, &jobs[probe], params, work_dir, keep))?;
    let probe_s = t.elapsed().as_secs_f64();
    Ok((probe, probe_done, probe_s))
}

/// What every job of the grid shares: the campaign, the data, the jobs, the parameters
/// and the work folder.
struct GridRun<'a> {
    /// The campaign as given.
    base: &'a Campaign,
    /// The data every job draws from.
    source: &'a Source,
    /// The jobs in grid order.
    jobs: &'a [Job],
    /// The grid's parameters.
    params: &'a ExploreValid,
    /// `out/work`.
    work_dir: &'a Path,
    /// Keep every job's data and maps.
    keep: bool,
}

impl GridRun<'_> {
    /// Takes the probe's index and result, the worker count and the progress bars; gives
    /// every job's result in job order, the rest run largest first on `threads` workers
    /// each with a one-thread pool (the first error in job order stops the grid).
    fn run_rest(
        &self,
        probe: usize,
        probe_done: JobResult,
        threads: f64,
        progress: Progress,
    ) -> Result<Vec<Option<JobResult>>> {
        let nm = self.params.mappers.len();
        let params = self.params;
        let keep = self.keep;
        // the rest, largest first, on `threads` workers each with a one-thread pool: a job's
        // stages run on its worker only, so at most `threads` jobs are in memory at once (on
        // one shared pool a waiting thread would steal and start further jobs)
        let jobs = self.jobs;
        let mut order: Vec<usize> = (0..jobs.len()).filter(|&i| i != probe).collect();
        order.sort_by(|&a, &b| {
            jobs[b]
                .work(nm)
                .total_cmp(&jobs[a].work(nm))
                .then(a.cmp(&b))
        });
        let cb = progress("explore", jobs.len());
        cb(1, jobs.len());
        let next = std::sync::atomic::AtomicUsize::new(0);
        let (tx, rx) = std::sync::mpsc::channel::<(usize, Result<JobResult>)>();
        let mut by_job: Vec<Option<JobResult>> = vec![None; jobs.len()];
        by_job[probe] = Some(probe_done);
        let mut first_error = None;
        std::thread::scope(|s| {
            let (order, base, source, next) = (&order, self.base, self.source, &next);
            for _ in 0..threads as usize {
                let tx = tx.clone();
                let work_dir = self.work_dir;
                s.spawn(move || {
                    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() else {
                        return;
                    };
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&i) = order.get(k) else { break };
                        let r = pool
                            .install(|| run_job(base, source, &jobs[i], params, work_dir, keep));
                        let failed = r.is_err();
                        if tx.send((i, r)).is_err() || failed {
                            // stop taking jobs after an error
                            next.store(order.len(), std::sync::atomic::Ordering::Relaxed);
                            break;
                        }
                    }
                });
            }
            drop(tx);
            let mut done = 1;
            for (i, r) in rx {
                match r {
                    Ok(r) => by_job[i] = Some(r),
                    Err(e) => {
                        // the first error in job order among those that failed
                        if first_error.as_ref().is_none_or(|(j, _)| i < *j) {
                            first_error = Some((i, e));
                        }
                    }
                }
                done += 1;
                cb(done, jobs.len());
            }
        });
        if let Some((_, e)) = first_error {
            return Err(e);
        }
        if by_job.iter().any(|r| r.is_none()) {
            return Err(Error::param(
                "threads",
                "a worker could not start its thread pool",
            ));
        }
        Ok(by_job)
    }
}

/// Takes the configurations, the jobs, every job's result (all present), the parameters
/// and the energy model; gives the rows in (configuration, mapper, seed) order, each
/// with its scan's cost.
fn rows_of(
    configs: &[Config],
    jobs: &[Job],
    by_job: &[Option<JobResult>],
    params: &ExploreValid,
    model: &EnergyModelValid,
) -> Vec<ExploreRow> {
    let nm = params.mappers.len();
    let mut rows = Vec::new();
    // rows in (configuration, mapper, seed) order
    let per_cfg = params.seeds.len();
    for (ci, _) in configs.iter().enumerate() {
        let chunk = &by_job[ci * per_cfg..(ci + 1) * per_cfg];
        for mi in 0..nm {
            for (si, r) in chunk.iter().enumerate() {
                let r = r.as_ref().expect("every job ran");
                let j = &jobs[ci * per_cfg + si];
                rows.push(ExploreRow {
                    config: j.config,
                    mapper: params.mappers[mi].name(),
                    seed: j.seed,
                    directions: j.directions,
                    samples: j.samples,
                    cost: model.scan(&ScanShape {
                        elements: j.config.elements,
                        directions: j.directions,
                        pulses: j.config.pulses,
                        samples: j.samples,
                        tx_power_dbm: j.config.tx_power_dbm,
                    }),
                    scores: r.scores[mi],
                });
            }
        }
    }
    rows
}

/// What one job gives: the scores per mapper (in `params.mappers` order) and its timing.
#[derive(Debug, Clone)]
struct JobResult {
    scores: Vec<Scores>,
    timing: Timing,
}

/// Make one job's data, map it with every mapper, score the maps.
fn run_job(
    base: &Campaign,
    source: &Source,
    job: &Job,
    params: &ExploreValid,
    work: &Path,
    keep: bool,
) -> Result<JobResult> {
    let c = configured(base, &job.config, job.seed)?;
    let dir = work.join(format!("{}_seed{}", job.config.key(), job.seed));
    let t0 = Instant::now();
    let (manifest, energy_path, data_s, energy_s) = match source {
        Source::Sweeps => {
            let sim = simulate(&c, &dir.join("sim"), SweepFormat::Parquet, &|_, _| {})?;
            let data_s = t0.elapsed().as_secs_f64();
            let sc = Campaign::load(&sim.manifest)?;
            let e = dir.join("energy.parquet");
            let t1 = Instant::now();
            crate::energy::run(&sc, &e, &|_, _| {})?;
            // the sweeps are read once: drop them now
            let _ = std::fs::remove_file(dir.join("sim").join("sweeps.parquet"));
            let _ = std::fs::remove_file(dir.join("sim").join("truth").join("rays.parquet"));
            (sim.manifest, e, data_s, t1.elapsed().as_secs_f64())
        }
        Source::Model(model) => {
            let e = dir.join("synth.parquet");
            let sp = SynthParams::default().seed(job.seed).check()?;
            synth(&c, model, &e, &sp, &|_, _| {})?;
            let manifest = write_campaign(&c, &dir.join("campaign"))?;
            (manifest, e, t0.elapsed().as_secs_f64(), 0.0)
        }
    };
    let mut scores = Vec::new();
    let mut map_s = Vec::new();
    for &method in &params.mappers {
        let opts = MapOptions {
            method,
            runs: vec![MapRun {
                campaign: manifest.clone(),
                energy: energy_path.clone(),
            }],
            out: dir.join(method.name()),
            elements: None,
            grid: params.grid,
            og: params.og,
            ekf: params.ekf,
            pose_noise: PoseNoise::default(),
            poses_from: Default::default(),
            odometry: Default::default(),
        }
        .check()?;
        let t = Instant::now();
        let r = run_map(&opts, &|_, _| {})?;
        map_s.push((method.name(), t.elapsed().as_secs_f64()));
        let tc = r.metrics.three_class.ok_or_else(|| {
            Error::input(
                &manifest,
                "the run has no truth to score against (three-class reference)",
            )
        })?;
        scores.push(Scores::of(&tc.building, &tc.building_all_free, &tc.whole));
    }
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(JobResult {
        scores,
        timing: Timing {
            config: job.config,
            seed: job.seed,
            scans: c.manifest.positions(),
            data_s,
            energy_s,
            map_s,
        },
    })
}
