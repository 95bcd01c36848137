//! `pradar check`: the posterior-predictive check of a channel model against a measured
//! energy table, cluster-free (DESIGN §2 "Model check").
//!
//! Takes a model file (fitted, calibrated or hand-made), the campaign (poses, directions,
//! band, array, noise, processing, layout — never its `[scene]`/`[clutter]` truth) and
//! the campaign's energy table; gives, for each statistic of [`stats`], how far the
//! measured table is from R `synth` draws of the model over the campaign's poses compared
//! with how far the draws are from each other.
//!
//! * **Draws**: R matrices y_r = synth(model, seed_r), r = 1..R, in memory
//!   ([`EnergySimulator`]: the same draws and detector as `synth`), seed_r from a ChaCha
//!   stream keyed by (seed, "Check", r): never the data's own seed, so a model checked
//!   against its own `synth` output at the campaign seed does not replay it. The draws
//!   run in parallel and are collected in order (same bytes with any thread count).
//!   With a posterior sample (`--posterior`, `calibrate`'s final population,
//!   [`PosteriorSample`]) draw r's free quantities are those of particle j_r, drawn by
//!   weight from a stream keyed by (seed, r): y_r ~ p(y | θ_j), θ_j ~ p(θ | data), the
//!   posterior predictive (Gelman, Meng & Stern 1996). Without it every draw is the model
//!   file's (a plug-in check: the posterior medians, no parameter uncertainty), whose draws
//!   differ less from each other than data from a model known only to its posterior do.
//! * **Distances**, per statistic s: the measured distances D_r = KS(s(y_obs), s(y_r))
//!   and the reference distances d_ij = KS(s(y_i), s(y_j)), i < j (R(R−1)/2 of them;
//!   the KS distance of [`stats::ks_distance`]). Under the model the measured table is
//!   one more draw, so D_r and d_ij have the same law.
//! * **Summaries**: D = median_r D_r, d = median_ij d_ij, the ratio D/d, and the
//!   predictive p-value p = #{d_ij ≥ D} / (R(R−1)/2), the share of reference distances at
//!   least as large as D (0 when D is beyond all of them, i.e. below 1/#pairs; the
//!   Monte Carlo form (1 + k)/(1 + n) would floor p at 1/191 for R = 20, and with ten
//!   statistics the Bonferroni rule could then never fail). D, a median of R distances,
//!   varies less than one d_ij, so p is conservative: under the model it falls below 0.05
//!   less often than 5 %.
//! * **Rule**: the model passes when every statistic's ratio D/d ≤ 1.5 and the smallest
//!   p-value times the number of statistics (Bonferroni) is ≥ 0.05. The ratio guards
//!   against a model whose draws are all far from the data but also far from each other;
//!   the p-value against a miss larger than the draws' own spread.
//!
//! Layout: [`stats`] (the statistics and the KS distance); the table and plots are in
//! [`crate::report::check`].

pub mod stats;

use crate::campaign::manifest::Campaign;
use crate::energy::EnergyMatrix;
use crate::error::{Error, Result};
use crate::export::{Cell, Column, Table};
use crate::model::file::ModelConfig;
use crate::model::EnergySimulator;
use crate::params::{ParamGuard, Valid};
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use stats::{ks_distance, StatContext, Statistics, NAMES};
use std::borrow::Cow;
use std::path::Path;

/// Key of the draws' seed stream (xor-ed into the seed): "Check\0\0\0".
const STREAM: u64 = 0x4368_6563_6b00_0000;

/// The largest KS ratio D/d a passing model may have.
pub const MAX_RATIO: f64 = 1.5;

/// The smallest Bonferroni-corrected p-value a passing model may have.
pub const MIN_P: f64 = 0.05;

/// Options of a check.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckParams {
    /// Draws R, in [2, 1000] (default 20).
    pub draws: usize,
    /// Seed (default: the campaign's).
    pub seed: Option<u64>,
    /// synth's ray cull (default 1e-3, as synth).
    pub cull: f64,
    /// A posterior sample (`calibrate`'s final population): each draw's free quantities
    /// come from a particle drawn by weight, the rest from the model file (None: every
    /// draw is the model file's, the plug-in check).
    pub posterior: Option<PosteriorSample>,
}

/// The draw counts [`CheckParams`]'s check accepts (`--draws`): the reference
/// distribution needs at least one draw↔draw pair.
pub const DRAWS_RANGE: std::ops::RangeInclusive<usize> = 2..=1000;

impl Default for CheckParams {
    fn default() -> Self {
        CheckParams {
            draws: 20,
            seed: None,
            cull: 1e-3,
            posterior: None,
        }
    }
}

/// A weighted sample of models' free quantities: `calibrate`'s `<stem>_posterior.csv`
/// (`weight, distance`, then per quantity its reported value and `<name>_raw`; the
/// reported, regression-adjusted value is the one used).
#[derive(Debug, Clone, PartialEq)]
pub struct PosteriorSample {
    /// The quantities' names (model keys, e.g. `intra_cluster_rate`, `walls.specular_gamma`).
    pub names: Vec<String>,
    /// Normalised weights, one per particle.
    pub weights: Vec<f64>,
    /// Per particle, one value per name (schema units).
    pub values: Vec<Vec<f64>>,
}

impl PosteriorSample {
    /// Read a posterior CSV; one clear line naming the file and the field when it is not
    /// one (no header, a non-numeric or non-finite value, a negative weight, no particle).
    pub fn read(path: &Path) -> Result<PosteriorSample> {
        let bad = |what: String| Error::input(path, what);
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let head: Vec<&str> = lines
            .next()
            .ok_or_else(|| bad("empty file: a header `weight,distance,...` is needed".into()))?
            .split(',')
            .map(str::trim)
            .collect();
        if head.len() < 4 || head[0] != "weight" || head[1] != "distance" {
            return Err(bad(
                "header: `weight,distance,<quantity>,<quantity>_raw,...` expected".into(),
            ));
        }
        let cols: Vec<(usize, String)> = head
            .iter()
            .enumerate()
            .skip(2)
            .filter(|(_, h)| !h.ends_with("_raw"))
            .map(|(i, h)| (i, h.to_string()))
            .collect();
        let (mut weights, mut values) = (Vec::new(), Vec::new());
        for (row, line) in lines.enumerate() {
            let f: Vec<&str> = line.split(',').map(str::trim).collect();
            if f.len() != head.len() {
                return Err(bad(format!(
                    "row {}: {} fields, the header has {}",
                    row + 1,
                    f.len(),
                    head.len()
                )));
            }
            let num = |i: usize| -> Result<f64> {
                f[i].parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        bad(format!(
                            "row {}, {}: `{}` is not a finite number",
                            row + 1,
                            head[i],
                            f[i]
                        ))
                    })
            };
            let w = num(0)?;
            if w < 0.0 {
                return Err(bad(format!("row {}, weight: {w} is negative", row + 1)));
            }
            weights.push(w);
            values.push(
                cols.iter()
                    .map(|(i, _)| num(*i))
                    .collect::<Result<Vec<f64>>>()?,
            );
        }
        if weights.is_empty() || weights.iter().sum::<f64>() <= 0.0 {
            return Err(bad("no particle with a positive weight".into()));
        }
        Ok(PosteriorSample::normalised(
            cols.into_iter().map(|(_, n)| n).collect(),
            weights,
            values,
        ))
    }

    /// A sample from its quantities' names, the particles' weights (any positive total:
    /// they are normalised here) and values (schema units).
    pub fn normalised(names: Vec<String>, mut weights: Vec<f64>, values: Vec<Vec<f64>>) -> Self {
        let total: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= total);
        PosteriorSample {
            names,
            weights,
            values,
        }
    }

    /// `model` with the free quantities of particle `i`; an error names a quantity the
    /// model file does not have.
    pub fn model(&self, model: &ModelConfig, i: usize) -> Result<ModelConfig> {
        let mut m = model.clone();
        for (name, v) in self.names.iter().zip(&self.values[i]) {
            let q = m.quantity_mut(name).ok_or_else(|| {
                Error::param(
                    "--posterior",
                    format!("quantity `{name}` is not in the model file"),
                )
            })?;
            q.value = *v;
        }
        Ok(m)
    }

    /// The particle of draw `r` (by weight, from the draw's own seed stream: [`draw_seed`]
    /// of the seed xor "PART").
    fn particle(&self, seed: u64, r: usize) -> usize {
        let u = (draw_seed(seed ^ 0x5041_5254, r) >> 11) as f64 / (1u64 << 53) as f64;
        let mut acc = 0.0;
        for (i, w) in self.weights.iter().enumerate() {
            acc += w;
            if u < acc {
                return i;
            }
        }
        self.weights.len() - 1
    }
}

/// Checked check options.
pub type CheckValid = Valid<CheckParams>;

impl ParamGuard for CheckParams {
    type Checked = CheckValid;

    fn check(&self) -> Result<CheckValid> {
        if !DRAWS_RANGE.contains(&self.draws) {
            return Err(Error::param(
                "--draws",
                format!("must be in [2, 1000], got {}", self.draws),
            ));
        }
        if !(0.0..1.0).contains(&self.cull) {
            return Err(Error::param(
                "check.cull",
                format!("must be in [0, 1), got {}", self.cull),
            ));
        }
        Ok(Valid::new(self.clone()))
    }
}

/// One statistic's result.
#[derive(Debug, Clone, PartialEq)]
pub struct StatResult {
    /// Name ([`NAMES`]).
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Measured distances D_r, one per draw.
    pub measured_ks: Vec<f64>,
    /// Reference distances d_ij, i < j.
    pub reference_ks: Vec<f64>,
    /// Median of the measured statistic.
    pub measured_median: f64,
    /// Median over draws of each draw's median.
    pub draws_median: f64,
}

impl StatResult {
    /// D: the median measured distance.
    pub fn ks(&self) -> f64 {
        crate::stats::median(&self.measured_ks).unwrap_or(f64::NAN)
    }
    /// d: the median reference distance.
    pub fn reference(&self) -> f64 {
        crate::stats::median(&self.reference_ks).unwrap_or(f64::NAN)
    }
    /// D/d (0 when both are 0, infinite when only d is).
    pub fn ratio(&self) -> f64 {
        let (a, b) = (self.ks(), self.reference());
        if a == 0.0 {
            0.0
        } else if b == 0.0 {
            f64::INFINITY
        } else {
            a / b
        }
    }
    /// The predictive p-value #{d_ij ≥ D} / #pairs (0 when D is beyond every reference
    /// distance: below 1/#pairs).
    pub fn p_value(&self) -> f64 {
        let d = self.ks();
        let k = self.reference_ks.iter().filter(|&&x| x >= d).count();
        k as f64 / self.reference_ks.len().max(1) as f64
    }
}

/// The result of a check: per statistic, plus the measured and drawn statistics (for the
/// CDF plots).
#[derive(Debug, Clone)]
pub struct CheckResult {
    /// One per statistic, in the order of [`NAMES`].
    pub stats: Vec<StatResult>,
    /// The measured table's statistics.
    pub measured: Statistics,
    /// Each draw's statistics.
    pub draws: Vec<Statistics>,
    /// The seed the draws' seeds came from.
    pub seed: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl CheckResult {
    /// The smallest p-value times the number of statistics (capped at 1).
    pub fn corrected_p(&self) -> f64 {
        let min = self
            .stats
            .iter()
            .map(StatResult::p_value)
            .fold(1.0, f64::min);
        (min * self.stats.len() as f64).min(1.0)
    }

    /// The largest ratio D/d.
    pub fn max_ratio(&self) -> f64 {
        self.stats.iter().map(StatResult::ratio).fold(0.0, f64::max)
    }

    /// Whether the model passes (module docs' rule).
    pub fn passes(&self) -> bool {
        self.max_ratio() <= MAX_RATIO && self.corrected_p() >= MIN_P
    }

    /// The statistics that miss: ratio over [`MAX_RATIO`] or p·n below [`MIN_P`].
    pub fn misses(&self) -> Vec<&'static str> {
        let n = self.stats.len() as f64;
        self.stats
            .iter()
            .filter(|s| s.ratio() > MAX_RATIO || s.p_value() * n < MIN_P)
            .map(|s| s.name)
            .collect()
    }

    /// The table: per statistic the medians side by side, D, d, D/d, p and the verdict.
    pub fn table(&self) -> Table {
        let mut t = Table::new(vec![
            Column::new("statistic", "statistic"),
            Column::new("unit", "unit"),
            Column::new("measured median", "measured_median"),
            Column::new("draws' median", "draws_median"),
            Column::new("KS measured↔draws (median)", "ks"),
            Column::new("KS draw↔draw (median)", "ks_reference"),
            Column::new("ratio", "ratio"),
            Column::new("p-value", "p_value"),
            Column::new("verdict", "verdict"),
        ]);
        let n = self.stats.len() as f64;
        for s in &self.stats {
            let ok = s.ratio() <= MAX_RATIO && s.p_value() * n >= MIN_P;
            let num = |v: f64| {
                if v.is_finite() {
                    Cell::num(v, format!("{v:.3}"))
                } else {
                    Cell::Missing("—".into())
                }
            };
            t.push(vec![
                Cell::text(s.name),
                Cell::text(s.unit),
                num(s.measured_median),
                num(s.draws_median),
                Cell::fixed(s.ks(), 3),
                Cell::fixed(s.reference(), 3),
                num(s.ratio()),
                Cell::num(s.p_value(), format!("{:.4}", s.p_value())),
                Cell::text(if ok { "pass" } else { "miss" }),
            ]);
        }
        t
    }

    /// One line: pass or fail, the corrected p-value and the largest ratio.
    pub fn verdict(&self) -> String {
        let misses = self.misses();
        format!(
            "{}: Bonferroni p = {:.4} (pass ≥ {MIN_P}), largest KS ratio {:.2} (pass ≤ {MAX_RATIO}){}",
            if self.passes() { "PASS" } else { "FAIL" },
            self.corrected_p(),
            self.max_ratio(),
            if misses.is_empty() {
                String::new()
            } else {
                format!("; misses: {}", misses.join(", "))
            }
        )
    }
}

/// The statistics' context of a campaign's energy table.
pub fn context(energy: &EnergyMatrix) -> StatContext {
    let bin_ns = energy.meta.bin_width_ns;
    StatContext {
        np: energy.positions,
        nd: energy.directions(),
        nb: energy.bins,
        bin_ns,
        first_bin: ((energy.meta.gate_ns() / bin_ns).ceil() as usize).min(energy.bins),
        mu: energy.meta.noise_mean(),
        angles_deg: energy.angles_rel_deg.clone(),
    }
}

/// The seed of draw r.
fn draw_seed(seed: u64, r: usize) -> u64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
    rng.set_stream(r as u64 + 1);
    rng.next_u64()
}

/// Check `model` against the energy table `energy` (read from `energy_path`) of campaign
/// `c`. `progress(done, R)` after each draw.
pub fn check(
    c: &Campaign,
    energy: &EnergyMatrix,
    energy_path: &Path,
    model: &ModelConfig,
    params: &CheckValid,
    progress: &dyn Fn(usize, usize),
) -> Result<CheckResult> {
    let t0 = std::time::Instant::now();
    let sim = EnergySimulator::for_table(c, energy, energy_path, params.cull)?;
    let ctx = context(energy);
    let measured = Statistics::of(&ctx, &energy.data);
    let seed = params.seed.unwrap_or(c.manifest.seed);
    let r = params.draws;
    progress(0, r);
    // draws in parallel, a thread's worth at a time, so progress is called from this
    // thread only (and needs not be Sync)
    let chunk = rayon::current_num_threads().max(1);
    let mut draws: Vec<Statistics> = Vec::with_capacity(r);
    for start in (0..r).step_by(chunk) {
        let part: Vec<Statistics> = (start..(start + chunk).min(r))
            .into_par_iter()
            .map(|i| -> Result<Statistics> {
                let drawn = match &params.posterior {
                    Some(post) => Cow::Owned(post.model(model, post.particle(seed, i))?),
                    None => Cow::Borrowed(model),
                };
                let mut e = sim.energies(&drawn, draw_seed(seed, i))?;
                // the measured campaign's missing sweeps are missing from the draws too
                energy
                    .meta
                    .mask_missing(energy.directions(), energy.bins, &mut e);
                Ok(Statistics::of(&ctx, &e))
            })
            .collect::<Result<_>>()?;
        draws.extend(part);
        progress(draws.len(), r);
    }
    let stats = (0..NAMES.len())
        .map(|k| {
            let measured_ks = draws
                .iter()
                .map(|d| ks_distance(&measured.values[k], &d.values[k]))
                .collect();
            let mut reference_ks = Vec::with_capacity(r * (r - 1) / 2);
            for i in 0..r {
                for j in i + 1..r {
                    reference_ks.push(ks_distance(&draws[i].values[k], &draws[j].values[k]));
                }
            }
            let draw_medians: Vec<f64> = draws
                .iter()
                .map(|d| d.values[k].median(ctx.bin_ns))
                .filter(|v| v.is_finite())
                .collect();
            StatResult {
                name: NAMES[k].0,
                unit: NAMES[k].1,
                measured_ks,
                reference_ks,
                measured_median: measured.values[k].median(ctx.bin_ns),
                draws_median: crate::stats::median(&draw_medians).unwrap_or(f64::NAN),
            }
        })
        .collect();
    Ok(CheckResult {
        stats,
        measured,
        draws,
        seed,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A posterior CSV as `calibrate` writes it is read (weights normalised, the `_raw`
    /// columns skipped), particles are drawn by weight and deterministically, and a bad
    /// file is one line naming the file and the field.
    #[test]
    fn posterior_sample_reads_draws_and_refuses() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cal_posterior.csv");
        std::fs::write(
            &p,
            "weight,distance,intra_cluster_rate,intra_cluster_rate_raw,walls.specular_gamma,walls.specular_gamma_raw\n\
             3e0,1,0.5,0.6,0.2,0.3\n\
             1e0,2,2.0,2.1,0.4,0.5\n\
             0,3,9.0,9.0,0.9,0.9\n",
        )
        .unwrap();
        let s = PosteriorSample::read(&p).unwrap();
        assert_eq!(s.names, ["intra_cluster_rate", "walls.specular_gamma"]);
        assert_eq!(s.weights, [0.75, 0.25, 0.0]);
        assert_eq!(s.values[1], [2.0, 0.4]);
        let picks: Vec<usize> = (0..4000).map(|r| s.particle(11, r)).collect();
        assert_eq!(
            picks,
            (0..4000).map(|r| s.particle(11, r)).collect::<Vec<_>>()
        );
        assert!(!picks.contains(&2), "a zero weight is never drawn");
        let share = picks.iter().filter(|&&i| i == 0).count() as f64 / 4000.0;
        assert!((share - 0.75).abs() < 0.03, "{share}");
        // a quantity the model file lacks (Table 1 has no [walls]) is named
        let e = s.model(&ModelConfig::table1_defaults(), 1).unwrap_err();
        assert!(e.to_string().contains("walls.specular_gamma"), "{e}");
        let one = PosteriorSample {
            names: vec!["intra_cluster_rate".into()],
            weights: vec![1.0],
            values: vec![vec![2.0]],
        };
        let m = one.model(&ModelConfig::table1_defaults(), 0).unwrap();
        assert_eq!(m.intra_cluster_rate.value, 2.0);
        for (text, field) in [
            ("", "empty"),
            ("w,d,a,a_raw\n1,1,1,1\n", "header"),
            ("weight,distance,a,a_raw\n1,1,1\n", "row 1"),
            ("weight,distance,a,a_raw\n1,1,x,1\n", "row 1, a"),
            ("weight,distance,a,a_raw\n-1,1,1,1\n", "weight"),
            ("weight,distance,a,a_raw\n0,1,1,1\n", "positive weight"),
            ("weight,distance,a,a_raw\n1,1,NaN,1\n", "row 1, a"),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = PosteriorSample::read(&p).unwrap_err().to_string();
            assert!(e.contains("cal_posterior.csv") && e.contains(field), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }

    fn result(measured_ks: Vec<f64>, reference_ks: Vec<f64>) -> StatResult {
        StatResult {
            name: "x",
            unit: "u",
            measured_ks,
            reference_ks,
            measured_median: 0.0,
            draws_median: 0.0,
        }
    }

    #[test]
    fn p_value_and_ratio() {
        let r = result(vec![0.2, 0.3, 0.4], vec![0.1, 0.2, 0.3, 0.4]);
        assert_eq!(r.ks(), 0.3);
        assert_eq!(r.reference(), 0.25);
        assert!((r.ratio() - 1.2).abs() < 1e-12);
        // d_ij ≥ 0.3: two of four
        assert!((r.p_value() - 0.5).abs() < 1e-12);
        let far = result(vec![0.9; 3], vec![0.1; 10]);
        assert_eq!(far.p_value(), 0.0);
        assert_eq!(result(vec![0.0], vec![0.0]).ratio(), 0.0);
        assert!(result(vec![0.1], vec![0.0]).ratio().is_infinite());
    }

    #[test]
    fn params_checked() {
        assert!(CheckParams {
            draws: 1,
            ..Default::default()
        }
        .check()
        .is_err());
        assert!(CheckParams::default().check().is_ok());
    }

    #[test]
    fn draw_seeds_differ() {
        let s: Vec<u64> = (0..5).map(|r| draw_seed(7, r)).collect();
        let mut u = s.clone();
        u.sort();
        u.dedup();
        assert_eq!(u.len(), 5);
        assert_ne!(draw_seed(7, 0), 7);
    }
}
