//! `pradar reproduce` ([`reproduce`]) as named steps: load the campaign, simulate it and
//! compute its energy table, analyse it (CLEAN → K-means → fit), write Table 1 with its fit
//! plots and the K_max table, Table 1 of the corridor without clutter, the heat maps and
//! cluster plots, the maps, the experiments, and the report page
//! ([`crate::report::reproduce`]).
//!
//! Scheduling: the geometry-only chain has its own files, so it runs on a side thread
//! beside simulate → energy → analysis → fit report, and then makes the experiments' sweeps
//! at the other N of fig6 once the main simulation has written its campaign (the lab takes
//! them instead of simulating them again). Every output is a pure function of its inputs,
//! so the files are the same whatever runs beside what; the page's stage timings say which
//! stage ran beside the others and its total is the job's wall time.
//!
//! Options are checked once ([`ReproduceOptions`] → [`ReproduceValid`]). A failed fit, K_max
//! table or geometry-only table is reported on the page, not raised: the rest of the report
//! still stands; any other error stops the job. A partial fit (a quantity not estimable) is
//! written and shown with its reasons in Table 1; the experiments, whose model data need
//! every quantity, are then not run and the page says why.

use super::experiment::{self, ExperimentValid};
use super::geometry::geometry_only_table;
use super::kmax::k_max_sensitivity;
use super::{analyse, table1_html_rows, write_builtin_corridor, Analysis, Progress};
use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::campaign::simulate::{simulate, SimReport};
use crate::energy::{self, EnergyMatrix, EnergyReport};
use crate::error::{Error, Result};
use crate::fit::channel::ChannelFit;
use crate::params::{ParamGuard, Valid};
use crate::report::reproduce::{self as page, FitPlot, ReproducePage};
use crate::report::{self, Section};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `reproduce` (checked by [`ParamGuard::check`] into a [`ReproduceValid`]).
#[derive(Debug, Clone)]
pub struct ReproduceOptions {
    /// Report folder (`reports/corridor`).
    pub out: PathBuf,
    /// Manifest to use instead of the built-in corridor.
    pub campaign: Option<PathBuf>,
    /// `--elements` override.
    pub elements: Option<usize>,
    /// Run the mapping experiments ([`experiment`]) into `out/experiments` (default true).
    pub experiments: bool,
    /// Their parameters, checked.
    pub experiment_params: ExperimentValid,
}

/// [`ReproduceOptions`] that passed their check.
pub type ReproduceValid = Valid<ReproduceOptions>;

impl ParamGuard for ReproduceOptions {
    type Checked = ReproduceValid;

    /// `--elements` a perfect square (16, 100, 400); the experiment parameters are checked
    /// by their type.
    fn check(&self) -> Result<ReproduceValid> {
        if let Some(n) = self.elements {
            let s = (n as f64).sqrt().round() as usize;
            if n == 0 || s * s != n {
                return Err(Error::param(
                    "--elements",
                    format!("{n} is not a perfect square (use 16, 100 or 400)"),
                ));
            }
        }
        Ok(Valid::new(self.clone()))
    }
}

/// Stage timings in run order.
#[derive(Default)]
struct Timings(Vec<(String, f64)>);

impl Timings {
    /// Run `f`, recording its wall time as `label`.
    fn time<T>(&mut self, label: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let t = Instant::now();
        let r = f()?;
        self.0.push((label.into(), t.elapsed().as_secs_f64()));
        Ok(r)
    }
}

/// The simulated campaign and its energy table.
struct Simulated {
    /// `work/simulated` (with the simulator's `truth/`).
    dir: PathBuf,
    /// What the simulator wrote.
    sim: SimReport,
    /// The simulated campaign (its manifest points at the sweeps).
    campaign: Campaign,
    /// `work/energy.parquet`.
    energy_path: PathBuf,
    /// What the energy stage reported.
    energy: EnergyReport,
    /// The energy table.
    em: EnergyMatrix,
}

/// Run the main job; returns the index path.
///
/// ```no_run
/// use pradar::params::ParamGuard;
/// use pradar::pipeline::experiment::ExperimentParams;
/// use pradar::pipeline::{reproduce, ReproduceOptions};
/// let opts = ReproduceOptions {
///     out: "reports/corridor".into(),
///     campaign: None,
///     elements: None,
///     experiments: false,
///     experiment_params: ExperimentParams::default().check()?,
/// }
/// .check()?;
/// let progress = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
/// let index = reproduce(&opts, &progress)?;
/// println!("report: {}", index.display());
/// # Ok::<(), pradar::error::Error>(())
/// ```
pub fn reproduce(opts: &ReproduceValid, progress: Progress) -> Result<PathBuf> {
    let out = &opts.out;
    let work = out.join("work");
    std::fs::create_dir_all(&work).map_err(|e| Error::io(&work, e))?;
    let started = Instant::now();
    let mut timings = Timings::default();
    let c = load_campaign(opts, &work)?;
    let np = c.manifest.positions();
    // the geometry-only chain is independent of the main one (its own files): it runs on
    // a side thread beside simulate → fit report, without progress bars (one bar at a time
    // on the terminal); then that thread makes the experiments' sweeps at the other N,
    // which need only the simulated campaign (fig6 would make them the same way)
    let own = c.manifest.array.elements;
    let sizes: Vec<usize> = match opts.experiments {
        true => (opts.experiment_params.compare_elements.iter())
            .copied()
            .filter(|&n| n != own)
            .collect(),
        false => Vec::new(),
    };
    let (to_side, simulated) = std::sync::mpsc::channel::<PathBuf>();
    let (main, (geometry, geometry_s, presim)) = std::thread::scope(|scope| {
        let (c, work) = (&c, &work);
        let exp_dir = out.join("experiments");
        let side = scope.spawn(move || {
            let t = Instant::now();
            let quiet = |_: &str, _: usize| -> Box<dyn Fn(usize, usize)> { Box::new(|_, _| {}) };
            let html = geometry_only_table(c, &work.join("geometry"), out, &quiet)
                .unwrap_or_else(|e| page::failed("geometry-only fit", &e));
            let secs = t.elapsed().as_secs_f64();
            let presim: Vec<(usize, Result<(PathBuf, PathBuf)>)> = match simulated.recv() {
                Ok(manifest) => (sizes.into_iter())
                    .map(|n| (n, experiment::lab::simulate_sweeps(&manifest, &exp_dir, n)))
                    .collect(),
                Err(_) => Vec::new(),
            };
            (html, secs, presim)
        });
        let main = (move || -> Result<_> {
            let s = simulate_campaign(c, work, progress, &mut timings)?;
            if opts.experiments {
                let _ = to_side.send(s.sim.manifest.clone());
            }
            drop(to_side);
            let mut a = analyse(&s.campaign, &s.em, work, true)?;
            timings.0.append(&mut a.timings);
            let table1 = timings.time("fit report (truth, plots)", || {
                table1_section(&s, &a, work, out)
            })?;
            let check = timings.time("check (fitted model, 20 synth draws)", || {
                Ok(check_section(&s, &a, out, progress))
            })?;
            Ok((s, a, table1, check, timings))
        })();
        (main, side.join().expect("geometry-only thread"))
    });
    let (s, a, table1, check, mut timings) = main?;
    timings.0.push((
        "geometry-only Table 1 (simulate → fit; beside the stages above)".into(),
        geometry_s,
    ));
    timings.time("report plots", || write_plots(&s, &a, out, progress))?;
    let maps = timings.time("maps (OG, OG boresight, EKF)", || {
        crate::report::maps::report_section(&s.sim.manifest, &s.energy_path, out, "maps")
    })?;
    let experiments = if opts.experiments {
        timings.time(
            "experiments (fig5, fig6, prior-sensitivity, pose-noise)",
            || run_experiments(opts, &s, &a.fit, presim, progress),
        )?
    } else {
        Vec::new()
    };
    let index = out.join("index.html");
    let report_page = ReproducePage {
        title: format!("pradar report: {}", s.campaign.manifest.name),
        campaign: campaign_summary(&s, np),
        positions: s.em.positions,
        check,
        table1,
        geometry,
        mpcs: mpc_summary(&a, s.em.positions),
        maps,
        experiments,
        timings: timings.0,
        wall_s: started.elapsed().as_secs_f64(),
    };
    page::write_index(&index, &report_page)?;
    Ok(index)
}

/// The campaign (the built-in corridor unless `--campaign`, written into `work/input`) with
/// the `--elements` override.
fn load_campaign(opts: &ReproduceOptions, work: &Path) -> Result<Campaign> {
    let src = match &opts.campaign {
        Some(p) => p.clone(),
        None => write_builtin_corridor(&work.join("input"))?,
    };
    let mut c = Campaign::load(&src)?;
    if let Some(n) = opts.elements {
        c.set_elements(n)?;
    }
    Ok(c)
}

/// Simulate `c` into `work/simulated` (Touchstone sweeps) and compute its energy table.
fn simulate_campaign(
    c: &Campaign,
    work: &Path,
    progress: Progress,
    timings: &mut Timings,
) -> Result<Simulated> {
    let np = c.manifest.positions();
    let dir = work.join("simulated");
    let sim = timings.time("simulate", || {
        let cb = progress("simulate", np);
        simulate(c, &dir, SweepFormat::Touchstone, &*cb)
    })?;
    let energy_path = work.join("energy.parquet");
    let (campaign, energy) = timings.time("energy", || {
        let sc = Campaign::load(&sim.manifest)?;
        let cb = progress("energy", np);
        let er = energy::run(&sc, &energy_path, &*cb)?;
        Ok((sc, er))
    })?;
    let em = EnergyMatrix::read(&energy_path)?;
    Ok(Simulated {
        dir,
        sim,
        campaign,
        energy_path,
        energy,
        em,
    })
}

/// The predictive check of the fitted model against the campaign's energy table
/// (`out/check/`: table, CDF panels): the section, or why it did not run.
fn check_section(s: &Simulated, a: &Analysis, out: &Path, progress: Progress) -> Section {
    let title = "Does the fitted model reproduce the channel?";
    let run = || -> Result<Section> {
        let f = a
            .fit
            .as_ref()
            .map_err(|e| Error::param("fit", e.to_string()))?;
        let model = f.model.require_estimable(&Default::default())?;
        let params = crate::check::CheckParams::default().check()?;
        let cb = progress("check", params.draws);
        let r = crate::check::check(&s.campaign, &s.em, &s.energy_path, &model, &params, &*cb)?;
        let what = "the fitted model (fitted_model.toml) against the corridor's energy table";
        crate::report::check::write(&out.join("check"), what, &r)?;
        Ok(crate::report::check::section(
            title,
            what,
            &r,
            "check/check_cdfs.png",
        ))
    };
    run().unwrap_or_else(|e| Section {
        title: title.into(),
        html: page::failed("check", &e),
    })
}

/// Table 1 (`fitted_model.toml`, `table1.md`, the fit plots) beside the simulator's truth
/// through the same estimators, the K note and the K_max table: the section's HTML.
fn table1_section(s: &Simulated, a: &Analysis, work: &Path, out: &Path) -> Result<String> {
    let truth =
        crate::fit::channel::fit_truth(&s.dir.join("truth"), &s.campaign, &Default::default()).ok();
    let table1 = match &a.fit {
        Ok(f) => {
            f.model.save(&out.join("fitted_model.toml"))?;
            crate::fit::channel::write_table1(&out.join("table1.md"), f, truth.as_ref())?;
            let plots = write_fit_plots(f, out)?;
            page::table1_fitted_html(&table1_html_rows(f, truth.as_ref()), &plots)
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
    Ok(page::table1_html(&note, &table1, &kmax))
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
fn write_plots(s: &Simulated, a: &Analysis, out: &Path, progress: Progress) -> Result<()> {
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
        report::energy_heatmap(em, p, &heat, -60.0, &marks)?;
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
                "position {p}: {} MPCs ({} diffuse) in {} clusters",
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

/// The mapping experiments on the simulated sweeps and the fitted model, into
/// `out/experiments` (not run when the fit failed or left a quantity not estimable: the
/// model data need every quantity).
fn run_experiments(
    opts: &ReproduceValid,
    s: &Simulated,
    fit: &Result<ChannelFit>,
    presim: Vec<(usize, Result<(PathBuf, PathBuf)>)>,
    progress: Progress,
) -> Result<Vec<Section>> {
    let not_run = match fit {
        Err(e) => Some(page::experiments_not_run(e)),
        Ok(f) if !f.model.not_estimable().is_empty() => {
            Some(page::experiments_not_run_partial(&f.model.not_estimable()))
        }
        Ok(_) => None,
    };
    if let Some(section) = not_run {
        // the sweeps made beside the fit are not the report's: removed with their folders
        let dir = opts.out.join("experiments");
        for (n, _) in &presim {
            let sweeps = experiment::lab::sweeps_dir(&dir, *n);
            if sweeps.exists() {
                std::fs::remove_dir_all(&sweeps).map_err(|e| Error::io(&sweeps, e))?;
            }
        }
        let _ = std::fs::remove_dir(dir.join("work"));
        let _ = std::fs::remove_dir(&dir);
        return Ok(vec![section]);
    }
    let inputs = experiment::ExperimentInputs {
        campaign: s.sim.manifest.clone(),
        energy: s.energy_path.clone(),
        model: opts.out.join("fitted_model.toml"),
    };
    let mut lab = experiment::Lab::new(
        inputs,
        opts.experiment_params.clone(),
        &opts.out.join("experiments"),
        progress,
    )?;
    // sweeps made beside the fit (one that failed is left to the lab, which reports it)
    for (n, r) in presim {
        if let Ok(r) = r {
            lab.preset_sweeps(n, r);
        }
    }
    let mut sections = Vec::new();
    for e in experiment::Experiment::ALL {
        let r = lab.run(e)?;
        sections.push(experiment::Lab::section(&r, "experiments/"));
    }
    Ok(sections)
}

/// The campaign summary of the report: band, array, positions, directions, what the
/// simulator and the energy stage did.
fn campaign_summary(s: &Simulated, np: usize) -> Vec<(String, String)> {
    let (m, em) = (&s.campaign.manifest, &s.em);
    vec![
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
        ("positions".into(), np.to_string()),
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
        ("sweeps".into(), s.sim.sweeps.to_string()),
        ("scatterers (truth)".into(), s.sim.scatterers.to_string()),
        (
            "clutter clusters (truth)".into(),
            s.sim.clusters.to_string(),
        ),
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
            format!("{:.3e} ({:.1} dB)", s.energy.n0, 10.0 * s.energy.n0.log10()),
        ),
        (
            "noise floor (configured)".into(),
            format!(
                "{} dBm per point at {} dBm",
                m.noise.floor_dbm, m.noise.tx_power_dbm
            ),
        ),
        ("energy table".into(), "work/energy.parquet".into()),
    ]
}

/// The MPC and cluster summary: counts, files and K per position.
fn mpc_summary(a: &Analysis, positions: usize) -> Vec<(String, String)> {
    let ks: Vec<String> = (a.clustering.positions.iter())
        .map(|p| p.k.to_string())
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
