#!/usr/bin/env python3
"""Write data/fit/scipy_fixtures.json: samples and the maximum-likelihood fits and KS
statistics scipy computes for them, and the fitted pdf at a few points of each sample, so
the Rust estimators in src/fit/estimators.rs are checked against an independent
implementation. Re-run to regenerate (deterministic seed)."""
import json
import os

import numpy as np
import scipy
from scipy import stats

rng = np.random.default_rng(20261122)
out = {"scipy_version": scipy.__version__, "cases": []}

x = rng.exponential(1 / 0.43, size=200)
loc, scale = stats.expon.fit(x, floc=0)
out["cases"].append({"family": "exponential", "data": x.tolist(), "rate": 1 / scale,
                     "ks": stats.kstest(x, "expon", args=(0, scale)).statistic})

x = 0.3 + rng.exponential(1 / 0.21, size=150)
loc, scale = stats.expon.fit(x, floc=0.3)
out["cases"].append({"family": "shifted_exponential", "delta": 0.3, "data": x.tolist(), "rate": 1 / scale,
                     "ks": stats.kstest(x, "expon", args=(0.3, scale)).statistic})

x = rng.laplace(2.0, 16.9 / np.sqrt(2), size=301)
loc, scale = stats.laplace.fit(x)
out["cases"].append({"family": "laplacian", "data": x.tolist(), "location": loc, "scale": scale,
                     "ks": stats.kstest(x, "laplace", args=(loc, scale)).statistic})

x = rng.normal(1.5, 0.4, size=120)
loc, scale = stats.norm.fit(x)
out["cases"].append({"family": "gaussian", "data": x.tolist(), "mean": loc, "std": scale,
                     "ks": stats.kstest(x, "norm", args=(loc, scale)).statistic})

x = rng.lognormal(0.2, 0.5, size=120)
s, loc, scale = stats.lognorm.fit(x, floc=0)
out["cases"].append({"family": "lognormal", "data": x.tolist(), "mu": float(np.log(scale)), "sigma": s,
                     "ks": stats.kstest(x, "lognorm", args=(s, 0, scale)).statistic})

x = rng.gamma(2.5, 1 / 1.7, size=200)
a, loc, scale = stats.gamma.fit(x, floc=0)
out["cases"].append({"family": "gamma", "data": x.tolist(), "shape": a, "rate": 1 / scale,
                     "ks": stats.kstest(x, "gamma", args=(a, 0, scale)).statistic})

x = rng.rayleigh(0.8, size=150)
loc, scale = stats.rayleigh.fit(x, floc=0)
out["cases"].append({"family": "rayleigh", "data": x.tolist(), "sigma": scale,
                     "ks": stats.kstest(x, "rayleigh", args=(0, scale)).statistic})

# the fitted pdf at the sample's 5 %, 25 %, 50 %, 75 % and 95 % quantiles (scipy's own fits)
def frozen(c):
    f = c["family"]
    if f == "exponential":
        return stats.expon(0, 1 / c["rate"])
    if f == "shifted_exponential":
        return stats.expon(c["delta"], 1 / c["rate"])
    if f == "laplacian":
        return stats.laplace(c["location"], c["scale"])
    if f == "gaussian":
        return stats.norm(c["mean"], c["std"])
    if f == "lognormal":
        return stats.lognorm(c["sigma"], 0, np.exp(c["mu"]))
    if f == "gamma":
        return stats.gamma(c["shape"], 0, 1 / c["rate"])
    if f == "rayleigh":
        return stats.rayleigh(0, c["sigma"])
    raise ValueError(f)


for c in out["cases"]:
    xs = np.quantile(c["data"], [0.05, 0.25, 0.5, 0.75, 0.95])
    c["pdf"] = [[float(x), float(frozen(c).pdf(x))] for x in xs]

path = os.path.join(os.path.dirname(__file__), "..", "data", "fit", "scipy_fixtures.json")
with open(path, "w") as f:
    json.dump(out, f, indent=1)
print("wrote", os.path.normpath(path), "scipy", scipy.__version__)
