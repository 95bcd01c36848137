//! A posterior sample of the model's free quantities (`--posterior`, `calibrate`'s final
//! population) and the particle each draw takes from it.
//!
//! Takes a posterior CSV (or names, weights and values); gives a [`PosteriorSample`], the
//! model with one particle's quantities, and the particle of draw r (by weight, from the
//! draw's seed stream).

use super::draw_seed;
use crate::error::{Error, Result};
use crate::model::file::ModelConfig;
use std::path::Path;

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
    pub(super) fn particle(&self, seed: u64, r: usize) -> usize {
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
