#!/usr/bin/env python3
"""Straightforward NumPy EKF update (dense H), as an engineer would first write it, on the
update dumped by `benches/ekf.rs numpy CELLS DIR`:

    S = H P H^T + R;  K = P H^T S^-1;  x = x + K nu;  P = (I - K H) P

Prints the best-of-3 wall time and the largest differences from the Rust result.
Usage: scripts/ekf_numpy.py DIR
"""
import sys
import time

import numpy as np

d = sys.argv[1]
x = np.load(f"{d}/x.npy")
P = np.load(f"{d}/P.npy")
H = np.load(f"{d}/H.npy")
nu = np.load(f"{d}/nu.npy")
R = np.diag(np.load(f"{d}/R.npy"))
n = x.size


def update(x, P):
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    x = x + K @ nu
    P = (np.eye(n) - K @ H) @ P
    return x, P


best = float("inf")
for _ in range(3):
    t = time.perf_counter()
    xn, Pn = update(x, P)
    best = min(best, time.perf_counter() - t)
xr = np.load(f"{d}/x_rust.npy")
Pr = np.load(f"{d}/P_rust.npy")
dx = np.max(np.abs(xn - xr)) / max(np.max(np.abs(xr)), 1e-300)
dp = np.max(np.abs(Pn - Pr)) / max(np.max(np.abs(Pr)), 1e-300)
print(f"numpy_dense_update cells={n} bins={H.shape[0]} seconds={best:.4f} "
      f"max_rel_diff_x={dx:.2e} max_rel_diff_P={dp:.2e}")
