#!/usr/bin/env python3
"""Write a synthetic benchmark campaign for pradar's energy stage.

Usage:
    python3 scripts/make_bench_campaign.py --out DIR --sweeps N
        [--points 801] [--format touchstone|parquet|both]

Writes into DIR:
  * layout.geojson      a FeatureCollection with one Polygon, {"role": "perimeter"}
  * campaign.toml       manifest (schema_version 1) with ceil(N/37) poses on a
                        line, 37 directions -90..90 step 5, pulses = 1, band
                        57.5-63.5 GHz with --points points;
                        so the campaign holds ceil(N/37)*37 >= N sweeps
  * sweeps/pPPP_dDD_k00.s2p   Touchstone v1, "# Hz S RI R 50", all four
                        S-parameters (S12 = S21, S11 = S22 = 0), "%.9e"
  * sweeps.parquet      long table position, direction, pulse (int32),
                        frequency_hz, re, im (float64)

--format touchstone (default) and parquet write campaign.toml pointing at
that format; --format both writes campaign.toml (Touchstone) and
campaign_parquet.toml (Parquet), which describe the same data.

Each S21 is the sum of 5 random echoes a*exp(-j 2 pi f tau) (|a| log-uniform
in [1e-3, 1e-2], uniform phase, tau uniform in 5..50 ns) plus complex
Gaussian noise (sigma 1e-4), drawn from numpy default_rng(1).  Headings cycle
through 0, 90, 180, -90 degrees so that global angles wrap.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

START_HZ = 57.5e9
STOP_HZ = 63.5e9
N_DIR = 37  # -90..90 step 5
PATTERN = "sweeps/p{position:03}_d{direction:02}_k{pulse:02}.s2p"
N_ECHO = 5
NOISE_SIGMA = 1e-4
ZERO = "%.9e" % 0.0


def manifest_text(n_pos: int, points: int, sweeps_block: str) -> str:
    lines = [
        "# Synthetic benchmark campaign written by scripts/make_bench_campaign.py",
        "schema_version = 1",
        'name = "bench"',
        'layout = "layout.geojson"',
        "seed = 1",
        "pulses = 1",
        "",
        "[band]",
        f"start_hz = {START_HZ!r}",
        f"stop_hz = {STOP_HZ!r}",
        f"points = {points}",
        "",
        "[array]",
        "elements = 400",
        "one_bit = true",
        "element_q = 1.0",
        'steering = "mechanical"',
        "",
        "[directions]",
        "start_deg = -90.0",
        "stop_deg = 90.0",
        "step_deg = 5.0",
        "",
        "[noise]",
        "floor_dbm = -100.0",
        "tx_power_dbm = 0.0",
        "",
        "[processing]",
        'window = "hann"',
        "oversample = 5",
        'coupling = "gate"',
        "gate_ns = 1.0",
        "max_delay_ns = 60.0",
        "noise_from_ns = 40.0",
        "",
    ]
    headings = (0.0, 90.0, 180.0, -90.0)
    for i in range(n_pos):
        lines += ["[[poses]]", f"x_m = {0.25 * i!r}", "y_m = 0.0", f"heading_deg = {headings[i % 4]!r}", ""]
    lines += ["[sweeps]", sweeps_block, ""]
    return "\n".join(lines)


def layout(n_pos: int) -> dict:
    x1 = 0.25 * max(n_pos - 1, 0) + 2.0
    ring = [[-2.0, -3.0], [x1, -3.0], [x1, 3.0], [-2.0, 3.0], [-2.0, -3.0]]
    return {
        "type": "FeatureCollection",
        "features": [{
            "type": "Feature",
            "properties": {"role": "perimeter"},
            "geometry": {"type": "Polygon", "coordinates": [ring]},
        }],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description="Write a synthetic energy-stage benchmark campaign.")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--sweeps", type=int, required=True, help="minimum number of sweeps")
    ap.add_argument("--points", type=int, default=801)
    ap.add_argument("--format", choices=("touchstone", "parquet", "both"), default="touchstone")
    args = ap.parse_args()
    if args.sweeps < 1 or args.points < 2:
        ap.error("--sweeps must be >= 1 and --points >= 2")

    t0 = time.perf_counter()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    points = args.points
    n_pos = math.ceil(args.sweeps / N_DIR)
    n_sweeps = n_pos * N_DIR
    write_ts = args.format in ("touchstone", "both")
    write_pq = args.format in ("parquet", "both")

    f = np.linspace(START_HZ, STOP_HZ, points)
    rng = np.random.default_rng(1)

    if write_ts:
        (out / "sweeps").mkdir(exist_ok=True)
        # Per row: f S11(re im) S21(re im) S12(re im) S22(re im); only S21/S12 vary.
        row_fmts = [f"{'%.9e' % fi} {ZERO} {ZERO} %.9e %.9e %.9e %.9e {ZERO} {ZERO}\n" for fi in f]
        file_fmt = "! synthetic benchmark sweep (scripts/make_bench_campaign.py)\n# Hz S RI R 50\n" + "".join(row_fmts)
    if write_pq:
        n_rows = n_sweeps * points
        sweep_ix = np.repeat(np.arange(n_sweeps), points)
        pq_pos = (sweep_ix // N_DIR).astype(np.int32)
        pq_dir = (sweep_ix % N_DIR).astype(np.int32)
        pq_pulse = np.zeros(n_rows, dtype=np.int32)
        pq_f = np.tile(f, n_sweeps)
        pq_re = np.empty(n_rows)
        pq_im = np.empty(n_rows)
        del sweep_ix

    for p in range(n_pos):
        amp = 10.0 ** rng.uniform(-3.0, -2.0, (N_DIR, N_ECHO))
        phase = rng.uniform(0.0, 2 * np.pi, (N_DIR, N_ECHO))
        tau = rng.uniform(5e-9, 50e-9, (N_DIR, N_ECHO))
        a = amp * np.exp(1j * phase)
        s21 = np.einsum("de,def->df", a, np.exp(-2j * np.pi * tau[:, :, None] * f[None, None, :]))
        s21 += (NOISE_SIGMA / np.sqrt(2)) * (rng.standard_normal((N_DIR, points))
                                             + 1j * rng.standard_normal((N_DIR, points)))
        if write_pq:
            sl = slice(p * N_DIR * points, (p + 1) * N_DIR * points)
            pq_re[sl] = s21.real.ravel()
            pq_im[sl] = s21.imag.ravel()
        if write_ts:
            for d in range(N_DIR):
                vals = np.empty((points, 4))
                vals[:, 0] = vals[:, 2] = s21[d].real
                vals[:, 1] = vals[:, 3] = s21[d].imag
                text = file_fmt % tuple(vals.ravel().tolist())
                (out / PATTERN.format(position=p, direction=d, pulse=0)).write_text(text)

    ts_block = f'format = "touchstone"\npattern = "{PATTERN}"'
    pq_block = 'format = "parquet"\npath = "sweeps.parquet"'
    if write_pq:
        table = pa.table({"position": pq_pos, "direction": pq_dir, "pulse": pq_pulse,
                          "frequency_hz": pq_f, "re": pq_re, "im": pq_im})
        pq.write_table(table, out / "sweeps.parquet")
    if args.format == "both":
        (out / "campaign.toml").write_text(manifest_text(n_pos, points, ts_block))
        (out / "campaign_parquet.toml").write_text(manifest_text(n_pos, points, pq_block))
    else:
        (out / "campaign.toml").write_text(manifest_text(n_pos, points, ts_block if write_ts else pq_block))
    (out / "layout.geojson").write_text(json.dumps(layout(n_pos), indent=1) + "\n")

    print(f"wrote {out}: positions={n_pos} directions={N_DIR} pulses=1 sweeps={n_sweeps} "
          f"points={points} format={args.format} seconds={time.perf_counter() - t0:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
