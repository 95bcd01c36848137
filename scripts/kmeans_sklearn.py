#!/usr/bin/env python3
"""scikit-learn side of scripts/bench-kmeans: fits KMeans (k-means++, n_init=10) on the same
standardised features and K as examples/kmeans_bench.rs wrote, times the fits, and prints
the mean adjusted Rand index between the two labelings.

Usage: kmeans_sklearn.py FEATURES.csv RUST_SECONDS
"""
import sys
import time

import numpy as np
import pandas as pd
from sklearn.cluster import KMeans
from sklearn.metrics import adjusted_rand_score


def main() -> int:
    df = pd.read_csv(sys.argv[1])
    rust_s = float(sys.argv[2])
    groups = [(key, g.sort_values("i")) for key, g in df.groupby(["position", "k"])]
    t0 = time.perf_counter()
    labels = []
    for (p, k), g in groups:
        x = g[["delay_z", "angle_z"]].to_numpy()
        km = KMeans(n_clusters=int(k), init="k-means++", n_init=10, random_state=1).fit(x)
        labels.append(km.labels_)
    sk_s = time.perf_counter() - t0
    aris = [adjusted_rand_score(g["label"].to_numpy(), lab) for ((_, g), lab) in zip(groups, labels)]
    print(f"fits={len(groups)} sklearn_seconds={sk_s:.4f} pradar_seconds={rust_s:.4f} "
          f"speedup={sk_s / max(rust_s, 1e-9):.1f}x mean_ARI={np.mean(aris):.3f} min_ARI={np.min(aris):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
