//! Range checks of numeric flags, run by clap while parsing.
//!
//! Each parser accepts exactly what the library's check of the same field accepts (named
//! beside it), so no value the library takes is refused here; checking at parse time only
//! moves the failure before any file is read and lets the message name the flag
//! (`error: invalid value '0' for '--cell-m <CELL_M>': must be in [0.005, 10] m`). The
//! binary prints such an error as one line and exits with status 1.

fn real(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .map_err(|e| format!("not a number ({e})"))
}

fn checked(s: &str, ok: impl Fn(f64) -> bool, range: &str) -> Result<f64, String> {
    let v = real(s)?;
    if ok(v) {
        Ok(v)
    } else {
        Err(format!("must be {range}"))
    }
}

/// An integer in `lo..=hi` (what the library's check of the same field accepts).
fn whole_in(s: &str, lo: usize, hi: usize, why: &str) -> Result<usize, String> {
    let s = s.trim();
    let bad = || format!("must be in [{lo}, {hi}] ({why})");
    match s.parse::<usize>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(_) => Err(bad()),
        Err(_) if s.starts_with('-') && s[1..].parse::<usize>().is_ok() => Err(bad()),
        Err(e) => Err(format!("not a whole number ({e})")),
    }
}

/// `fit --closed-loop`: in [0, `MAX_DRAWS`] (0: not run; [`pradar::closed_loop`]).
pub fn closed_loop_draws(s: &str) -> Result<usize, String> {
    whole_in(
        s,
        0,
        pradar::closed_loop::MAX_DRAWS,
        "draws of the written model; 0 runs none",
    )
}

/// `--k-max`: in [1, 64] (`ClusterParams` k_max, [`pradar::cluster::params::MAX_K`]).
pub fn k_max(s: &str) -> Result<usize, String> {
    whole_in(
        s,
        1,
        pradar::cluster::params::MAX_K,
        "the search over K costs K^2.3",
    )
}

/// `--bootstrap`: in [40, 100000] (`FitParams` bootstrap).
pub fn bootstrap(s: &str) -> Result<usize, String> {
    use pradar::fit::params::{MAX_BOOTSTRAP, MIN_BOOTSTRAP};
    whole_in(
        s,
        MIN_BOOTSTRAP,
        MAX_BOOTSTRAP,
        "a 95 % interval needs a resample in each 2.5 % tail",
    )
}

/// `calibrate --simulations`: in [`MIN_POPULATION`, `MAX_SIMULATIONS`]
/// (`calibrate::params`; it must also reach the population, which the library checks).
///
/// [`MIN_POPULATION`]: pradar::calibrate::params::MIN_POPULATION
/// [`MAX_SIMULATIONS`]: pradar::calibrate::params::MAX_SIMULATIONS
pub fn simulations(s: &str) -> Result<usize, String> {
    use pradar::calibrate::params::{MAX_SIMULATIONS, MIN_POPULATION};
    whole_in(s, MIN_POPULATION, MAX_SIMULATIONS, "the simulation budget")
}

/// `calibrate --population`: in [`MIN_POPULATION`, `MAX_POPULATION`] (`calibrate::params`).
///
/// [`MIN_POPULATION`]: pradar::calibrate::params::MIN_POPULATION
/// [`MAX_POPULATION`]: pradar::calibrate::params::MAX_POPULATION
pub fn population(s: &str) -> Result<usize, String> {
    use pradar::calibrate::params::{MAX_POPULATION, MIN_POPULATION};
    whole_in(
        s,
        MIN_POPULATION,
        MAX_POPULATION,
        "particles per generation",
    )
}

/// `check --draws`: in [`pradar::check::DRAWS_RANGE`] (`CheckParams` draws; below it the
/// p-value cannot reach α, [`pradar::check::draws_why`]).
pub fn draws(s: &str) -> Result<usize, String> {
    let r = pradar::check::DRAWS_RANGE;
    whole_in(s, *r.start(), *r.end(), &pradar::check::draws_why())
}

/// `check --fail-below`: in [0, 1] (a p-value).
pub fn probability(s: &str) -> Result<f64, String> {
    checked(s, |v| (0.0..=1.0).contains(&v), "in [0, 1]")
}

/// `--cell-m`: in [`pradar::mapping::grid::CELL_M_RANGE`] (`GridParams` cell_m).
pub fn cell_m(s: &str) -> Result<f64, String> {
    let r = pradar::mapping::grid::CELL_M_RANGE;
    checked(
        s,
        |v| r.contains(&v),
        &format!("in [{}, {}] m", r.start(), r.end()),
    )
}

/// `--pfa`: in (0, 0.5] (`OgParams` pfa).
pub fn pfa(s: &str) -> Result<f64, String> {
    checked(s, |v| v > 0.0 && v <= 0.5, "in (0, 0.5]")
}

/// `--prior`: in (0, 1) (`OgParams` prior).
pub fn open_unit(s: &str) -> Result<f64, String> {
    checked(s, |v| v > 0.0 && v < 1.0, "in (0, 1)")
}

/// `--mu0`, `--sigma0`: finite and > 0 (`EkfParams` mu0, sigma0).
pub fn positive(s: &str) -> Result<f64, String> {
    checked(s, |v| v.is_finite() && v > 0.0, "finite and > 0")
}

/// `--pose-noise-m`, `--pose-noise-deg`, `--margin-db`, `--diffuse-db`: finite and ≥ 0
/// (`PoseNoise`, `ExtractParams` margin_db, `DiffuseParams` discrete_db).
pub fn non_negative(s: &str) -> Result<f64, String> {
    checked(s, |v| v.is_finite() && v >= 0.0, "finite and >= 0")
}

/// `--og-credit-depth`: finite and >= 0 m, or `guard` (every visible cell: infinity, read
/// as no depth limit by the CLI).
pub fn credit_depth(s: &str) -> Result<f64, String> {
    if s.trim() == "guard" {
        return Ok(f64::INFINITY);
    }
    checked(
        s,
        |v| v.is_finite() && v >= 0.0,
        "finite and >= 0, or `guard`",
    )
}

/// `--dynamic-range-db`: > 0 (`ExtractParams` dynamic_range_db; infinity means no limit).
pub fn dynamic_range_db(s: &str) -> Result<f64, String> {
    checked(s, |v| v > 0.0, "> 0")
}

/// `--set NAME=VALUE` (synth): a quantity name and a number; the model's check
/// (`ModelConfig::require_estimable`) judges the name and the value.
pub fn name_value(s: &str) -> Result<(String, f64), String> {
    let Some((name, v)) = s.split_once('=') else {
        return Err("expected NAME=VALUE".into());
    };
    let name = name.trim();
    if name.is_empty() {
        return Err("expected NAME=VALUE (empty name)".into());
    }
    Ok((name.to_string(), real(v)?))
}

/// `START:STOP:STEP` degrees (`--directions`: `Directions::check`).
pub fn directions(s: &str) -> Result<pradar::campaign::manifest::Directions, String> {
    let v: Vec<&str> = s.split(':').collect();
    if v.len() != 3 {
        return Err("expected START:STOP:STEP in degrees, e.g. -90:90:5".into());
    }
    let d = pradar::campaign::manifest::Directions {
        start_deg: real(v[0])?,
        stop_deg: real(v[1])?,
        step_deg: real(v[2])?,
    };
    d.check().map_err(|e| e.to_string())?;
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_match_the_library_checks() {
        assert!(k_max("0").is_err() && k_max("1").is_ok() && k_max("64").is_ok());
        assert!(k_max("65").is_err() && k_max("100000").is_err());
        assert!(k_max("-2").unwrap_err().starts_with("must be in [1, 64]"));
        assert!(bootstrap("0").is_err() && bootstrap("1").is_err() && bootstrap("39").is_err());
        assert!(bootstrap("40").is_ok() && bootstrap("100001").is_err());
        // the bounds are the library's: each accepted here exactly when its check accepts it
        let grid = |c: f64| {
            pradar::params::ParamGuard::check(&pradar::mapping::GridParams {
                cell_m: c,
                ..Default::default()
            })
            .is_ok()
        };
        for v in ["0", "0.004", "0.005", "0.1", "10", "10.5", "inf"] {
            assert_eq!(cell_m(v).is_ok(), grid(v.parse().unwrap()), "--cell-m {v}");
        }
        let check = |n: usize| {
            pradar::params::ParamGuard::check(&pradar::check::CheckParams {
                draws: n,
                ..Default::default()
            })
            .is_ok()
        };
        for n in [0, 1, 2, 18, 19, 20, 1000, 1001] {
            assert_eq!(draws(&n.to_string()).is_ok(), check(n), "--draws {n}");
        }
        let calibrate = |n: usize| {
            pradar::params::ParamGuard::check(&pradar::calibrate::CalibrateParams {
                population: n,
                simulations: n,
                ..Default::default()
            })
            .is_ok()
        };
        for n in [19, 20, 400, 10_000, 10_001] {
            let ok = population(&n.to_string()).is_ok() && simulations(&n.to_string()).is_ok();
            assert_eq!(ok, calibrate(n), "--population {n} --simulations {n}");
        }
        assert!(pfa("0").is_err() && pfa("0.5").is_ok() && pfa("1.5").is_err());
        assert!(open_unit("0").is_err() && open_unit("1").is_err() && open_unit("0.5").is_ok());
        assert!(positive("0").is_err() && positive("inf").is_err() && positive("1e-3").is_ok());
        assert!(non_negative("-1").is_err() && non_negative("0").is_ok());
        assert!(non_negative("NaN").is_err());
        assert_eq!(credit_depth("guard"), Ok(f64::INFINITY));
        assert_eq!(credit_depth("0.05"), Ok(0.05));
        assert!(credit_depth("inf").is_err() && credit_depth("-0.1").is_err());
        assert!(credit_depth("NaN").is_err() && credit_depth("guards").is_err());
        assert!(dynamic_range_db("0").is_err() && dynamic_range_db("inf").is_ok());
        assert!(dynamic_range_db("NaN").is_err());
        assert_eq!(
            name_value("diffuse.decay=12").unwrap(),
            ("diffuse.decay".to_string(), 12.0)
        );
        assert!(name_value("decay").is_err() && name_value("=1").is_err());
        assert!(name_value("decay=x").is_err());
    }
}
