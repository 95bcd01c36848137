//! `pradar` command line: parses arguments ([`cli`]) and calls one library function per
//! subcommand ([`pradar::pipeline::commands`], [`pradar::pipeline::reproduce`]).
//!
//! Each `fn <subcommand>` turns its arguments into the library's parameter structs, runs the
//! library entry with a progress bar (none with `--quiet`) and prints the returned summary.
//! Errors are printed as one line `error: …` with exit status 1: the library's (whose
//! `Display` names the file, line or field) and every usage error clap reports (invalid,
//! out-of-range or missing flag values, conflicting flags, a required flag absent, an
//! unknown flag or subcommand: its message up to the usage, joined into one line, naming
//! the flags). Only `--help` and `--version` keep clap's output and status 0. Seeds accept
//! a leading `-` as a value, so `--seed -1` is refused as an invalid value of `--seed`.

mod cli;

use anyhow::Result;
use clap::error::ErrorKind;
use clap::Parser;
use cli::{
    CalibrateArgs, CheckArgs, Cli, ClusterArgs, Cmd, EnergyArgs, ExperimentArgs, ExtractArgs,
    FitArgs, ImportArgs, MapArgs, ReportArgs, ReproduceArgs, SimulateArgs, SynthArgs,
};
use indicatif::{ProgressBar, ProgressStyle};
use pradar::params::ParamGuard;
use pradar::pipeline::commands;
use pradar::pipeline::experiment::{ExperimentParams, InputOptions};

fn main() {
    let cli = parse_args();
    if let Err(e) = run(cli) {
        // the top error only: the library's `Display` already includes its cause (an I/O
        // error's OS message), which `{:#}` would print a second time
        let msg = format!("{e}").replace('\n', " ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}

/// Parse the command line; a usage error (a bad flag value, a conflict, a missing or
/// unknown flag) is one `error:` line and exit status 1. `--help` and `--version` print
/// as clap prints them.
fn parse_args() -> Cli {
    match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e)
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) =>
        {
            e.exit()
        }
        Err(e) => {
            eprintln!("{}", one_line(&e.render().to_string()));
            std::process::exit(1);
        }
    }
}

/// clap's message in one line: its text up to the usage (the `error:` line, a conflict's
/// or a missing flag's names, a tip), joined.
fn one_line(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:"))
        .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
        .collect();
    lines.join(" ")
}

fn run(cli: Cli) -> Result<()> {
    let quiet = cli.quiet;
    match cli.cmd {
        Cmd::Import(a) => import(a, quiet),
        Cmd::Simulate(a) => simulate(a, quiet),
        Cmd::Energy(a) => energy(a, quiet),
        Cmd::Synth(a) => synth(a, quiet),
        Cmd::Map(a) => map(a, quiet),
        Cmd::Extract(a) => extract(a, quiet),
        Cmd::Cluster(a) => cluster(a, quiet),
        Cmd::Fit(a) => fit(a, quiet),
        Cmd::Calibrate(a) => calibrate(a, quiet),
        Cmd::Check(a) => check(a, quiet),
        Cmd::Report(a) => report_cmd(a, quiet),
        Cmd::Reproduce(a) => reproduce(a, quiet),
        Cmd::Experiment(a) => experiment(a, quiet),
    }
}

/// Print a command's summary unless `--quiet`.
fn report(quiet: bool, summary: impl std::fmt::Display) {
    if !quiet {
        println!("{summary}");
    }
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

/// Run a single-stage command under one bar (its length comes with the first step).
fn with_bar<T>(
    quiet: bool,
    label: &str,
    f: impl FnOnce(commands::StepProgress) -> pradar::Result<T>,
) -> pradar::Result<T> {
    let pb = bar(quiet, label, 0);
    let r = f(&|d, t| {
        pb.set_length(t as u64);
        pb.set_position(d as u64)
    });
    pb.finish_and_clear();
    r
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

/// `import`: the problems found before processing go to stderr one per line, then one
/// `error:` line with their count (exit 1, nothing written).
fn import(a: ImportArgs, quiet: bool) -> Result<()> {
    use pradar::campaign::import::{ImportParams, SweepFiles};
    let sweeps = match (a.sweeps, a.name_pattern, a.index) {
        (Some(glob), Some(pattern), _) => SweepFiles::Glob { glob, pattern },
        (_, _, Some(index)) => SweepFiles::Index(index),
        _ => anyhow::bail!("import: give --sweeps GLOB --name-pattern PATTERN, or --index CSV"),
    };
    let params = ImportParams {
        poses: a.poses,
        sweeps,
        directions: a.directions,
        layout: a.layout,
        base: a.base,
        name: a.name,
        elements: a.elements,
        out: a.out,
        to_parquet: a.to_parquet,
    };
    let pb = bar(quiet, "import", 0);
    let r = pradar::campaign::import::run(&params, &|d, t| {
        pb.set_length(t as u64);
        pb.set_position(d as u64)
    });
    pb.finish_and_clear();
    let outcome = r?;
    if !outcome.problems.is_empty() {
        for p in &outcome.problems {
            eprintln!("{p}");
        }
        let count = |k: &str| outcome.problems.iter().filter(|p| p.starts_with(k)).count();
        anyhow::bail!(
            "import: {} problem(s) before processing ({} missing, {} duplicated, {} extra, {} unreadable, {} grid); nothing written",
            outcome.problems.len(),
            count("missing"),
            count("duplicated"),
            count("extra"),
            count("unreadable"),
            count("grid")
        );
    }
    report(quiet, outcome);
    Ok(())
}

fn simulate(a: SimulateArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Simulate {
        campaign: a.campaign,
        out: a.out,
        elements: a.elements,
        format: a.format,
    };
    report(
        quiet,
        with_bar(quiet, "simulate", |p| commands::simulate(&cmd, p))?,
    );
    Ok(())
}

fn energy(a: EnergyArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Energy {
        campaign: a.campaign,
        out: a.out,
    };
    report(
        quiet,
        with_bar(quiet, "energy", |p| commands::energy(&cmd, p))?,
    );
    Ok(())
}

fn synth(a: SynthArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Synth {
        model: a.model,
        campaign: a.campaign,
        out: a.out,
        elements: a.elements,
        values: a.set.into_iter().collect(),
        params: pradar::model::SynthParams {
            seed: a.seed,
            truth_dir: a.truth,
            ..Default::default()
        },
    };
    report(
        quiet,
        with_bar(quiet, "synth", |p| commands::synth(&cmd, p))?,
    );
    Ok(())
}

fn calibrate(a: CalibrateArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Calibrate {
        energy: a.energy,
        campaign: a.campaign,
        out: a.out,
        prior: a.prior,
        report: a.report,
        chain: a.chain,
        params: pradar::calibrate::CalibrateParams {
            simulations: a.simulations,
            population: a.population,
            seed: a.seed,
            ..Default::default()
        },
    };
    report(
        quiet,
        with_bar(quiet, "calibrate", |p| commands::calibrate(&cmd, p))?,
    );
    Ok(())
}

fn check(a: CheckArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Check {
        model: a.model,
        campaign: a.campaign,
        energy: a.energy,
        out: a.out,
        params: pradar::check::CheckParams {
            draws: a.draws,
            seed: a.seed,
            ..Default::default()
        },
    };
    let summary = with_bar(quiet, "check", |p| commands::check(&cmd, p))?;
    let r = &summary.result;
    report(quiet, &summary);
    if let Some(p) = a.fail_below {
        if r.corrected_p() < p || r.max_ratio() > pradar::check::MAX_RATIO {
            anyhow::bail!("check failed (--fail-below {p}): {}", r.verdict());
        }
    }
    Ok(())
}

fn map(a: MapArgs, quiet: bool) -> Result<()> {
    use pradar::mapping::{EkfParams, GridParams, MapOptions, MapRun, OgParams};
    let single = a
        .campaign
        .zip(a.energy)
        .map(|(campaign, energy)| MapRun { campaign, energy });
    let cmd = commands::Map {
        options: MapOptions {
            method: a.method,
            runs: single.into_iter().collect(),
            out: a.out,
            elements: a.elements,
            grid: GridParams {
                cell_m: a.cell_m,
                ..Default::default()
            },
            og: OgParams {
                pfa: a.pfa,
                prior: a.prior,
                passes: a.passes as usize,
                ..Default::default()
            },
            ekf: EkfParams {
                variant: a.ekf,
                mu0: a.mu0,
                sigma0: a.sigma0,
                ..Default::default()
            },
            pose_noise: pradar::mapping::job::PoseNoise {
                position_m: a.pose_noise_m,
                heading_deg: a.pose_noise_deg,
                seed: a.pose_seed,
            },
        },
        run_specs: a.run,
    };
    report(quiet, with_bar(quiet, "map", |p| commands::map(&cmd, p))?);
    Ok(())
}

fn extract(a: ExtractArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Extract {
        energy: a.energy,
        campaign: a.campaign,
        out: a.out,
        params: pradar::mpc::ExtractParams {
            diffuse: pradar::mpc::DiffuseParams {
                enabled: !a.no_diffuse,
                discrete_db: a.diffuse_db,
                ..Default::default()
            },
            ..pradar::mpc::ExtractParams::default()
                .method(a.method)
                .margin_db(a.margin_db)
                .dynamic_range_db(a.dynamic_range_db)
        },
    };
    report(quiet, commands::extract(&cmd)?);
    Ok(())
}

fn cluster(a: ClusterArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Cluster {
        mpcs: a.mpcs,
        out: a.out,
        params: pradar::cluster::ClusterParams::default()
            .k_max(a.k_max)
            .seed(a.seed)
            .criterion(a.criterion),
    };
    let summary = commands::cluster(&cmd)?;
    if let Some(w) = summary.warning() {
        eprintln!("warning: {w}");
    }
    report(quiet, summary);
    Ok(())
}

fn fit(a: FitArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Fit {
        clusters: a.clusters,
        campaign: a.campaign,
        out: a.out,
        table: a.table,
        truth: a.truth,
        energy: a.energy,
        params: pradar::fit::channel::FitParams {
            bootstrap: a.bootstrap,
            seed: a.seed,
        },
    };
    let summary = commands::fit(&cmd)?;
    for w in summary.warnings() {
        eprintln!("warning: {w}");
    }
    report(quiet, summary);
    Ok(())
}

fn reproduce(a: ReproduceArgs, quiet: bool) -> Result<()> {
    let opts = pradar::pipeline::ReproduceOptions {
        out: a.out,
        campaign: a.campaign,
        elements: a.elements,
        experiments: !a.skip_experiments,
        experiment_params: ExperimentParams::default().seeds(a.seeds).check()?,
    }
    .check()?;
    let progress = |label: &str, total: usize| stage_bar(quiet, label, total);
    let index = pradar::pipeline::reproduce(&opts, &progress)?;
    report(quiet, format_args!("report: {}", index.display()));
    Ok(())
}

fn report_cmd(a: ReportArgs, quiet: bool) -> Result<()> {
    let opts = pradar::pipeline::ReportOptions {
        out: a.out,
        campaign: a.campaign,
        energy: a.energy,
        model: a.model,
        truth: a.truth,
        experiments: !a.skip_experiments,
        experiment_params: ExperimentParams::default().seeds(a.seeds).check()?,
    }
    .check()?;
    let progress = |label: &str, total: usize| stage_bar(quiet, label, total);
    let index = pradar::pipeline::report(&opts, &progress)?;
    report(quiet, format_args!("report: {}", index.display()));
    Ok(())
}

fn experiment(a: ExperimentArgs, quiet: bool) -> Result<()> {
    let cmd = commands::Experiments {
        name: a.name,
        inputs: InputOptions {
            campaign: a.campaign,
            energy: a.energy,
            model: a.model,
        },
        params: ExperimentParams::default().seeds(a.seeds),
        out: a.out,
    };
    let progress = |label: &str, total: usize| stage_bar(quiet, label, total);
    report(quiet, commands::experiments(&cmd, &progress)?);
    Ok(())
}
