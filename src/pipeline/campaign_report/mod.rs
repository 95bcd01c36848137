//! `pradar report` ([`report`]): the report of any campaign, measured or simulated, and the
//! one code path of the report page, which `pradar reproduce` ([`super::reproduce`]) takes
//! after simulating the built-in corridor.
//!
//! Takes a campaign manifest with its sweeps (or an energy table of them), optionally a
//! model file and a simulator's truth folder; gives `out/index.html` with the campaign
//! summary, the energy heat maps with their MPCs, the clusters, Table 1 (titled with the
//! campaign's name; a truth column only with a truth), the fitted model with its predictive
//! check (and the held-out check: a model fitted on each half of the walk, checked on the
//! other), the OG and EKF maps with their metrics against the layout, the experiments, and
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
//!
//! Layout: this module holds the options, the job and its source, the output guard and the
//! scheduler ([`run_inner`]); [`gather`] obtains the energy table,
//! [`render`] writes the sections (Table 1, the check, the plots, the summaries), and
//! [`experiments`] runs the mapping experiments.

mod experiments;
mod gather;
mod render;

use super::experiment::{self, ExperimentValid};
use super::geometry::geometry_only_table;
use super::{analyse, Progress};
use crate::campaign::manifest::Campaign;
use crate::error::{Error, Result};
use crate::params::{ParamGuard, Valid};
use crate::report::reproduce::{self as page, ReproducePage};
use crate::report::Section;
use crate::simulate::has_scene;
use experiments::run_experiments;
use gather::obtain;
use render::{
    campaign_summary, check_section, closed_loop_note, explore_section, holdout_html, mpc_summary,
    table1_section, write_plots,
};
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
/// energy stage's `[noise]` floor far from the data's N0,
/// [`energy::EnergyReport::warnings`](crate::energy::EnergyReport::warnings), also shown on
/// the page beside N0) for the command line to print.
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
            let closed_loop = timings.time(
                "closed loop (the chain on draws of the written model)",
                || Ok(closed_loop_note(&s, &mut a, progress)),
            )?;
            let table1 = timings.time("fit report (truth, plots)", || {
                table1_section(&s, &a, &closed_loop, work, out)
            })?;
            let check = timings.time("check (20 synth draws)", || {
                Ok(check_section(job, &s, &a, progress))
            })?;
            // the held-out check beside the in-sample one, in its section
            let held_out = timings.time(
                "held-out check (fit on each half, check on the other)",
                || Ok(holdout_html(job, &s, progress)),
            )?;
            let check = Section {
                html: check.html + &held_out,
                ..check
            };
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
