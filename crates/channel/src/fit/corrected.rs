//! The bias-corrected Table 1 as data: what `crate::correction` (indirect inference by
//! simulation of the whole chain at the fitted point) gives for each quantity beside the
//! paper's method's value, and the partition stability printed under the table.
//!
//! Only types live here, so that Table 1 ([`table1`](super::table1)) can render them while
//! the computing stays downstream of the model stage (the correction draws `synth`).

use crate::model::file::{CorrectionMeta, ModelConfig};

/// One quantity of the bias-corrected Table 1.
#[derive(Debug, Clone, PartialEq)]
pub struct CorrectedQuantity {
    /// The model file's key (`inter_cluster_rate`, …, `rays_per_cluster`).
    pub key: &'static str,
    /// The paper's method's value (the chain on the data; NaN when not estimable, ∞ for
    /// Γ without excess decay).
    pub raw: f64,
    /// The bias-corrected value (NaN when not identifiable or not corrected).
    pub value: f64,
    /// Its 95 % interval (sampling spread and simulation noise of the correction).
    pub interval: Option<[f64; 2]>,
    /// The binding function's own slope: how much the chain's estimate moves when the
    /// quantity moves (d log T / d log θ; for Γ on the rate 1/Γ), from common draws.
    pub slope: f64,
    /// Why the quantity is not corrected ("not identifiable from this campaign: …"), if so.
    pub not_identifiable: Option<String>,
}

impl CorrectedQuantity {
    /// Whether a corrected value is given.
    pub fn is_corrected(&self) -> bool {
        self.not_identifiable.is_none() && !self.value.is_nan()
    }
}

/// The partition stability of the data's clustering: the adjusted Rand index between the
/// chain's partition of each position and its partition of random 80 % subsamples of that
/// position's MPCs (same points compared).
#[derive(Debug, Clone, PartialEq)]
pub struct PartitionStability {
    /// Mean ARI per position (NaN for a position with fewer than 2 discrete MPCs).
    pub per_position: Vec<f64>,
    /// The MPC-weighted mean over positions.
    pub overall: f64,
    /// Subsamples per position.
    pub resamples: usize,
}

/// The bias correction of a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Corrected {
    /// Per quantity, in Table 1's order.
    pub quantities: Vec<CorrectedQuantity>,
    /// Simulated draws per evaluation (R).
    pub draws: usize,
    /// Steps made after the start (two candidates each).
    pub iterations: usize,
    /// Whether the remaining bias fell within the simulation noise of its mean.
    pub settled: bool,
    /// Runs of the whole chain (synth → extract → cluster → estimators).
    pub chain_runs: usize,
    /// Wall time, s.
    pub seconds: f64,
    /// Seed of the draws.
    pub seed: u64,
    /// The slope below which a quantity is not identifiable.
    pub min_slope: f64,
    /// How far the fold check looked: secants to 1/F and F times each value.
    pub far_factor: f64,
    /// The partition stability of the data's clustering, when measured.
    pub stability: Option<PartitionStability>,
}

impl Corrected {
    /// The model file with the corrected values: each corrected quantity's value and
    /// interval replaced, each one not identifiable kept at its raw value and flagged
    /// (`not_estimable = "not identifiable …"`, drawn as stated), and `[correction]` with
    /// the raw values and slopes. Quantities the paper's method could not estimate stay
    /// as they were.
    pub fn apply(&self, raw: &ModelConfig) -> ModelConfig {
        let mut m = raw.clone();
        let mut raws = std::collections::BTreeMap::new();
        let mut slopes = std::collections::BTreeMap::new();
        for c in &self.quantities {
            let Some(q) = m.quantity_mut(c.key) else {
                continue;
            };
            if !q.is_estimable() {
                continue;
            }
            raws.insert(c.key.to_string(), c.raw);
            if c.slope.is_finite() {
                slopes.insert(c.key.to_string(), c.slope);
            }
            match &c.not_identifiable {
                None if !c.value.is_nan() => {
                    q.value = c.value;
                    q.interval = c.interval;
                }
                Some(why) => q.not_estimable = Some(why.clone()),
                None => {}
            }
        }
        m.correction = Some(CorrectionMeta {
            method: "indirect-inference".into(),
            draws: self.draws,
            iterations: self.iterations,
            settled: self.settled,
            seed: self.seed,
            raw: raws,
            slope: slopes,
        });
        m
    }

    /// The entry of quantity `key`, if corrected.
    pub fn get(&self, key: &str) -> Option<&CorrectedQuantity> {
        self.quantities.iter().find(|q| q.key == key)
    }

    /// One line for the table's foot: the method, R, the steps and the stability (no wall
    /// time: the same inputs give the same bytes).
    pub fn summary_line(&self) -> String {
        let mut s = format!(
            "Bias-corrected: indirect inference, the whole chain (synth → extract → cluster → these estimators) run {} times, R = {} draws per point (⌈R/3⌉ at the fold check's), {} step{} ({}); a quantity whose binding slope is below {} (at the fitted point, or as a secant to 1/{} or {} times it) is not identifiable from this campaign.",
            self.chain_runs,
            self.draws,
            self.iterations,
            if self.iterations == 1 { "" } else { "s" },
            if self.settled {
                "settled within the simulation noise"
            } else {
                "stopped at the step cap, or nothing identifiable to move"
            },
            self.min_slope,
            self.far_factor,
            self.far_factor
        );
        if let Some(st) = &self.stability {
            let low = st
                .per_position
                .iter()
                .filter(|a| a.is_finite() && **a < 0.5)
                .count();
            s.push_str(&format!(
                " Partition stability (ARI between the data's clusters and the chain's clusters of {} random 80 % subsamples of each position's MPCs): {:.2} overall, below 0.5 at {} of {} positions.",
                st.resamples,
                st.overall,
                low,
                st.per_position.iter().filter(|a| a.is_finite()).count()
            ));
        }
        s
    }
}
