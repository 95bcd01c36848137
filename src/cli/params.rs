//! How each subcommand's arguments become the library's command structs
//! ([`pradar::pipeline::commands`], [`pradar::pipeline::ReproduceOptions`],
//! [`pradar::pipeline::ReportOptions`]): one `into_…` method per `…Args`, taking the
//! parsed flags and giving the struct the library entry runs. Nothing here reads a file.

use super::{
    CalibrateArgs, CheckArgs, ClusterArgs, EnergyArgs, ExperimentArgs, ExploreArgs, ExploreData,
    ExtractArgs, FitArgs, ImportArgs, MapArgs, ReportArgs, ReproduceArgs, SimulateArgs, SynthArgs,
};
use anyhow::Result;
use pradar::mapping::job::{MapOptions, MapRun, OdometryNoise, PoseNoise};
use pradar::mapping::{EkfParams, GridParams, OgParams};
use pradar::params::ParamGuard;
use pradar::pipeline::commands;
use pradar::pipeline::commands::{ImportParams, SweepFiles};
use pradar::pipeline::experiment::{ExperimentParams, InputOptions};
use pradar::pipeline::{ReportOptions, ReportValid, ReproduceOptions, ReproduceValid};

impl ImportArgs {
    /// The import's parameters: the one place they are built from the flags.
    pub fn into_params(self) -> Result<ImportParams> {
        let sweeps = match (self.sweeps, self.name_pattern, self.index) {
            (Some(glob), Some(pattern), _) => SweepFiles::Glob { glob, pattern },
            (_, _, Some(index)) => SweepFiles::Index(index),
            _ => anyhow::bail!("import: give --sweeps GLOB --name-pattern PATTERN, or --index CSV"),
        };
        Ok(ImportParams {
            poses: self.poses,
            sweeps,
            directions: self.directions,
            layout: self.layout,
            base: self.base,
            name: self.name,
            elements: self.elements,
            out: self.out,
            to_parquet: self.to_parquet,
            allow_missing: self.allow_missing,
        })
    }
}

impl SimulateArgs {
    /// `simulate`'s command.
    pub fn into_command(self) -> commands::Simulate {
        commands::Simulate {
            campaign: self.campaign,
            out: self.out,
            elements: self.elements,
            format: self.format,
        }
    }
}

impl EnergyArgs {
    /// `energy`'s command.
    pub fn into_command(self) -> commands::Energy {
        commands::Energy {
            campaign: self.campaign,
            out: self.out,
        }
    }
}

impl SynthArgs {
    /// `synth`'s command.
    pub fn into_command(self) -> commands::Synth {
        commands::Synth {
            model: self.model,
            campaign: self.campaign,
            out: self.out,
            elements: self.elements,
            values: self.set.into_iter().collect(),
            params: pradar::model::SynthParams {
                seed: self.seed,
                truth_dir: self.truth,
                ..Default::default()
            },
        }
    }
}

impl CalibrateArgs {
    /// `calibrate`'s command.
    pub fn into_command(self) -> commands::Calibrate {
        commands::Calibrate {
            energy: self.energy,
            campaign: self.campaign,
            out: self.out,
            prior: self.prior,
            no_walls: self.no_walls,
            report: self.report,
            chain: self.chain,
            params: pradar::calibrate::CalibrateParams {
                simulations: self.simulations,
                population: self.population,
                seed: self.seed,
                distance: self.distance,
                ridge: self.ridge,
                ..Default::default()
            },
        }
    }
}

/// What `check` runs: the check of `--model`, or the held-out check (`--holdout`, which
/// clap keeps apart from `--model` and `--posterior`).
pub enum CheckCommand {
    /// `check --model M`.
    Model(commands::Check),
    /// `check --holdout`.
    Holdout(commands::Holdout),
}

impl CheckArgs {
    /// `check`'s command (`--fail-below` stays with the arguments).
    pub fn into_command(self) -> CheckCommand {
        let params = pradar::check::CheckParams {
            draws: self.draws,
            seed: self.seed,
            ..Default::default()
        };
        match self.model {
            Some(model) => CheckCommand::Model(commands::Check {
                model,
                campaign: self.campaign,
                energy: self.energy,
                out: self.out,
                params,
                posterior: self.posterior,
            }),
            // clap requires --model unless --holdout
            None => CheckCommand::Holdout(commands::Holdout {
                campaign: self.campaign,
                energy: self.energy,
                out: self.out,
                params,
                estimator: self.estimator.unwrap_or_default(),
            }),
        }
    }
}

impl MapArgs {
    /// `map`'s command: `--campaign` + `--energy` as the first run, then the `--run`s.
    pub fn into_command(self) -> commands::Map {
        let single = self
            .campaign
            .zip(self.energy)
            .map(|(campaign, energy)| MapRun { campaign, energy });
        commands::Map {
            options: MapOptions {
                method: self.method,
                runs: single.into_iter().collect(),
                out: self.out,
                elements: self.elements,
                grid: GridParams {
                    cell_m: self.cell_m,
                    ..Default::default()
                },
                og: OgParams {
                    pfa: self.pfa,
                    prior: self.prior,
                    bound_silent: self.og_bound_silent,
                    credit_depth_m: self
                        .og_credit_depth
                        .is_finite()
                        .then_some(self.og_credit_depth),
                    credit: self.og_credit,
                    ..Default::default()
                },
                ekf: EkfParams {
                    variant: self.ekf,
                    update: self.ekf_update,
                    mu0: self.mu0,
                    sigma0: self.sigma0,
                    kappa: self.kappa,
                    arc_explain: self.ekf_arc_explain,
                    ..Default::default()
                },
                pose_noise: PoseNoise {
                    position_m: self.pose_noise_m,
                    heading_deg: self.pose_noise_deg,
                    seed: self.pose_seed,
                },
                poses_from: self.poses_from,
                odometry: OdometryNoise {
                    step_m: self.odometry_m,
                    step_deg: self.odometry_deg,
                    seed: self.pose_seed,
                },
            },
            run_specs: self.run,
        }
    }
}

impl ExtractArgs {
    /// `extract`'s command.
    pub fn into_command(self) -> commands::Extract {
        commands::Extract {
            energy: self.energy,
            campaign: self.campaign,
            out: self.out,
            params: pradar::mpc::ExtractParams {
                diffuse: pradar::mpc::DiffuseParams {
                    enabled: !self.no_diffuse,
                    discrete_db: self.diffuse_db,
                    ..Default::default()
                },
                ..pradar::mpc::ExtractParams::default()
                    .method(self.method)
                    .margin_db(self.margin_db)
                    .dynamic_range_db(self.dynamic_range_db)
            },
        }
    }
}

impl ClusterArgs {
    /// `cluster`'s command.
    pub fn into_command(self) -> commands::Cluster {
        commands::Cluster {
            mpcs: self.mpcs,
            out: self.out,
            params: pradar::cluster::ClusterParams::default()
                .k_max(self.k_max)
                .seed(self.seed)
                .criterion(self.criterion),
        }
    }
}

impl FitArgs {
    /// `fit`'s command.
    pub fn into_command(self) -> commands::Fit {
        commands::Fit {
            clusters: self.clusters,
            campaign: self.campaign,
            out: self.out,
            table: self.table,
            truth: self.truth,
            energy: self.energy,
            params: pradar::fit::channel::FitParams {
                bootstrap: self.bootstrap,
                seed: self.seed,
            },
            closed_loop: self.closed_loop,
        }
    }
}

impl ReproduceArgs {
    /// `reproduce`'s options, checked.
    pub fn into_options(self) -> Result<ReproduceValid> {
        Ok(ReproduceOptions {
            out: self.out,
            campaign: self.campaign,
            elements: self.elements,
            experiments: !self.skip_experiments,
            experiment_params: ExperimentParams::default()
                .seeds(self.seeds.seeds)
                .check()?,
        }
        .check()?)
    }
}

impl ReportArgs {
    /// `report`'s options, checked.
    pub fn into_options(self) -> Result<ReportValid> {
        Ok(ReportOptions {
            out: self.out,
            campaign: self.campaign,
            energy: self.energy,
            model: self.model,
            truth: self.truth,
            experiments: !self.skip_experiments,
            experiment_params: ExperimentParams::default()
                .seeds(self.seeds.seeds)
                .check()?,
            explore: self.explore,
        }
        .check()?)
    }
}

impl ExperimentArgs {
    /// `experiment`'s command.
    pub fn into_command(self) -> commands::Experiments {
        commands::Experiments {
            name: self.name,
            inputs: InputOptions {
                campaign: self.campaign,
                energy: self.energy,
                model: self.model,
            },
            params: ExperimentParams::default()
                .seeds(self.seeds.seeds)
                .fig6_data(self.data),
            out: self.out,
        }
    }
}

impl ExploreArgs {
    /// `explore`'s command (`--model` means model data, with or without `--data model`).
    pub fn into_command(self) -> commands::Explore {
        let data = match (self.data, self.model) {
            (_, Some(m)) => pradar::explore::DataKind::Model(m),
            (ExploreData::Model | ExploreData::Sweeps, None) => pradar::explore::DataKind::Sweeps,
        };
        commands::Explore {
            campaign: self.campaign,
            data,
            energy_model: self.energy_model,
            params: pradar::explore::ExploreParams {
                elements: self.elements,
                pulses: self.pulses,
                step_deg: self.step_deg,
                bandwidth_ghz: self.bandwidth_ghz,
                tx_power_dbm: self.tx_power_dbm,
                mappers: self.mapper,
                seeds: self.seeds,
                max_minutes: self.max_minutes,
                ..Default::default()
            },
            keep_work: self.keep_work,
            out: self.out,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Cli, Cmd};
    use super::CheckCommand;
    use clap::Parser;
    use pradar::mapping::job::PoseNoise;
    use pradar::mapping::{EkfParams, GridParams, OgParams};
    use pradar::pipeline::experiment::ExperimentParams;

    /// One subcommand parsed from its required arguments only.
    fn parse(argv: &[&str]) -> Cmd {
        let mut full = vec!["pradar"];
        full.extend_from_slice(argv);
        Cli::try_parse_from(full).unwrap().cmd
    }

    /// `check --holdout` fits its own models: `--model` and `--posterior` beside it are
    /// refused naming both flags, and without either `--model` is required.
    #[test]
    fn check_holdout_conflicts_with_model() {
        let base = [
            "pradar",
            "check",
            "--campaign",
            "c.toml",
            "--energy",
            "e.parquet",
        ];
        for extra in [["--model", "m.toml"], ["--posterior", "p.csv"]] {
            let mut argv = base.to_vec();
            argv.push("--holdout");
            argv.extend(extra);
            let e = Cli::try_parse_from(argv).err().unwrap().to_string();
            assert!(e.contains("--holdout") && e.contains(extra[0]), "{e}");
        }
        let e = Cli::try_parse_from(base).err().unwrap().to_string();
        assert!(e.contains("--model"), "{e}");
    }

    /// `map` without mapper flags gives the library's defaults: the CLI's defaults cannot
    /// drift from `OgParams::default()`, `EkfParams::default()` and `GridParams::default()`.
    #[test]
    fn map_flags_default_to_the_library_defaults() {
        let options = |extra: &[&str]| {
            let mut argv = vec![
                "map",
                "--campaign",
                "c.toml",
                "--energy",
                "e.parquet",
                "--out",
                "o",
            ];
            argv.extend_from_slice(extra);
            let Cmd::Map(args) = parse(&argv) else {
                panic!("not map")
            };
            args.into_command().options
        };
        let o = options(&[]);
        assert_eq!(o.method, pradar::mapping::Method::default());
        assert_eq!(o.og, OgParams::default());
        assert_eq!(o.ekf, EkfParams::default());
        assert_eq!(o.grid, GridParams::default());
        assert_eq!(
            o.pose_noise,
            PoseNoise {
                seed: PoseNoise::DEFAULT_SEED,
                ..Default::default()
            }
        );
        let guard = options(&["--og-credit-depth", "guard"]);
        assert_eq!(guard.og.credit_depth_m, None);
        let echo = options(&["--og-credit", "echo"]);
        assert_eq!(echo.og.credit, pradar::mapping::og::OgCredit::Echo);
        assert_eq!(o.og.credit, pradar::mapping::og::OgCredit::Ring);
        use pradar::mapping::job::{OdometryNoise, PosesFrom};
        use pradar::params::ParamGuard;
        assert_eq!(o.poses_from, PosesFrom::Manifest);
        assert_eq!(o.odometry, OdometryNoise::default());
        let s = options(&[
            "--poses-from",
            "sweeps",
            "--odometry-m",
            "0.2",
            "--pose-seed",
            "4",
        ]);
        assert_eq!(s.poses_from, PosesFrom::Sweeps);
        assert_eq!(
            s.odometry,
            OdometryNoise {
                step_m: 0.2,
                seed: 4,
                ..Default::default()
            }
        );
        // sweeps and --pose-noise-* together: one named error at the check
        let both = options(&["--poses-from", "odometry", "--pose-noise-m", "0.1"]);
        let msg = both.check().unwrap_err().to_string();
        assert!(msg.contains("--poses-from"), "{msg}");
    }

    /// Every other subcommand's defaults are the library's: each parsed with only its
    /// required arguments gives the library's default parameter struct.
    #[test]
    fn every_subcommand_defaults_to_the_library_defaults() {
        let (c, e, m, o) = ("--campaign", "--energy", "--model", "--out");
        match parse(&["simulate", c, "c.toml", o, "s"]) {
            Cmd::Simulate(a) => assert_eq!(a.into_command().format, Default::default()),
            _ => unreachable!(),
        }
        match parse(&["synth", m, "m.toml", c, "c.toml", o, "e.parquet"]) {
            Cmd::Synth(a) => {
                let cmd = a.into_command();
                assert_eq!(cmd.params, pradar::model::SynthParams::default());
                assert!(cmd.values.is_empty() && cmd.elements.is_none());
            }
            _ => unreachable!(),
        }
        match parse(&["calibrate", e, "e.parquet", c, "c.toml", o, "m.toml"]) {
            Cmd::Calibrate(a) => {
                let cmd = a.into_command();
                assert_eq!(cmd.params, pradar::calibrate::CalibrateParams::default());
                // the default prior (every quantity free), not the clusters' only
                assert!(cmd.prior.is_none() && !cmd.no_walls);
            }
            _ => unreachable!(),
        }
        match parse(&["check", m, "m.toml", c, "c.toml", e, "e.parquet"]) {
            Cmd::Check(a) => {
                assert!(a.fail_below.is_none());
                match a.into_command() {
                    CheckCommand::Model(cmd) => {
                        assert_eq!(cmd.params, pradar::check::CheckParams::default())
                    }
                    CheckCommand::Holdout(_) => unreachable!(),
                }
            }
            _ => unreachable!(),
        }
        match parse(&["check", "--holdout", c, "c.toml", e, "e.parquet"]) {
            Cmd::Check(a) => match a.into_command() {
                CheckCommand::Holdout(cmd) => {
                    assert_eq!(cmd.params, pradar::check::CheckParams::default())
                }
                CheckCommand::Model(_) => unreachable!(),
            },
            _ => unreachable!(),
        }
        match parse(&["extract", e, "e.parquet", c, "c.toml", o, "m.parquet"]) {
            Cmd::Extract(a) => assert_eq!(
                a.into_command().params,
                pradar::mpc::ExtractParams::default()
            ),
            _ => unreachable!(),
        }
        match parse(&["cluster", "--mpcs", "m.parquet", o, "k.parquet"]) {
            Cmd::Cluster(a) => assert_eq!(
                a.into_command().params,
                pradar::cluster::ClusterParams::default()
            ),
            _ => unreachable!(),
        }
        let fit = [
            "fit",
            "--clusters",
            "k.parquet",
            c,
            "c.toml",
            o,
            "m.toml",
            "--table",
            "t.md",
        ];
        match parse(&fit) {
            Cmd::Fit(a) => assert_eq!(
                a.into_command().params,
                pradar::fit::channel::FitParams::default()
            ),
            _ => unreachable!(),
        }
        let seeds = ExperimentParams::default().seeds;
        match parse(&["report", c, "c.toml"]) {
            Cmd::Report(a) => {
                assert_eq!(
                    a.out,
                    std::path::Path::new(pradar::pipeline::DEFAULT_REPORT_OUT)
                );
                assert_eq!(a.seeds.seeds, seeds);
                assert!(!a.skip_experiments);
            }
            _ => unreachable!(),
        }
        match parse(&["reproduce"]) {
            Cmd::Reproduce(a) => {
                assert_eq!(
                    a.out,
                    std::path::Path::new(pradar::pipeline::DEFAULT_REPRODUCE_OUT)
                );
                assert_eq!(a.seeds.seeds, seeds);
                assert!(!a.skip_experiments);
            }
            _ => unreachable!(),
        }
        match parse(&["experiment", "all", o, "x"]) {
            Cmd::Experiment(a) => assert_eq!(a.into_command().params, ExperimentParams::default()),
            _ => unreachable!(),
        }
    }
}
