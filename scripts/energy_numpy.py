#!/usr/bin/env python3
"""Plain NumPy reference implementation of pradar's energy stage.

This is the benchmark baseline for ``pradar energy``: written the way an
engineer would first write it (loop over sweeps, a simple Touchstone line
parser, numpy FFT), but doing the same work as the Rust stage.

Usage:
    python3 scripts/energy_numpy.py --campaign CAMPAIGN.toml --out OUT.parquet

Per (position, direction, pulse) S21(f) is loaded (Touchstone v1 .s2p or a
Parquet long table), coupling is removed ("none" | "mean" | "gate"), the
sweep is windowed (Hann or rect), zero-padded to Nfft = (points-1)*L
(L = oversample, odd) and inverse-FFT'd:

    h[n] = sum_k w_k S_k exp(+j 2 pi k n / Nfft) / sum_k w_k

With dt = 1/(Nfft*df) and bin width T_b = L*dt, bin b is centred at delay
b*T_b and its energy is the mean of |h[n mod Nfft]|^2 over
n = b*L-(L-1)/2 .. b*L+(L-1)/2, for b < nbins =
min(points-1, floor(max_delay_ns*1e-9/T_b)+1).  Energies are averaged over
pulses and written as a long table (position, direction, angle_rel_deg,
angle_global_deg, bin, delay_ns, energy) with file-level key-value metadata
(schema_version, bin_width_ns, pulses, n0, enbw, array, tw, ...).

Prints ``sweeps=N seconds=S sweeps_per_s=R`` at the end (S is measured from
reading the manifest to having written the output; interpreter start-up and
imports are not included).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

UNIT_SCALE = {"hz": 1.0, "khz": 1e3, "mhz": 1e6, "ghz": 1e9}
PROCESSING_DEFAULTS = {
    "window": "hann",
    "oversample": 5,
    "coupling": "gate",
    "gate_ns": 1.0,
    "max_delay_ns": 60.0,
    "noise_from_ns": 40.0,
}


class CampaignError(Exception):
    pass


# --------------------------------------------------------------------------
# Touchstone v1 (.s2p)
# --------------------------------------------------------------------------
def read_s2p_s21(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Return (frequency_hz, S21) from a Touchstone v1 two-port file."""
    unit, fmt = "ghz", "ma"  # Touchstone default option line: # GHz S MA R 50
    tokens: list[str] = []
    seen_option = False
    with open(path, "r", encoding="latin-1") as fh:
        for line in fh:
            bang = line.find("!")
            if bang >= 0:
                line = line[:bang]
            line = line.strip()
            if not line:
                continue
            if line.startswith("#"):
                if seen_option:  # only the first option line counts
                    continue
                seen_option = True
                opts = line[1:].lower().split()
                i = 0
                while i < len(opts):
                    o = opts[i]
                    if o in UNIT_SCALE:
                        unit = o
                    elif o in ("ri", "ma", "db"):
                        fmt = o
                    elif o == "r":
                        i += 1  # reference impedance value
                    elif o == "s":
                        pass
                    else:
                        raise CampaignError(f"{path}: unsupported option '{o}' in option line")
                    i += 1
                continue
            if line.startswith("["):
                raise CampaignError(f"{path}: Touchstone v2 keywords are not supported")
            tokens.extend(line.split())
    if len(tokens) % 9 != 0 or not tokens:
        raise CampaignError(f"{path}: expected 9 numbers per frequency, got {len(tokens)} numbers")
    data = np.array(tokens, dtype=float).reshape(-1, 9)
    f = data[:, 0] * UNIT_SCALE[unit]
    a, b = data[:, 3], data[:, 4]  # S21 is the 2nd pair (order S11 S21 S12 S22)
    if fmt == "ri":
        s21 = a + 1j * b
    elif fmt == "ma":
        s21 = a * np.exp(1j * np.deg2rad(b))
    else:  # db
        s21 = 10.0 ** (a / 20.0) * np.exp(1j * np.deg2rad(b))
    return f, s21


# --------------------------------------------------------------------------
# Manifest
# --------------------------------------------------------------------------
def load_manifest(path: Path) -> dict:
    with open(path, "rb") as fh:
        m = tomllib.load(fh)
    for key in ("band", "directions", "poses", "sweeps"):
        if key not in m:
            raise CampaignError(f"{path}: missing [{key}]")
    if m.get("schema_version", 1) != 1:
        raise CampaignError(f"{path}: unsupported schema_version {m.get('schema_version')}")
    proc = dict(PROCESSING_DEFAULTS)
    proc.update(m.get("processing", {}))
    m["processing"] = proc
    L = int(proc["oversample"])
    if L < 1 or L % 2 == 0:
        raise CampaignError(f"processing.oversample must be odd and >= 1, got {L}")
    if proc["window"] not in ("hann", "rect"):
        raise CampaignError(f"processing.window must be 'hann' or 'rect', got {proc['window']!r}")
    if proc["coupling"] not in ("none", "mean", "gate"):
        raise CampaignError(f"processing.coupling must be none|mean|gate, got {proc['coupling']!r}")
    if int(m["band"]["points"]) < 2:
        raise CampaignError("band.points must be >= 2")
    return m


def direction_count(d: dict) -> int:
    return int(round((d["stop_deg"] - d["start_deg"]) / d["step_deg"])) + 1


def wrap_deg(a: np.ndarray) -> np.ndarray:
    """Wrap angles in degrees to (-180, 180]."""
    return 180.0 - np.mod(180.0 - a, 360.0)


def check_freqs(f: np.ndarray, f_ref: np.ndarray, df: float, what: str) -> None:
    if f.shape != f_ref.shape:
        raise CampaignError(f"{what}: {f.size} frequency points, manifest band has {f_ref.size}")
    if np.max(np.abs(f - f_ref)) > 1e-3 * df:
        raise CampaignError(f"{what}: frequencies do not match the manifest band")


# --------------------------------------------------------------------------
# Energy stage
# --------------------------------------------------------------------------
def run(campaign: Path, out: Path) -> int:
    t0 = time.perf_counter()
    m = load_manifest(campaign)
    base = campaign.parent
    band, proc = m["band"], m["processing"]
    start_hz, stop_hz, points = float(band["start_hz"]), float(band["stop_hz"]), int(band["points"])
    n_pos = len(m["poses"])
    n_dir = direction_count(m["directions"])
    n_pulse = int(m.get("pulses", 1))
    n_sweeps = n_pos * n_dir * n_pulse

    L = int(proc["oversample"])
    df = (stop_hz - start_hz) / (points - 1)
    nfft = (points - 1) * L
    dt = 1.0 / (nfft * df)
    tb = L * dt
    nbins = min(points - 1, int(math.floor(float(proc["max_delay_ns"]) * 1e-9 / tb)) + 1)
    f_ref = np.linspace(start_hz, stop_hz, points)

    w = np.hanning(points) if proc["window"] == "hann" else np.ones(points)
    wsum = w.sum()
    half = (L - 1) // 2
    # idx[b, i] = (b*L - half + i) mod Nfft
    idx = (np.arange(nbins)[:, None] * L + np.arange(-half, half + 1)[None, :]) % nfft
    n_gate = 0
    if proc["coupling"] == "gate":
        # zero samples with signed delay in [-gate_ns, gate_ns) (start and wrapped end)
        n_gate = min(nfft, int(np.count_nonzero(np.arange(nfft) * dt < float(proc["gate_ns"]) * 1e-9)))

    sw = m["sweeps"]
    fmt = sw.get("format", "touchstone")
    cube = None
    if fmt == "parquet":
        table = pd.read_parquet(base / sw["path"], engine="pyarrow",
                                columns=["position", "direction", "pulse", "frequency_hz", "re", "im"])
        table = table.sort_values(["position", "direction", "pulse", "frequency_hz"], kind="stable")
        if len(table) != n_sweeps * points:
            raise CampaignError(f"{sw['path']}: {len(table)} rows, expected {n_sweeps} sweeps x {points} points")
        keys = np.stack([table[c].to_numpy() for c in ("position", "direction", "pulse")], axis=1)
        keys = keys.reshape(n_pos, n_dir, n_pulse, points, 3)
        grid = np.stack(np.meshgrid(np.arange(n_pos), np.arange(n_dir), np.arange(n_pulse), indexing="ij"), axis=-1)
        if not np.array_equal(keys, np.broadcast_to(grid[:, :, :, None, :], keys.shape)):
            raise CampaignError(f"{sw['path']}: (position, direction, pulse) grid is incomplete or out of range")
        fq = table["frequency_hz"].to_numpy().reshape(n_pos, n_dir, n_pulse, points)
        if np.max(np.abs(fq - f_ref)) > 1e-3 * df:
            raise CampaignError(f"{sw['path']}: frequencies do not match the manifest band")
        cube = (table["re"].to_numpy() + 1j * table["im"].to_numpy()).reshape(n_pos, n_dir, n_pulse, points)
        del table, keys, fq
    elif fmt != "touchstone":
        raise CampaignError(f"sweeps.format must be touchstone or parquet, got {fmt!r}")

    energy = np.zeros((n_pos, n_dir, nbins))
    for p in range(n_pos):
        for k in range(n_pulse):
            # load all directions of this (position, pulse)
            s = np.empty((n_dir, points), dtype=complex)
            for d in range(n_dir):
                if cube is not None:
                    s[d] = cube[p, d, k]
                else:
                    rel = sw["pattern"].format(position=p, direction=d, pulse=k)
                    f, s21 = read_s2p_s21(base / rel)
                    check_freqs(f, f_ref, df, rel)
                    s[d] = s21
            if proc["coupling"] == "mean":
                s = s - s.mean(axis=0, keepdims=True)
            for d in range(n_dir):
                x = np.zeros(nfft, dtype=complex)
                ws = w * s[d]
                if points <= nfft:
                    x[:points] = ws
                else:  # L == 1: sample k = points-1 aliases onto k = 0
                    x[:] = ws[:nfft]
                    x[: points - nfft] += ws[nfft:]
                h = np.fft.ifft(x) * (nfft / wsum)
                if n_gate:
                    # signed delays in [-gate, gate): the start and the wrapped end
                    h[:n_gate] = 0.0
                    h[nfft - n_gate:] = 0.0
                pw = h.real ** 2 + h.imag ** 2
                energy[p, d] += pw[idx].mean(axis=1)
    energy /= n_pulse

    # ---- output table ----
    dcfg = m["directions"]
    ang_rel = float(dcfg["start_deg"]) + np.arange(n_dir) * float(dcfg["step_deg"])
    heading = np.array([float(ps.get("heading_deg", 0.0)) for ps in m["poses"]])
    ang_glob = wrap_deg(heading[:, None] + ang_rel[None, :])
    delay_ns = np.arange(nbins) * tb * 1e9
    P, D, B = np.meshgrid(np.arange(n_pos), np.arange(n_dir), np.arange(nbins), indexing="ij")
    cols = {
        "position": pa.array(P.ravel().astype(np.int32)),
        "direction": pa.array(D.ravel().astype(np.int32)),
        "angle_rel_deg": pa.array(ang_rel[D.ravel()]),
        "angle_global_deg": pa.array(ang_glob[P.ravel(), D.ravel()]),
        "bin": pa.array(B.ravel().astype(np.int32)),
        "delay_ns": pa.array(delay_ns[B.ravel()]),
        "energy": pa.array(energy.ravel()),
    }
    noise_bins = delay_ns >= float(proc["noise_from_ns"])
    if not noise_bins.any():  # fall back to the last bin
        noise_bins[-1] = True
    tw = 1.0
    n0 = float(energy[:, :, noise_bins].mean()) / tw
    enbw = float(points * np.sum(w ** 2) / wsum ** 2)
    meta = {
        "schema_version": "1",
        "stage": "energy",
        "producer": "scripts/energy_numpy.py",
        "campaign": str(m.get("name", "")),
        "bin_width_ns": repr(tb * 1e9),
        "pulses": str(n_pulse),
        "n0": repr(n0),
        "enbw": repr(enbw),
        "tw": repr(tw),
        "array": json.dumps(m.get("array", {}), sort_keys=True),
        "start_hz": repr(start_hz),
        "stop_hz": repr(stop_hz),
        "points": str(points),
        "window": proc["window"],
        "oversample": str(L),
        "coupling": proc["coupling"],
        "gate_ns": repr(float(proc["gate_ns"])),
        "max_delay_ns": repr(float(proc["max_delay_ns"])),
        "noise_from_ns": repr(float(proc["noise_from_ns"])),
    }
    tbl = pa.table(cols).replace_schema_metadata(meta)
    out.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(tbl, out)

    secs = time.perf_counter() - t0
    print(f"sweeps={n_sweeps} seconds={secs:.3f} sweeps_per_s={n_sweeps / secs:.1f}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description="NumPy reference for the pradar energy stage.")
    ap.add_argument("--campaign", type=Path, required=True, help="campaign manifest (TOML)")
    ap.add_argument("--out", type=Path, required=True, help="output energy table (Parquet)")
    args = ap.parse_args()
    try:
        return run(args.campaign, args.out)
    except (CampaignError, OSError, KeyError, ValueError, tomllib.TOMLDecodeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
