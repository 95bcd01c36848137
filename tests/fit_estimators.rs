//! Estimators against scipy (fixtures written by scripts/make_scipy_fixtures.py).

use pradar::fit::{fit, ks_statistic, Family};

#[test]
fn mles_and_ks_match_scipy() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/fit/scipy_fixtures.json"
    ))
    .unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for case in v["cases"].as_array().unwrap() {
        let name = case["family"].as_str().unwrap();
        let data: Vec<f64> = case["data"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let g = |k: &str| case[k].as_f64().unwrap();
        let (family, want): (Family, Vec<f64>) = match name {
            "exponential" => (Family::Exponential, vec![g("rate")]),
            "shifted_exponential" => (
                Family::ShiftedExponential { delta: g("delta") },
                vec![g("rate")],
            ),
            "laplacian" => (Family::Laplacian, vec![g("location"), g("scale")]),
            "gaussian" => (Family::Gaussian, vec![g("mean"), g("std")]),
            "lognormal" => (Family::LogNormal, vec![g("mu"), g("sigma")]),
            "gamma" => (Family::Gamma, vec![g("shape"), g("rate")]),
            "rayleigh" => (Family::Rayleigh, vec![g("sigma")]),
            other => panic!("unknown family {other}"),
        };
        let f = fit(family, &data).unwrap();
        // scipy's gamma fit is a numerical optimiser; the closed forms agree to rounding
        let tol = if name == "gamma" { 1e-4 } else { 1e-10 };
        for (got, want) in f.params.iter().zip(&want) {
            assert!(
                (got - want).abs() <= tol * want.abs().max(1.0),
                "{name}: {got} vs scipy {want}"
            );
        }
        let d = ks_statistic(&data, |x| f.cdf(x));
        let tol_ks = if name == "gamma" { 1e-4 } else { 1e-10 };
        assert!(
            (d - g("ks")).abs() <= tol_ks,
            "{name}: KS {d} vs scipy {}",
            g("ks")
        );
        // the closed-form pdf against scipy's at the sample's quantiles (scipy's own fit;
        // the parameters agree to the tolerance above, gamma's to 1e-4)
        let tol_pdf = if name == "gamma" { 1e-3 } else { 1e-8 };
        for pt in case["pdf"].as_array().unwrap() {
            let (x, want) = (pt[0].as_f64().unwrap(), pt[1].as_f64().unwrap());
            let got = f.pdf(x);
            assert!(
                (got - want).abs() <= tol_pdf * want,
                "{name}: pdf({x}) {got} vs scipy {want}"
            );
        }
        eprintln!(
            "{name}: params {:?} (scipy {:?}), KS {d:.6} (scipy {:.6}), AIC {:.2}",
            f.params,
            want,
            g("ks"),
            f.aic()
        );
    }
}
