//! The dense (diffuse) component's quantities, from the MPCs the diffuse stage labelled
//! diffuse ([`crate::mpc::diffuse`]).
//!
//! Takes the clustered MPC table (its `component`, `wall_unit_db`, `incidence_deg`,
//! `power_db`, `delay_ns` columns) and the fit's resampling settings; gives the model file's
//! `[diffuse]` section ([`DiffuseModel`]), or None when the table holds no diffuse MPC.
//!
//! For a diffuse MPC i, y_i = power_db − wall_unit_db is the cell's energy over the energy
//! E₁ a Lambertian wall of 1 m²/m would leave there (the diffuse stage's prediction), and
//! x_i = 10·log10 cos α_i its incidence term. Under the model E = σ′·E₁·cos^(n−1)α · X, X
//! exponential of mean 1 (a Rayleigh cell):
//! * `lambert_exponent` n = 1 + the least-squares slope of y on x (at least 0; not
//!   estimable with fewer than 10 MPCs or when the incidences span less than 3 dB of x);
//! * `wall_rcs_per_m` σ′ = median(10^((y − (n−1)·x)/10)) / ln 2: the exponential law's mean
//!   read from its median (the diffuse stage's own level estimator);
//! * `power_share`: the diffuse MPCs' share of the extracted MPCs' linear power;
//! * `decay` = −10·log10(e)/slope of the least-squares line of power_db against delay_ns
//!   (not estimable when the slope is not negative).
//!
//! Intervals: 95 % bootstrap resampling whole positions (seeded; the same block resampling
//! as the cluster quantities). The CLEAN peaks of a Rayleigh continuum are the local maxima
//! of the cells, so σ′ reads the peaks' level, above the mean cell; `docs/fit.md` has the
//! measured ratio against the simulator's wall backscatter.

use crate::error::Result;
use crate::fit::estimators::bootstrap_groups;
use crate::fit::quantities::ls_line;
use crate::model::file::{DiffuseModel, Quantity};
use crate::mpc::{Component, Mpc};
use std::path::Path;

/// One diffuse MPC's inputs.
#[derive(Debug, Clone, Copy)]
struct Row {
    y: f64,
    x: f64,
    power_db: f64,
    delay_ns: f64,
}

/// The Lambert exponent of `rows`, or why not.
fn exponent(rows: &[Row]) -> std::result::Result<f64, String> {
    if rows.len() < 10 {
        return Err(format!("{} diffuse MPCs (fewer than 10)", rows.len()));
    }
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, r| {
            (a.0.min(r.x), a.1.max(r.x))
        });
    if hi - lo < 3.0 {
        return Err(format!(
            "incidences span {:.1} dB of cos α (less than 3 dB)",
            hi - lo
        ));
    }
    let xy: Vec<(f64, f64)> = rows.iter().map(|r| (r.x, r.y)).collect();
    let (slope, _) = ls_line(&xy).ok_or("no spread of incidence")?;
    Ok((1.0 + slope).max(0.0))
}

/// σ′ of `rows` with exponent `n`.
fn level(rows: &[Row], n: f64) -> Option<f64> {
    let v: Vec<f64> = rows
        .iter()
        .map(|r| 10f64.powf((r.y - (n - 1.0) * r.x) / 10.0))
        .collect();
    crate::stats::upper_median(&v).map(|m| m / std::f64::consts::LN_2)
}

/// The power decay of `rows`, or why not.
fn decay(rows: &[Row]) -> std::result::Result<f64, String> {
    let pairs: Vec<(f64, f64)> = rows.iter().map(|r| (r.delay_ns, r.power_db)).collect();
    let (slope, _) = ls_line(&pairs)
        .ok_or_else(|| format!("{} diffuse MPCs without spread in delay", rows.len()))?;
    if slope >= 0.0 {
        return Err(format!(
            "no decaying trend in {} diffuse powers",
            rows.len()
        ));
    }
    Ok(-10.0 * std::f64::consts::LOG10_E / slope)
}

/// A quantity with its position-bootstrap interval; `stat` works on row indices (given as
/// f64 in the groups).
fn quantity(
    value: std::result::Result<f64, String>,
    unit: &str,
    family: &str,
    groups: &[Vec<f64>],
    stat: impl Fn(&[f64]) -> Option<f64>,
    r: &Resample,
    offset: u64,
) -> Quantity {
    match value {
        Ok(v) => Quantity {
            interval: bootstrap_groups(groups, stat, r.bootstrap, r.seed ^ offset, r.block),
            n: Some(groups.iter().map(Vec::len).sum()),
            ..Quantity::new(v, unit, family)
        },
        Err(reason) => Quantity::not_estimable(unit, family, reason),
    }
}

/// Resampling settings of the diffuse quantities.
pub(super) struct Resample {
    pub(super) bootstrap: usize,
    pub(super) seed: u64,
    pub(super) block: usize,
}

/// The `[diffuse]` section fitted to `mpcs` (None when none is diffuse); `np` positions.
pub(super) fn fit_diffuse(mpcs: &[Mpc], np: usize, r: &Resample) -> Option<DiffuseModel> {
    let mut rows: Vec<Row> = Vec::new();
    let mut groups: Vec<Vec<f64>> = vec![Vec::new(); np];
    let mut total = vec![0.0; np];
    let mut diffuse_power = vec![0.0; np];
    for m in mpcs {
        let lin = 10f64.powf(m.power_db / 10.0);
        // a folded echo is not at its range: out of the share's total as of the fit
        if m.position < np && m.component != Component::Folded {
            total[m.position] += lin;
        }
        let (Component::Diffuse, Some(w), true) = (m.component, m.wall, m.position < np) else {
            continue;
        };
        let cos = w.incidence_deg.to_radians().cos().max(1e-3);
        groups[m.position].push(rows.len() as f64);
        diffuse_power[m.position] += lin;
        rows.push(Row {
            y: m.power_db - w.unit_db,
            x: 10.0 * cos.log10(),
            power_db: m.power_db,
            delay_ns: m.delay_ns,
        });
    }
    if rows.is_empty() {
        return None;
    }
    let pick = |idx: &[f64]| -> Vec<Row> { idx.iter().map(|&i| rows[i as usize]).collect() };
    let n = exponent(&rows);
    let n_used = *n.as_ref().unwrap_or(&1.0);
    let lambert_exponent = quantity(
        n.clone(),
        "1",
        "constant",
        &groups,
        |idx| exponent(&pick(idx)).ok(),
        r,
        21,
    );
    let wall = level(&rows, n_used).ok_or_else(|| "no diffuse MPC".to_string());
    let wall_rcs_per_m = quantity(
        wall,
        "m2/m",
        "exponential",
        &groups,
        |idx| {
            let rs = pick(idx);
            level(&rs, exponent(&rs).unwrap_or(1.0))
        },
        r,
        22,
    );
    // power share: per-position (diffuse, total) pairs resampled as positions
    let share_groups: Vec<Vec<f64>> = (0..np)
        .filter(|&p| total[p] > 0.0)
        .map(|p| vec![p as f64])
        .collect();
    let share = |ps: &[f64]| {
        let (d, t) = ps.iter().fold((0.0, 0.0), |a, &p| {
            (a.0 + diffuse_power[p as usize], a.1 + total[p as usize])
        });
        (t > 0.0).then(|| d / t)
    };
    let all: Vec<f64> = share_groups.iter().flatten().copied().collect();
    let power_share = quantity(
        share(&all).ok_or_else(|| "no MPC power".to_string()),
        "1",
        "constant",
        &share_groups,
        share,
        r,
        23,
    );
    let decay_q = quantity(
        decay(&rows),
        "ns",
        "exponential",
        &groups,
        |idx| decay(&pick(idx)).ok(),
        r,
        24,
    );
    Some(DiffuseModel {
        wall_rcs_per_m,
        lambert_exponent,
        power_share,
        decay: decay_q,
    })
}

/// [`fit_diffuse`] on the MPC table at `path`.
pub(super) fn fit_diffuse_table(
    path: &Path,
    np: usize,
    r: &Resample,
) -> Result<Option<DiffuseModel>> {
    Ok(fit_diffuse(&crate::mpc::read_mpcs(path)?, np, r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mpc::WallCell;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Diffuse MPCs drawn from the model E = σ′·E₁·cos^(n−1)α·X recover σ′ and n.
    #[test]
    fn recovers_wall_level_and_exponent() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (sigma, n) = (0.02, 2.0);
        let mpcs: Vec<Mpc> = (0..2000)
            .map(|i| {
                let alpha: f64 = rng.gen_range(0.0..80.0);
                let unit_db = -90.0 - rng.gen_range(0.0..20.0);
                let x: f64 = -(1.0 - rng.gen::<f64>()).ln();
                let e =
                    sigma * 10f64.powf(unit_db / 10.0) * alpha.to_radians().cos().powf(n - 1.0) * x;
                Mpc {
                    position: i % 10,
                    delay_ns: 10.0 + (i % 50) as f64,
                    angle_rel_deg: 0.0,
                    angle_global_deg: 0.0,
                    power_db: 10.0 * e.log10(),
                    snr_db: 30.0,
                    x_m: 0.0,
                    y_m: 0.0,
                    direction: 0,
                    bin: 0,
                    component: Component::Diffuse,
                    wall: Some(WallCell {
                        unit_db,
                        incidence_deg: alpha,
                    }),
                }
            })
            .collect();
        let r = Resample {
            bootstrap: 50,
            seed: 1,
            block: 1,
        };
        let d = fit_diffuse(&mpcs, 10, &r).unwrap();
        let got_n = d.lambert_exponent.value;
        assert!((got_n - n).abs() < 0.15, "n {got_n}");
        let got_s = d.wall_rcs_per_m.value;
        assert!((got_s / sigma - 1.0).abs() < 0.1, "σ′ {got_s}");
        assert!((d.power_share.value - 1.0).abs() < 1e-12);
        let [lo, hi] = d.wall_rcs_per_m.interval.unwrap();
        assert!(lo < got_s && got_s < hi);
        // no trend of power with delay here beyond chance: the decay is either not
        // estimable or long
        assert!(
            !d.decay.is_estimable() || d.decay.value > 50.0,
            "{:?}",
            d.decay
        );
    }
}
