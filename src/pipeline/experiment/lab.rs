//! What the experiments share: the [`Lab`] that makes model data and sweeps, maps every
//! case once per process, scores it ([`CaseFigures`], defined with the other result types in
//! [`crate::mapping::experiment`]: three regions, module docs of [`super`]) and writes each
//! experiment's data files (`NAME.md|.csv|.json`) with its case table. The images and the
//! HTML are drawn from a result by [`crate::report::experiments`]; nothing here calls the
//! report.
//!
//! Parallelism: [`Lab::prepare`] gathers the cases of every experiment asked for, makes
//! their model data in parallel (sweeps at another N in case order), then runs every map
//! on the pool at once; each experiment then finds its maps made. A map and a model-data
//! draw depend only on their options and seed, so the files do not depend on the thread
//! count or on what ran beside them.

use super::super::Progress;
use super::{Experiment, ExperimentInputs, ExperimentValid};
use crate::campaign::layout::Layout;
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy;
use crate::error::{Error, Result};
use crate::export::LineChart;
use crate::export::{Cell, Column, Table};
pub use crate::mapping::experiment::score_columns;
pub use crate::mapping::experiment::{
    Case, CaseFigures, DataSource, ExperimentResult, Figure, Panel, PanelTile,
};
use crate::mapping::job::{
    run_map, MapOptions, MapReport, MapRun, MapValid, OdometryNoise, PoseNoise, PosesFrom,
};
use crate::mapping::reference::{CellClass, LayoutRaster, ReferenceMap};
use crate::mapping::{EkfParams, Method, OgParams};
use crate::model::file::ModelConfig;
use crate::model::{synth, SynthParams};
use crate::params::ParamGuard;
use crate::simulate::simulate;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A case's folder name under `maps/`: data, N, mapper, and whatever differs from the base.
pub fn case_key(case: &Case, base: &ExperimentValid) -> String {
    let mut k = match case.source {
        DataSource::Sweeps => format!("sweeps_n{}_{}", case.elements, case.method),
        DataSource::Model(s) => format!("model_s{s}_n{}_{}", case.elements, case.method),
        DataSource::Physics(s) => format!("physics_s{s}_n{}_{}", case.elements, case.method),
    };
    if case.method == "og" && case.og_prior != base.og.prior {
        k.push_str(&format!("_prior{:.3}", case.og_prior));
    }
    if case.method == "ekf" && case.mu0 != base.ekf.mu0 {
        k.push_str(&format!("_mu{:.4}", case.mu0));
    }
    if case.pose_noise.position_m > 0.0 {
        k.push_str(&format!("_pos{:.0}mm", case.pose_noise.position_m * 1000.0));
    }
    if case.pose_noise.heading_deg > 0.0 {
        k.push_str(&format!("_hdg{:.1}deg", case.pose_noise.heading_deg));
    }
    if case.poses_from != PosesFrom::Manifest {
        let o = &case.odometry;
        k.push_str(&format!(
            "_{}_odo{:.0}mm{:.1}deg_s{}",
            case.poses_from.name(),
            o.step_m * 1000.0,
            o.step_deg,
            o.seed
        ));
    }
    k
}

fn count(rate: f64, cells: usize) -> usize {
    (rate * cells as f64).round() as usize
}

/// A mapped case's figures from its map report.
fn case_figures(key: String, case: Case, r: &MapReport) -> CaseFigures {
    let m = &r.metrics;
    let i = &m.building;
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
        all_free_wrong_interior: count(m.building_all_free.wrong_cell_rate, i.cells),
        classes: m.classes,
        three_class: m.three_class,
        slam: r.slam.first().cloned(),
    }
}

/// A mapped case: its figures and its binary map (for the panels).
pub(super) type Mapped = (CaseFigures, Vec<bool>);

/// Runs experiments, sharing model data and maps between them.
pub struct Lab<'a> {
    inputs: ExperimentInputs,
    pub(super) params: ExperimentValid,
    pub(super) out: PathBuf,
    model: ModelConfig,
    pub(super) campaign_elements: usize,
    /// "simulated sweeps" for a campaign with a `[scene]`, else "measured sweeps".
    pub(super) sweeps_word: &'static str,
    reference: ReferenceMap,
    synth_cache: HashMap<(usize, u64), PathBuf>,
    sweeps_cache: HashMap<usize, (PathBuf, PathBuf)>,
    /// The campaign simulated at (N, seed) for [`DataSource::Physics`].
    physics_cache: HashMap<(usize, u64), (PathBuf, PathBuf)>,
    /// Why the sweeps at N could not be made ([`Lab::sweeps_failure`]): not tried again.
    sweeps_failed: HashMap<usize, String>,
    map_cache: HashMap<String, MapReport>,
    progress: Progress<'a>,
}

impl<'a> Lab<'a> {
    /// A lab writing into `out` (maps in `out/maps`, model data in `out/work/synth`).
    pub fn new(
        inputs: ExperimentInputs,
        params: ExperimentValid,
        out: &Path,
        progress: Progress<'a>,
    ) -> Result<Lab<'a>> {
        let model = ModelConfig::load(&inputs.model)?;
        let c = Campaign::load(&inputs.campaign)?;
        let layout = Layout::load(&c.layout_path())?;
        let reference = layout.rasterize(params.grid.cell_m, params.grid.margin_m);
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
        Ok(Lab {
            campaign_elements: c.manifest.array.elements,
            sweeps_word: match crate::simulate::has_scene(&c)? {
                true => "simulated sweeps",
                false => "measured sweeps",
            },
            inputs,
            params,
            out: out.to_path_buf(),
            model,
            reference,
            synth_cache: HashMap::new(),
            sweeps_cache: HashMap::new(),
            physics_cache: HashMap::new(),
            sweeps_failed: HashMap::new(),
            map_cache: HashMap::new(),
            progress,
        })
    }

    /// The inputs in use.
    pub fn inputs(&self) -> &ExperimentInputs {
        &self.inputs
    }

    /// The case of these data, N and mapper with the base parameters and no pose noise.
    pub(super) fn base_case(
        &self,
        source: DataSource,
        elements: usize,
        method: &'static str,
    ) -> Case {
        Case {
            source,
            elements,
            method,
            og_prior: self.params.og.prior,
            mu0: self.params.ekf.mu0,
            pose_noise: PoseNoise::default(),
            poses_from: PosesFrom::Manifest,
            odometry: OdometryNoise::default(),
        }
    }

    /// Model data at N elements and this seed (synth once per process).
    fn model_data(&mut self, elements: usize, seed: u64) -> Result<PathBuf> {
        self.make_model_data(&[(elements, seed)])?;
        Ok(self.synth_cache[&(elements, seed)].clone())
    }

    /// Model data at each (N, seed) not made yet, made in parallel (each `synth` depends
    /// only on its N and seed, so the files do not depend on the thread count).
    fn make_model_data(&mut self, wanted: &[(usize, u64)]) -> Result<()> {
        let mut todo: Vec<(usize, u64)> = Vec::new();
        for k in wanted {
            if !self.synth_cache.contains_key(k) && !todo.contains(k) {
                todo.push(*k);
            }
        }
        if todo.is_empty() {
            return Ok(());
        }
        // a model quantity the fit could not estimate has no value to draw from
        let model = self
            .model
            .require_estimable(&Default::default())
            .map_err(|e| Error::input(&self.inputs.model, e.to_string()))?;
        let campaign = Campaign::load(&self.inputs.campaign)?;
        let dir = self.out.join("work").join("synth");
        let made: Vec<PathBuf> = todo
            .par_iter()
            .map(|&(elements, seed)| -> Result<PathBuf> {
                let path = dir.join(format!("n{elements}_s{seed}.parquet"));
                let mut c = campaign.clone();
                c.set_elements(elements)?;
                let sp = SynthParams::default()
                    .seed(seed)
                    .truth_dir(dir.join(format!("n{elements}_s{seed}_truth")))
                    .check()?;
                synth(&c, &model, &path, &sp, &|_, _| {})?;
                Ok(path)
            })
            .collect::<Result<_>>()?;
        for (k, p) in todo.into_iter().zip(made) {
            self.synth_cache.insert(k, p);
        }
        Ok(())
    }

    /// Sweeps at N elements: the campaign's own, or the campaign simulated again at N (it
    /// needs a `[scene]`), once per process. Returns (manifest, energy table).
    pub(super) fn sweeps_data(&mut self, elements: usize) -> Result<(PathBuf, PathBuf)> {
        if elements == self.campaign_elements {
            return Ok((self.inputs.campaign.clone(), self.inputs.energy.clone()));
        }
        if let Some(p) = self.sweeps_cache.get(&elements) {
            return Ok(p.clone());
        }
        let r = simulate_sweeps(&self.inputs.campaign, &self.out, elements)?;
        self.sweeps_cache.insert(elements, r.clone());
        Ok(r)
    }

    /// Why the sweeps at N elements cannot be made (the error's text), None when they can
    /// ([`Lab::sweeps_data`]); a failure is kept, so the experiments' planning
    /// ([`Lab::prepare`]) and the experiment itself do not simulate it twice.
    pub(super) fn sweeps_failure(&mut self, elements: usize) -> Option<String> {
        if let Some(why) = self.sweeps_failed.get(&elements) {
            return Some(why.clone());
        }
        let why = self.sweeps_data(elements).err()?.to_string();
        self.sweeps_failed.insert(elements, why.clone());
        Some(why)
    }

    /// The campaign simulated at N elements with the manifest's seed plus `seed`, and its
    /// energy table (made once per process, [`simulate_physics`]).
    fn physics_data(&mut self, elements: usize, seed: u64) -> Result<(PathBuf, PathBuf)> {
        if let Some(p) = self.physics_cache.get(&(elements, seed)) {
            return Ok(p.clone());
        }
        let r = simulate_physics(&self.inputs.campaign, &self.out, elements, seed)?;
        self.physics_cache.insert((elements, seed), r.clone());
        Ok(r)
    }

    /// Take sweeps at N elements made beforehand by [`simulate_sweeps`] (same campaign,
    /// same folder): the lab then does not simulate them again.
    pub fn preset_sweeps(&mut self, elements: usize, made: (PathBuf, PathBuf)) {
        self.sweeps_cache.insert(elements, made);
    }

    /// The checked `pradar map` options of one case (its data made first, once per process).
    fn map_options(&mut self, case: &Case, key: &str) -> Result<MapValid> {
        let (campaign, energy, elements) = match case.source {
            DataSource::Sweeps => {
                let (c, e) = self.sweeps_data(case.elements)?;
                (c, e, None)
            }
            DataSource::Physics(s) => {
                let (c, e) = self.physics_data(case.elements, s)?;
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
            out: self.out.join("maps").join(key),
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
            poses_from: case.poses_from,
            odometry: case.odometry,
        };
        opts.check()
    }

    /// Map every case with a progress bar labelled `label`. Each map is made once per
    /// process: the data of the cases not yet mapped are made first (model data in parallel,
    /// sweeps in case order), then
    /// their maps run in parallel. A map depends only on its options, so the results do not
    /// depend on the thread count.
    pub(super) fn map_all(&mut self, label: &str, cases: &[Case]) -> Result<Vec<Mapped>> {
        let cb = (self.progress)(label, cases.len());
        let mut todo: Vec<(String, MapValid)> = Vec::new();
        // the model data of the maps not made yet, all at once (in parallel)
        let wanted: Vec<(usize, u64)> = (cases.iter())
            .filter(|c| !self.map_cache.contains_key(&case_key(c, &self.params)))
            .filter_map(|c| match c.source {
                DataSource::Model(s) => Some((c.elements, s)),
                DataSource::Sweeps | DataSource::Physics(_) => None,
            })
            .collect();
        self.make_model_data(&wanted)?;
        for c in cases {
            let key = case_key(c, &self.params);
            if !self.map_cache.contains_key(&key) && todo.iter().all(|(k, _)| *k != key) {
                let opts = self.map_options(c, &key)?;
                todo.push((key, opts));
            }
        }
        // the maps run on the pool; this thread counts them for the progress bar
        let mut done = cases.len() - todo.len();
        cb(done, cases.len());
        let (tx, rx) = std::sync::mpsc::channel::<()>();
        let reports: Vec<MapReport> = std::thread::scope(|s| {
            let todo = &todo;
            let worker = s.spawn(move || {
                todo.par_iter()
                    .map(|(_, opts)| {
                        let r = run_map(opts, &|_, _| {});
                        let _ = tx.send(());
                        r
                    })
                    .collect::<Result<Vec<_>>>()
            });
            for () in rx {
                done += 1;
                cb(done, cases.len());
            }
            worker.join().expect("map worker")
        })?;
        for ((key, _), r) in todo.into_iter().zip(reports) {
            self.map_cache.insert(key, r);
        }
        Ok(cases
            .iter()
            .map(|c| {
                let key = case_key(c, &self.params);
                let r = &self.map_cache[&key];
                (case_figures(key, *c, r), r.binary.clone())
            })
            .collect())
    }

    /// A panel tile: the binary map (scored against the reference when drawn).
    pub(super) fn tile(&self, title: String, binary: &[bool]) -> PanelTile {
        PanelTile {
            title,
            occupied: binary.to_vec(),
        }
    }

    /// The reference's own tile.
    pub(super) fn reference_tile(&self) -> PanelTile {
        let occupied = self
            .reference
            .cells
            .iter()
            .map(|c| *c == CellClass::Occupied);
        let b: Vec<bool> = occupied.collect();
        self.tile("reference".into(), &b)
    }

    /// The experiment's panel: `tiles`, `columns` per row, against the reference.
    pub(super) fn panel(&self, tiles: Vec<PanelTile>, columns: usize) -> Panel {
        Panel {
            reference: self.reference.clone(),
            tiles,
            columns,
        }
    }

    /// The cases (maps) of one experiment; sweeps at another N are made on the way.
    pub fn cases(&mut self, e: Experiment) -> Vec<Case> {
        match e {
            Experiment::Fig5 => self.fig5_cases(),
            Experiment::Fig6 => {
                let sizes = self.params.compare_elements.clone();
                self.fig6_cases(&sizes).0
            }
            Experiment::PriorSensitivity => self.prior_cases(),
            Experiment::PoseNoise => self.pose_cases(self.params.pose_elements),
            Experiment::Slam => self.slam_cases(),
        }
    }

    /// Make the maps of all these experiments at once, before [`Lab::run`] runs them one
    /// by one: their model data in parallel, then every map on the pool, so the cores do
    /// not wait at the end of each experiment's maps for its slowest one. The maps and
    /// files are those [`Lab::run`] alone makes (each map depends only on its options).
    pub fn prepare(&mut self, which: &[Experiment]) -> Result<()> {
        let mut cases = Vec::new();
        for &e in which {
            cases.extend(self.cases(e));
        }
        self.map_all("experiments' maps", &cases).map(|_| ())
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
            Experiment::Slam => self.slam()?,
        };
        let name = e.name();
        let table = case_table(&r.cases);
        let mut md = String::new();
        for (k, v) in &r.findings {
            md.push_str(&format!("- {k}: {v}\n"));
        }
        md.push('\n');
        md.push_str(&table.to_markdown());
        crate::io::write_bytes(&dir.join(format!("{name}.md")), md.as_bytes())?;
        crate::io::write_bytes(&dir.join(format!("{name}.csv")), table.to_csv().as_bytes())?;
        let json = serde_json::to_string_pretty(&r)
            .map_err(|err| Error::param("experiment", err.to_string()))?;
        crate::io::write_bytes(&dir.join(format!("{name}.json")), json.as_bytes())?;
        Ok(r)
    }

    /// The seeds (of the model data, and of fig6's physics sweeps).
    pub(super) fn seeds(&self) -> Vec<u64> {
        self.params.seeds.clone()
    }
}

/// Where [`simulate_sweeps`] puts the sweeps at N elements: `out/work/sweeps_n<N>`.
pub fn sweeps_dir(out: &Path, elements: usize) -> PathBuf {
    out.join("work").join(format!("sweeps_n{elements}"))
}

/// The campaign `campaign` simulated again at N elements into [`sweeps_dir`], with
/// its energy table: (manifest, energy table). What [`Lab`] does for sweeps at another N;
/// `reproduce` runs it early, beside the fit.
pub fn simulate_sweeps(campaign: &Path, out: &Path, elements: usize) -> Result<(PathBuf, PathBuf)> {
    simulate_into(campaign, &sweeps_dir(out, elements), elements, 0)
}

/// The campaign `campaign` simulated at N elements with its manifest's seed plus `seed`
/// (a new realisation of its `[scene]`: clutter and noise), with its energy table, into
/// `out/work/physics_nN_sS`: (manifest, energy table).
pub fn simulate_physics(
    campaign: &Path,
    out: &Path,
    elements: usize,
    seed: u64,
) -> Result<(PathBuf, PathBuf)> {
    let dir = out
        .join("work")
        .join(format!("physics_n{elements}_s{seed}"));
    simulate_into(campaign, &dir, elements, seed)
}

/// The campaign simulated at N elements with its manifest's seed plus `seed` (0: its own)
/// into `dir` (Parquet sweeps), and its energy table there: (manifest, energy table).
fn simulate_into(
    campaign: &Path,
    dir: &Path,
    elements: usize,
    seed: u64,
) -> Result<(PathBuf, PathBuf)> {
    let mut c = Campaign::load(campaign)?;
    c.set_elements(elements)?;
    c.manifest.seed = c.manifest.seed.wrapping_add(seed);
    let sim = simulate(&c, dir, SweepFormat::Parquet, &|_, _| {})?;
    let sc = Campaign::load(&sim.manifest)?;
    let e = dir.join("energy.parquet");
    energy::run(&sc, &e, &|_, _| {})?;
    Ok((sim.manifest, e))
}

/// The mean of `v` (NaN when empty).
pub(super) fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// `v` with `digits` decimals, comma-separated.
pub(super) fn join(v: &[f64], digits: usize) -> String {
    v.iter()
        .map(|x| format!("{x:.digits$}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `v` comma-separated.
pub(super) fn join_u(v: &[u64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The case table of an experiment (`NAME.md` after the findings, and `NAME.csv`): one row
/// per map; ψ and F1 shown with 3 decimals (full precision in the CSV); the all-free map's
/// wrong cells in the CSV only. The seed is the model data's or the physics sweeps', or the
/// odometry's where the poses come from one (`slam`).
pub fn case_table(cases: &[CaseFigures]) -> Table {
    let col = Column::new;
    let mut columns = vec![
        col("map", "map"),
        col("data", "data"),
        col("seed", "seed"),
        col("N", "elements"),
        col("mapper", "mapper"),
        col("OG prior", "og_prior"),
        col("EKF μ0 (m)", "mu0_m"),
        col("pose σ (m)", "pose_sigma_m"),
        col("heading σ (°)", "heading_sigma_deg"),
    ];
    columns.extend(score_columns());
    columns.push(col("all-free ψ whole", "all_free_psi_whole"));
    columns.push(col("all-free wrong whole", "all_free_wrong_whole").csv_only());
    let mut t = Table::new(columns);
    let plain = |v: f64| Cell::num(v, v.to_string());
    for c in cases {
        let k = &c.case;
        let (data, seed) = match k.source {
            // the odometry's seed where the poses come from one (`experiment slam`)
            DataSource::Sweeps if k.poses_from != PosesFrom::Manifest => {
                ("sweeps", Cell::text(k.odometry.seed.to_string()))
            }
            DataSource::Sweeps => ("sweeps", Cell::missing("")),
            DataSource::Model(s) => ("model", Cell::text(s.to_string())),
            DataSource::Physics(s) => ("physics", Cell::text(s.to_string())),
        };
        let mut row = vec![
            Cell::text(&c.key),
            Cell::text(data),
            seed,
            Cell::count(k.elements),
            Cell::text(k.method),
            plain(k.og_prior),
            plain(k.mu0),
            plain(k.pose_noise.position_m),
            plain(k.pose_noise.heading_deg),
        ];
        row.extend(c.score_cells());
        row.push(Cell::fixed(c.all_free_psi_whole, 3));
        row.push(Cell::count(c.all_free_wrong_whole));
        t.push(row);
    }
    t
}

/// Assemble a result.
pub(super) fn result(
    name: &str,
    caption: &str,
    cases: Vec<CaseFigures>,
    findings: Vec<(String, String)>,
    panel: Panel,
    charts: Vec<LineChart>,
    figures: Vec<Figure>,
) -> ExperimentResult {
    ExperimentResult {
        name: name.to_string(),
        cases,
        findings,
        caption: caption.to_string(),
        panel,
        charts,
        figures,
    }
}
