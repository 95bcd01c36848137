//! `pradar` command line: parses arguments and calls the library.

use anyhow::Result;
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use pradar::campaign::manifest::{Campaign, SweepFormat};
use pradar::pipeline::experiment::ExperimentParams;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "pradar",
    version,
    about = "mm-wave personal radar campaigns: simulate, energy matrices, channel statistics, maps"
)]
struct Cli {
    /// No progress bars (for scripts).
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Touchstone,
    Parquet,
}

#[derive(Clone, Copy, ValueEnum)]
enum MapMethod {
    /// Side-lobe-aware occupancy grid.
    Og,
    /// Boresight-only baseline.
    OgBoresight,
    /// EKF over the RRCS per cell.
    Ekf,
}

#[derive(Clone, Copy, ValueEnum)]
enum ExtractMethod {
    Clean,
    Peaks,
}

#[derive(Clone, Copy, ValueEnum)]
enum KCriterion {
    Silhouette,
    Ch,
    Gap,
    ChannelBic,
    GaussBic,
    Cv,
    CvShared,
}

#[derive(Subcommand)]
enum Cmd {
    /// Simulate a campaign: sweeps (Touchstone or Parquet), manifest with [sweeps], truth/.
    Simulate {
        /// Input manifest with [scene] (and optionally [clutter]).
        #[arg(long)]
        campaign: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Override [array] elements (16, 100, 400).
        #[arg(long)]
        elements: Option<usize>,
        /// Sweep file format.
        #[arg(long, value_enum, default_value = "touchstone")]
        format: Format,
    },
    /// Energy matrices from a campaign's sweeps.
    Energy {
        /// Manifest with [sweeps].
        #[arg(long)]
        campaign: PathBuf,
        /// Output energy Parquet.
        #[arg(long)]
        out: PathBuf,
    },
    /// Statistical channel model: an energy table (and its truth) from a model file.
    Synth {
        /// Model file (fitted_model.toml or hand-written, DESIGN §3 "Model").
        #[arg(long)]
        model: PathBuf,
        /// Campaign manifest (layout, poses, directions, band, array, noise; no sweeps).
        #[arg(long)]
        campaign: PathBuf,
        /// Output energy Parquet.
        #[arg(long)]
        out: PathBuf,
        /// Override [array] elements (16, 100, 400).
        #[arg(long)]
        elements: Option<usize>,
        /// Seed (default: the campaign's).
        #[arg(long)]
        seed: Option<u64>,
        /// Ground-truth folder (default: <out stem>_truth beside the output).
        #[arg(long)]
        truth: Option<PathBuf>,
    },
    /// Occupancy-grid map from one run (--campaign + --energy) or several (--run, fused).
    Map {
        /// Inverse sensor model.
        #[arg(long, value_enum, default_value = "og")]
        method: MapMethod,
        /// Campaign manifest of a single run (with --energy).
        #[arg(long, requires = "energy", conflicts_with = "run")]
        campaign: Option<PathBuf>,
        /// Energy Parquet of a single run (with --campaign).
        #[arg(long, requires = "campaign")]
        energy: Option<PathBuf>,
        /// A run `campaign.toml=energy.parquet` (repeatable: runs are fused).
        #[arg(long)]
        run: Vec<String>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Override [array] elements (16, 100, 400).
        #[arg(long)]
        elements: Option<usize>,
        /// Cell side, m.
        #[arg(long, default_value_t = 0.1)]
        cell_m: f64,
        /// Detector false-alarm probability per bin.
        #[arg(long, default_value_t = 1e-3)]
        pfa: f64,
        /// Prior occupancy probability.
        #[arg(long, default_value_t = 0.5)]
        prior: f64,
        /// EKF implementation (`--method ekf`): dense (exact) or scalable (tiled).
        #[arg(long, default_value = "scalable")]
        ekf: String,
        /// EKF prior mean of the RRCS μ0, m.
        #[arg(long, default_value_t = 0.01)]
        mu0: f64,
        /// EKF prior standard deviation σ0, m.
        #[arg(long, default_value_t = 0.1)]
        sigma0: f64,
        /// Pose noise given to the mapper: position standard deviation per axis, m.
        #[arg(long, default_value_t = 0.0)]
        pose_noise_m: f64,
        /// Pose noise given to the mapper: heading standard deviation, degrees.
        #[arg(long, default_value_t = 0.0)]
        pose_noise_deg: f64,
        /// Seed of the pose-noise draws.
        #[arg(long, default_value_t = 1)]
        pose_seed: u64,
    },
    /// Extract MPCs (2-D CLEAN, or the local-maximum baseline) from an energy table.
    Extract {
        /// Energy Parquet.
        #[arg(long)]
        energy: PathBuf,
        /// The campaign the energy came from.
        #[arg(long)]
        campaign: PathBuf,
        /// Output MPC Parquet.
        #[arg(long)]
        out: PathBuf,
        /// Method.
        #[arg(long, value_enum, default_value = "clean")]
        method: ExtractMethod,
        /// Keep components above the floor plus this margin, dB.
        #[arg(long, default_value_t = 13.0)]
        margin_db: f64,
        /// Stop at components this far below the position's strongest, dB.
        #[arg(long, default_value_t = pradar::mpc::ExtractParams::default().dynamic_range_db)]
        dynamic_range_db: f64,
    },
    /// Cluster MPCs per position with K-means (writes <out> and <stem>_summary.parquet).
    Cluster {
        /// MPC Parquet from `extract`.
        #[arg(long)]
        mpcs: PathBuf,
        /// Output clustered MPC Parquet.
        #[arg(long)]
        out: PathBuf,
        /// Largest K tried per position.
        #[arg(long, default_value_t = 8)]
        k_max: usize,
        /// Seed of the k-means++ draws.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Criterion choosing K.
        #[arg(long, value_enum, default_value = "cv")]
        criterion: KCriterion,
    },
    /// Fit the channel model (Table 1) from clustered MPCs.
    Fit {
        /// Clustered MPC Parquet from `cluster`.
        #[arg(long)]
        clusters: PathBuf,
        /// The campaign (analysis view: [scene]/[clutter] are never read).
        #[arg(long)]
        campaign: PathBuf,
        /// Output model file.
        #[arg(long)]
        out: PathBuf,
        /// Table 1 Markdown (a CSV is written beside it).
        #[arg(long)]
        table: PathBuf,
        /// Bootstrap resamples.
        #[arg(long, default_value_t = 1000)]
        bootstrap: usize,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// A simulator's truth/ folder: add the same estimators on its true clusters.
        #[arg(long)]
        truth: Option<PathBuf>,
    },
    /// The main job: simulate the built-in corridor, compute energy matrices, write the report.
    Reproduce {
        /// Report folder.
        #[arg(long, default_value = "reports/corridor")]
        out: PathBuf,
        /// Use this manifest instead of the built-in corridor.
        #[arg(long)]
        campaign: Option<PathBuf>,
        /// Override [array] elements.
        #[arg(long)]
        elements: Option<usize>,
        /// Skip the mapping experiments.
        #[arg(long)]
        skip_experiments: bool,
        /// Model-data seeds of the experiments (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
        seeds: Vec<u64>,
    },
    /// The paper's mapping experiments: fig5, fig6, prior-sensitivity, pose-noise (or all).
    Experiment {
        /// fig5 | fig6 | prior-sensitivity | pose-noise | all.
        name: String,
        /// Output folder (DIR/NAME/ per experiment, DIR/maps/, DIR/index.html).
        #[arg(long)]
        out: PathBuf,
        /// Campaign manifest (default: the built-in corridor, simulated).
        #[arg(long)]
        campaign: Option<PathBuf>,
        /// Energy table of the campaign's sweeps (default: computed, simulating if needed).
        #[arg(long)]
        energy: Option<PathBuf>,
        /// Model file for model data (default: fitted from the campaign's energy table).
        #[arg(long)]
        model: Option<PathBuf>,
        /// Model-data seeds (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
        seeds: Vec<u64>,
    },
}

fn bar(quiet: bool, label: &str, total: usize) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total as u64);
    pb.set_style(
        ProgressStyle::with_template("{prefix:>12} [{bar:30}] {pos}/{len} {elapsed}")
            .expect("template")
            .progress_chars("=> "),
    );
    pb.set_prefix(label.to_string());
    pb
}

/// One stage's bar of the multi-stage jobs, cleared when the stage completes.
fn stage_bar(quiet: bool, label: &str, total: usize) -> Box<dyn Fn(usize, usize)> {
    let pb = bar(quiet, label, total);
    Box::new(move |d, t| {
        pb.set_position(d as u64);
        if d == t {
            pb.finish_and_clear();
        }
    })
}

fn run(cli: Cli) -> Result<()> {
    let quiet = cli.quiet;
    match cli.cmd {
        Cmd::Simulate {
            campaign,
            out,
            elements,
            format,
        } => {
            let mut c = Campaign::load(&campaign)?;
            if let Some(n) = elements {
                c.set_elements(n)?;
            }
            let pb = bar(quiet, "simulate", c.manifest.positions());
            let fmt = match format {
                Format::Touchstone => SweepFormat::Touchstone,
                Format::Parquet => SweepFormat::Parquet,
            };
            let r = pradar::campaign::simulate::simulate(&c, &out, fmt, &|d, _| {
                pb.set_position(d as u64)
            })?;
            pb.finish_and_clear();
            if !quiet {
                println!(
                    "simulated {} sweeps ({} scatterers, {} clutter clusters) -> {}",
                    r.sweeps,
                    r.scatterers,
                    r.clusters,
                    r.manifest.display()
                );
            }
        }
        Cmd::Energy { campaign, out } => {
            let c = Campaign::load(&campaign)?;
            let pb = bar(quiet, "energy", c.manifest.positions());
            let r = pradar::energy::run(&c, &out, &|d, _| pb.set_position(d as u64))?;
            pb.finish_and_clear();
            if !quiet {
                println!(
                    "{} sweeps -> {} rows in {} (N0 {:.3e}, noise bin mean {:.3e})",
                    r.sweeps,
                    r.rows,
                    out.display(),
                    r.n0,
                    r.noise_bin_mean
                );
            }
        }
        Cmd::Synth {
            model,
            campaign,
            out,
            elements,
            seed,
            truth,
        } => {
            let mut c = Campaign::load(&campaign)?;
            if let Some(n) = elements {
                c.set_elements(n)?;
            }
            let m = pradar::campaign::modelfile::ModelConfig::load(&model)?;
            let p = pradar::model::SynthParams {
                seed,
                truth_dir: truth,
                ..Default::default()
            };
            let pb = bar(quiet, "synth", c.manifest.positions());
            let r = pradar::model::synth(&c, &m, &out, &p, &|d, _| pb.set_position(d as u64))?;
            pb.finish_and_clear();
            if !quiet {
                println!(
                    "synthesised {} profiles ({} clusters, {:.1} rays seen per position) -> {} (truth in {})",
                    r.profiles,
                    r.clusters,
                    r.rays_per_position,
                    out.display(),
                    r.truth_dir.display()
                );
            }
        }
        Cmd::Map {
            method,
            campaign,
            energy,
            run,
            out,
            elements,
            cell_m,
            pfa,
            prior,
            ekf,
            mu0,
            sigma0,
            pose_noise_m,
            pose_noise_deg,
            pose_seed,
        } => {
            use pradar::mapping::{MapOptions, MapRun, Method};
            let mut runs = Vec::new();
            if let (Some(c), Some(e)) = (campaign, energy) {
                runs.push(MapRun {
                    campaign: c,
                    energy: e,
                });
            }
            for r in &run {
                runs.push(MapRun::parse(r)?);
            }
            let opts = MapOptions {
                method: match method {
                    MapMethod::Og => Method::Og,
                    MapMethod::OgBoresight => Method::OgBoresight,
                    MapMethod::Ekf => Method::Ekf,
                },
                runs,
                out: out.clone(),
                elements,
                grid: pradar::mapping::GridParams {
                    cell_m,
                    ..Default::default()
                },
                og: pradar::mapping::OgParams {
                    pfa,
                    prior,
                    ..Default::default()
                },
                ekf: pradar::mapping::EkfParams {
                    variant: pradar::mapping::EkfVariant::parse(&ekf)?,
                    mu0,
                    sigma0,
                    ..Default::default()
                },
                pose_noise: pradar::mapping::job::PoseNoise {
                    position_m: pose_noise_m,
                    heading_deg: pose_noise_deg,
                    seed: pose_seed,
                },
            };
            let pb = bar(quiet, "map", 0);
            let r =
                pradar::mapping::run_map(&pradar::params::ParamGuard::check(&opts)?, &|d, t| {
                    pb.set_length(t as u64);
                    pb.set_position(d as u64)
                })?;
            pb.finish_and_clear();
            if !quiet {
                let m = &r.metrics.observable;
                println!(
                    "{} map {}x{} -> {} (observable: psi {:.3}, F1 {:.3}; all-free psi {:.3})",
                    r.method,
                    r.rows,
                    r.cols,
                    out.display(),
                    m.psi,
                    m.f1,
                    r.metrics.observable_all_free.psi
                );
            }
        }
        Cmd::Extract {
            energy,
            campaign,
            out,
            method,
            margin_db,
            dynamic_range_db,
        } => {
            let c = Campaign::load(&campaign)?;
            let em = pradar::energy::EnergyMatrix::read(&energy)?;
            let params = pradar::mpc::ExtractParams::default()
                .method(match method {
                    ExtractMethod::Clean => pradar::mpc::Method::Clean,
                    ExtractMethod::Peaks => pradar::mpc::Method::Peaks,
                })
                .margin_db(margin_db)
                .dynamic_range_db(dynamic_range_db);
            let mpcs = pradar::mpc::extract(&em, &c, &params)?;
            let meta = pradar::mpc::table_metadata(&em, &c, &params);
            pradar::mpc::write_mpcs(&out, &mpcs, meta)?;
            if !quiet {
                println!(
                    "{} MPCs from {} positions -> {}",
                    mpcs.len(),
                    em.positions,
                    out.display()
                );
            }
        }
        Cmd::Cluster {
            mpcs,
            out,
            k_max,
            seed,
            criterion,
        } => {
            let m = pradar::mpc::read_mpcs(&mpcs)?;
            let sector = pradar::mpc::read_sector_deg(&mpcs)?.unwrap_or(180.0);
            let params = pradar::cluster::ClusterParams::default()
                .k_max(k_max)
                .seed(seed)
                .sector_deg(sector)
                .criterion(match criterion {
                    KCriterion::Silhouette => pradar::cluster::Criterion::Silhouette,
                    KCriterion::Ch => pradar::cluster::Criterion::CalinskiHarabasz,
                    KCriterion::Gap => pradar::cluster::Criterion::Gap,
                    KCriterion::ChannelBic => pradar::cluster::Criterion::ChannelBic,
                    KCriterion::GaussBic => pradar::cluster::Criterion::GaussBic,
                    KCriterion::Cv => pradar::cluster::Criterion::CrossValidated,
                    KCriterion::CvShared => pradar::cluster::Criterion::CrossValidatedShared,
                });
            let headings: Vec<f64> = {
                let np = m.iter().map(|x| x.position + 1).max().unwrap_or(0);
                (0..np)
                    .map(|p| {
                        m.iter()
                            .find(|x| x.position == p)
                            .map(|x| x.angle_global_deg - x.angle_rel_deg)
                            .unwrap_or(0.0)
                    })
                    .collect()
            };
            let c = pradar::cluster::cluster(&m, &headings, &params)?;
            let summary = pradar::cluster::write(&out, &c)?;
            let capped = c.positions_at_k_max(params.k_max);
            if !capped.is_empty() {
                eprintln!(
                    "warning: K = K_max = {} at {} of {} positions (the criterion still preferred more clusters there; the counts are set by --k-max)",
                    params.k_max,
                    capped.len(),
                    c.positions.len()
                );
            }
            if !quiet {
                println!(
                    "{} clusters over {} positions -> {} and {}",
                    c.summary.len(),
                    c.positions.len(),
                    out.display(),
                    summary.display()
                );
            }
        }
        Cmd::Fit {
            clusters,
            campaign,
            out,
            table,
            bootstrap,
            seed,
            truth,
        } => {
            let c = Campaign::load(&campaign)?;
            let params = pradar::fit::channel::FitParams { bootstrap, seed };
            let f = pradar::fit::channel::fit_channel(&clusters, &c, &params)?;
            let t = match &truth {
                Some(dir) => Some(pradar::fit::channel::fit_truth(dir, &c, &params)?),
                None => None,
            };
            f.model.save(&out)?;
            pradar::fit::channel::write_table1(&table, &f, t.as_ref())?;
            if !quiet {
                for r in pradar::fit::channel::table1_rows(&f, t.as_ref()) {
                    println!("{:<38} {:<60} {:<20} truth {}", r[0], r[1], r[2], r[7]);
                }
            }
        }
        Cmd::Reproduce {
            out,
            campaign,
            elements,
            skip_experiments,
            seeds,
        } => {
            let opts = pradar::pipeline::ReproduceOptions {
                out,
                campaign,
                elements,
                experiments: !skip_experiments,
                experiment_params: ExperimentParams::default().seeds(seeds),
            };
            let progress = |label: &str, total: usize| stage_bar(quiet, label, total);
            let index = pradar::pipeline::reproduce(&opts, &progress)?;
            if !quiet {
                println!("report: {}", index.display());
            }
        }
        Cmd::Experiment {
            name,
            out,
            campaign,
            energy,
            model,
            seeds,
        } => {
            use pradar::pipeline::experiment::{run_experiments, Experiment, InputOptions};
            let which = if name == "all" {
                Experiment::ALL.to_vec()
            } else {
                vec![Experiment::parse(&name)?]
            };
            let inputs = InputOptions {
                campaign,
                energy,
                model,
            };
            let params = ExperimentParams::default().seeds(seeds);
            let progress = |label: &str, total: usize| stage_bar(quiet, label, total);
            let results = run_experiments(&which, &inputs, &params, &out, &progress)?;
            if !quiet {
                for r in &results {
                    println!("{}:", r.name);
                    for (k, v) in &r.findings {
                        println!("  {k}: {v}");
                    }
                }
                println!("report: {}", out.join("index.html").display());
            }
        }
    }
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        let msg = format!("{e:#}").replace('\n', " ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}
