//! What a check gives: per statistic its distances and p-values ([`StatResult`]), and the
//! whole check ([`CheckResult`]): the verdict by the rule, the misses and the table.
//!
//! Takes the distances, statistics and noise floors the check computed; gives the
//! figures, the table and the one-line verdict.

use super::rule::rank_p;
use super::stats::Statistics;
use super::{NoiseFloors, ALPHA, MAX_NOISE_DB};
use crate::export::{Cell, Column, Table};

/// One statistic's result.
#[derive(Debug, Clone, PartialEq)]
pub struct StatResult {
    /// Name ([`NAMES`](super::stats::NAMES)).
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Measured distances D_r, one per draw.
    pub measured_ks: Vec<f64>,
    /// Reference distances d_ij, i < j.
    pub reference_ks: Vec<f64>,
    /// Each draw's leave-one-out distance D_i (module docs).
    pub draws_loo: Vec<f64>,
    /// Median of the measured statistic.
    pub measured_median: f64,
    /// Median over draws of each draw's median.
    pub draws_median: f64,
    /// The Westfall–Young adjusted p-value p̃ (module docs).
    pub adjusted_p: f64,
}

impl StatResult {
    /// D: the median measured distance (the measured table's leave-one-out distance).
    pub fn ks(&self) -> f64 {
        crate::stats::median(&self.measured_ks).unwrap_or(f64::NAN)
    }
    /// d: the median reference distance.
    pub fn reference(&self) -> f64 {
        crate::stats::median(&self.reference_ks).unwrap_or(f64::NAN)
    }
    /// D/d (0 when both are 0, infinite when only d is), information only.
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
    /// The Monte Carlo p-value (1 + #{i : D_i ≥ D}) / (R + 1) of this statistic alone.
    pub fn p_value(&self) -> f64 {
        rank_p(self.ks(), &self.draws_loo)
    }
    /// Whether the statistic misses (its adjusted p-value at or below [`ALPHA`]).
    pub fn misses(&self) -> bool {
        self.adjusted_p <= ALPHA
    }
}

/// The result of a check: per statistic, plus the measured and drawn statistics (for the
/// CDF plots).
#[derive(Debug, Clone)]
pub struct CheckResult {
    /// One per statistic, in the order of [`NAMES`](super::stats::NAMES).
    pub stats: Vec<StatResult>,
    /// The measured table's statistics.
    pub measured: Statistics,
    /// Each draw's statistics.
    pub draws: Vec<Statistics>,
    /// The noise floors.
    pub noise: NoiseFloors,
    /// The joint (Westfall–Young max-T) p-value.
    pub joint_p: f64,
    /// The seed the draws' seeds came from.
    pub seed: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl CheckResult {
    /// The largest ratio D/d (information).
    pub fn max_ratio(&self) -> f64 {
        self.stats.iter().map(StatResult::ratio).fold(0.0, f64::max)
    }

    /// Whether the model passes (module docs' rule): p > [`ALPHA`] and the noise floors
    /// within [`MAX_NOISE_DB`].
    pub fn passes(&self) -> bool {
        self.passes_at(ALPHA)
    }

    /// The rule at level `alpha` (`--fail-below`): p > `alpha` and the noise floors within
    /// [`MAX_NOISE_DB`].
    pub fn passes_at(&self, alpha: f64) -> bool {
        self.joint_p > alpha && self.noise.agree()
    }

    /// The statistics that miss (adjusted p at or below [`ALPHA`]), and `noise` when the
    /// floors differ.
    pub fn misses(&self) -> Vec<&'static str> {
        let mut m: Vec<&'static str> = (self.stats.iter())
            .filter(|s| s.misses())
            .map(|s| s.name)
            .collect();
        if !self.noise.agree() {
            m.insert(0, "noise");
        }
        m
    }

    /// The table: per statistic the medians side by side, D, d, D/d, its own p, the
    /// adjusted p and the verdict.
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
            Column::new("adjusted p", "p_adjusted"),
            Column::new("verdict", "verdict"),
        ]);
        for s in &self.stats {
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
                Cell::num(s.p_value(), format!("{:.3}", s.p_value())),
                Cell::num(s.adjusted_p, format!("{:.3}", s.adjusted_p)),
                Cell::text(if s.misses() { "miss" } else { "pass" }),
            ]);
        }
        t
    }

    /// One line: pass or fail, the rule with its p-value, the noise floors' offset and
    /// the misses.
    pub fn verdict(&self) -> String {
        let misses: Vec<&str> = (self.misses().into_iter())
            .filter(|&m| m != "noise")
            .collect();
        let noise = if self.noise.agree() {
            format!(
                "noise floor {:+.1} dB from the draws' (fails beyond ±{MAX_NOISE_DB} dB)",
                self.noise.offset_db()
            )
        } else {
            self.noise.line()
        };
        let rule = format!(
            "max-T p = {:.3} (fails at ≤ {ALPHA}: Westfall–Young over {} statistics, {} draws)",
            self.joint_p,
            self.stats.len(),
            self.draws.len()
        );
        let (first, second) = if self.noise.agree() {
            (rule, noise)
        } else {
            (noise, rule)
        };
        format!(
            "{}: {first}; {second}{}",
            if self.passes() { "PASS" } else { "FAIL" },
            if misses.is_empty() {
                String::new()
            } else {
                format!("; misses: {}", misses.join(", "))
            }
        )
    }
}
