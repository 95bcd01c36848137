//! `pradar` command line: parses arguments ([`cli`]) and calls one library function per
//! subcommand ([`pradar::pipeline::commands`], [`pradar::pipeline::reproduce`]).
//!
//! Each subcommand's arguments become the library's command struct ([`cli::params`]); the
//! library entry runs with a progress bar (none with `--quiet`) and its summary is printed.
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
use cli::{CheckArgs, Cli, Cmd, ImportArgs};
use indicatif::{ProgressBar, ProgressStyle};
use pradar::pipeline::commands;

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
    let stages = |label: &str, total: usize| stage_bar(quiet, label, total);
    match cli.cmd {
        Cmd::Import(a) => import(a, quiet)?,
        Cmd::Simulate(a) => {
            let cmd = a.into_command();
            report(
                quiet,
                with_bar(quiet, "simulate", |p| commands::simulate(&cmd, p))?,
            )
        }
        Cmd::Energy(a) => {
            let cmd = a.into_command();
            let summary = with_bar(quiet, "energy", |p| commands::energy(&cmd, p))?;
            for w in &summary.report.warnings {
                eprintln!("warning: {w}");
            }
            report(quiet, summary)
        }
        Cmd::Synth(a) => {
            let cmd = a.into_command();
            report(
                quiet,
                with_bar(quiet, "synth", |p| commands::synth(&cmd, p))?,
            )
        }
        Cmd::Map(a) => {
            let cmd = a.into_command();
            report(quiet, with_bar(quiet, "map", |p| commands::map(&cmd, p))?)
        }
        Cmd::Extract(a) => report(quiet, commands::extract(&a.into_command())?),
        Cmd::Cluster(a) => {
            let summary = commands::cluster(&a.into_command())?;
            if let Some(w) = summary.warning() {
                eprintln!("warning: {w}");
            }
            report(quiet, summary)
        }
        Cmd::Fit(a) => {
            let summary = commands::fit(&a.into_command())?;
            for w in summary.warnings() {
                eprintln!("warning: {w}");
            }
            report(quiet, summary)
        }
        Cmd::Calibrate(a) => {
            let cmd = a.into_command();
            report(
                quiet,
                with_bar(quiet, "calibrate", |p| commands::calibrate(&cmd, p))?,
            )
        }
        Cmd::Check(a) => check(a, quiet)?,
        Cmd::Report(a) => {
            let done = pradar::pipeline::report(&a.into_options()?, &stages)?;
            report_done(quiet, &done)
        }
        Cmd::Reproduce(a) => {
            let done = pradar::pipeline::reproduce(&a.into_options()?, &stages)?;
            report_done(quiet, &done)
        }
        Cmd::Experiment(a) => report(quiet, commands::experiments(&a.into_command(), &stages)?),
        Cmd::Explore(a) => report(quiet, commands::explore(&a.into_command(), &stages)?),
        Cmd::Zoo(a) => report(
            quiet,
            commands::zoo(&commands::Zoo {
                out: a.out,
                seed: a.seed,
                count: a.count,
            })?,
        ),
    }
    Ok(())
}

/// Print a command's summary unless `--quiet`.
fn report(quiet: bool, summary: impl std::fmt::Display) {
    if !quiet {
        println!("{summary}");
    }
}

/// `report` and `reproduce`: their stages' warnings (as the stage's own command prints
/// them), then the page's path.
fn report_done(quiet: bool, done: &pradar::pipeline::ReportOutput) {
    for w in &done.warnings {
        eprintln!("warning: {w}");
    }
    report(quiet, format_args!("report: {}", done.index.display()))
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

/// `import`: a `warning:` line per item `--allow-missing` left out; with problems, the
/// `error:` summary first, then at most 20 problems and the count of the rest (exit 1,
/// nothing written).
fn import(a: ImportArgs, quiet: bool) -> Result<()> {
    let params = a.into_params()?;
    let outcome = with_bar(quiet, "import", |p| commands::import(&params, p))?;
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    // the summary first, then at most 20 problems (the rest counted); exit 1
    if let Some((summary, lines)) = outcome.problem_report() {
        eprintln!("error: {summary}");
        for l in lines {
            eprintln!("  {l}");
        }
        std::process::exit(1);
    }
    report(quiet, outcome);
    Ok(())
}

/// `check`: the summary (with `--quiet` its verdict line only), then with `--fail-below` an
/// error when the check fails.
fn check(a: CheckArgs, quiet: bool) -> Result<()> {
    let fail_below = a.fail_below;
    let cmd = match a.into_command() {
        cli::params::CheckCommand::Model(cmd) => cmd,
        cli::params::CheckCommand::Holdout(cmd) => return holdout(&cmd, fail_below, quiet),
    };
    let summary = with_bar(quiet, "check", |p| commands::check(&cmd, p))?;
    if quiet {
        // `--quiet` silences progress and the table, never the verdict
        println!("{}", summary.result.verdict());
    } else {
        report(quiet, &summary);
    }
    if let Some(msg) = fail_below.and_then(|p| summary.failure(p)) {
        anyhow::bail!(msg);
    }
    Ok(())
}

/// `check --holdout`: each way's table and the verdict lines (with `--quiet` the verdict
/// lines only: both ways' and the combined one), then with `--fail-below` an error when
/// either way fails.
fn holdout(cmd: &commands::Holdout, fail_below: Option<f64>, quiet: bool) -> Result<()> {
    let summary = with_bar(quiet, "check", |p| commands::holdout(cmd, p))?;
    if quiet {
        println!("{}", summary.verdict());
    } else {
        report(quiet, &summary);
    }
    if let Some(msg) = fail_below.and_then(|p| summary.failure(p)) {
        anyhow::bail!(msg);
    }
    Ok(())
}
