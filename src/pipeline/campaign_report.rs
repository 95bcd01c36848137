//! `pradar report` ([`report`]): the report of any campaign, measured or simulated, and the
//! one code path of the report page, which `pradar reproduce` ([`super::reproduce`]) takes
//! after simulating the built-in corridor.
//!
//! Takes a campaign manifest with its sweeps (or an energy table of them), optionally a
//! model file and a simulator's truth folder; gives `out/index.html` with the campaign
//! summary, the energy heat maps with their MPCs, the clusters, Table 1 (titled with the
//! campaign's name; a truth column only with a truth), the fitted model with its predictive
//! check, the OG and EKF maps with their metrics against the layout, the experiments, and
//! the stage timings.
//!
//! * **Stages that cannot run say why on the page** and the rest still stands: the
//!   geometry-only Table 1 needs the simulator's `[scene]` (a measured campaign has none);
//!   the truth column needs a truth folder (given by `--truth`, or `truth/` beside the
//!   manifest as `simulate` writes it) whose fit succeeds; the check, the K_max table and
//!   the experiments need a model; a failed map says so. Extraction and clustering errors
//!   are errors of the data and stop the job.
//! * **Warnings**: the energy stage's (the manifest's `[noise]` floor implying an N0 more
//!   than 3 dB from the data's) is returned ([`ReportOutput::warnings`]) for the command
//!   line to print as `energy` does, and shown on the page beside N0 (a given energy table
//!   has none: the stage did not run).
//! * **`--model M`** is the model the check and the experiments' model data use (a
//!   calibrated model, say); Table 1 and `fitted_model.toml` are still fitted from the
//!   campaign. Without it both use the fitted model.
//! * **A failed run leaves nothing behind** ([`OutGuard`]): what the run created under
//!   `out` (and `out` itself when the run made it) is removed when the job fails, also on a
//!   panic; files of an earlier report in `out` are kept. Outputs are written inside `out`,
//!   not staged elsewhere and renamed, because the maps' and the experiments' records name
//!   their inputs by absolute path. Inputs inside `out` are refused, so neither the run
//!   nor its cleanup can overwrite or remove them.
//! * Scheduling: the geometry-only chain has its own files, so it runs on a side thread
//!   beside energy → analysis → fit report, and then makes the experiments' sweeps at the
//!   other N of fig6 once the analysed campaign is known (the lab takes them instead of
//!   simulating them again). Every output is a pure function of its inputs, so the files
//!   are the same whatever runs beside what; the page's stage timings say which stage ran
//!   beside the others and its total is the job's wall time.

use super::experiment::{self, ExperimentValid};
use super::geometry::geometry_only_table;
use super::kmax::k_max_sensitivity;
use super::{analyse, table1_html_rows, Analysis, Progress};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::energy::{self, EnergyMatrix};
use crate::error::{Error, Result};
use crate::fit::channel::ChannelFit;
use crate::params::{ParamGuard, Valid};
use crate::report::reproduce::{self as page, FitPlot, ReproducePage};
use crate::report::{self, Section};
use crate::simulate::{has_scene, simulate, SimReport};
use std::collections::HashSet;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `report`'s report folder when none is given.
pub const DEFAULT_REPORT_OUT: &str = "reports/campaign";

/// Options of `report` (checked by [`ParamGuard::check`] into a [`ReportValid`]).
#[derive(Debug, Clone)]
pub struct ReportOptions {
    /// Report folder.
    pub out: PathBuf,
    /// The campaign's manifest.
    pub campaign: PathBuf,
    /// Energy table of its sweeps (default: computed from them into `out/work`).
    pub energy: Option<PathBuf>,
    /// Model the check and the experiments use (default: the one fitted from the campaign).
    pub model: Option<PathBuf>,
    /// A simulator's truth folder for Table 1's truth column (default: `truth/` beside the
    /// manifest when it holds `rays.parquet`; none for a measured campaign).
    pub truth: Option<PathBuf>,
    /// Run the mapping experiments into `out/experiments` (default true).
    pub experiments: bool,
    /// Their parameters, checked.
    pub experiment_params: ExperimentValid,
    /// A `pradar explore` folder whose section the page shows (its files copied into
    /// `out/explore/`).
    pub explore: Option<PathBuf>,
}

/// [`ReportOptions`] that passed their check.
pub type ReportValid = Valid<ReportOptions>;

impl ParamGuard for ReportOptions {
    type Checked = ReportValid;

    /// The inputs are regular files (the truth a folder) and none lies inside `out` (the
    /// report would overwrite it or, failing, remove it).
    fn check(&self) -> Result<ReportValid> {
        crate::io::regular_input(&self.campaign, "--campaign")?;
        let mut inputs = vec![(self.campaign.clone(), "--campaign")];
        for (p, what) in [(&self.energy, "--energy"), (&self.model, "--model")] {
            if let Some(p) = p {
                crate::io::regular_input(p, what)?;
                inputs.push((p.clone(), what));
            }
        }
        if let Some(d) = &self.explore {
            if !d.join(EXPLORE_SECTION).is_file() {
                return Err(Error::input(
                    d,
                    format!("--explore: no {EXPLORE_SECTION} (not a `pradar explore` folder)"),
                ));
            }
        }
        if let Some(t) = &self.truth {
            if !t.is_dir() {
                return Err(Error::input(t, "--truth: not a folder"));
            }
            inputs.push((t.clone(), "--truth"));
        }
        refuse_inside(&self.out, &inputs)?;
        Ok(Valid::new(self.clone()))
    }
}

/// Refuse an input inside the report folder `out`.
pub(crate) fn refuse_inside(out: &Path, inputs: &[(PathBuf, &str)]) -> Result<()> {
    let Ok(out_c) = std::fs::canonicalize(out) else {
        return Ok(()); // out does not exist yet: nothing can be inside it
    };
    for (p, what) in inputs {
        if let Ok(pc) = std::fs::canonicalize(p) {
            if pc.starts_with(&out_c) {
                return Err(Error::input(
                    p,
                    format!(
                        "{what} lies inside --out {}; the report would overwrite it (choose another --out)",
                        out.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// What `report` and `reproduce` made: the page, and the warnings their stages gave (the
/// energy stage's `[noise]` floor far from the data's N0, [`energy::EnergyReport::warnings`],
/// also shown on the page beside N0) for the command line to print.
#[derive(Debug, Clone)]
pub struct ReportOutput {
    /// The page, `out/index.html`.
    pub index: PathBuf,
    /// One line each, printed after `warning: `.
    pub warnings: Vec<String>,
}

/// The report of a campaign's sweeps (or of its energy table); returns the index path and
/// the warnings ([`ReportOutput`]).
///
/// ```no_run
/// use pradar::params::ParamGuard;
/// use pradar::pipeline::experiment::ExperimentParams;
/// use pradar::pipeline::{report, ReportOptions};
/// let opts = ReportOptions {
///     out: "lab/report".into(),
///     campaign: "lab/campaign.toml".into(),
///     energy: Some("lab/energy.parquet".into()),
///     model: None,
///     truth: None,
///     experiments: true,
///     experiment_params: ExperimentParams::default().check()?,
///     explore: None,
/// }
/// .check()?;
/// let progress = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
/// let done = report(&opts, &progress)?;
/// println!("report: {}", done.index.display());
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn report(opts: &ReportValid, progress: Progress) -> Result<ReportOutput> {
    let c = Campaign::load(&opts.campaign)?;
    let truth = match &opts.truth {
        Some(t) => Some(t.clone()),
        None => c
            .path
            .parent()
            .map(|d| d.join("truth"))
            .filter(|t| t.join("rays.parquet").is_file()),
    };
    let job = Job {
        out: &opts.out,
        model: opts.model.as_deref(),
        truth,
        experiments: opts.experiments.then_some(&opts.experiment_params),
        // the smaller run, as reproduce: `fit` makes the full one
        correction: Some(crate::correction::CorrectionParams::quick()),
        explore: opts.explore.as_deref(),
        progress,
    };
    run(
        &job,
        Source::Campaign {
            campaign: &c,
            energy: opts.energy.as_deref(),
        },
    )
}

/// The section `pradar explore` writes for a report (links under `explore/`).
pub const EXPLORE_SECTION: &str = "report_section.html";

/// `report --explore DIR`: DIR's files copied into `out/explore/` and its section.
fn explore_section(dir: &Path, out: &Path) -> Result<Section> {
    let dest = out.join("explore");
    std::fs::create_dir_all(&dest).map_err(|e| Error::io(&dest, e))?;
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut names: Vec<String> = rd
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != EXPLORE_SECTION)
        .collect();
    names.sort();
    for n in names {
        let bytes = std::fs::read(dir.join(&n)).map_err(|e| Error::io(dir.join(&n), e))?;
        crate::io::write_bytes(&dest.join(&n), &bytes)?;
    }
    let html = crate::io::read_text(&dir.join(EXPLORE_SECTION))?;
    Ok(Section {
        title: "Design space (explore)".into(),
        html,
    })
}

/// One run of the page: where it goes and what it uses beside the data.
pub(crate) struct Job<'a, 'p> {
    /// Report folder.
    pub out: &'a Path,
    /// Model for the check and the experiments (None: the fitted one).
    pub model: Option<&'a Path>,
    /// Truth folder for Table 1's truth column (a simulated source sets its own).
    pub truth: Option<PathBuf>,
    /// The experiments' parameters, when they run.
    pub experiments: Option<&'a ExperimentValid>,
    /// The bias correction of Table 1 (`crate::correction`), when it runs.
    pub correction: Option<crate::correction::CorrectionParams>,
    /// A `pradar explore` folder to show (`report --explore`).
    pub explore: Option<&'a Path>,
    /// Progress bars.
    pub progress: Progress<'p>,
}

/// Where the report's energy table comes from.
pub(crate) enum Source<'a> {
    /// Simulate this campaign into `work/simulated` (Touchstone sweeps), then its energy.
    Simulate(&'a Campaign),
    /// This campaign's sweeps (the energy computed into `work/`) or the given energy table.
    Campaign {
        /// The campaign.
        campaign: &'a Campaign,
        /// Its energy table, if given.
        energy: Option<&'a Path>,
    },
}

impl Source<'_> {
    /// The campaign as given (the simulator's input for [`Source::Simulate`]).
    fn input(&self) -> &Campaign {
        match self {
            Source::Simulate(c) => c,
            Source::Campaign { campaign, .. } => campaign,
        }
    }
}

/// Stage timings in run order.
#[derive(Default)]
pub(crate) struct Timings(Vec<(String, f64)>);

impl Timings {
    /// Run `f`, recording its wall time as `label`.
    fn time<T>(&mut self, label: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let t = Instant::now();
        let r = f()?;
        self.0.push((label.into(), t.elapsed().as_secs_f64()));
        Ok(r)
    }
}

/// The analysed campaign and its energy table.
struct Data {
    /// The analysed campaign (the simulated one for [`Source::Simulate`]).
    campaign: Campaign,
    /// What the simulator wrote, when it ran.
    sim: Option<SimReport>,
    /// Truth folder for the truth column.
    truth: Option<PathBuf>,
    /// The energy table's path.
    energy_path: PathBuf,
    /// Where the energy table came from, for the summary.
    energy_shown: String,
    /// The energy stage's warnings when it ran here (none for a given table).
    energy_warnings: Vec<String>,
    /// The energy table.
    em: EnergyMatrix,
}

/// Removes what a failed run created under the report folder ([`OutGuard::done`] keeps it).
pub(crate) struct OutGuard {
    /// The report folder.
    out: PathBuf,
    /// Whether it existed before the run.
    existed: bool,
    /// Its entries before the run.
    before: HashSet<OsString>,
    /// The run succeeded.
    kept: bool,
}

impl OutGuard {
    /// Create `out` (if needed), noting what was there.
    pub(crate) fn begin(out: &Path) -> Result<OutGuard> {
        let existed = out.exists();
        if existed && !out.is_dir() {
            return Err(Error::input(out, "--out: not a folder"));
        }
        let before = match existed {
            true => std::fs::read_dir(out)
                .map_err(|e| Error::io(out, e))?
                .filter_map(|e| e.ok().map(|e| e.file_name()))
                .collect(),
            false => HashSet::new(),
        };
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
        Ok(OutGuard {
            out: out.to_path_buf(),
            existed,
            before,
            kept: false,
        })
    }

    /// The run succeeded: keep its files.
    pub(crate) fn done(mut self) {
        self.kept = true;
    }
}

impl Drop for OutGuard {
    fn drop(&mut self) {
        if self.kept {
            return;
        }
        if !self.existed {
            let _ = std::fs::remove_dir_all(&self.out);
            return;
        }
        if let Ok(rd) = std::fs::read_dir(&self.out) {
            for e in rd.flatten() {
                if self.before.contains(&e.file_name()) {
                    continue;
                }
                let p = e.path();
                let _ = match e.file_type().map(|t| t.is_dir()) {
                    Ok(true) => std::fs::remove_dir_all(&p),
                    _ => std::fs::remove_file(&p),
                };
            }
        }
    }
}

/// The page's one code path: obtain the energy table from `source`, analyse it, and write
/// every section into `job.out`; returns the index path. A failure removes what it made.
pub(crate) fn run(job: &Job, source: Source) -> Result<ReportOutput> {
    let guard = OutGuard::begin(job.out)?;
    let done = run_inner(job, source)?;
    guard.done();
    Ok(done)
}

/// [`run`] without the guard (`reproduce` holds its own, made before it writes its input).
pub(crate) fn run_inner(job: &Job, source: Source) -> Result<ReportOutput> {
    let (out, progress) = (job.out, job.progress);
    let work = out.join("work");
    std::fs::create_dir_all(&work).map_err(|e| Error::io(&work, e))?;
    let started = Instant::now();
    let mut timings = Timings::default();
    let input = source.input();
    let scene = has_scene(input)?;
    // the geometry-only chain is independent of the main one (its own files): it runs on
    // a side thread beside energy → fit report, without progress bars (one bar at a time
    // on the terminal); then that thread makes the experiments' sweeps at the other N,
    // which need only the analysed campaign with its [scene] (fig6 would make them the
    // same way)
    let own = input.manifest.array.elements;
    let sizes: Vec<usize> = match (job.experiments, scene) {
        (Some(p), true) => (p.compare_elements.iter())
            .copied()
            .filter(|&n| n != own)
            .collect(),
        _ => Vec::new(),
    };
    let (to_side, analysed) = std::sync::mpsc::channel::<PathBuf>();
    let (main, (geometry, geometry_s, presim)) = std::thread::scope(|scope| {
        let work = &work;
        let exp_dir = out.join("experiments");
        let side = scope.spawn(move || {
            let t = Instant::now();
            let quiet = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
            let html = match scene {
                true => geometry_only_table(input, &work.join("geometry"), out, &quiet)
                    .unwrap_or_else(|e| page::failed("geometry-only fit", &e)),
                false => page::not_run(
                    "the campaign has no [scene] section (a measured campaign): the geometry-only table simulates the campaign without its clutter",
                ),
            };
            let secs = t.elapsed().as_secs_f64();
            let presim: Vec<(usize, Result<(PathBuf, PathBuf)>)> = match analysed.recv() {
                Ok(manifest) => (sizes.into_iter())
                    .map(|n| (n, experiment::lab::simulate_sweeps(&manifest, &exp_dir, n)))
                    .collect(),
                Err(_) => Vec::new(),
            };
            (html, secs, presim)
        });
        let main = (|| -> Result<_> {
            let s = obtain(job, &source, work, &mut timings)?;
            if job.experiments.is_some() {
                let _ = to_side.send(s.campaign.path.clone());
            }
            drop(to_side);
            let mut a = analyse(&s.campaign, &s.em, &s.energy_path, work, true)?;
            timings.0.append(&mut a.timings);
            let mut correction_note = None;
            if let Some(p) = job.correction {
                let label = format!("bias correction (R = {})", p.draws);
                correction_note = timings.time(&label, || {
                    Ok(correct_fit(&s, &mut a, &p.check()?, job.progress))
                })?;
            }
            let table1 = timings.time("fit report (truth, plots)", || {
                table1_section(&s, &a, work, out)
            })?;
            let table1 = table1 + correction_note.as_deref().unwrap_or("");
            let check = timings.time("check (20 synth draws)", || {
                Ok(check_section(job, &s, &a, progress))
            })?;
            Ok((s, a, table1, check))
        })();
        (main, side.join().expect("geometry-only thread"))
    });
    let (s, a, table1, check) = main?;
    timings.0.push((
        "geometry-only Table 1 (simulate → fit; beside the stages above)".into(),
        geometry_s,
    ));
    timings.time("report plots", || write_plots(&s, &a, out, progress))?;
    let maps = timings.time("maps (OG, OG boresight, EKF)", || {
        Ok(
            crate::mapping::job::report_maps(&s.campaign.path, &s.energy_path, &out.join("maps"))
                .map(|maps| crate::report::maps::report_section(&maps, "maps"))
                .unwrap_or_else(|e| Section {
                    title: "Maps".into(),
                    html: page::failed("mapping", &e),
                }),
        )
    })?;
    let experiments = match job.experiments {
        Some(p) => timings.time(
            "experiments (fig5, fig6, prior-sensitivity, pose-noise)",
            || Ok(run_experiments(job, p, &s, &a.fit, presim)),
        )?,
        None => Vec::new(),
    };
    let mut experiments = experiments;
    if let Some(d) = job.explore {
        experiments.push(explore_section(d, out).unwrap_or_else(|e| Section {
            title: "Design space (explore)".into(),
            html: page::failed("the explore section", &e),
        }));
    }
    let name = &s.campaign.manifest.name;
    let index = out.join("index.html");
    let report_page = ReproducePage {
        title: format!("pradar report: {name}"),
        name: name.clone(),
        campaign: campaign_summary(&s),
        labels: (0..s.em.positions)
            .map(|p| s.campaign.manifest.label(p))
            .collect(),
        check,
        table1,
        geometry,
        mpcs: mpc_summary(&a, &s.campaign.manifest),
        maps,
        experiments,
        timings: timings.0,
        wall_s: started.elapsed().as_secs_f64(),
    };
    page::write_index(&index, &report_page)?;
    Ok(ReportOutput {
        index,
        warnings: s.energy_warnings,
    })
}

/// The energy table of the source: simulated then computed, computed from the campaign's
/// sweeps, or read as given.
fn obtain(job: &Job, source: &Source, work: &Path, timings: &mut Timings) -> Result<Data> {
    let progress = job.progress;
    let energy_path = work.join("energy.parquet");
    // the energy stage's warnings go on to the page and the command line
    let compute = |c: &Campaign, timings: &mut Timings| -> Result<Vec<String>> {
        timings.time("energy", || {
            let cb = progress("energy", c.manifest.positions());
            energy::run(c, &energy_path, &*cb).map(|r| r.warnings)
        })
    };
    let (campaign, sim, truth, energy_path, energy_shown, energy_warnings) = match source {
        Source::Simulate(c) => {
            let dir = work.join("simulated");
            let sim = timings.time("simulate", || {
                let cb = progress("simulate", c.manifest.positions());
                simulate(c, &dir, SweepFormat::Touchstone, &*cb)
            })?;
            let sc = Campaign::load(&sim.manifest)?;
            let warnings = compute(&sc, timings)?;
            let truth = Some(dir.join("truth"));
            (
                sc,
                Some(sim),
                truth,
                energy_path,
                "work/energy.parquet".into(),
                warnings,
            )
        }
        Source::Campaign { campaign, energy } => {
            let c = (*campaign).clone();
            match energy {
                Some(e) => {
                    let shown = format!("{} (given)", e.display());
                    (
                        c,
                        None,
                        job.truth.clone(),
                        e.to_path_buf(),
                        shown,
                        Vec::new(),
                    )
                }
                None => {
                    let warnings = compute(&c, timings)?;
                    let shown = "work/energy.parquet (computed from the sweeps)".into();
                    (c, None, job.truth.clone(), energy_path, shown, warnings)
                }
            }
        }
    };
    let em = EnergyMatrix::read(&energy_path)?;
    crate::energy::matrix::check_campaign(&campaign, &em, &energy_path)?;
    Ok(Data {
        campaign,
        sim,
        truth,
        energy_path,
        energy_shown,
        energy_warnings,
        em,
    })
}

/// The predictive check of the model (`--model`, else the fitted one) against the
/// campaign's energy table (`out/check/`: table, CDF panels): the section, or why it did
/// not run.
fn check_section(job: &Job, s: &Data, a: &Analysis, progress: Progress) -> Section {
    let title = "Does the fitted model reproduce the channel?";
    let name = &s.campaign.manifest.name;
    let run = || -> Result<Section> {
        let (model, what) = match job.model {
            Some(m) => (
                crate::model::file::ModelConfig::load(m)?,
                format!(
                    "the model {} against the energy table of {name}",
                    m.display()
                ),
            ),
            None => {
                let f = a
                    .fit
                    .as_ref()
                    .map_err(|e| Error::param("fit", e.to_string()))?;
                (
                    f.model_out().require_estimable(&Default::default())?,
                    format!(
                        "the fitted model (fitted_model.toml) against the energy table of {name}"
                    ),
                )
            }
        };
        let params = crate::check::CheckParams::default().check()?;
        let cb = progress("check", params.draws);
        let r = crate::check::check(&s.campaign, &s.em, &s.energy_path, &model, &params, &*cb)?;
        crate::report::check::write(&job.out.join("check"), &what, &r)?;
        Ok(crate::report::check::section(
            title,
            &what,
            &r,
            "check/check_cdfs.png",
        ))
    };
    run().unwrap_or_else(|e| Section {
        title: title.into(),
        html: page::failed("check", &e),
    })
}

/// The bias correction of the analysis's fit (`crate::correction`) with the partition
/// stability of its clustering, kept in the fit; a correction that fails leaves the fit as
/// the paper's method gave it (Table 1 then has no corrected column) and returns the
/// page's note saying why.
fn correct_fit(
    s: &Data,
    a: &mut Analysis,
    p: &crate::correction::CorrectionValid,
    progress: Progress,
) -> Option<String> {
    let Ok(f) = &mut a.fit else {
        return None;
    };
    let cb = progress("correct", 0);
    let run = || -> Result<crate::fit::corrected::Corrected> {
        let mut c =
            crate::correction::correct(&s.campaign, &s.em, &s.energy_path, f, p, &|d, t| cb(d, t))?;
        let headings: Vec<f64> = s
            .campaign
            .manifest
            .poses
            .iter()
            .map(|p| p.heading_deg)
            .collect();
        let params = a.cluster_params.check()?;
        c.stability = Some(crate::correction::stability::partition_stability(
            &a.clustering.mpcs,
            &a.clustering.cluster_id,
            &headings,
            &params,
            p.resamples,
            p.seed.unwrap_or(s.campaign.manifest.seed),
        )?);
        Ok(c)
    };
    match run() {
        Ok(c) => {
            f.correction = Some(c);
            None
        }
        Err(e) => Some(page::failed("the bias correction", &e)),
    }
}

/// Table 1 (`fitted_model.toml`, `table1.md`, the fit plots) beside the simulator's truth
/// through the same estimators when there is one (else the page says why there is no truth
/// column), the K note and the K_max table: the section's HTML.
fn table1_section(s: &Data, a: &Analysis, work: &Path, out: &Path) -> Result<String> {
    let name = &s.campaign.manifest.name;
    let (truth, truth_note) = match &s.truth {
        None => (
            None,
            "<p>No truth column: the campaign has no simulator's truth folder (a measured campaign).</p>\n".to_string(),
        ),
        Some(dir) => match crate::fit::channel::fit_truth(dir, &s.campaign, &Default::default()) {
            Ok(t) => (Some(t), String::new()),
            Err(e) => (None, format!("<p>No truth column: {}</p>\n", crate::report::html_escape(&format!("the fit of the truth in {} failed: {e}", dir.display())))),
        },
    };
    let table1 = match &a.fit {
        Ok(f) => {
            let model = f.model_out();
            model.check()?;
            model.save(&out.join("fitted_model.toml"))?;
            crate::fit::channel::write_table1(&out.join("table1.md"), name, f, truth.as_ref())?;
            let plots = write_fit_plots(f, out)?;
            page::table1_fitted_html(name, &table1_html_rows(f, truth.as_ref()), &plots)
        }
        Err(e) => page::failed("fit", e),
    };
    let kmax = match k_max_sensitivity(
        &s.campaign,
        &a.clustering,
        &a.cluster_params,
        a.fit.as_ref().ok(),
        truth.as_ref(),
        work,
        out,
    ) {
        Ok(t) => page::kmax_html(&t),
        Err(e) => page::failed("K_max sensitivity", &e),
    };
    let note = page::k_cap_note(&a.clustering, a.cluster_params.k_max);
    Ok(page::table1_html(
        &note,
        &format!("{table1}{truth_note}"),
        &kmax,
    ))
}
/// `out/fit_<quantity>.png` per fitted quantity with at least 2 samples (none for a quantity
/// that is not estimable: it has no samples, and Table 1 says why).
fn write_fit_plots(f: &ChannelFit, out: &Path) -> Result<Vec<FitPlot>> {
    let mut plots = Vec::new();
    for (name, d) in &f.details {
        if d.samples.len() < 2 {
            plots.push((name.clone(), None));
            continue;
        }
        let png = format!("fit_{name}.png");
        report::fit_plot(&out.join(&png), name, &d.q.unit, &d.samples, &d.fitted)?;
        plots.push((name.clone(), Some(png)));
    }
    Ok(plots)
}

/// An MPC as (angle_rel_deg, delay_ns, power_db) for the cluster plots.
type Point3 = (f64, f64, f64);
/// Per position the energy heat map with its MPCs marked and the MPCs coloured by cluster;
/// then every MPC and centroid in the global frame (`mpcs_global.png`).
fn write_plots(s: &Data, a: &Analysis, out: &Path, progress: Progress) -> Result<()> {
    let (em, mpcs, clustering) = (&s.em, &a.mpcs, &a.clustering);
    let cb = progress("plots", s.campaign.manifest.positions());
    let max_delay = em.delay_ns(em.bins - 1);
    for p in 0..em.positions {
        let marks: Vec<(f64, f64)> = mpcs
            .iter()
            .filter(|m| m.position == p)
            .map(|m| (m.angle_rel_deg, crate::units::range_m(m.delay_ns)))
            .collect();
        let heat = out.join(format!("energy_p{p:02}.png"));
        let label = s.campaign.manifest.label(p);
        report::energy_heatmap(em, p, &label, &heat, -60.0, &marks)?;
        // the position's MPCs with their labels local to the position (None: diffuse)
        let mut labels = clustering.positions[p].labels.iter();
        let (pts, local): (Vec<Point3>, Vec<Option<usize>>) = mpcs
            .iter()
            .filter(|m| m.position == p)
            .map(|m| {
                let l = match m.component {
                    crate::mpc::Component::Discrete => labels.next().copied(),
                    crate::mpc::Component::Diffuse => None,
                };
                ((m.angle_rel_deg, m.delay_ns, m.power_db), l)
            })
            .unzip();
        report::mpc_clusters_plot(
            &out.join(format!("clusters_p{p:02}.png")),
            &format!(
                "position {label}: {} MPCs ({} diffuse) in {} clusters",
                pts.len(),
                local.iter().filter(|l| l.is_none()).count(),
                clustering.positions[p].k
            ),
            &pts,
            &local,
            max_delay,
        )?;
        cb(p + 1, em.positions);
    }
    let layout = crate::campaign::Layout::load(&s.campaign.layout_path())?;
    let poses: Vec<(f64, f64)> = (s.campaign.manifest.poses.iter())
        .map(|p| (p.x_m, p.y_m))
        .collect();
    let pts: Vec<(f64, f64, Option<usize>)> = mpcs
        .iter()
        .zip(&clustering.cluster_id)
        .map(|(m, &c)| (m.x_m, m.y_m, c))
        .collect();
    let cents: Vec<(f64, f64, usize)> = (clustering.summary.iter())
        .map(|s| (s.centroid_x_m, s.centroid_y_m, s.cluster_id))
        .collect();
    report::global_map_plot(&out.join("mpcs_global.png"), &layout, &poses, &pts, &cents)
}

/// The mapping experiments on the campaign's sweeps and the model (`--model`, else the
/// fitted one), into `out/experiments`: their sections, or one saying why they did not run
/// (the fit failed or left a quantity not estimable: the model data need every quantity;
/// or an experiment failed).
fn run_experiments(
    job: &Job,
    params: &ExperimentValid,
    s: &Data,
    fit: &Result<ChannelFit>,
    presim: Vec<(usize, Result<(PathBuf, PathBuf)>)>,
) -> Vec<Section> {
    let dir = job.out.join("experiments");
    let not_run = match (job.model, fit) {
        (Some(_), _) => None,
        (None, Err(e)) => Some(page::experiments_not_run(e)),
        // a schema-1 style partial model (no stated values) cannot be drawn from
        (None, Ok(f)) if f.model.require_estimable(&Default::default()).is_err() => {
            Some(page::experiments_not_run_partial(&f.model.not_estimable()))
        }
        (None, Ok(_)) => None,
    };
    if let Some(section) = not_run {
        remove_experiments(&dir, &presim);
        return vec![section];
    }
    let inputs = experiment::ExperimentInputs {
        campaign: s.campaign.path.clone(),
        energy: s.energy_path.clone(),
        model: match job.model {
            Some(m) => m.to_path_buf(),
            None => job.out.join("fitted_model.toml"),
        },
    };
    let run = || -> Result<Vec<Section>> {
        let mut lab = experiment::Lab::new(inputs, params.clone(), &dir, job.progress)?;
        // sweeps made beside the fit (one that failed is left to the lab, which reports it)
        for (n, r) in presim {
            if let Ok(r) = r {
                lab.preset_sweeps(n, r);
            }
        }
        lab.prepare(&experiment::Experiment::ALL)?;
        let mut sections = Vec::new();
        for e in experiment::Experiment::ALL {
            let r = lab.run(e)?;
            report::experiments::write_figures(&r, &dir)?;
            sections.push(report::experiments::section(&r, "experiments/"));
        }
        Ok(sections)
    };
    run().unwrap_or_else(|e| {
        let _ = std::fs::remove_dir_all(&dir);
        vec![Section {
            title: "Experiments".into(),
            html: page::failed("the experiments", &e),
        }]
    })
}

/// The sweeps made beside the fit for experiments that do not run are not the report's:
/// removed with their folders.
fn remove_experiments(dir: &Path, presim: &[(usize, Result<(PathBuf, PathBuf)>)]) {
    for (n, _) in presim {
        let sweeps = experiment::lab::sweeps_dir(dir, *n);
        if sweeps.exists() {
            let _ = std::fs::remove_dir_all(&sweeps);
        }
    }
    let _ = std::fs::remove_dir(dir.join("work"));
    let _ = std::fs::remove_dir(dir);
}

/// The campaign summary of the report: band, array, positions, directions, what the
/// simulator (when it ran) and the energy stage did.
fn campaign_summary(s: &Data) -> Vec<(String, String)> {
    let (m, em) = (&s.campaign.manifest, &s.em);
    let mut rows = vec![
        ("campaign".to_string(), m.name.clone()),
        (
            "band".into(),
            format!(
                "{:.3}–{:.3} GHz, {} points",
                m.band.start_hz / 1e9,
                m.band.stop_hz / 1e9,
                m.band.points
            ),
        ),
        (
            "array".into(),
            format!("{} elements ({})", m.array.elements, m.array.label()),
        ),
        (
            "positions".into(),
            if m.labels.is_empty() {
                m.positions().to_string()
            } else {
                format!("{} ({})", m.positions(), m.labels.join(", "))
            },
        ),
        (
            "directions".into(),
            format!(
                "{} ({}° to {}° step {}°)",
                m.directions.count(),
                m.directions.start_deg,
                m.directions.stop_deg,
                m.directions.step_deg
            ),
        ),
        ("pulses".into(), m.pulses.to_string()),
    ];
    match &s.sim {
        Some(sim) => rows.extend([
            ("sweeps".into(), sim.sweeps.to_string()),
            ("scatterers (truth)".into(), sim.scatterers.to_string()),
            ("clutter clusters (truth)".into(), sim.clusters.to_string()),
        ]),
        None => rows.push((
            "sweeps".into(),
            format!(
                "{} (manifest {})",
                (m.positions() * m.directions.count() - m.missing().len()) * m.pulses,
                s.campaign.path.display()
            ),
        )),
    }
    let missing = m.missing();
    if !missing.is_empty() {
        rows.push((
            "missing sweeps (skipped by every stage)".into(),
            missing
                .iter()
                .map(|&(p, d)| {
                    format!("position {}, direction {}", m.label(p), m.direction_name(d))
                })
                .collect::<Vec<_>>()
                .join("; "),
        ));
    }
    if let Some(dropped) = m
        .sweeps
        .as_ref()
        .map(|s| &s.dropped_positions)
        .filter(|d| !d.is_empty())
    {
        rows.push(("positions left out (no sweep)".into(), dropped.join(", ")));
    }
    rows.extend([
        (
            "bin width".into(),
            format!("{:.4} ns", em.meta.bin_width_ns),
        ),
        ("bins kept".into(), em.bins.to_string()),
        (
            "window ENBW / TW".into(),
            format!("{:.3} / {:.3}", em.meta.enbw, em.meta.tw),
        ),
        ("coupling removal".into(), em.meta.coupling.clone()),
        (
            "N0 (estimated)".into(),
            format!("{:.3e} ({:.1} dB)", em.meta.n0, 10.0 * em.meta.n0.log10()),
        ),
    ]);
    // the energy stage's warning (the manifest's [noise] floor far from N0), as printed
    rows.extend(
        (s.energy_warnings.iter()).map(|w| ("N0 warning".to_string(), format!("warning: {w}"))),
    );
    if s.sim.is_some() {
        rows.push((
            "noise floor (configured)".into(),
            format!(
                "{} dBm per point at {} dBm",
                m.noise.floor_dbm, m.noise.tx_power_dbm
            ),
        ));
    }
    rows.push(("energy table".into(), s.energy_shown.clone()));
    rows
}

/// The MPC and cluster summary: counts, files and K per position.
fn mpc_summary(a: &Analysis, m: &crate::campaign::manifest::Manifest) -> Vec<(String, String)> {
    let positions = m.positions();
    let ks: Vec<String> = (a.clustering.positions.iter().enumerate())
        .map(|(p, c)| match m.labels.get(p) {
            Some(l) => format!("{l}: {}", c.k),
            None => c.k.to_string(),
        })
        .collect();
    vec![
        (
            "MPCs".to_string(),
            format!(
                "{} over {} positions (work/mpcs.parquet)",
                a.mpcs.len(),
                positions
            ),
        ),
        (
            "clusters".to_string(),
            format!(
                "{} (work/clusters.parquet, work/clusters_summary.parquet)",
                a.clustering.summary.len()
            ),
        ),
        (
            "K per position (cross-validated criterion)".to_string(),
            ks.join(", "),
        ),
    ]
}
