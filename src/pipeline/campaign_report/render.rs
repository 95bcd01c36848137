//! The report's sections: Table 1 with its fit plots and the K_max table, the predictive
//! check (in sample and held out), the heat maps and cluster plots, the campaign and MPC summaries, and the
//! `pradar explore` section.
//!
//! Takes the gathered [`Data`] and the [`Analysis`]; gives each
//! section's HTML (or the summary rows the page lays out) and writes its files into `out`.

use super::gather::Data;
use super::{Job, EXPLORE_SECTION};
use crate::error::{Error, Result};
use crate::fit::channel::ChannelFit;
use crate::params::ParamGuard;
use crate::pipeline::kmax::k_max_sensitivity;
use crate::pipeline::{table1_html_rows, Analysis, Progress};
use crate::report::reproduce::{self as page, FitPlot};
use crate::report::{self, Section};
use std::path::Path;

/// `report --explore DIR`: DIR's files copied into `out/explore/` and its section.
pub(super) fn explore_section(dir: &Path, out: &Path) -> Result<Section> {
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

/// The predictive check of the model (`--model`, else the fitted one) against the
/// campaign's energy table (`out/check/`: table, CDF panels): the section, or why it did
/// not run.
pub(super) fn check_section(job: &Job, s: &Data, a: &Analysis, progress: Progress) -> Section {
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
                    f.model.require_estimable(&Default::default())?,
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

/// The held-out check of the campaign's table ([`crate::check::holdout()`]: a model fitted
/// on each half of the walk, checked on the other; `out/check/holdout.md` and
/// `holdout.csv`): its lines and table for the check section, or why it did not run (a
/// campaign of fewer than 4 positions, a half whose fit fails).
pub(super) fn holdout_html(job: &Job, s: &Data, progress: Progress) -> String {
    // a campaign too small to halve is not a failure of the check
    if let Err(e) = crate::check::holdout::halves(&s.campaign) {
        return page::not_run(&format!("the held-out check: {e}")) + "\n";
    }
    let run = || -> Result<String> {
        let params = crate::check::CheckParams::default().check()?;
        let cb = progress("held-out check", 2 * params.draws);
        let r = crate::check::holdout(
            &s.campaign,
            &s.em,
            &s.energy_path,
            &params,
            &crate::check::Estimator::Chain,
            &*cb,
        )?;
        let dir = job.out.join("check");
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        crate::report::check::write_holdout_tables(&dir, &r)?;
        Ok(crate::report::check::holdout_html(&r))
    };
    run().unwrap_or_else(|e| page::failed("the held-out check", &e) + "\n")
}

/// Table 1's closed-loop column ([`crate::closed_loop`]: the chain on
/// [`DEFAULT_DRAWS`](crate::closed_loop::DEFAULT_DRAWS) draws of the written model over
/// the campaign's poses) written into the fit; gives the note under Table 1: the rule, or
/// why the column is absent (no fit, a failed run).
pub(super) fn closed_loop_note(s: &Data, a: &mut Analysis, progress: Progress) -> String {
    let Ok(f) = a.fit.as_mut() else {
        return String::new();
    };
    let run = || -> Result<_> {
        let params = crate::closed_loop::ClosedLoopParams::default().check()?;
        let cb = progress("closed loop", params.draws);
        let written = f.model.require_estimable(&Default::default())?;
        crate::closed_loop::closed_loop(
            &s.campaign,
            &s.em,
            &s.energy_path,
            &written,
            &Default::default(),
            &params,
            &*cb,
        )
    };
    match run() {
        Ok(identified) => {
            f.identified = identified;
            let d = crate::closed_loop::DEFAULT_DRAWS;
            format!(
                "<p>Identifiable? The chain read {d} tables drawn from the written model over \
                 this campaign's poses: a quantity is \"not identifiable from this campaign\" \
                 when the median of its {d} readings lies outside the campaign's 95 % \
                 interval (or the chain read it in fewer than half of them, or it has no \
                 interval): the chain's own bias there exceeds what the campaign \
                 resolves.</p>\n"
            )
        }
        Err(e) => page::failed("the closed loop (Table 1's identifiability)", &e),
    }
}

/// Table 1 (`fitted_model.toml`, `table1.md`, the fit plots) beside the simulator's truth
/// through the same estimators when there is one (else the page says why there is no truth
/// column), the K note and the K_max table: the section's HTML.
pub(super) fn table1_section(
    s: &Data,
    a: &Analysis,
    closed_loop: &str,
    work: &Path,
    out: &Path,
) -> Result<String> {
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
            f.model.check()?;
            f.model.save(&out.join("fitted_model.toml"))?;
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
        &format!("{table1}{closed_loop}{truth_note}"),
        &kmax,
    ))
}
/// `out/fit_<quantity>.png` per fitted quantity with at least 2 samples (none for a quantity
/// that is not estimable: it has no samples, and Table 1 says why).
pub(super) fn write_fit_plots(f: &ChannelFit, out: &Path) -> Result<Vec<FitPlot>> {
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
pub(super) fn write_plots(s: &Data, a: &Analysis, out: &Path, progress: Progress) -> Result<()> {
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
        // the position's MPCs with their labels local to the position (None: diffuse or
        // folded)
        let mut labels = clustering.positions[p].labels.iter();
        let (pts, local): (Vec<Point3>, Vec<Option<usize>>) = mpcs
            .iter()
            .filter(|m| m.position == p)
            .map(|m| {
                let l = match m.component {
                    crate::mpc::Component::Discrete => labels.next().copied(),
                    crate::mpc::Component::Diffuse | crate::mpc::Component::Folded => None,
                };
                ((m.angle_rel_deg, m.delay_ns, m.power_db), l)
            })
            .unzip();
        report::mpc_clusters_plot(
            &out.join(format!("clusters_p{p:02}.png")),
            &format!(
                "position {label}: {} MPCs ({}) in {} clusters",
                pts.len(),
                unclustered(mpcs.iter().filter(|m| m.position == p)),
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

/// The campaign summary of the report: band, array, positions, directions, what the
/// simulator (when it ran) and the energy stage did.
pub(super) fn campaign_summary(s: &Data) -> Vec<(String, String)> {
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

/// The unclustered among `mpcs`: "N diffuse", with ", M folded" when some are.
fn unclustered<'a>(mpcs: impl Iterator<Item = &'a crate::mpc::Mpc>) -> String {
    use crate::mpc::Component;
    let (mut diffuse, mut folded) = (0, 0);
    for m in mpcs {
        match m.component {
            Component::Diffuse => diffuse += 1,
            Component::Folded => folded += 1,
            Component::Discrete => {}
        }
    }
    if folded > 0 {
        format!("{diffuse} diffuse, {folded} folded")
    } else {
        format!("{diffuse} diffuse")
    }
}

/// The MPC and cluster summary: counts, files and K per position.
pub(super) fn mpc_summary(
    a: &Analysis,
    m: &crate::campaign::manifest::Manifest,
) -> Vec<(String, String)> {
    let positions = m.positions();
    let ks: Vec<String> = (a.clustering.positions.iter().enumerate())
        .map(|(p, c)| match m.labels.get(p) {
            Some(l) => format!("{l}: {}", c.k),
            None => c.k.to_string(),
        })
        .collect();
    let folded = (a.mpcs.iter())
        .filter(|x| x.component == crate::mpc::Component::Folded)
        .count();
    // the fold stage's count, beside the fold warning's figures (shown only when it labelled)
    let fold = (folded > 0).then(|| {
        (
            "folded MPCs (kept out of the clusters)".to_string(),
            format!(
                "{folded}: wall echoes from beyond the unambiguous range {:.1} m",
                crate::campaign::fold::unambiguous_range_m(&m.band)
            ),
        )
    });
    let mut rows = vec![
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
    ];
    rows.extend(fold);
    rows
}
