//! fig5: EKF maps at the campaign's array from its sweeps (simulated or measured) and from model data
//! (every seed), side by side with the reference.

use super::lab::{join, mean, result, CaseFigures, DataSource, Figure, Lab};
use super::ExperimentResult;
use crate::error::Result;

impl Lab<'_> {
    pub(super) fn fig5(&mut self) -> Result<ExperimentResult> {
        let n = self.campaign_elements;
        let cases = self.fig5_cases();
        let done = self.map_all("fig5", &cases)?;
        let tiles = vec![
            self.reference_tile(),
            self.tile(
                format!("EKF, {}: ψ {:.2}", self.sweeps_word, done[0].0.psi_whole),
                &done[0].1,
            ),
            self.tile(
                format!(
                    "EKF, model data (seed {}): ψ {:.2}",
                    self.params.seeds[0], done[1].0.psi_whole
                ),
                &done[1].1,
            ),
        ];
        let panel = self.panel(tiles, 3);
        let model_psi: Vec<f64> = done[1..].iter().map(|d| d.0.psi_whole).collect();
        let findings = vec![
            (
                format!("ψ whole, {}", self.sweeps_word),
                format!("{:.3}", done[0].0.psi_whole),
            ),
            (
                "ψ whole, model data (mean over seeds)".to_string(),
                format!("{:.3} ({})", mean(&model_psi), join(&model_psi, 3)),
            ),
            (
                "ψ whole, all-free map".to_string(),
                format!("{:.3}", done[0].0.all_free_psi_whole),
            ),
        ];
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let keys: Vec<String> = cases.iter().take(2).map(|c| c.key.clone()).collect();
        Ok(result(
            "fig5",
            &format!("EKF maps ({n} elements, the campaign's array) from the {} and from model data (synth with the model file), 0.1 m cells. Colours: black occupied in both, red false occupied, blue missed occupied, white free, grey outside (free in the map).", self.sweeps_word),
            cases,
            findings,
            panel,
            Vec::new(),
            vec![Figure::EkfMeans(keys)],
        ))
    }

    /// The campaign's sweeps, then model data at every seed: EKF at the campaign's N.
    pub(super) fn fig5_cases(&self) -> Vec<super::Case> {
        let n = self.campaign_elements;
        let mut cases = vec![self.base_case(DataSource::Sweeps, n, "ekf")];
        for s in self.seeds() {
            cases.push(self.base_case(DataSource::Model(s), n, "ekf"));
        }
        cases
    }
}
