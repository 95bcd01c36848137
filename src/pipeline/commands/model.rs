//! The model commands: `calibrate` (an energy table and its campaign into a model file by
//! ABC-SMC, with its posterior CSV and an optional report) and `check` (a model file
//! against an energy table: the posterior-predictive check, its table and plots, and the
//! `--fail-below` verdict). `check --holdout` runs the held-out check instead
//! ([`holdout`], [`crate::check::holdout`]): no model file is given — a model is fitted on
//! each half of the walk and checked on the other half, both ways — so `--model` (and
//! `--posterior`, a posterior of a model) conflict with it. Each takes its command struct
//! and gives a summary whose `Display` is printed.

use super::{campaign_inputs, refuse, StepProgress};
use crate::campaign::manifest::Campaign;
use crate::error::Result;
use crate::model::file::ModelConfig;
use crate::params::ParamGuard;
use std::fmt;
use std::path::{Path, PathBuf};

/// `pradar calibrate`: the channel model fitted without clustering (ABC-SMC with `synth`
/// as the simulator, [`crate::calibrate`]).
#[derive(Debug, Clone)]
pub struct Calibrate {
    /// Energy Parquet (measured or synthesised).
    pub energy: PathBuf,
    /// The campaign (analysis view: `[scene]`/`[clutter]` are never read).
    pub campaign: PathBuf,
    /// Output model file; the final population is written beside it as
    /// `<stem>_posterior.csv`.
    pub out: PathBuf,
    /// Prior file (model schema; default: [`crate::calibrate::Prior::default_prior`],
    /// every quantity free at its [`crate::calibrate::DEFAULT_PRIOR`] range).
    pub prior: Option<PathBuf>,
    /// Without a prior file: the clusters' quantities only, no `[diffuse]` or `[walls]`
    /// ([`crate::calibrate::Prior::no_walls`]).
    pub no_walls: bool,
    /// Budget, population, seed.
    pub params: crate::calibrate::CalibrateParams,
    /// Report folder (`index.html` with the marginal posteriors and correlations, and the
    /// predictive checks of the calibrated model, plug-in and posterior predictive, and of
    /// the chain's).
    pub report: Option<PathBuf>,
    /// The cluster chain's model file (`fit` output), shown beside the posterior in the
    /// report.
    pub chain: Option<PathBuf>,
}

/// What `calibrate` wrote.
#[derive(Debug, Clone)]
pub struct CalibrateSummary {
    /// The calibration.
    pub calibration: crate::calibrate::Calibration,
    /// The model file written.
    pub out: PathBuf,
    /// The posterior CSV written.
    pub posterior: PathBuf,
}

impl fmt::Display for CalibrateSummary {
    /// One line per free quantity (median and 95 % credible interval), then the run.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.calibration;
        for (k, name) in c.free.iter().enumerate() {
            let q = c.model.quantity(name).expect("a free quantity exists");
            let [lo, hi] = q.interval.unwrap_or([f64::NAN; 2]);
            writeln!(
                f,
                "{name:<26} {:>10.4} {:<5} 95 % [{lo:.4}, {hi:.4}]{}",
                q.value,
                q.unit,
                if c.informed(k) {
                    String::new()
                } else {
                    format!(
                        "  not informed: the interval spans {:.0} % of the prior's ln-range",
                        100.0 * c.width_share(k)
                    )
                }
            )?;
        }
        let p = &c.posterior;
        if !p.heldout_r2.is_empty() {
            let r2: Vec<String> = p.heldout_r2.iter().map(|r| format!("{r:.2}")).collect();
            writeln!(
                f,
                "held-out R² of the summaries' projection (5-fold, last generation; in order): {}",
                r2.join(" ")
            )?;
        }
        write!(
            f,
            "calibrated with {} simulations in {} generations ({:.1} s, {:.1} simulations/s, final ε {:.3}, acceptance {:.3}) -> {} (posterior in {})",
            p.simulations,
            p.generations,
            c.wall_s,
            p.simulations as f64 / c.wall_s.max(1e-9),
            p.epsilon,
            p.acceptance,
            self.out.display(),
            self.posterior.display()
        )
    }
}

/// The posterior CSV beside a calibrated model file: `<stem>_posterior.csv`.
pub fn posterior_csv(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "calibrated".into());
    out.with_file_name(format!("{stem}_posterior.csv"))
}

/// Run `pradar calibrate` ([`crate::calibrate::calibrate()`]).
pub fn calibrate(cmd: &Calibrate, progress: StepProgress) -> Result<CalibrateSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let posterior = posterior_csv(&cmd.out);
    let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
    inputs.push((cmd.energy.clone(), "--energy"));
    if let Some(p) = &cmd.prior {
        inputs.push((p.clone(), "--prior"));
    }
    if let Some(p) = &cmd.chain {
        inputs.push((p.clone(), "--chain"));
    }
    let mut outputs = vec![
        (cmd.out.clone(), "--out"),
        (posterior.clone(), "--out (its posterior CSV)"),
    ];
    if let Some(r) = &cmd.report {
        outputs.push((r.join("index.html"), "--report"));
        outputs.push((r.join("posterior.png"), "--report"));
        outputs.push((r.join("check_calibrated.png"), "--report"));
        outputs.push((r.join("check_posterior.png"), "--report"));
        if cmd.chain.is_some() {
            outputs.push((r.join("check_chain.png"), "--report"));
        }
    }
    refuse(&outputs, &inputs)?;
    let chain = match &cmd.chain {
        Some(p) => Some(ModelConfig::load(p)?),
        None => None,
    };
    let params = cmd.params.check()?;
    let prior = match &cmd.prior {
        Some(p) => crate::calibrate::Prior::load(p)?,
        None if cmd.no_walls => crate::calibrate::Prior::no_walls(),
        None => crate::calibrate::Prior::default_prior(),
    };
    let em = crate::energy::EnergyMatrix::read(&cmd.energy)?;
    let calibration = crate::calibrate::calibrate(&c, &em, &cmd.energy, &prior, &params, progress)?;
    calibration.write_posterior_csv(&posterior)?;
    if let Some(r) = &cmd.report {
        std::fs::create_dir_all(r).map_err(|e| crate::error::Error::io(r, e))?;
        let sec =
            crate::report::calibrate::section(r, "posterior.png", &calibration, chain.as_ref())?;
        let mut sections = vec![sec];
        // the predictive check of the calibrated model (and of the chain's), as `pradar
        // check` gives it: its default draws, the calibration's seed
        let check_params = crate::check::CheckParams {
            seed: cmd.params.seed,
            ..Default::default()
        }
        .check()?;
        let energy_name = cmd.energy.display().to_string();
        // the posterior predictive: each draw's free quantities from a particle of the
        // final population (`pradar check --posterior` on the CSV just written)
        let predictive = crate::check::CheckParams {
            seed: cmd.params.seed,
            posterior: Some(calibration.posterior_sample()),
            ..Default::default()
        }
        .check()?;
        let mut models = vec![
            (
                "Does the calibrated model reproduce the channel?",
                format!("the calibrated model (posterior medians) against {energy_name}"),
                Ok(calibration.model.clone()),
                "check_calibrated.png",
                &check_params,
            ),
            (
                "Does the calibrated posterior reproduce the channel? (posterior predictive)",
                format!(
                    "draws from the calibrated posterior (each draw's free quantities from a particle of {}) against {energy_name}",
                    posterior.display()
                ),
                Ok(calibration.model.clone()),
                "check_posterior.png",
                &predictive,
            ),
        ];
        if let (Some(m), Some(p)) = (&chain, &cmd.chain) {
            models.push((
                "Does the cluster chain's model reproduce the channel?",
                format!(
                    "the cluster chain's model {} against {energy_name}",
                    p.display()
                ),
                m.clone()
                    .require_estimable(&Default::default())
                    .map_err(|e| crate::error::Error::input(p, e.to_string())),
                "check_chain.png",
                &check_params,
            ));
        }
        for (title, what, model, png, params) in models {
            let run = || -> Result<crate::report::Section> {
                let model = model?;
                let res = crate::check::check(&c, &em, &cmd.energy, &model, params, &|_, _| {})?;
                crate::report::check::cdf_plot(&r.join(png), &res)?;
                Ok(crate::report::check::section(title, &what, &res, png))
            };
            sections.push(run().unwrap_or_else(|e| crate::report::Section {
                title: title.into(),
                html: format!(
                    "<p>Not checked: {}</p>\n",
                    crate::report::html_escape(&e.to_string())
                ),
            }));
        }
        crate::report::write_index(&r.join("index.html"), "pradar calibrate", &sections)?;
    }
    calibration.model.save(&cmd.out)?;
    Ok(CalibrateSummary {
        calibration,
        out: cmd.out.clone(),
        posterior,
    })
}

/// `pradar check`: the posterior-predictive check of a model against an energy table.
#[derive(Debug, Clone)]
pub struct Check {
    /// Model file (fitted, calibrated or hand-made).
    pub model: PathBuf,
    /// Campaign manifest (poses, directions, band, array, noise, processing, layout).
    pub campaign: PathBuf,
    /// The measured energy table of the campaign.
    pub energy: PathBuf,
    /// Output folder (`check.csv`, `check.md`, `check_cdfs.png`, `index.html`), if any.
    pub out: Option<PathBuf>,
    /// Draws, seed, cull.
    pub params: crate::check::CheckParams,
    /// `calibrate`'s posterior CSV: each draw's free quantities from a particle
    /// ([`crate::check::PosteriorSample`]); None: the model file's values in every draw.
    pub posterior: Option<PathBuf>,
}

/// What `check` found.
#[derive(Debug, Clone)]
pub struct CheckSummary {
    /// The result.
    pub result: crate::check::CheckResult,
    /// The output folder, if any.
    pub out: Option<PathBuf>,
}

impl fmt::Display for CheckSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.result.table().to_markdown())?;
        write!(
            f,
            "{} ({} draws, {:.1} s)",
            self.result.verdict(),
            self.result.draws.len(),
            self.result.wall_s
        )?;
        if let Some(o) = &self.out {
            write!(f, " -> {}", o.display())?;
        }
        Ok(())
    }
}

impl CheckSummary {
    /// The check against `check --fail-below P`: the message the command fails with when
    /// the check's p-value is at or below `fail_below` (the rule's P is
    /// [`crate::check::ALPHA`]) or the noise floors differ by more than
    /// [`crate::check::MAX_NOISE_DB`], `None` when it passes.
    pub fn failure(&self, fail_below: f64) -> Option<String> {
        let r = &self.result;
        (!r.passes_at(fail_below))
            .then(|| format!("check failed (--fail-below {fail_below}): {}", r.verdict()))
    }
}

/// Run `pradar check` ([`crate::check::check()`]); writes the table and plots when `out`
/// is set.
pub fn check(cmd: &Check, progress: StepProgress) -> Result<CheckSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    if let Some(o) = &cmd.out {
        let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
        inputs.push((cmd.model.clone(), "--model"));
        inputs.push((cmd.energy.clone(), "--energy"));
        if let Some(p) = &cmd.posterior {
            inputs.push((p.clone(), "--posterior"));
        }
        let outputs: Vec<(PathBuf, &str)> =
            ["check.csv", "check.md", "check_cdfs.png", "index.html"]
                .iter()
                .map(|n| (o.join(n), "--out"))
                .collect();
        refuse(&outputs, &inputs)?;
    }
    let model = ModelConfig::load(&cmd.model)?
        .require_estimable(&Default::default())
        .map_err(|e| crate::error::Error::input(&cmd.model, e.to_string()))?;
    let mut params = cmd.params.clone();
    if let Some(p) = &cmd.posterior {
        let post = crate::check::PosteriorSample::read(p)?;
        // every quantity of the sample must be in the model file (one line naming it)
        post.model(&model, 0)?;
        params.posterior = Some(post);
    }
    let params = params.check()?;
    let em = crate::energy::EnergyMatrix::read(&cmd.energy)?;
    let result = crate::check::check(&c, &em, &cmd.energy, &model, &params, progress)?;
    if let Some(o) = &cmd.out {
        let what = format!(
            "model {} against {}",
            cmd.model.display(),
            cmd.energy.display()
        );
        crate::report::check::write(o, &what, &result)?;
    }
    Ok(CheckSummary {
        result,
        out: cmd.out.clone(),
    })
}

/// `pradar check --holdout`: the held-out check of a campaign's energy table
/// ([`crate::check::holdout()`]).
#[derive(Debug, Clone)]
pub struct Holdout {
    /// Campaign manifest.
    pub campaign: PathBuf,
    /// The campaign's measured energy table.
    pub energy: PathBuf,
    /// Output folder ([`crate::report::check::holdout_files`]), if any.
    pub out: Option<PathBuf>,
    /// Draws, seed, cull (no posterior).
    pub params: crate::check::CheckParams,
    /// The estimator of each half's model (`--estimator`), with the held-out check's
    /// options ([`crate::check::Estimator::of`]).
    pub estimator: crate::check::EstimatorKind,
}

/// What `check --holdout` found.
#[derive(Debug, Clone)]
pub struct HoldoutSummary {
    /// The result.
    pub result: crate::check::HoldoutResult,
    /// The output folder, if any.
    pub out: Option<PathBuf>,
}

impl fmt::Display for HoldoutSummary {
    /// Each way's table, then both ways' verdict lines and the combined verdict.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.result;
        for w in &r.ways {
            let (fit, on) = r.pair(w);
            writeln!(
                f,
                "fitted on {} ({:.1} s), checked on {} ({:.1} s):\n",
                fit.describe(),
                w.fit_s,
                on.describe(),
                w.result.wall_s
            )?;
            writeln!(f, "{}", w.result.table().to_markdown())?;
        }
        write!(f, "{} ({:.1} s)", r.lines().join("\n"), r.wall_s)?;
        if let Some(o) = &self.out {
            write!(f, " -> {}", o.display())?;
        }
        Ok(())
    }
}

impl HoldoutSummary {
    /// The verdict lines `--quiet` prints: both ways' and the combined one.
    pub fn verdict(&self) -> String {
        self.result.lines().join("\n")
    }

    /// The check against `check --holdout --fail-below P`: the message the command fails
    /// with when either way's p-value is at or below `fail_below` or its noise floors
    /// differ, `None` when both pass.
    pub fn failure(&self, fail_below: f64) -> Option<String> {
        let r = &self.result;
        let failed: Vec<String> = (r.ways.iter())
            .filter(|w| !w.result.passes_at(fail_below))
            .map(|w| r.way_line(w))
            .collect();
        (!failed.is_empty()).then(|| {
            format!(
                "held-out check failed (--fail-below {fail_below}): {}",
                failed.join("; ")
            )
        })
    }
}

/// Run `pradar check --holdout`; writes the files when `out` is set.
pub fn holdout(cmd: &Holdout, progress: StepProgress) -> Result<HoldoutSummary> {
    let c = Campaign::load(&cmd.campaign)?;
    let em = crate::energy::EnergyMatrix::read(&cmd.energy)?;
    let params = cmd.params.check()?;
    let estimator = crate::check::Estimator::of(cmd.estimator)?;
    // the halves (and a campaign too small for them) known before the outputs are named
    crate::check::holdout::halves(&c)?;
    if let Some(o) = &cmd.out {
        let mut inputs: Vec<(PathBuf, &str)> = campaign_inputs(&c).into();
        inputs.push((cmd.energy.clone(), "--energy"));
        let outputs: Vec<(PathBuf, &str)> = (crate::report::check::holdout_files().iter())
            .map(|n| (o.join(n), "--out"))
            .collect();
        refuse(&outputs, &inputs)?;
    }
    let result = crate::check::holdout(&c, &em, &cmd.energy, &params, &estimator, progress)?;
    if let Some(o) = &cmd.out {
        let what = format!("the energy table {}", cmd.energy.display());
        crate::report::check::write_holdout(o, &what, &result)?;
    }
    Ok(HoldoutSummary {
        result,
        out: cmd.out.clone(),
    })
}
