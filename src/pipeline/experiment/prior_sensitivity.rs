//! prior-sensitivity: at N = 16 on model data, the OG prior p0 and the EKF μ0 each scaled by
//! 1 ± `prior_change` with everything else fixed.
//!
//! The binary rules stay p > 0.5 and x̂ − κσ̂ > μ0, so μ0 moves the EKF's threshold as it
//! moves its prior. Reported: the relative change Δψ/ψ = (ψ̄(changed) − ψ̄(base))/ψ̄(base)
//! of the mean ψ over seeds, on the observable region and on the whole map.

use super::lab::{join_u, mean, result, Case, CaseFigures, DataSource, Figure, Lab, Mapped, Panel};
use super::ExperimentResult;
use crate::error::{Error, Result};
use crate::export::LineChart;

impl Lab<'_> {
    pub(super) fn prior_sensitivity(&mut self) -> Result<ExperimentResult> {
        let n = self.params.sensitivity_elements;
        let c = self.params.prior_change;
        let factors = self.prior_factors();
        let cases = self.prior_cases();
        let done = self.map_all("prior-sensitivity", &cases)?;
        let panel = self.prior_panel(&done, factors)?;
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let (findings, charts) = self.relative_changes(&cases, n, factors);
        let first = self.params.seeds[0];
        Ok(result(
            "prior-sensitivity",
            &format!("N = {n}, model data, seeds {}: the OG prior p0 = {} and the EKF μ0 = {} m each changed by ±{:.0} % (binary rules unchanged: p > 0.5, x̂ − {:.2}σ̂ > μ0). The paper reports about +5 % for the OG and +220 % for the EKF; here is what is measured. Panel: seed {first}.", join_u(&self.params.seeds), self.params.og.prior, self.params.ekf.mu0, c * 100.0, self.params.ekf.kappa),
            cases,
            findings,
            panel,
            charts,
            vec![Figure::Plot("relative change of psi".into())],
        ))
    }

    /// The factors the priors are scaled by: 1 − c, 1, 1 + c (c = `prior_change`).
    fn prior_factors(&self) -> [f64; 3] {
        let c = self.params.prior_change;
        [1.0 - c, 1.0, 1.0 + c]
    }

    /// Model data at N = `sensitivity_elements`, every seed: the OG and the EKF with their
    /// prior scaled by each factor 1 − c, 1, 1 + c.
    pub(super) fn prior_cases(&self) -> Vec<Case> {
        let n = self.params.sensitivity_elements;
        let mut cases = Vec::new();
        for s in self.seeds() {
            for f in self.prior_factors() {
                let mut og = self.base_case(DataSource::Model(s), n, "og");
                og.og_prior = self.params.og.prior * f;
                let mut ekf = self.base_case(DataSource::Model(s), n, "ekf");
                ekf.mu0 = self.params.ekf.mu0 * f;
                cases.push(og);
                cases.push(ekf);
            }
        }
        cases
    }

    /// The panel: the first seed's OG then EKF maps at each factor.
    fn prior_panel(&self, done: &[Mapped], factors: [f64; 3]) -> Result<Panel> {
        let first = self.params.seeds[0];
        let mut tiles = Vec::new();
        for m in ["og", "ekf"] {
            for f in factors {
                let d = done
                    .iter()
                    .find(|d| {
                        d.0.case.method == m
                            && d.0.case.source == DataSource::Model(first)
                            && self.factor_of(&d.0.case) == f
                    })
                    .ok_or_else(|| Error::param("prior-sensitivity", "missing case"))?;
                let label = if m == "og" {
                    format!("OG, p0 = {:.2}: ψ {:.2}", d.0.case.og_prior, d.0.psi_whole)
                } else {
                    format!("EKF, μ0 = {:.3} m: ψ {:.2}", d.0.case.mu0, d.0.psi_whole)
                };
                tiles.push(self.tile(label, &d.1));
            }
        }
        Ok(self.panel(tiles, 3))
    }

    /// Δψ/ψ per mapper and region at each factor: the findings and the two charts
    /// (observable region, whole map).
    fn relative_changes(
        &self,
        cases: &[CaseFigures],
        n: usize,
        factors: [f64; 3],
    ) -> (Vec<(String, String)>, Vec<LineChart>) {
        let c = self.params.prior_change;
        let chart = |region: &str| LineChart {
            title: format!("N = {n}: relative change of ψ ({region})"),
            x_label: "prior change (%)".into(),
            y_label: "Δψ/ψ (%)".into(),
            series: Vec::new(),
        };
        let mut charts = vec![chart("observable region"), chart("whole map")];
        let mut findings = Vec::new();
        for m in ["og", "ekf"] {
            let mean_psi = |f: f64, whole: bool| {
                let v: Vec<f64> = cases
                    .iter()
                    .filter(|c| c.case.method == m && self.factor_of(&c.case) == f)
                    .map(|c| if whole { c.psi_whole } else { c.psi_observable })
                    .collect();
                mean(&v)
            };
            for (ci, whole) in [false, true].into_iter().enumerate() {
                let base = mean_psi(1.0, whole);
                let pts: Vec<(f64, f64)> = factors
                    .iter()
                    .map(|&f| {
                        (
                            (f - 1.0) * 100.0,
                            100.0 * (mean_psi(f, whole) - base) / base,
                        )
                    })
                    .collect();
                let what = if m == "og" { "OG prior p0" } else { "EKF μ0" };
                let region = if whole { "whole map" } else { "observable" };
                findings.push((
                    format!("{what}, Δψ/ψ ({region})"),
                    format!(
                        "−{p:.0} %: {:+.1} %, +{p:.0} %: {:+.1} % (mean ψ {:.3} → {:.3} / {:.3})",
                        pts[0].1,
                        pts[2].1,
                        base,
                        mean_psi(factors[0], whole),
                        mean_psi(factors[2], whole),
                        p = c * 100.0
                    ),
                ));
                charts[ci].series.push((m.to_uppercase(), pts));
            }
        }
        (findings, charts)
    }

    /// The prior factor of a case relative to the base parameters (1 when unchanged).
    fn factor_of(&self, c: &Case) -> f64 {
        let f = if c.method == "og" {
            c.og_prior / self.params.og.prior
        } else {
            c.mu0 / self.params.ekf.mu0
        };
        // snap to the factors used (they were made by multiplication)
        [
            1.0 - self.params.prior_change,
            1.0,
            1.0 + self.params.prior_change,
        ]
        .into_iter()
        .find(|g| (g - f).abs() < 1e-9)
        .unwrap_or(f)
    }
}
