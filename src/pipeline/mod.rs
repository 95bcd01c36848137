//! The main job (`pradar reproduce`): simulate the built-in corridor into a work folder,
//! compute its energy matrices, extract and cluster MPCs, fit Table 1 (also on the corridor
//! without clutter), map it (OG, boresight OG, EKF), run the mapping experiments
//! ([`experiment`]) and write the report: campaign summary, per-position heat maps, MPC
//! clusters, Table 1, maps, every experiment's table and panel, and stage timings.

use crate::campaign::manifest::{Campaign, SweepFormat};
use crate::campaign::simulate::simulate;
use crate::energy::{self, EnergyMatrix};
use crate::error::{Error, Result};
use crate::report::{self, kv_table, Section};
use crate::{cluster, mpc};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod experiment;

/// The built-in corridor manifest.
pub const CORRIDOR_MANIFEST: &str = include_str!("../../data/corridor/campaign.toml");
/// The built-in corridor layout.
pub const CORRIDOR_LAYOUT: &str = include_str!("../../data/corridor/layout.geojson");

/// Options of `reproduce`.
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
    /// Their parameters.
    pub experiment_params: experiment::ExperimentParams,
}

/// Progress callback factory: (stage label, total steps) → per-step callback.
pub type Progress<'a> = &'a dyn Fn(&str, usize) -> Box<dyn Fn(usize, usize) + 'a>;

/// Write the built-in corridor campaign (manifest + layout) into `dir`.
pub fn write_builtin_corridor(dir: &Path) -> Result<PathBuf> {
    let m = dir.join("campaign.toml");
    crate::io::write_bytes(&m, CORRIDOR_MANIFEST.as_bytes())?;
    crate::io::write_bytes(&dir.join("layout.geojson"), CORRIDOR_LAYOUT.as_bytes())?;
    Ok(m)
}

/// Run the main job; returns the index path.
pub fn reproduce(opts: &ReproduceOptions, progress: Progress) -> Result<PathBuf> {
    let out = &opts.out;
    let work = out.join("work");
    std::fs::create_dir_all(&work).map_err(|e| Error::io(&work, e))?;
    let mut timings: Vec<(String, f64)> = Vec::new();
    let src = match &opts.campaign {
        Some(p) => p.clone(),
        None => write_builtin_corridor(&work.join("input"))?,
    };
    let mut c = Campaign::load(&src)?;
    if let Some(n) = opts.elements {
        c.set_elements(n)?;
    }
    let np = c.manifest.positions();
    let t = Instant::now();
    let sim_dir = work.join("simulated");
    let cb = progress("simulate", np);
    let sim = simulate(&c, &sim_dir, SweepFormat::Touchstone, &*cb)?;
    timings.push(("simulate".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let sc = Campaign::load(&sim.manifest)?;
    let energy_path = work.join("energy.parquet");
    let cb = progress("energy", np);
    let er = energy::run(&sc, &energy_path, &*cb)?;
    timings.push(("energy".into(), t.elapsed().as_secs_f64()));
    let em = EnergyMatrix::read(&energy_path)?;
    // MPC extraction, clustering and the fit
    let Analysis {
        mpcs,
        clustering,
        cluster_params,
        fit: fitted,
        timings: chain_timings,
    } = analyse(&sc, &em, &work, true)?;
    timings.extend(chain_timings);
    let t = Instant::now();
    let truth =
        crate::fit::channel::fit_truth(&sim_dir.join("truth"), &sc, &Default::default()).ok();
    let table1_html = match &fitted {
        Ok(f) => {
            f.model.save(&out.join("fitted_model.toml"))?;
            crate::fit::channel::write_table1(&out.join("table1.md"), f, truth.as_ref())?;
            let mut h = table1_html_rows(f, truth.as_ref());
            h.push_str("</table><p>From the simulated corridor's clusters; reported beside the paper with no pass mark (<a href=\"table1.md\">table1.md</a>, <a href=\"fitted_model.toml\">fitted_model.toml</a>).</p>\n");
            for (name, d) in &f.details {
                if d.samples.len() < 2 {
                    h.push_str(&format!("<p>{name}: fewer than 2 samples, no plot.</p>\n"));
                    continue;
                }
                let png = format!("fit_{name}.png");
                report::fit_plot(&out.join(&png), name, &d.q.unit, &d.samples, &d.fitted)?;
                h.push_str(&format!("<a href=\"{png}\"><img style=\"max-width:640px\" src=\"{png}\" alt=\"{name}\"></a>\n"));
            }
            h
        }
        Err(e) => format!("<p>fit failed: {}</p>", report::html_escape(&e.to_string())),
    };
    let table1_html = format!("{}{table1_html}", k_cap_note(&clustering, &cluster_params));
    let kmax_html = match k_max_sensitivity(
        &sc,
        &clustering,
        &cluster_params,
        fitted.as_ref().ok(),
        truth.as_ref(),
        &work,
        out,
    ) {
        Ok(h) => h,
        Err(e) => format!(
            "<p>K_max sensitivity failed: {}</p>",
            report::html_escape(&e.to_string())
        ),
    };
    let table1_html = format!("{table1_html}{kmax_html}");
    timings.push((
        "fit report (truth, plots)".into(),
        t.elapsed().as_secs_f64(),
    ));
    // Table 1 of the same corridor with the clutter section removed (geometry only)
    let t = Instant::now();
    let geometry_html = match geometry_only_table(&c, &work.join("geometry"), out, progress) {
        Ok(h) => h,
        Err(e) => format!(
            "<p>geometry-only fit failed: {}</p>",
            report::html_escape(&e.to_string())
        ),
    };
    timings.push((
        "geometry-only Table 1 (simulate → fit)".into(),
        t.elapsed().as_secs_f64(),
    ));
    let t = Instant::now();
    let cb = progress("plots", np);
    let max_delay = em.delay_ns(em.bins - 1);
    for p in 0..em.positions {
        let marks: Vec<(f64, f64)> = mpcs
            .iter()
            .filter(|m| m.position == p)
            .map(|m| (m.angle_rel_deg, crate::units::range_m(m.delay_ns)))
            .collect();
        report::energy_heatmap(
            &em,
            p,
            &out.join(format!("energy_p{p:02}.png")),
            -60.0,
            &marks,
        )?;
        let idx: Vec<usize> = (0..mpcs.len()).filter(|&i| mpcs[i].position == p).collect();
        let pts: Vec<(f64, f64, f64)> = idx
            .iter()
            .map(|&i| (mpcs[i].angle_rel_deg, mpcs[i].delay_ns, mpcs[i].power_db))
            .collect();
        let labels = &clustering.positions[p].labels;
        report::mpc_clusters_plot(
            &out.join(format!("clusters_p{p:02}.png")),
            &format!(
                "position {p}: {} MPCs in {} clusters",
                pts.len(),
                clustering.positions[p].k
            ),
            &pts,
            labels,
            max_delay,
        )?;
        cb(p + 1, em.positions);
    }
    let layout = crate::campaign::Layout::load(&sc.layout_path())?;
    let poses: Vec<(f64, f64)> = sc.manifest.poses.iter().map(|p| (p.x_m, p.y_m)).collect();
    let pts: Vec<(f64, f64, usize)> = mpcs
        .iter()
        .zip(&clustering.cluster_id)
        .map(|(m, &c)| (m.x_m, m.y_m, c))
        .collect();
    let cents: Vec<(f64, f64, usize)> = clustering
        .summary
        .iter()
        .map(|s| (s.centroid_x_m, s.centroid_y_m, s.cluster_id))
        .collect();
    report::global_map_plot(&out.join("mpcs_global.png"), &layout, &poses, &pts, &cents)?;
    timings.push(("report plots".into(), t.elapsed().as_secs_f64()));
    let m = &sc.manifest;
    let summary = vec![
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
        ("sweeps".into(), sim.sweeps.to_string()),
        ("scatterers (truth)".into(), sim.scatterers.to_string()),
        ("clutter clusters (truth)".into(), sim.clusters.to_string()),
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
            format!("{:.3e} ({:.1} dB)", er.n0, 10.0 * er.n0.log10()),
        ),
        (
            "noise floor (configured)".into(),
            format!(
                "{} dBm per point at {} dBm",
                m.noise.floor_dbm, m.noise.tx_power_dbm
            ),
        ),
        ("energy table".into(), "work/energy.parquet".into()),
    ];
    let mut heat = String::new();
    for p in 0..em.positions {
        heat.push_str(&format!("<a href=\"energy_p{p:02}.png\"><img src=\"energy_p{p:02}.png\" alt=\"position {p}\"></a>\n"));
    }
    let t = Instant::now();
    let maps = crate::mapping::job::report_section(&sim.manifest, &energy_path, out, "maps")?;
    timings.push((
        "maps (OG, OG boresight, EKF)".into(),
        t.elapsed().as_secs_f64(),
    ));
    let mut experiment_sections = Vec::new();
    if opts.experiments {
        let t = Instant::now();
        match &fitted {
            Ok(_) => {
                let inputs = experiment::ExperimentInputs {
                    campaign: sim.manifest.clone(),
                    energy: energy_path.clone(),
                    model: out.join("fitted_model.toml"),
                };
                let mut lab = experiment::Lab::new(
                    inputs,
                    opts.experiment_params.clone(),
                    &out.join("experiments"),
                    progress,
                )?;
                for e in experiment::Experiment::ALL {
                    let r = lab.run(e)?;
                    experiment_sections.push(experiment::Lab::section(&r, "experiments/"));
                }
            }
            Err(e) => experiment_sections.push(Section {
                title: "Experiments".into(),
                html: format!(
                    "<p>not run: the fit gave no model ({})</p>",
                    report::html_escape(&e.to_string())
                ),
            }),
        }
        timings.push((
            "experiments (fig5, fig6, prior-sensitivity, pose-noise)".into(),
            t.elapsed().as_secs_f64(),
        ));
    }
    let ks: Vec<String> = clustering
        .positions
        .iter()
        .map(|p| p.k.to_string())
        .collect();
    let mut mpc_html = kv_table(&[
        (
            "MPCs".to_string(),
            format!(
                "{} over {} positions (work/mpcs.parquet)",
                mpcs.len(),
                em.positions
            ),
        ),
        (
            "clusters".to_string(),
            format!(
                "{} (work/clusters.parquet, work/clusters_summary.parquet)",
                clustering.summary.len()
            ),
        ),
        (
            "K per position (cross-validated criterion)".to_string(),
            ks.join(", "),
        ),
    ]);
    mpc_html.push_str("<p>MPCs are marked (white circles) on the energy heat maps above.</p>\n<a href=\"mpcs_global.png\"><img style=\"max-width:900px\" src=\"mpcs_global.png\" alt=\"global\"></a><br>\n");
    for p in 0..em.positions {
        mpc_html.push_str(&format!("<a href=\"clusters_p{p:02}.png\"><img src=\"clusters_p{p:02}.png\" alt=\"clusters {p}\"></a>\n"));
    }
    let total: f64 = timings.iter().map(|t| t.1).sum();
    let mut trows: Vec<(String, String)> = timings
        .iter()
        .map(|(k, v)| (k.clone(), format!("{v:.2} s")))
        .collect();
    trows.push(("total".into(), format!("{total:.2} s")));
    let mut sections = vec![
        Section {
            title: "Campaign".into(),
            html: kv_table(&summary),
        },
        Section {
            title: "Energy matrices (range vs direction, dB re position peak)".into(),
            html: heat,
        },
        Section {
            title: "Table 1 (corridor)".into(),
            html: table1_html,
        },
        Section {
            title: "Table 1 of the corridor without clutter (geometry only)".into(),
            html: geometry_html,
        },
        Section {
            title: "MPCs (2-D CLEAN) and clusters (K-means)".into(),
            html: mpc_html,
        },
        Section {
            title: "Stage timings".into(),
            html: kv_table(&trows),
        },
    ];
    sections.insert(sections.len() - 1, maps);
    for e in experiment_sections {
        sections.insert(sections.len() - 1, e);
    }
    let index = out.join("index.html");
    report::write_index(&index, &format!("pradar report: {}", m.name), &sections)?;
    Ok(index)
}

/// What the analysis chain (CLEAN → K-means → fit) gave for one energy table.
pub struct Analysis {
    /// Extracted MPCs.
    pub mpcs: Vec<mpc::Mpc>,
    /// Their clustering.
    pub clustering: cluster::Clustering,
    /// The clustering parameters used.
    pub cluster_params: cluster::ClusterParams,
    /// The channel fit (Table 1, model file), or why it failed (too few clusters, say).
    pub fit: Result<crate::fit::channel::ChannelFit>,
    /// Stage timings, s.
    pub timings: Vec<(String, f64)>,
}

/// Run CLEAN (default parameters), K-means (default criterion, the campaign's sector) and
/// the channel fit (default
/// bootstrap) on an energy table of campaign `sc`, writing `work/clusters.parquet` and
/// `work/clusters_summary.parquet` (and `work/mpcs.parquet` when `keep_mpcs`). Extraction or
/// clustering errors are returned; a failed fit is kept in [`Analysis::fit`].
pub fn analyse(sc: &Campaign, em: &EnergyMatrix, work: &Path, keep_mpcs: bool) -> Result<Analysis> {
    let mut timings = Vec::new();
    let t = Instant::now();
    let xp = mpc::ExtractParams::default();
    let mpcs = mpc::extract(em, sc, &xp)?;
    if keep_mpcs {
        mpc::write_mpcs(
            &work.join("mpcs.parquet"),
            &mpcs,
            mpc::table_metadata(em, sc, &xp),
        )?;
    }
    timings.push(("extract (CLEAN)".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let headings: Vec<f64> = sc.manifest.poses.iter().map(|p| p.heading_deg).collect();
    let params = cluster::ClusterParams::default().sector_deg(sc.manifest.directions.width_deg());
    let clustering = cluster::cluster(&mpcs, &headings, &params)?;
    let cp = work.join("clusters.parquet");
    cluster::write(&cp, &clustering)?;
    timings.push(("cluster (K-means)".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let fit = crate::fit::channel::fit_channel(&cp, sc, &Default::default());
    timings.push(("fit (Table 1)".into(), t.elapsed().as_secs_f64()));
    Ok(Analysis {
        mpcs,
        clustering,
        cluster_params: params,
        fit,
        timings,
    })
}

/// The larger caps of the K_max sensitivity table.
const K_MAX_TRIED: [usize; 3] = [12, 16, 24];

/// Table 1's cluster-count quantities refitted with the clustering cap raised to 12, 16 and
/// 24, beside the default fit and the truth, as `out/table1_kmax.md` and an HTML table
/// (clusterings in `work/clusters_kmax<K>.parquet`). Where the criterion keeps preferring
/// more clusters (the built-in corridor) these values are set by K_max, not found; the
/// table shows by how much (README "Corridor and K_max").
fn k_max_sensitivity(
    sc: &Campaign,
    base: &cluster::Clustering,
    params: &cluster::ClusterParams,
    default_fit: Option<&crate::fit::channel::ChannelFit>,
    truth: Option<&crate::fit::channel::ChannelFit>,
    work: &Path,
    out: &Path,
) -> Result<String> {
    let headings: Vec<f64> = sc.manifest.poses.iter().map(|p| p.heading_deg).collect();
    let row = |label: String, ks: String, f: Option<&crate::fit::channel::ChannelFit>| {
        let v = |g: fn(&crate::campaign::modelfile::ModelConfig) -> f64, digits: usize| {
            f.map_or("—".to_string(), |f| format!("{:.*}", digits, g(&f.model)))
        };
        [
            label,
            ks,
            v(|m| m.inter_cluster_rate.value, 3),
            v(|m| m.perimeter_spacing.value, 2),
            v(|m| m.intra_cluster_rate.value, 3),
            v(|m| m.intra_cluster_aoa.value, 1),
            v(|m| m.ray_decay.value, 2),
        ]
    };
    let ks_of = |c: &cluster::Clustering, k_max: usize| {
        let ks: Vec<usize> = c.positions.iter().map(|p| p.k).collect();
        let (lo, hi) = (
            ks.iter().min().copied().unwrap_or(0),
            ks.iter().max().copied().unwrap_or(0),
        );
        format!(
            "{lo}–{hi} ({} of {} at the cap)",
            c.positions_at_k_max(k_max).len(),
            c.positions.len()
        )
    };
    let mut rows = vec![row(
        format!("{} (default)", params.k_max),
        ks_of(base, params.k_max),
        default_fit,
    )];
    for k in K_MAX_TRIED.into_iter().filter(|&k| k > params.k_max) {
        let p = cluster::ClusterParams {
            k_max: k,
            ..*params
        };
        let c = cluster::cluster(&base.mpcs, &headings, &p)?;
        let path = work.join(format!("clusters_kmax{k}.parquet"));
        cluster::write(&path, &c)?;
        let f = crate::fit::channel::fit_channel(&path, sc, &Default::default()).ok();
        rows.push(row(k.to_string(), ks_of(&c, k), f.as_ref()));
    }
    if let Some(t) = truth {
        rows.push(row(
            "simulator truth (same estimators)".into(),
            "—".into(),
            Some(t),
        ));
    }
    let head = [
        "K_max",
        "K per position",
        "Λ (1/ns)",
        "d_c (m)",
        "λ (1/ns)",
        "AoA std (deg)",
        "γ (ns)",
    ];
    let mut md = String::from(
        "# Table 1 against the clustering cap K_max\n\nThe cluster-count quantities refitted with K_max raised; where positions end at the cap, the criterion still preferred more clusters and the values are set by K_max.\n\n",
    );
    md.push_str(&format!(
        "| {} |\n|{}\n",
        head.join(" | "),
        "---|".repeat(head.len())
    ));
    let mut h = String::from("<h3>Table 1 against the clustering cap K_max</h3><table><tr>");
    for c in head {
        h.push_str(&format!("<th>{}</th>", report::html_escape(c)));
    }
    h.push_str("</tr>\n");
    for r in &rows {
        md.push_str(&format!("| {} |\n", r.join(" | ")));
        h.push_str("<tr>");
        for c in r {
            h.push_str(&format!("<td>{}</td>", report::html_escape(c)));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table><p>Where positions end at the cap, the criterion still preferred more clusters: these values are set by K_max, not found (<a href=\"table1_kmax.md\">table1_kmax.md</a>).</p>\n");
    crate::io::write_bytes(&out.join("table1_kmax.md"), md.as_bytes())?;
    Ok(h)
}

/// A paragraph on the K chosen per position, saying where K_max bound
/// ([`cluster::Clustering::positions_at_k_max`]).
fn k_cap_note(c: &cluster::Clustering, params: &cluster::ClusterParams) -> String {
    let k_max = params.k_max;
    let ks: Vec<String> = c.positions.iter().map(|p| p.k.to_string()).collect();
    let capped = c.positions_at_k_max(k_max);
    let mut h = format!("<p>K chosen per position: {}.", ks.join(", "));
    if !capped.is_empty() {
        h.push_str(&format!(
            " <b>K = K_max = {k_max} at {} of {} positions</b>: the criterion still preferred more clusters there, so the cluster counts, and with them Λ, λ, the AoA spread and d_c, are set by K_max rather than found (README, \"Corridor and K_max\").",
            capped.len(),
            c.positions.len()
        ));
    }
    h.push_str("</p>\n");
    h
}

/// Table 1 as HTML rows (ours, interval, family, KS p, AIC, paper, truth).
fn table1_html_rows(
    f: &crate::fit::channel::ChannelFit,
    truth: Option<&crate::fit::channel::ChannelFit>,
) -> String {
    report::html_table(&crate::fit::table1::table(f, truth))
}

/// Simulate the campaign `c` with its `[clutter]` section removed (walls, corners, edges,
/// specular paths only) into `dir`, run energy → CLEAN → K-means → fit, write
/// `out/table1_geometry.md` and return the HTML table.
fn geometry_only_table(c: &Campaign, dir: &Path, out: &Path, progress: Progress) -> Result<String> {
    let text = crate::io::read_text(&c.path)?;
    let mut t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, e.to_string()))?;
    t.remove("clutter");
    if let Some(toml::Value::Table(a)) = t.get_mut("array") {
        a.insert(
            "elements".into(),
            toml::Value::Integer(c.manifest.array.elements as i64),
        );
    }
    let input = dir.join("input");
    std::fs::create_dir_all(&input).map_err(|e| Error::io(&input, e))?;
    let layout = c.layout_path();
    let layout_name = layout
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "layout.geojson".into());
    crate::io::write_bytes(
        &input.join(&layout_name),
        crate::io::read_text(&layout)?.as_bytes(),
    )?;
    t.insert("layout".into(), toml::Value::String(layout_name));
    let manifest = input.join("campaign.toml");
    let body = toml::to_string(&t).map_err(|e| Error::input(&manifest, e.to_string()))?;
    crate::io::write_bytes(&manifest, body.as_bytes())?;
    let gc = Campaign::load(&manifest)?;
    let np = gc.manifest.positions();
    let cb = progress("simulate (geometry only)", np);
    let sim = simulate(&gc, &dir.join("simulated"), SweepFormat::Parquet, &*cb)?;
    let sc = Campaign::load(&sim.manifest)?;
    let e = dir.join("energy.parquet");
    let cb = progress("energy (geometry only)", np);
    energy::run(&sc, &e, &*cb)?;
    let em = EnergyMatrix::read(&e)?;
    let a = analyse(&sc, &em, dir, false)?;
    let note = k_cap_note(&a.clustering, &a.cluster_params);
    let (mpcs, clustering, f) = (a.mpcs, a.clustering, a.fit?);
    crate::fit::channel::write_table1(&out.join("table1_geometry.md"), &f, None)?;
    let mut h = table1_html_rows(&f, None);
    h.push_str(&format!(
        "<p>The corridor simulated without its <code>[clutter]</code> section: walls (diffuse and specular), corners, edges and objects only; {} MPCs in {} clusters over {np} positions. What the chain calls clusters here is the layout's own structure (<a href=\"table1_geometry.md\">table1_geometry.md</a>).</p>\n",
        mpcs.len(),
        clustering.summary.len()
    ));
    h.push_str(&note);
    Ok(h)
}
