//! pose-noise: at N = 100 on model data, the mapper is given poses with Gaussian noise
//! ([`PoseNoise`]) while the data were taken at the true poses.
//!
//! Levels: σ per axis 0, 2, 5, 10 cm with no heading noise, and heading σ 0, 1, 2, 5° with no
//! position noise; one draw per pose, keyed by the data seed; scored on the true poses'
//! observable region; mean ψ over seeds.

use super::lab::{join_u, mean, result, Case, CaseFigures, DataSource, Figure, Lab, Mapped, Panel};
use super::ExperimentResult;
use crate::error::Result;
use crate::export::LineChart;
use crate::mapping::job::PoseNoise;

impl Lab<'_> {
    pub(super) fn pose_noise(&mut self) -> Result<ExperimentResult> {
        let n = self.params.pose_elements;
        let cases = self.pose_cases(n);
        let done = self.map_all("pose-noise", &cases)?;
        let panel = self.pose_panel(&done);
        let cases: Vec<CaseFigures> = done.into_iter().map(|d| d.0).collect();
        let (findings, charts) = self.psi_vs_noise(&cases, n);
        let first = self.params.seeds[0];
        Ok(result(
            "pose-noise",
            &format!("N = {n}, model data, seeds {}: the mappers are given noisy poses (Gaussian, independent per pose; the data were taken at the true poses; scored on the true poses' observable region). Panel: seed {first}, no noise and the largest levels.", join_u(&self.params.seeds)),
            cases,
            findings,
            panel,
            charts,
            vec![Figure::Plot("psi vs pose noise".into())],
        ))
    }

    /// (position σ, heading σ) settings: each position level with exact heading, then each
    /// heading level with exact position (the noiseless setting once).
    fn pose_settings(&self) -> Vec<(f64, f64)> {
        let mut settings: Vec<(f64, f64)> = self
            .params
            .position_noise_m
            .iter()
            .map(|&p| (p, 0.0))
            .collect();
        for &h in &self.params.heading_noise_deg {
            if h > 0.0 || !settings.contains(&(0.0, 0.0)) {
                settings.push((0.0, h));
            }
        }
        settings
    }

    /// Every seed × setting × mapper at N elements, the noise keyed by the seed.
    pub(super) fn pose_cases(&self, n: usize) -> Vec<Case> {
        let settings = self.pose_settings();
        let mut cases = Vec::new();
        for s in self.seeds() {
            for &(p, h) in &settings {
                for m in ["og", "ekf"] {
                    let mut c = self.base_case(DataSource::Model(s), n, m);
                    c.pose_noise = PoseNoise {
                        position_m: p,
                        heading_deg: h,
                        seed: s,
                    };
                    cases.push(c);
                }
            }
        }
        cases
    }

    /// The panel: the first seed's maps per mapper with no noise and the largest levels.
    fn pose_panel(&self, done: &[Mapped]) -> Panel {
        let first = self.params.seeds[0];
        let largest = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
        let pmax = largest(&self.params.position_noise_m);
        let hmax = largest(&self.params.heading_noise_deg);
        let mut tiles = Vec::new();
        for m in ["og", "ekf"] {
            for (p, h) in [(0.0, 0.0), (pmax, 0.0), (0.0, hmax)] {
                if let Some(d) = done.iter().find(|d| {
                    d.0.case.method == m
                        && d.0.case.source == DataSource::Model(first)
                        && d.0.case.pose_noise.position_m == p
                        && d.0.case.pose_noise.heading_deg == h
                }) {
                    tiles.push(self.tile(
                        format!(
                            "{}, σ {:.0} cm / {:.0}°: ψ {:.2}",
                            m.to_uppercase(),
                            p * 100.0,
                            h,
                            d.0.psi_whole
                        ),
                        &d.1,
                    ));
                }
            }
        }
        self.panel(tiles, 3)
    }

    /// Mean ψ per mapper and region against each noise level: the findings and the two
    /// charts (position noise, heading noise).
    fn psi_vs_noise(
        &self,
        cases: &[CaseFigures],
        n: usize,
    ) -> (Vec<(String, String)>, Vec<LineChart>) {
        let mut findings = Vec::new();
        let mut pos_chart = LineChart {
            title: format!("N = {n}: ψ vs position noise (heading exact)"),
            x_label: "position σ per axis (cm)".into(),
            y_label: "ψ (cells)".into(),
            series: Vec::new(),
        };
        let mut hdg_chart = LineChart {
            title: format!("N = {n}: ψ vs heading noise (position exact)"),
            x_label: "heading σ (deg)".into(),
            y_label: "ψ (cells)".into(),
            series: Vec::new(),
        };
        let points = |v: &[(f64, f64)]| {
            v.iter()
                .map(|(x, y)| format!("{x:.0}: {y:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        for m in ["og", "ekf"] {
            let psi = |p: f64, h: f64, whole: bool| {
                let v: Vec<f64> = cases
                    .iter()
                    .filter(|c| {
                        c.case.method == m
                            && c.case.pose_noise.position_m == p
                            && c.case.pose_noise.heading_deg == h
                    })
                    .map(|c| if whole { c.psi_whole } else { c.psi_observable })
                    .collect();
                mean(&v)
            };
            for whole in [false, true] {
                let name = format!(
                    "{} ({})",
                    m.to_uppercase(),
                    if whole { "whole" } else { "observable" }
                );
                let pp: Vec<(f64, f64)> = self
                    .params
                    .position_noise_m
                    .iter()
                    .map(|&p| (p * 100.0, psi(p, 0.0, whole)))
                    .collect();
                let hh: Vec<(f64, f64)> = self
                    .params
                    .heading_noise_deg
                    .iter()
                    .map(|&h| (h, psi(0.0, h, whole)))
                    .collect();
                findings.push((format!("{name}: mean ψ vs position σ (cm)"), points(&pp)));
                findings.push((format!("{name}: mean ψ vs heading σ (°)"), points(&hh)));
                pos_chart.series.push((name.clone(), pp));
                hdg_chart.series.push((name, hh));
            }
        }
        (findings, vec![pos_chart, hdg_chart])
    }
}
