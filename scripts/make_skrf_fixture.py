#!/usr/bin/env python3
"""Build the scikit-rf Touchstone fixtures in data/touchstone/.

These fixture files were made by this script with scikit-rf (skrf) 2.2.0
(numpy 2.4.6, Python 3.11.7).  Re-running it with another skrf version may
change the header comment and the number formatting, not the values.

A 2-port Network over 57.5-63.5 GHz with 11 points (k = 0..10) is built with

    S21 = S12 = 0.0123 * exp(-1j*2*pi*f*20e-9) * (1 + 0.1*k/10)
    S11 = 0.05 + 0.02j          (constant)
    S22 = -0.01j                (constant)

and written with ``Network.write_touchstone`` three times:

    skrf_ri.s2p   form='ri'  (real / imaginary)
    skrf_ma.s2p   form='ma'  (magnitude / angle in degrees)
    skrf_db.s2p   form='db'  (20*log10|S| / angle in degrees)

The exact doubles handed to skrf are stored in ``skrf_expected.json``
(keys frequency_hz, s11_re, s11_im, s21_re, s21_im, s12_re, s12_im,
s22_re, s22_im).  JSON floats are written with Python's repr, so they
round-trip to the identical IEEE-754 doubles.

Note: with these numbers f*20 ns is an integer at every point (1150 + 12k),
so the S21/S12 phase is 0 up to rounding (|angle| < 1e-10 deg); S11 and
S22 carry the non-trivial angles (21.8 deg and -90 deg).

skrf 2.2.0 writes the frequency column in Hz (option line "# Hz S RI R 50.0",
note the float reference impedance and the trailing blank) for a Network whose
Frequency unit is Hz, which is what this script uses.

Usage: python3 scripts/make_skrf_fixture.py [--out data/touchstone]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import skrf as rf

REPO = Path(__file__).resolve().parent.parent
POINTS = 11
START_HZ = 57.5e9
STOP_HZ = 63.5e9
Z0 = 50.0


def build() -> tuple[np.ndarray, np.ndarray]:
    """Return (f_hz, s) with s shaped (points, 2, 2), s[:, i, j] = S(i+1)(j+1)."""
    f = np.linspace(START_HZ, STOP_HZ, POINTS)
    k = np.arange(POINTS)
    s21 = 0.0123 * np.exp(-1j * 2 * np.pi * f * 20e-9) * (1 + 0.1 * k / 10)
    s = np.zeros((POINTS, 2, 2), dtype=complex)
    s[:, 0, 0] = 0.05 + 0.02j
    s[:, 1, 0] = s21
    s[:, 0, 1] = s21
    s[:, 1, 1] = -0.01j
    return f, s


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=REPO / "data" / "touchstone")
    args = ap.parse_args()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)

    f, s = build()
    freq = rf.Frequency.from_f(f, unit="Hz")
    ntwk = rf.Network(frequency=freq, s=s, z0=Z0, name="skrf_fixture")
    # skrf must hold exactly what we gave it.
    assert np.array_equal(ntwk.f, f) and np.array_equal(ntwk.s, s)

    for form in ("ri", "ma", "db"):
        path = out / f"skrf_{form}.s2p"
        ntwk.write_touchstone(filename=str(path), form=form)
        # skrf appends the extension only when missing; make sure of the name.
        assert path.exists(), path

    expected = {"frequency_hz": [float(x) for x in f]}
    for name, (i, j) in (("s11", (0, 0)), ("s21", (1, 0)), ("s12", (0, 1)), ("s22", (1, 1))):
        expected[f"{name}_re"] = [float(x) for x in s[:, i, j].real]
        expected[f"{name}_im"] = [float(x) for x in s[:, i, j].imag]
    (out / "skrf_expected.json").write_text(json.dumps(expected, indent=1) + "\n")

    # Read the files back with skrf as a sanity check.
    for form in ("ri", "ma", "db"):
        back = rf.Network(str(out / f"skrf_{form}.s2p"))
        err = np.max(np.abs(back.s - s))
        assert np.allclose(back.f, f, rtol=1e-15, atol=0), form
        assert err < 1e-12, (form, err)
        print(f"wrote {out / f'skrf_{form}.s2p'} (skrf {rf.__version__}, read back max |dS| = {err:.2e})")
    print(f"wrote {out / 'skrf_expected.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
