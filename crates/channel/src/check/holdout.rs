//! The held-out check (DESIGN §2 "Model check": a measured campaign has no second
//! realisation, so the model is also checked on positions the fit did not see).
//!
//! Takes the campaign, its energy table (and the table's path, which messages name) and
//! the check's options; gives a [`HoldoutResult`]: the two halves' position labels and,
//! for each way, the model fitted on one half and its [`CheckResult`] against the other.
//!
//! * **Split**: the positions in walk order (pose order) cut into two contiguous halves,
//!   A = positions 0..⌈n/2⌉ and B = the rest ([`halves`]). Contiguous, not alternating:
//!   neighbouring poses 0.4 m apart see the same walls and clutter from nearly the same
//!   place, so a model fitted on every other pose would be checked on returns it has all
//!   but seen; a contiguous half is a part of the building the fit did not see (along a
//!   corridor, the other end). A half needs at least 2 positions (the fit's bootstrap
//!   resamples positions, the check's per-position statistics compare several), so a
//!   campaign of fewer than 4 positions is refused with one line naming the manifest and
//!   its count.
//! * **Each way** (fit on A → check on B, fit on B → check on A): the campaign and the
//!   energy table restricted to the fit half
//!   ([`Campaign::restrict`](crate::campaign::manifest::Campaign::restrict),
//!   [`EnergyMatrix::restrict`](crate::energy::EnergyMatrix::restrict): poses, labels and
//!   missing sweeps remapped, the profiles copied bit for bit); the chain as `report`
//!   runs it (`pipeline::analyse`): [`extract_and_cluster`] with
//!   [`ChainParams::for_campaign`], [`fit_clustering`] with the default [`FitParams`], then
//!   the layout's levels ([`fit_levels`]; when they cannot be read the fit's model is kept
//!   and [`Way::levels_error`] says why); then [`check`] of that model, as written
//!   (plug-in: the model's own values in every draw, no posterior), against the other
//!   half's table. The draws carry the whole table's recorded N0 (a half keeps the
//!   table's metadata) and come from the check's seed, as a check of the whole table's.
//! * **Verdict**: each way has the check's own verdict ([`CheckResult::passes`]: max-T
//!   p > α and the noise floors within [`MAX_NOISE_DB`](super::MAX_NOISE_DB)); the
//!   held-out check **passes only when both ways pass**, and both p-values are reported.
//!   Each way rejects a correct model with probability at most α, so the pair does with at
//!   most 2α (10 % at α = 0.05), whatever their dependence: the ways share the building, and
//!   with equal halves their draws' noise streams too (keyed by the check's seed and the
//!   half's own position index). A fit
//!   that fails on a half (too few clusters, a quantity not drawable) is an error naming
//!   the half.
//!
//! * **Estimator** ([`Estimator`], `check --holdout --estimator`): the model each way
//!   writes is the chain's as above (`chain`, the default: the paper's method), that model
//!   refined on the fit half by simulated minimum distance (`smm`, [`crate::smm`]), or
//!   `calibrate`'s on the fit half under the default prior at [`CALIBRATE_SIMULATIONS`]
//!   (its posterior medians). The combined verdict line names an estimator other than the
//!   chain. docs/zoo.md compares the three on the zoo.
//!
//! Cost: with the chain, two chains on half the positions and two checks of R draws over
//! half the poses, about one fit and one check of the whole table; `smm` adds 100–170
//! evaluations of 8 draws per way, `calibrate` 600 simulations per way.

use super::{check, CheckResult, CheckValid, ALPHA};
use crate::calibrate::{calibrate, CalibrateParams, CalibrateValid, Prior};
use crate::campaign::manifest::Campaign;
use crate::chain::{extract_and_cluster, ChainParams};
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::export::{Cell, Column, Table};
use crate::fit::channel::{fit_clustering, FitParams};
use crate::model::file::ModelConfig;
use crate::model::levels::fit_levels;
use crate::params::ParamGuard;
use crate::smm::{refine, SmmParams, SmmValid};
use std::path::Path;

/// Fewest positions a half may have.
pub const MIN_HALF: usize = 2;

/// The halves' names, in order.
pub const NAMES: [&str; 2] = ["A", "B"];

/// One half of the campaign's positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Half {
    /// "A" (the first positions in walk order) or "B" (the rest).
    pub name: &'static str,
    /// The positions' indices in the whole campaign.
    pub positions: Vec<usize>,
    /// Their labels ([`Manifest::label`](crate::campaign::manifest::Manifest::label)).
    pub labels: Vec<String>,
}

impl Half {
    /// "A (positions 0–5)": the name and the first and last labels.
    pub fn describe(&self) -> String {
        match (self.labels.first(), self.labels.last()) {
            (Some(a), Some(b)) if self.labels.len() > 1 => {
                format!("{} (positions {a}–{b})", self.name)
            }
            (Some(a), _) => format!("{} (position {a})", self.name),
            _ => self.name.to_string(),
        }
    }
}

/// One way: the model fitted on one half, checked against the other.
#[derive(Debug, Clone)]
pub struct Way {
    /// Index of the half the model was fitted on (0: A, 1: B); checked on the other.
    pub fitted_on: usize,
    /// The model fitted on it (after the levels), as checked.
    pub model: ModelConfig,
    /// Why the levels could not be read from the fit half's table, if so (the model is
    /// then the cluster fit's).
    pub levels_error: Option<String>,
    /// The fit's wall time (chain and levels), s.
    pub fit_s: f64,
    /// The check against the other half.
    pub result: CheckResult,
}

/// The held-out check: the halves and both ways.
#[derive(Debug, Clone)]
pub struct HoldoutResult {
    /// A and B.
    pub halves: [Half; 2],
    /// Fitted on A → checked on B, then fitted on B → checked on A.
    pub ways: [Way; 2],
    /// The estimator of both ways' models.
    pub estimator: EstimatorKind,
    /// Wall time, s.
    pub wall_s: f64,
}

impl HoldoutResult {
    /// Whether the held-out check passes: both ways pass.
    pub fn passes(&self) -> bool {
        self.ways.iter().all(|w| w.result.passes())
    }

    /// The half a way was fitted on and the one it was checked on.
    pub fn pair(&self, w: &Way) -> (&Half, &Half) {
        (&self.halves[w.fitted_on], &self.halves[1 - w.fitted_on])
    }

    /// One way's line: the halves, then the check's verdict.
    pub fn way_line(&self, w: &Way) -> String {
        let (fit, on) = self.pair(w);
        format!(
            "held out, fitted on {} → checked on {}: {}",
            fit.describe(),
            on.describe(),
            w.result.verdict()
        )
    }

    /// The combined verdict in one line: PASS only when both ways pass, with both
    /// p-values.
    pub fn verdict(&self) -> String {
        let ps: Vec<String> = (self.ways.iter())
            .map(|w| {
                format!(
                    "p = {:.3} fitted on {}{}",
                    w.result.joint_p,
                    self.halves[w.fitted_on].name,
                    if w.result.passes() { "" } else { " (fails)" }
                )
            })
            .collect();
        // the default estimator's line as it always was; another names itself
        let by = match self.estimator {
            EstimatorKind::Chain => String::new(),
            e => format!(" (estimator {})", e.name()),
        };
        format!(
            "held-out check{by}: {}: {} (passes only when both ways pass, each at α = {ALPHA})",
            if self.passes() { "PASS" } else { "FAIL" },
            ps.join(", ")
        )
    }

    /// The table: one row per way — the halves, the max-T p-value, the noise floor's
    /// offset from the draws', the misses and the verdict.
    pub fn table(&self) -> Table {
        let mut t = Table::new(vec![
            Column::new("fitted on", "fitted_on"),
            Column::new("checked on", "checked_on"),
            Column::new("max-T p", "p"),
            Column::new("noise floor − draws' (dB)", "noise_offset_db"),
            Column::new("misses", "misses"),
            Column::new("verdict", "verdict"),
        ]);
        for w in &self.ways {
            let (fit, on) = self.pair(w);
            let r = &w.result;
            let misses = r.misses();
            t.push(vec![
                Cell::text(fit.describe()),
                Cell::text(on.describe()),
                Cell::num(r.joint_p, format!("{:.3}", r.joint_p)),
                Cell::fixed(r.noise.offset_db(), 1),
                if misses.is_empty() {
                    Cell::missing("—")
                } else {
                    Cell::text(misses.join(", "))
                },
                Cell::text(if r.passes() { "PASS" } else { "FAIL" }),
            ]);
        }
        t
    }

    /// Both ways' lines, then the combined verdict.
    pub fn lines(&self) -> Vec<String> {
        let mut v: Vec<String> = self.ways.iter().map(|w| self.way_line(w)).collect();
        v.push(self.verdict());
        v
    }
}

/// The two halves of `c`'s positions (module docs: A = 0..⌈n/2⌉, B = the rest); refused
/// with one line naming the manifest when a half would have fewer than [`MIN_HALF`].
pub fn halves(c: &Campaign) -> Result<[Half; 2]> {
    let m = &c.manifest;
    let n = m.positions();
    let cut = n.div_ceil(2);
    if n - cut < MIN_HALF {
        return Err(Error::input(
            &c.path,
            format!(
                "the held-out check needs at least {MIN_HALF} positions in each half; the campaign has {n} (halves of {cut} and {})",
                n - cut
            ),
        ));
    }
    let half = |k: usize, r: std::ops::Range<usize>| Half {
        name: NAMES[k],
        labels: r.clone().map(|p| m.label(p)).collect(),
        positions: r.collect(),
    };
    Ok([half(0, 0..cut), half(1, cut..n)])
}

/// The estimator whose model a way writes and checks.
#[derive(Debug, Clone, PartialEq)]
pub enum Estimator {
    /// The chain as `report` runs it (the paper's method, then the layout's levels).
    Chain,
    /// The chain's model refined by simulated minimum distance ([`crate::smm`]) on the
    /// fit half's table.
    Smm(SmmValid),
    /// `calibrate` on the fit half's table under the default prior ([`Prior::default_prior`],
    /// every quantity of the model free): its written model (posterior medians), plug-in.
    Calibrate(CalibrateValid),
}

/// The simulation budget of the held-out check's `calibrate` ([`Estimator::of`]):
/// it runs twice per check, so a fifth of `calibrate`'s default 3000 — the budget at which
/// issue 54 measured it on the 70 m hall.
pub const CALIBRATE_SIMULATIONS: usize = 600;

/// Its population (half the budget: two generations at least).
pub const CALIBRATE_POPULATION: usize = 300;

/// Which estimator, without its options: what `--estimator` names and a result records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EstimatorKind {
    /// [`Estimator::Chain`].
    #[default]
    Chain,
    /// [`Estimator::Smm`].
    Smm,
    /// [`Estimator::Calibrate`].
    Calibrate,
}

impl EstimatorKind {
    /// Every kind, in the CLI's order.
    pub const ALL: [EstimatorKind; 3] = [
        EstimatorKind::Chain,
        EstimatorKind::Smm,
        EstimatorKind::Calibrate,
    ];

    /// Its name (`--estimator`).
    pub fn name(&self) -> &'static str {
        match self {
            EstimatorKind::Chain => "chain",
            EstimatorKind::Smm => "smm",
            EstimatorKind::Calibrate => "calibrate",
        }
    }
}

impl Estimator {
    /// The estimator of `kind` with the held-out check's options: smm's defaults, and
    /// `calibrate` at [`CALIBRATE_SIMULATIONS`] and [`CALIBRATE_POPULATION`] (its defaults
    /// otherwise).
    pub fn of(kind: EstimatorKind) -> Result<Estimator> {
        Ok(match kind {
            EstimatorKind::Chain => Estimator::Chain,
            EstimatorKind::Smm => Estimator::Smm(SmmParams::default().check()?),
            EstimatorKind::Calibrate => Estimator::Calibrate(
                CalibrateParams::default()
                    .simulations(CALIBRATE_SIMULATIONS)
                    .population(CALIBRATE_POPULATION)
                    .check()?,
            ),
        })
    }

    /// Its kind.
    pub fn kind(&self) -> EstimatorKind {
        match self {
            Estimator::Chain => EstimatorKind::Chain,
            Estimator::Smm(_) => EstimatorKind::Smm,
            Estimator::Calibrate(_) => EstimatorKind::Calibrate,
        }
    }
}

/// The model `estimator` writes on (`c`, `em`) (module docs), and why the chain's levels
/// failed, if so.
fn fit_model(
    c: &Campaign,
    em: &EnergyMatrix,
    path: &Path,
    estimator: &Estimator,
) -> Result<(ModelConfig, Option<String>)> {
    match estimator {
        Estimator::Chain => chain_model(c, em, path),
        Estimator::Smm(p) => {
            let (model, levels_error) = chain_model(c, em, path)?;
            Ok((refine(c, em, path, &model, p, &|_| {})?.model, levels_error))
        }
        Estimator::Calibrate(p) => Ok((
            calibrate(c, em, path, &Prior::default_prior(), p, &|_, _| {})?.model,
            None,
        )),
    }
}

/// The model of the chain on (`c`, `em`), as `pipeline::analyse` fits it (module docs),
/// and why its levels failed, if so.
fn chain_model(
    c: &Campaign,
    em: &EnergyMatrix,
    path: &Path,
) -> Result<(ModelConfig, Option<String>)> {
    let chain = ChainParams::for_campaign(c)?;
    let (_, clustering) = extract_and_cluster(em, c, &chain)?;
    let fit = fit_clustering(path, &clustering, c, &FitParams::default().check()?)?;
    let (model, levels_error) = match fit_levels(c, em, &fit.model) {
        Ok((m, _)) => (m, None),
        Err(e) => (fit.model, Some(e.to_string())),
    };
    Ok((model.require_estimable(&Default::default())?, levels_error))
}

/// The held-out check of campaign `c` on its energy table `em` (read from `energy_path`,
/// which messages name); `params` as [`check`]'s, without a posterior (the check is of the
/// halves' own fitted models). `progress(done, 2R)` after each draw of either way.
pub fn holdout(
    c: &Campaign,
    em: &EnergyMatrix,
    energy_path: &Path,
    params: &CheckValid,
    estimator: &Estimator,
    progress: &dyn Fn(usize, usize),
) -> Result<HoldoutResult> {
    let t0 = std::time::Instant::now();
    if params.posterior.is_some() {
        return Err(Error::param(
            "--posterior",
            "the held-out check draws each half's own fitted model (plug-in), not a posterior",
        ));
    }
    crate::energy::matrix::check_campaign(c, em, energy_path)?;
    let halves = halves(c)?;
    let r = params.draws;
    let part = |k: usize| -> Result<(Campaign, EnergyMatrix)> {
        let keep = &halves[k].positions;
        Ok((c.restrict(keep)?, em.restrict(keep)?))
    };
    let parts = [part(0)?, part(1)?];
    let mut ways = Vec::with_capacity(2);
    for k in 0..2 {
        let ((fc, fe), (oc, oe)) = (&parts[k], &parts[1 - k]);
        let t = std::time::Instant::now();
        let (model, levels_error) = fit_model(fc, fe, energy_path, estimator).map_err(|e| {
            Error::input(
                energy_path,
                format!(
                    "held-out check: the fit on half {} failed: {e}",
                    halves[k].describe()
                ),
            )
        })?;
        let fit_s = t.elapsed().as_secs_f64();
        let result = check(oc, oe, energy_path, &model, params, &|done, _| {
            progress(k * r + done, 2 * r)
        })?;
        ways.push(Way {
            fitted_on: k,
            model,
            levels_error,
            fit_s,
            result,
        });
    }
    let ways: [Way; 2] = ways.try_into().expect("two ways");
    Ok(HoldoutResult {
        halves,
        ways,
        estimator: estimator.kind(),
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Contiguous halves in walk order, A the larger when n is odd; a half under 2
    /// positions is refused naming the manifest and the count.
    #[test]
    fn halves_split_and_refuse() {
        let text = |n: usize| {
            let mut t = String::from(
                "schema_version = 1\nname = \"t\"\nlayout = \"l.geojson\"\nseed = 3\n\
                 [band]\nstart_hz = 57.5e9\nstop_hz = 63.5e9\npoints = 801\n\
                 [array]\nelements = 16\n\
                 [directions]\nstart_deg = -10.0\nstop_deg = 10.0\nstep_deg = 10.0\n\
                 [noise]\nfloor_dbm = -100.0\n",
            );
            for i in 0..n {
                t += &format!("[[poses]]\nx_m = {i}.5\ny_m = 0.5\nheading_deg = 0\n");
            }
            t
        };
        let campaign = |n: usize| Campaign {
            manifest: toml::from_str(&text(n)).unwrap(),
            path: "dir/campaign.toml".into(),
        };
        let [a, b] = halves(&campaign(7)).unwrap();
        assert_eq!(a.positions, [0, 1, 2, 3]);
        assert_eq!(b.positions, [4, 5, 6]);
        assert_eq!(b.labels, ["4", "5", "6"]);
        assert_eq!(b.describe(), "B (positions 4–6)");
        let [a, b] = halves(&campaign(4)).unwrap();
        assert_eq!((a.positions.len(), b.positions.len()), (2, 2));
        for n in [1, 2, 3] {
            let e = halves(&campaign(n)).unwrap_err().to_string();
            assert!(
                e.contains("campaign.toml")
                    && e.contains(&format!("the campaign has {n}"))
                    && !e.contains('\n'),
                "{e}"
            );
        }
        let mut c = campaign(5);
        c.manifest.labels = ["P1", "P2", "P3", "P4", "P5"].map(String::from).to_vec();
        let [a, b] = halves(&c).unwrap();
        assert_eq!(
            (a.describe(), b.describe()),
            ("A (positions P1–P3)".into(), "B (positions P4–P5)".into())
        );
    }
}
