//! The paper's mapping experiments (DESIGN §2 "Experiments" 2–5): `pradar experiment NAME
//! --out DIR`.
//!
//! Takes a campaign (the built-in corridor unless `--campaign`), the energy table of its
//! sweeps (simulated by `simulate` → `energy` unless given) and a model file (`--model`; by
//! default the chain CLEAN → K-means → fit is run on that energy table and its
//! `fitted_model.toml` used — never the simulator's `[clutter]` truth). Gives, per experiment
//! `NAME` in `DIR/NAME/`: `NAME.md` and `NAME.csv` (the table), `NAME.json` (every case with
//! all its figures), `NAME.png` (the maps in one panel) and, where a figure is a curve,
//! `NAME_plot.png`; every map it made in `DIR/maps/<case>/` (the `pradar map` files: PNG,
//! PGM and YAML, metrics.json); model data in `DIR/work/synth/`; and `DIR/index.html` linking
//! the experiments run.
//!
//! Choices (where DESIGN and the issue are silent):
//! * **model data** = `synth` with the model file on the campaign's layout and trajectory,
//!   the campaign's array type (the corridor's is the 1-bit transmitarray) at N elements;
//!   seeds 1, 2, 3 (`--seeds`): a seed draws a new channel (clusters, rays, shadowing) and new
//!   detector noise;
//! * **mappers**: the side-lobe-aware occupancy grid `og` (prior 0.5, P_fa 1e-3, binary
//!   p > 0.5) and the scalable EKF (μ0 0.01 m, σ0 0.1 m, binary x̂ − 2σ̂ > μ0), 0.1 m cells —
//!   `pradar map`'s defaults, not tuned on the reference;
//! * **figures** per map: ψ, F1 and the wrong-cell count on three regions, each the same
//!   for every N, mapper, prior and pose noise of a campaign except (b): (a) the *whole map*
//!   (every cell of the grid, cells outside the perimeter counted as free), (b) the
//!   *observable region* of that run (cells in some −3 dB main lobe; it widens with the beam,
//!   so N = 16 is scored on slightly more cells than N = 100) and (c) the *interior*: the
//!   reference's known cells (inside the perimeter; its PGM marks the outside unknown), where
//!   wrong cells are what an indoor map gets wrong. Each beside the all-free map's;
//! * **fig6 statement**: the paper's "N = 16 has more wrong cells than N = 100" is checked per
//!   mapper and seed on the interior and on the whole map, and on the campaign's sweeps
//!   simulated at both N when the campaign has a `[scene]`;
//! * **fig5**: EKF maps at the campaign's array (400-element 1-bit for the corridor) from the
//!   simulated sweeps and from model data (every seed), side by side with the reference;
//! * **fig6**: OG and EKF on model data at N = 16 and N = 100, every seed (and on the
//!   sweeps simulated at both N);
//! * **prior-sensitivity**: at N = 16 on model data, the OG prior p0 and the EKF μ0 each
//!   scaled by 1 ± 0.4 (p0 0.3 / 0.5 / 0.7, μ0 0.006 / 0.01 / 0.014 m) with everything else
//!   fixed (the binary rules stay p > 0.5 and x̂ − 2σ̂ > μ0, so μ0 moves the EKF's threshold as
//!   it moves its prior); relative change Δψ/ψ = (ψ̄(changed) − ψ̄(base))/ψ̄(base) of the mean ψ
//!   over seeds;
//! * **pose-noise**: at N = 100 on model data, the mapper is given poses with Gaussian noise
//!   ([`PoseNoise`]: σ per axis 0, 2, 5, 10 cm with no heading noise, and heading σ 0, 1, 2, 5°
//!   with no position noise; one draw per pose, keyed by the data seed) while the data were
//!   taken at the true poses; mean ψ over seeds.
//!
//! Maps shared between experiments (the base cases) are computed once per process.

use super::{analyse, write_builtin_corridor, Progress};
use crate::campaign::layout::{CellClass, Layout, ReferenceMap};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::campaign::modelfile::ModelConfig;
use crate::campaign::simulate::simulate;
use crate::energy::{self, EnergyMatrix};
use crate::error::{Error, Result};
use crate::mapping::job::{run_map, MapOptions, MapReport, MapRun, PoseNoise};
use crate::mapping::{EkfParams, GridParams, Method, OgParams};
use crate::model::{synth, SynthParams};
use crate::params::ParamGuard;
use crate::report::{self, html_escape, LineChart, MapTile, Section};
use serde::Serialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The experiments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Experiment {
    /// EKF maps from simulated sweeps and from model data.
    Fig5,
    /// OG vs EKF for N = 16 and N = 100 on model data.
    Fig6,
    /// OG prior and EKF μ0 changed by ±40 %.
    PriorSensitivity,
    /// ψ as pose noise grows.
    PoseNoise,
}

impl Experiment {
    /// Every experiment, in report order.
    pub const ALL: [Experiment; 4] = [
        Experiment::Fig5,
        Experiment::Fig6,
        Experiment::PriorSensitivity,
        Experiment::PoseNoise,
    ];
    /// Command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Experiment::Fig5 => "fig5",
            Experiment::Fig6 => "fig6",
            Experiment::PriorSensitivity => "prior-sensitivity",
            Experiment::PoseNoise => "pose-noise",
        }
    }
    /// Parse a command-line name (`all` is handled by the caller).
    pub fn parse(s: &str) -> Result<Experiment> {
        Experiment::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| {
                Error::param(
                    "experiment",
                    format!(
                        "unknown experiment `{s}` (fig5|fig6|prior-sensitivity|pose-noise|all)"
                    ),
                )
            })
    }
}

/// Parameters of the experiments (defaults: the issue's; builder setters, [`Self::check`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentParams {
    /// Model-data seeds (1, 2, 3).
    pub seeds: Vec<u64>,
    /// Array sizes compared by fig6 (16, 100).
    pub compare_elements: Vec<usize>,
    /// Array size of prior-sensitivity (16).
    pub sensitivity_elements: usize,
    /// Relative change of the priors (0.4).
    pub prior_change: f64,
    /// Array size of pose-noise (100).
    pub pose_elements: usize,
    /// Position noise levels, m per axis (0, 0.02, 0.05, 0.1).
    pub position_noise_m: Vec<f64>,
    /// Heading noise levels, degrees (0, 1, 2, 5).
    pub heading_noise_deg: Vec<f64>,
    /// Grid parameters of every map.
    pub grid: GridParams,
    /// Base occupancy-grid parameters.
    pub og: OgParams,
    /// Base EKF parameters.
    pub ekf: EkfParams,
}

impl Default for ExperimentParams {
    fn default() -> Self {
        ExperimentParams {
            seeds: vec![1, 2, 3],
            compare_elements: vec![16, 100],
            sensitivity_elements: 16,
            prior_change: 0.4,
            pose_elements: 100,
            position_noise_m: vec![0.0, 0.02, 0.05, 0.10],
            heading_noise_deg: vec![0.0, 1.0, 2.0, 5.0],
            grid: GridParams::default(),
            og: OgParams::default(),
            ekf: EkfParams::default(),
        }
    }
}

impl ExperimentParams {
    /// Set the model-data seeds.
    pub fn seeds(mut self, seeds: Vec<u64>) -> Self {
        self.seeds = seeds;
        self
    }
    /// Validate.
    pub fn check(&self) -> Result<()> {
        if self.seeds.is_empty() {
            return Err(Error::param("seeds", "give at least one seed"));
        }
        let mut s = self.seeds.clone();
        s.sort_unstable();
        s.dedup();
        if s.len() != self.seeds.len() {
            return Err(Error::param("seeds", "seeds must be distinct"));
        }
        if self.compare_elements.len() < 2 {
            return Err(Error::param("compare_elements", "give two array sizes"));
        }
        if !(self.prior_change.is_finite() && self.prior_change > 0.0 && self.prior_change < 1.0) {
            return Err(Error::param("prior_change", "must be in (0, 1)"));
        }
        for (name, v) in [
            ("position_noise_m", &self.position_noise_m),
            ("heading_noise_deg", &self.heading_noise_deg),
        ] {
            if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(Error::param(name, "levels must be finite and >= 0"));
            }
        }
        self.grid.check()?;
        self.og.check()?;
        self.ekf.check()?;
        for f in [1.0 - self.prior_change, 1.0 + self.prior_change] {
            OgParams {
                prior: self.og.prior * f,
                ..self.og
            }
            .check()?;
        }
        Ok(())
    }
}

/// Where the experiments' inputs come from (all optional).
#[derive(Debug, Clone, Default)]
pub struct InputOptions {
    /// Campaign manifest (default: the built-in corridor).
    pub campaign: Option<PathBuf>,
    /// Energy table of its sweeps (default: computed from its `[sweeps]`, or simulated).
    pub energy: Option<PathBuf>,
    /// Model file (default: fitted from that energy table).
    pub model: Option<PathBuf>,
}

/// The experiments' inputs, resolved.
#[derive(Debug, Clone)]
pub struct ExperimentInputs {
    /// Campaign manifest of the energy table (layout, trajectory, array).
    pub campaign: PathBuf,
    /// Energy table of its (simulated or measured) sweeps.
    pub energy: PathBuf,
    /// Model file used for model data.
    pub model: PathBuf,
}

/// Resolve the inputs into `work`: write the built-in corridor, simulate it (Parquet sweeps)
/// when the campaign has no `[sweeps]`, compute its energy table, fit a model.
pub fn prepare_inputs(
    opts: &InputOptions,
    work: &Path,
    progress: Progress,
) -> Result<ExperimentInputs> {
    std::fs::create_dir_all(work).map_err(|e| Error::io(work, e))?;
    let src = match &opts.campaign {
        Some(p) => p.clone(),
        None => write_builtin_corridor(&work.join("input"))?,
    };
    let c = Campaign::load(&src)?;
    let np = c.manifest.positions();
    let (campaign, energy) = match (&opts.energy, &c.manifest.sweeps) {
        (Some(e), _) => (src.clone(), e.clone()),
        (None, Some(_)) => {
            let e = work.join("energy.parquet");
            energy::run(&c, &e, &*progress("energy", np))?;
            (src.clone(), e)
        }
        (None, None) => {
            let sim = simulate(
                &c,
                &work.join("simulated"),
                SweepFormat::Parquet,
                &*progress("simulate", np),
            )?;
            let sc = Campaign::load(&sim.manifest)?;
            let e = work.join("energy.parquet");
            energy::run(&sc, &e, &*progress("energy", np))?;
            (sim.manifest, e)
        }
    };
    let model = match &opts.model {
        Some(m) => {
            ModelConfig::load(m)?;
            m.clone()
        }
        None => {
            let sc = Campaign::load(&campaign)?;
            let em = EnergyMatrix::read(&energy)?;
            let dir = work.join("analysis");
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
            let fit = analyse(&sc, &em, &dir, false)?.fit?;
            let m = work.join("fitted_model.toml");
            fit.model.save(&m)?;
            m
        }
    };
    Ok(ExperimentInputs {
        campaign,
        energy,
        model,
    })
}

/// Where a map's data come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum DataSource {
    /// The campaign's sweeps (simulated or measured).
    Sweeps,
    /// `synth` with the model file, this seed.
    Model(u64),
}

/// One map of an experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Case {
    /// Data.
    pub source: DataSource,
    /// Array elements.
    pub elements: usize,
    /// Mapper (`og` or `ekf`).
    pub method: &'static str,
    /// OG prior p0.
    pub og_prior: f64,
    /// EKF prior mean μ0, m.
    pub mu0: f64,
    /// Pose noise given to the mapper.
    pub pose_noise: PoseNoise,
}

impl Case {
    /// Folder name under `maps/`: data, N, mapper, and whatever differs from the base.
    pub fn key(&self, base: &ExperimentParams) -> String {
        let mut k = match self.source {
            DataSource::Sweeps => format!("sweeps_n{}_{}", self.elements, self.method),
            DataSource::Model(s) => format!("model_s{s}_n{}_{}", self.elements, self.method),
        };
        if self.method == "og" && self.og_prior != base.og.prior {
            k.push_str(&format!("_prior{:.3}", self.og_prior));
        }
        if self.method == "ekf" && self.mu0 != base.ekf.mu0 {
            k.push_str(&format!("_mu{:.4}", self.mu0));
        }
        if self.pose_noise.position_m > 0.0 {
            k.push_str(&format!("_pos{:.0}mm", self.pose_noise.position_m * 1000.0));
        }
        if self.pose_noise.heading_deg > 0.0 {
            k.push_str(&format!("_hdg{:.1}deg", self.pose_noise.heading_deg));
        }
        k
    }
}

/// Figures of one map (see the module docs for the two regions).
#[derive(Debug, Clone, Serialize)]
pub struct CaseFigures {
    /// Folder under `maps/`.
    pub key: String,
    /// The case.
    pub case: Case,
    /// ψ on the whole map, cells.
    pub psi_whole: f64,
    /// ψ on the observable region, cells.
    pub psi_observable: f64,
    /// Occupied F1 on the whole map.
    pub f1_whole: f64,
    /// Occupied F1 on the observable region.
    pub f1_observable: f64,
    /// Wrong cells on the whole map.
    pub wrong_whole: usize,
    /// Wrong cells on the observable region.
    pub wrong_observable: usize,
    /// Cells of the observable region.
    pub observable_cells: usize,
    /// Occupied cells of the map (whole).
    pub map_occupied: usize,
    /// ψ of the all-free map, whole.
    pub all_free_psi_whole: f64,
    /// ψ of the all-free map, observable region.
    pub all_free_psi_observable: f64,
    /// Wrong cells of the all-free map, whole.
    pub all_free_wrong_whole: usize,
    /// ψ on the interior (the reference's known cells: inside the perimeter).
    pub psi_interior: f64,
    /// Wrong cells on the interior.
    pub wrong_interior: usize,
    /// Occupied F1 on the interior.
    pub f1_interior: f64,
    /// Cells of the interior.
    pub interior_cells: usize,
}

fn count(rate: f64, cells: usize) -> usize {
    (rate * cells as f64).round() as usize
}

impl CaseFigures {
    fn new(key: String, case: Case, r: &MapReport, reference: &ReferenceMap) -> CaseFigures {
        let m = &r.metrics;
        let s = reference.spec;
        let refo: Vec<bool> = reference
            .cells
            .iter()
            .map(|c| *c == CellClass::Occupied)
            .collect();
        let interior: Vec<bool> = reference
            .cells
            .iter()
            .map(|c| *c != CellClass::Outside)
            .collect();
        let i = crate::mapping::metrics::evaluate(&r.binary, &refo, &interior, s.rows, s.cols);
        CaseFigures {
            psi_interior: i.psi,
            wrong_interior: count(i.wrong_cell_rate, i.cells),
            f1_interior: i.f1,
            interior_cells: i.cells,
            key,
            case,
            psi_whole: m.whole.psi,
            psi_observable: m.observable.psi,
            f1_whole: m.whole.f1,
            f1_observable: m.observable.f1,
            wrong_whole: count(m.whole.wrong_cell_rate, m.whole.cells),
            wrong_observable: count(m.observable.wrong_cell_rate, m.observable.cells),
            observable_cells: m.observable.cells,
            map_occupied: m.whole.map_occupied,
            all_free_psi_whole: m.whole_all_free.psi,
            all_free_psi_observable: m.observable_all_free.psi,
            all_free_wrong_whole: count(m.whole_all_free.wrong_cell_rate, m.whole_all_free.cells),
        }
    }
}

/// What one experiment measured and wrote.
#[derive(Debug, Clone, Serialize)]
pub struct ExperimentResult {
    /// Experiment name.
    pub name: String,
    /// Every map, with its figures.
    pub cases: Vec<CaseFigures>,
    /// Derived statements (e.g. fig6's N = 16 vs N = 100 check, relative ψ changes).
    pub findings: Vec<(String, String)>,
    /// Report section (links relative to the experiments folder's parent, see
    /// [`Lab::section`]).
    #[serde(skip)]
    pub html: String,
}

/// Runs experiments, sharing model data and maps between them.
pub struct Lab<'a> {
    inputs: ExperimentInputs,
    params: ExperimentParams,
    out: PathBuf,
    model: ModelConfig,
    campaign_elements: usize,
    reference: ReferenceMap,
    synth_cache: HashMap<(usize, u64), PathBuf>,
    sweeps_cache: HashMap<usize, (PathBuf, PathBuf)>,
    map_cache: HashMap<String, MapReport>,
    progress: Progress<'a>,
}

impl<'a> Lab<'a> {
    /// A lab writing into `out` (maps in `out/maps`, model data in `out/work/synth`).
    pub fn new(
        inputs: ExperimentInputs,
        params: ExperimentParams,
        out: &Path,
        progress: Progress<'a>,
    ) -> Result<Lab<'a>> {
        params.check()?;
        let model = ModelConfig::load(&inputs.model)?;
        let c = Campaign::load(&inputs.campaign)?;
        let layout = Layout::load(&c.layout_path())?;
        let reference = layout.rasterize(params.grid.cell_m, params.grid.margin_m);
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
        Ok(Lab {
            campaign_elements: c.manifest.array.elements,
            inputs,
            params,
            out: out.to_path_buf(),
            model,
            reference,
            synth_cache: HashMap::new(),
            sweeps_cache: HashMap::new(),
            map_cache: HashMap::new(),
            progress,
        })
    }

    /// The inputs in use.
    pub fn inputs(&self) -> &ExperimentInputs {
        &self.inputs
    }

    fn base_case(&self, source: DataSource, elements: usize, method: &'static str) -> Case {
        Case {
            source,
            elements,
            method,
            og_prior: self.params.og.prior,
            mu0: self.params.ekf.mu0,
            pose_noise: PoseNoise::default(),
        }
    }

    /// Model data at N elements and this seed (synth once per process).
    fn model_data(&mut self, elements: usize, seed: u64) -> Result<PathBuf> {
        if let Some(p) = self.synth_cache.get(&(elements, seed)) {
            return Ok(p.clone());
        }
        let dir = self.out.join("work").join("synth");
        let path = dir.join(format!("n{elements}_s{seed}.parquet"));
        let mut c = Campaign::load(&self.inputs.campaign)?;
        c.set_elements(elements)?;
        let sp = SynthParams::default()
            .seed(seed)
            .truth_dir(dir.join(format!("n{elements}_s{seed}_truth")));
        synth(&c, &self.model, &path, &sp, &|_, _| {})?;
        self.synth_cache.insert((elements, seed), path.clone());
        Ok(path)
    }

    /// Sweeps at N elements: the campaign's own, or the campaign simulated again at N (it
    /// needs a `[scene]`), once per process. Returns (manifest, energy table).
    fn sweeps_data(&mut self, elements: usize) -> Result<(PathBuf, PathBuf)> {
        if elements == self.campaign_elements {
            return Ok((self.inputs.campaign.clone(), self.inputs.energy.clone()));
        }
        if let Some(p) = self.sweeps_cache.get(&elements) {
            return Ok(p.clone());
        }
        let mut c = Campaign::load(&self.inputs.campaign)?;
        c.set_elements(elements)?;
        let dir = self.out.join("work").join(format!("sweeps_n{elements}"));
        let sim = simulate(&c, &dir, SweepFormat::Parquet, &|_, _| {})?;
        let sc = Campaign::load(&sim.manifest)?;
        let e = dir.join("energy.parquet");
        energy::run(&sc, &e, &|_, _| {})?;
        let r = (sim.manifest, e);
        self.sweeps_cache.insert(elements, r.clone());
        Ok(r)
    }

    /// Map one case (once per process) and return its report.
    fn map(&mut self, case: &Case) -> Result<(String, MapReport)> {
        let key = case.key(&self.params);
        if let Some(r) = self.map_cache.get(&key) {
            return Ok((key, r.clone()));
        }
        let (campaign, energy, elements) = match case.source {
            DataSource::Sweeps => {
                let (c, e) = self.sweeps_data(case.elements)?;
                (c, e, None)
            }
            DataSource::Model(s) => (
                self.inputs.campaign.clone(),
                self.model_data(case.elements, s)?,
                Some(case.elements),
            ),
        };
        let method = Method::parse(case.method)?;
        let opts = MapOptions {
            method,
            runs: vec![MapRun { campaign, energy }],
            out: self.out.join("maps").join(&key),
            elements,
            grid: self.params.grid,
            og: OgParams {
                prior: case.og_prior,
                ..self.params.og
            },
            ekf: EkfParams {
                mu0: case.mu0,
                ..self.params.ekf
            },
            pose_noise: case.pose_noise,
        };
        let r = run_map(&opts.check()?, &|_, _| {})?;
        self.map_cache.insert(key.clone(), r.clone());
        Ok((key, r))
    }

    /// Map every case with a progress bar labelled `label`.
    fn map_all(&mut self, label: &str, cases: &[Case]) -> Result<Vec<(CaseFigures, Vec<bool>)>> {
        let cb = (self.progress)(label, cases.len());
        let mut out = Vec::new();
        for (i, c) in cases.iter().enumerate() {
            let (key, r) = self.map(c)?;
            out.push((
                CaseFigures::new(key, *c, &r, &self.reference),
                r.binary.clone(),
            ));
            cb(i + 1, cases.len());
        }
        Ok(out)
    }

    fn tile(&self, title: String, binary: &[bool]) -> MapTile {
        MapTile {
            title,
            cells: binary
                .iter()
                .zip(&self.reference.cells)
                .map(|(&b, &r)| report::scored_colour(b, r))
                .collect(),
        }
    }

    fn reference_tile(&self) -> MapTile {
        let occupied = self
            .reference
            .cells
            .iter()
            .map(|c| *c == CellClass::Occupied);
        let b: Vec<bool> = occupied.collect();
        self.tile("reference".into(), &b)
    }

    fn panel(&self, name: &str, tiles: &[MapTile], columns: usize) -> Result<()> {
        let s = self.reference.spec;
        report::map_panel(
            &self.out.join(name).join(format!("{name}.png")),
            s.rows,
            s.cols,
            tiles,
            columns,
        )
    }

    /// Run one experiment: map its cases, write its files, return its figures.
    pub fn run(&mut self, e: Experiment) -> Result<ExperimentResult> {
        let dir = self.out.join(e.name());
        std::fs::create_dir_all(&dir).map_err(|err| Error::io(&dir, err))?;
        let r = match e {
            Experiment::Fig5 => self.fig5()?,
            Experiment::Fig6 => self.fig6()?,
            Experiment::PriorSensitivity => self.prior_sensitivity()?,
            Experiment::PoseNoise => self.pose_noise()?,
        };
        let name = e.name();
        let (md, csv) = case_tables(&r.cases, &r.findings);
        crate::io::write_bytes(&dir.join(format!("{name}.md")), md.as_bytes())?;
        crate::io::write_bytes(&dir.join(format!("{name}.csv")), csv.as_bytes())?;
        let json = serde_json::to_string_pretty(&r)
            .map_err(|err| Error::param("experiment", err.to_string()))?;
        crate::io::write_bytes(&dir.join(format!("{name}.json")), json.as_bytes())?;
        Ok(r)
    }

    fn seeds(&self) -> Vec<u64> {
        self.params.seeds.clone()
    }

    fn fig5(&mut self) -> Result<ExperimentResult> {
        let n = self.campaign_elements;
        let mut cases = vec![self.base_case(DataSource::Sweeps, n, "ekf")];
        for s in self.seeds() {
            cases.push(self.base_case(DataSource::Model(s), n, "ekf"));
        }
        let done = self.map_all("fig5", &cases)?;
        let tiles = vec![
            self.reference_tile(),
            self.tile(
                format!("EKF, simulated sweeps: ψ {:.2}", done[0].0.psi_whole),
                &done[0].1,
            ),
            self.tile(
                format!(
                    "EKF, model data (seed {}): ψ {:.2}",
                    self.params.seeds[0], done[1].0.psi_whole
                ),
                &done[1].1,
            ),
        ];
        self.panel("fig5", &tiles, 3)?;
        let model_psi: Vec<f64> = done[1..].iter().map(|d| d.0.psi_whole).collect();
        let findings = vec![
            (
                "ψ whole, simulated sweeps".to_string(),
                format!("{:.3}", done[0].0.psi_whole),
            ),
            (
                "ψ whole, model data (mean over seeds)".to_string(),
                format!("{:.3} ({})", mean(&model_psi), join(&model_psi, 3)),
            ),
            (
                "ψ whole, all-free map".to_string(),
                format!("{:.3}", done[0].0.all_free_psi_whole),
            ),
        ];
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let mut extra = String::new();
        for c in cases.iter().take(2) {
            extra.push_str(&format!(
                "<figure><img src=\"{{P}}maps/{k}/ekf_mean.png\" alt=\"{k}\"><figcaption>mean RRCS, {k}</figcaption></figure>\n",
                k = c.key
            ));
        }
        Ok(self.result(
            "fig5",
            &format!("EKF maps ({n} elements, the campaign's array) from the simulated sweeps and from model data (synth with the model file), 0.1 m cells. Colours: black occupied in both, red false occupied, blue missed occupied, white free, grey outside (free in the map)."),
            cases,
            findings,
            &extra,
        ))
    }

    fn fig6(&mut self) -> Result<ExperimentResult> {
        let sizes = self.params.compare_elements.clone();
        let mut cases = Vec::new();
        for &n in &sizes {
            for s in self.seeds() {
                for m in ["og", "ekf"] {
                    cases.push(self.base_case(DataSource::Model(s), n, m));
                }
            }
        }
        // the same comparison on (simulated) sweeps, when the campaign can be simulated
        let mut sweeps_note = None;
        for &n in &sizes {
            if let Err(e) = self.sweeps_data(n) {
                sweeps_note = Some(e.to_string());
            }
        }
        if sweeps_note.is_none() {
            for &n in &sizes {
                for m in ["og", "ekf"] {
                    cases.push(self.base_case(DataSource::Sweeps, n, m));
                }
            }
        }
        let done = self.map_all("fig6", &cases)?;
        let first = self.params.seeds[0];
        let mut tiles = Vec::new();
        for src in [DataSource::Model(first), DataSource::Sweeps] {
            for &n in &sizes {
                let row: Vec<&(CaseFigures, Vec<bool>)> = ["og", "ekf"]
                    .iter()
                    .filter_map(|m| {
                        done.iter().find(|d| {
                            d.0.case.elements == n
                                && d.0.case.method == *m
                                && d.0.case.source == src
                        })
                    })
                    .collect();
                if row.is_empty() {
                    continue;
                }
                tiles.push(self.reference_tile());
                for d in row {
                    let what = match src {
                        DataSource::Model(s) => format!("model s{s}"),
                        DataSource::Sweeps => "sweeps".into(),
                    };
                    tiles.push(self.tile(
                        format!(
                            "{what}, N = {n}, {}: {} / {} wrong",
                            d.0.case.method.to_uppercase(),
                            d.0.wrong_interior,
                            d.0.wrong_whole
                        ),
                        &d.1,
                    ));
                }
            }
        }
        self.panel("fig6", &tiles, 3)?;
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let (small, large) = (sizes[0], sizes[1]);
        let mut findings = Vec::new();
        let wrong = |src: DataSource, n: usize, m: &str, interior: bool| {
            cases
                .iter()
                .find(|c| c.case.elements == n && c.case.method == m && c.case.source == src)
                .map(|c| {
                    if interior {
                        c.wrong_interior
                    } else {
                        c.wrong_whole
                    }
                })
        };
        for interior in [true, false] {
            let region = if interior { "interior" } else { "whole map" };
            for m in ["og", "ekf"] {
                let mut holds = 0;
                let mut pairs = Vec::new();
                for s in self.seeds() {
                    let src = DataSource::Model(s);
                    let (a, b) = (
                        wrong(src, small, m, interior).unwrap_or(0),
                        wrong(src, large, m, interior).unwrap_or(0),
                    );
                    holds += (a > b) as usize;
                    pairs.push(format!("seed {s}: {a} vs {b}"));
                }
                findings.push((
                    format!(
                        "model data, {}: N = {small} more wrong cells than N = {large} ({region})",
                        m.to_uppercase()
                    ),
                    format!(
                        "{holds} of {} seeds ({})",
                        self.params.seeds.len(),
                        pairs.join("; ")
                    ),
                ));
            }
            for m in ["og", "ekf"] {
                let v = match (
                    wrong(DataSource::Sweeps, small, m, interior),
                    wrong(DataSource::Sweeps, large, m, interior),
                ) {
                    (Some(a), Some(b)) => {
                        format!("{} ({a} vs {b})", if a > b { "yes" } else { "no" })
                    }
                    _ => format!(
                        "not run: {}",
                        sweeps_note.clone().unwrap_or_else(|| "no sweeps".into())
                    ),
                };
                findings.push((
                    format!(
                        "simulated sweeps, {}: N = {small} more wrong cells than N = {large} ({region})",
                        m.to_uppercase()
                    ),
                    v,
                ));
            }
        }
        for &n in &sizes {
            for m in ["og", "ekf"] {
                let sel: Vec<&CaseFigures> = cases
                    .iter()
                    .filter(|c| {
                        c.case.elements == n
                            && c.case.method == m
                            && matches!(c.case.source, DataSource::Model(_))
                    })
                    .collect();
                let w: Vec<f64> = sel.iter().map(|c| c.wrong_interior as f64).collect();
                let p: Vec<f64> = sel.iter().map(|c| c.psi_interior).collect();
                let f: Vec<f64> = sel.iter().map(|c| c.f1_interior).collect();
                let ww: Vec<f64> = sel.iter().map(|c| c.wrong_whole as f64).collect();
                let pw: Vec<f64> = sel.iter().map(|c| c.psi_whole).collect();
                findings.push((
                    format!("model data, N = {n}, {} (mean over seeds)", m.to_uppercase()),
                    format!(
                        "interior: wrong cells {:.1}, ψ {:.3}, F1 {:.3}; whole map: wrong cells {:.1}, ψ {:.3}",
                        mean(&w),
                        mean(&p),
                        mean(&f),
                        mean(&ww),
                        mean(&pw)
                    ),
                ));
            }
        }
        Ok(self.result(
            "fig6",
            &format!("OG (side-lobe aware) vs EKF on model data at N = {small} and N = {large}, seeds {}; the panel shows seed {first} (colours as fig5). Wrong cells and ψ on the interior (the reference's known cells) and on the whole map (the same cells for both N in each). The same comparison on the campaign's sweeps simulated at both N is listed beside it.", join_u(&self.params.seeds)),
            cases,
            findings,
            "",
        ))
    }

    fn prior_sensitivity(&mut self) -> Result<ExperimentResult> {
        let n = self.params.sensitivity_elements;
        let c = self.params.prior_change;
        let factors = [1.0 - c, 1.0, 1.0 + c];
        let mut cases = Vec::new();
        for s in self.seeds() {
            for f in factors {
                let mut og = self.base_case(DataSource::Model(s), n, "og");
                og.og_prior = self.params.og.prior * f;
                let mut ekf = self.base_case(DataSource::Model(s), n, "ekf");
                ekf.mu0 = self.params.ekf.mu0 * f;
                cases.push(og);
                cases.push(ekf);
            }
        }
        let done = self.map_all("prior-sensitivity", &cases)?;
        let first = self.params.seeds[0];
        let mut tiles = Vec::new();
        for m in ["og", "ekf"] {
            for f in factors {
                let d = done
                    .iter()
                    .find(|d| {
                        d.0.case.method == m
                            && d.0.case.source == DataSource::Model(first)
                            && self.factor_of(&d.0.case) == f
                    })
                    .ok_or_else(|| Error::param("prior-sensitivity", "missing case"))?;
                let label = if m == "og" {
                    format!("OG, p0 = {:.2}: ψ {:.2}", d.0.case.og_prior, d.0.psi_whole)
                } else {
                    format!("EKF, μ0 = {:.3} m: ψ {:.2}", d.0.case.mu0, d.0.psi_whole)
                };
                tiles.push(self.tile(label, &d.1));
            }
        }
        self.panel("prior-sensitivity", &tiles, 3)?;
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let mut findings = Vec::new();
        let mut charts = vec![
            LineChart {
                title: format!("N = {n}: relative change of ψ (observable region)"),
                x_label: "prior change (%)".into(),
                y_label: "Δψ/ψ (%)".into(),
                series: Vec::new(),
            },
            LineChart {
                title: format!("N = {n}: relative change of ψ (whole map)"),
                x_label: "prior change (%)".into(),
                y_label: "Δψ/ψ (%)".into(),
                series: Vec::new(),
            },
        ];
        for m in ["og", "ekf"] {
            let mean_psi = |f: f64, whole: bool| {
                let v: Vec<f64> = cases
                    .iter()
                    .filter(|c| c.case.method == m && self.factor_of(&c.case) == f)
                    .map(|c| if whole { c.psi_whole } else { c.psi_observable })
                    .collect();
                mean(&v)
            };
            for (ci, whole) in [false, true].into_iter().enumerate() {
                let base = mean_psi(1.0, whole);
                let pts: Vec<(f64, f64)> = factors
                    .iter()
                    .map(|&f| {
                        (
                            (f - 1.0) * 100.0,
                            100.0 * (mean_psi(f, whole) - base) / base,
                        )
                    })
                    .collect();
                let what = if m == "og" { "OG prior p0" } else { "EKF μ0" };
                let region = if whole { "whole map" } else { "observable" };
                findings.push((
                    format!("{what}, Δψ/ψ ({region})"),
                    format!(
                        "−{p:.0} %: {:+.1} %, +{p:.0} %: {:+.1} % (mean ψ {:.3} → {:.3} / {:.3})",
                        pts[0].1,
                        pts[2].1,
                        base,
                        mean_psi(factors[0], whole),
                        mean_psi(factors[2], whole),
                        p = c * 100.0
                    ),
                ));
                charts[ci].series.push((m.to_uppercase(), pts));
            }
        }
        report::line_plots(
            &self
                .out
                .join("prior-sensitivity")
                .join("prior-sensitivity_plot.png"),
            &charts,
        )?;
        Ok(self.result(
            "prior-sensitivity",
            &format!("N = {n}, model data, seeds {}: the OG prior p0 = {} and the EKF μ0 = {} m each changed by ±{:.0} % (binary rules unchanged: p > 0.5, x̂ − 2σ̂ > μ0). The paper reports about +5 % for the OG and +220 % for the EKF; here is what is measured. Panel: seed {first}.", join_u(&self.params.seeds), self.params.og.prior, self.params.ekf.mu0, c * 100.0),
            cases,
            findings,
            "<img src=\"{P}prior-sensitivity/prior-sensitivity_plot.png\" alt=\"relative change of psi\" style=\"max-width:960px\">\n",
        ))
    }

    /// The prior factor of a case relative to the base parameters (1 when unchanged).
    fn factor_of(&self, c: &Case) -> f64 {
        let f = if c.method == "og" {
            c.og_prior / self.params.og.prior
        } else {
            c.mu0 / self.params.ekf.mu0
        };
        // snap to the factors used (they were made by multiplication)
        [
            1.0 - self.params.prior_change,
            1.0,
            1.0 + self.params.prior_change,
        ]
        .into_iter()
        .find(|g| (g - f).abs() < 1e-9)
        .unwrap_or(f)
    }

    fn pose_noise(&mut self) -> Result<ExperimentResult> {
        let n = self.params.pose_elements;
        let mut settings: Vec<(f64, f64)> = self
            .params
            .position_noise_m
            .iter()
            .map(|&p| (p, 0.0))
            .collect();
        for &h in &self.params.heading_noise_deg {
            if h > 0.0 || !settings.contains(&(0.0, 0.0)) {
                settings.push((0.0, h));
            }
        }
        let mut cases = Vec::new();
        for s in self.seeds() {
            for &(p, h) in &settings {
                for m in ["og", "ekf"] {
                    let mut c = self.base_case(DataSource::Model(s), n, m);
                    c.pose_noise = PoseNoise {
                        position_m: p,
                        heading_deg: h,
                        seed: s,
                    };
                    cases.push(c);
                }
            }
        }
        let done = self.map_all("pose-noise", &cases)?;
        let first = self.params.seeds[0];
        let pmax = self
            .params
            .position_noise_m
            .iter()
            .cloned()
            .fold(0.0, f64::max);
        let hmax = self
            .params
            .heading_noise_deg
            .iter()
            .cloned()
            .fold(0.0, f64::max);
        let mut tiles = Vec::new();
        for m in ["og", "ekf"] {
            for (p, h) in [(0.0, 0.0), (pmax, 0.0), (0.0, hmax)] {
                if let Some(d) = done.iter().find(|d| {
                    d.0.case.method == m
                        && d.0.case.source == DataSource::Model(first)
                        && d.0.case.pose_noise.position_m == p
                        && d.0.case.pose_noise.heading_deg == h
                }) {
                    tiles.push(self.tile(
                        format!(
                            "{}, σ {:.0} cm / {:.0}°: ψ {:.2}",
                            m.to_uppercase(),
                            p * 100.0,
                            h,
                            d.0.psi_whole
                        ),
                        &d.1,
                    ));
                }
            }
        }
        self.panel("pose-noise", &tiles, 3)?;
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let mut findings = Vec::new();
        let mut pos_chart = LineChart {
            title: format!("N = {n}: ψ vs position noise (heading exact)"),
            x_label: "position σ per axis (cm)".into(),
            y_label: "ψ (cells)".into(),
            series: Vec::new(),
        };
        let mut hdg_chart = LineChart {
            title: format!("N = {n}: ψ vs heading noise (position exact)"),
            x_label: "heading σ (deg)".into(),
            y_label: "ψ (cells)".into(),
            series: Vec::new(),
        };
        for m in ["og", "ekf"] {
            let psi = |p: f64, h: f64, whole: bool| {
                let v: Vec<f64> = cases
                    .iter()
                    .filter(|c| {
                        c.case.method == m
                            && c.case.pose_noise.position_m == p
                            && c.case.pose_noise.heading_deg == h
                    })
                    .map(|c| if whole { c.psi_whole } else { c.psi_observable })
                    .collect();
                mean(&v)
            };
            for whole in [false, true] {
                let name = format!(
                    "{} ({})",
                    m.to_uppercase(),
                    if whole { "whole" } else { "observable" }
                );
                let pp: Vec<(f64, f64)> = self
                    .params
                    .position_noise_m
                    .iter()
                    .map(|&p| (p * 100.0, psi(p, 0.0, whole)))
                    .collect();
                let hh: Vec<(f64, f64)> = self
                    .params
                    .heading_noise_deg
                    .iter()
                    .map(|&h| (h, psi(0.0, h, whole)))
                    .collect();
                findings.push((
                    format!("{name}: mean ψ vs position σ (cm)"),
                    pp.iter()
                        .map(|(x, y)| format!("{x:.0}: {y:.3}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                ));
                findings.push((
                    format!("{name}: mean ψ vs heading σ (°)"),
                    hh.iter()
                        .map(|(x, y)| format!("{x:.0}: {y:.3}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                ));
                pos_chart.series.push((name.clone(), pp));
                hdg_chart.series.push((name, hh));
            }
        }
        report::line_plots(
            &self.out.join("pose-noise").join("pose-noise_plot.png"),
            &[pos_chart, hdg_chart],
        )?;
        Ok(self.result(
            "pose-noise",
            &format!("N = {n}, model data, seeds {}: the mappers are given noisy poses (Gaussian, independent per pose; the data were taken at the true poses; scored on the true poses' observable region). Panel: seed {first}, no noise and the largest levels.", join_u(&self.params.seeds)),
            cases,
            findings,
            "<img src=\"{P}pose-noise/pose-noise_plot.png\" alt=\"psi vs pose noise\" style=\"max-width:960px\">\n",
        ))
    }

    /// Assemble a result; `extra` HTML may use `{P}` for the experiments folder prefix.
    fn result(
        &self,
        name: &str,
        caption: &str,
        cases: Vec<CaseFigures>,
        findings: Vec<(String, String)>,
        extra: &str,
    ) -> ExperimentResult {
        let mut html = format!(
            "<p>{}</p>\n<a href=\"{{P}}{name}/{name}.png\"><img src=\"{{P}}{name}/{name}.png\" alt=\"{name}\" style=\"max-width:1280px\"></a>\n{extra}",
            html_escape(caption)
        );
        html.push_str(&report::kv_table(&findings));
        html.push_str("<details><summary>every map</summary>\n<table><tr><th>map</th><th>ψ whole</th><th>wrong whole</th><th>F1 whole</th><th>ψ obs.</th><th>wrong obs.</th><th>F1 obs.</th><th>obs. cells</th><th>ψ interior</th><th>wrong interior</th><th>F1 interior</th></tr>\n");
        for c in &cases {
            html.push_str(&format!(
                "<tr><td><a href=\"{{P}}maps/{k}/metrics.json\">{k}</a></td><td>{:.3}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{}</td><td>{:.3}</td><td>{}</td><td>{:.3}</td><td>{}</td><td>{:.3}</td></tr>\n",
                c.psi_whole,
                c.wrong_whole,
                c.f1_whole,
                c.psi_observable,
                c.wrong_observable,
                c.f1_observable,
                c.observable_cells,
                c.psi_interior,
                c.wrong_interior,
                c.f1_interior,
                k = html_escape(&c.key)
            ));
        }
        html.push_str(&format!(
            "</table></details>\n<p>Files: <a href=\"{{P}}{name}/{name}.md\">{name}.md</a>, <a href=\"{{P}}{name}/{name}.csv\">{name}.csv</a>, <a href=\"{{P}}{name}/{name}.json\">{name}.json</a>.</p>\n"
        ));
        ExperimentResult {
            name: name.to_string(),
            cases,
            findings,
            html,
        }
    }

    /// The report section of a result, links prefixed by `prefix` (the experiments folder
    /// relative to the page: `""` for `DIR/index.html`, `"experiments/"` in `reproduce`).
    pub fn section(r: &ExperimentResult, prefix: &str) -> Section {
        let title = match r.name.as_str() {
            "fig5" => "Experiment fig5: EKF maps from simulated sweeps and from model data",
            "fig6" => "Experiment fig6: OG vs EKF, N = 16 vs N = 100 (model data)",
            "prior-sensitivity" => "Experiment prior-sensitivity: OG prior and EKF μ0 ±40 %",
            _ => "Experiment pose-noise: ψ as pose noise grows",
        };
        Section {
            title: title.into(),
            html: r.html.replace("{P}", prefix),
        }
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn join(v: &[f64], digits: usize) -> String {
    v.iter()
        .map(|x| format!("{x:.digits$}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn join_u(v: &[u64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The case table as Markdown (findings first) and CSV.
fn case_tables(cases: &[CaseFigures], findings: &[(String, String)]) -> (String, String) {
    let mut md = String::new();
    for (k, v) in findings {
        md.push_str(&format!("- {k}: {v}\n"));
    }
    md.push_str("\n| map | data | seed | N | mapper | OG prior | EKF μ0 (m) | pose σ (m) | heading σ (°) | ψ whole | wrong whole | F1 whole | ψ obs. | wrong obs. | F1 obs. | obs. cells | ψ interior | wrong interior | F1 interior | all-free ψ whole |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let mut csv = String::from("map,data,seed,elements,mapper,og_prior,mu0_m,pose_sigma_m,heading_sigma_deg,psi_whole,wrong_whole,f1_whole,psi_observable,wrong_observable,f1_observable,observable_cells,psi_interior,wrong_interior,f1_interior,all_free_psi_whole,all_free_wrong_whole\n");
    for c in cases {
        let (data, seed) = match c.case.source {
            DataSource::Sweeps => ("sweeps", String::new()),
            DataSource::Model(s) => ("model", s.to_string()),
        };
        let k = &c.case;
        md.push_str(&format!(
            "| {} | {data} | {seed} | {} | {} | {} | {} | {} | {} | {:.3} | {} | {:.3} | {:.3} | {} | {:.3} | {} | {:.3} | {} | {:.3} | {:.3} |\n",
            c.key, k.elements, k.method, k.og_prior, k.mu0, k.pose_noise.position_m, k.pose_noise.heading_deg,
            c.psi_whole, c.wrong_whole, c.f1_whole, c.psi_observable, c.wrong_observable, c.f1_observable,
            c.observable_cells, c.psi_interior, c.wrong_interior, c.f1_interior, c.all_free_psi_whole
        ));
        csv.push_str(&format!(
            "{},{data},{seed},{},{},{},{},{},{},{:.6},{},{:.6},{:.6},{},{:.6},{},{:.6},{},{:.6},{:.6},{}\n",
            c.key, k.elements, k.method, k.og_prior, k.mu0, k.pose_noise.position_m, k.pose_noise.heading_deg,
            c.psi_whole, c.wrong_whole, c.f1_whole, c.psi_observable, c.wrong_observable, c.f1_observable,
            c.observable_cells, c.psi_interior, c.wrong_interior, c.f1_interior, c.all_free_psi_whole, c.all_free_wrong_whole
        ));
    }
    (md, csv)
}

/// `pradar experiment`: resolve the inputs into `out/work`, run `which` and write
/// `out/index.html`.
pub fn run_experiments(
    which: &[Experiment],
    inputs: &InputOptions,
    params: &ExperimentParams,
    out: &Path,
    progress: Progress,
) -> Result<Vec<ExperimentResult>> {
    params.check()?;
    let resolved = prepare_inputs(inputs, &out.join("work"), progress)?;
    let mut lab = Lab::new(resolved, params.clone(), out, progress)?;
    let mut results = Vec::new();
    for &e in which {
        results.push(lab.run(e)?);
    }
    let mut sections = vec![Section {
        title: "Inputs".into(),
        html: report::kv_table(&[
            (
                "campaign".to_string(),
                lab.inputs().campaign.display().to_string(),
            ),
            (
                "energy (sweeps)".into(),
                lab.inputs().energy.display().to_string(),
            ),
            ("model".into(), lab.inputs().model.display().to_string()),
            ("seeds".into(), join_u(&params.seeds)),
        ]),
    }];
    sections.extend(results.iter().map(|r| Lab::section(r, "")));
    report::write_index(&out.join("index.html"), "pradar experiments", &sections)?;
    Ok(results)
}
