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

It also writes the reader zoo of issue 18 in ``zoo/`` (see ``write_zoo``): 1- to
4-port files in RI/MA/DB and Hz..GHz, Touchstone 2.0/2.1, HFSS port-impedance
comments, -inf dB, noise blocks (v1 and v2), a BOM, a Latin-1 comment, CR line
endings, per-port and complex option-line impedances; ``zoo/zoo_expected.json``
holds what scikit-rf reads back from each (the reference for the Rust reader).

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


# ---------------------------------------------------------------------------
# The reader "zoo" (issue 18): every form, unit and port count, v2, a noise
# block, -inf dB, a BOM, a Latin-1 comment, CR line endings, per-port and
# complex reference impedance.  Written to data/touchstone/zoo/; what scikit-rf
# reads back from each file (not what was handed to it: the reference is
# skrf's *reading*) goes to zoo/zoo_expected.json as
#   {file: {ports, f, s_re, s_im (row-major per point), z0_re, z0_im, noise}}
# with every number a repr() string.
# ---------------------------------------------------------------------------

ZOO_POINTS = 6  # a multiple of 3: the old reader regrouped such .s1p files silently


def zoo_network(ports: int, z0=50.0, unit: str = "GHz") -> "rf.Network":
    """A reproducible network: S_ij = (0.1 + 0.05 i + 0.01 j) * (1 + 0.02 k) e^{-j(0.3 i + 0.2 j) k}."""
    f = np.linspace(START_HZ, STOP_HZ, ZOO_POINTS)
    k = np.arange(ZOO_POINTS)[:, None, None]
    i = np.arange(1, ports + 1)[None, :, None]
    j = np.arange(1, ports + 1)[None, None, :]
    s = (0.1 + 0.05 * i + 0.01 * j) * (1 + 0.02 * k) * np.exp(-1j * (0.3 * i + 0.2 * j) * k)
    # from_f takes the values in `unit`; skrf then writes them in that unit
    scale = {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6, "GHz": 1e9}[unit]
    freq = rf.Frequency.from_f(f / scale, unit=unit)
    return rf.Network(frequency=freq, s=s, z0=z0, name="zoo")


def write_zoo(out: Path) -> None:
    zoo = out / "zoo"
    zoo.mkdir(parents=True, exist_ok=True)
    files: list[str] = []

    def write(ntwk, name, **kw):
        path = zoo / name
        text = ntwk.write_touchstone(return_string=True, **kw)
        path.write_bytes(text.encode("latin-1"))
        files.append(name)
        return path

    # every form x unit x port count (1, 2, 3, 4) in v1
    units = {1: "MHz", 2: "Hz", 3: "kHz", 4: "GHz"}
    for ports in (1, 2, 3, 4):
        for form in ("ri", "ma", "db"):
            write(zoo_network(ports, unit=units[ports]), f"p{ports}_{form}.s{ports}p", form=form)
    # v2: two-port and four-port, per-port [Reference]
    write(zoo_network(2, z0=[50.0, 75.0]), "v2_p2.ts", form="ri", version="2.0")
    write(zoo_network(4, z0=[50.0, 50.0, 25.0, 100.0]), "v2_p4_db.ts", form="db", version="2.1")
    # HFSS-style per-point complex port impedances (`! Port Impedance`)
    n = zoo_network(2)
    n.z0 = np.array([[50 + 1j * k, 75 - 0.5j * k] for k in range(ZOO_POINTS)])
    write(n, "hfss_z0.s2p", form="ma", write_z0=True)
    # -inf dB: |S11| = 0 written by skrf as -inf
    n = zoo_network(2)
    s = n.s.copy()
    s[:, 0, 0] = 0
    n.s = s
    with np.errstate(divide="ignore"):
        write(n, "minus_inf.s2p", form="db")
    # a noise block after the two-port data (v1) and a [Noise Data] block (v2)
    n = zoo_network(2)
    nf = rf.Frequency.from_f(np.linspace(START_HZ, STOP_HZ, 3) / 1e9, unit="GHz")
    n.set_noise_a(nf, nfmin_db=1.5, gamma_opt=0.3 + 0.1j, rn=10.0)
    write(n, "noise.s2p", form="ri")
    write(n, "noise_v2.ts", form="ri", version="2.0")
    # bytes scikit-rf tolerates: a UTF-8 BOM, a Latin-1 degree sign, CR line endings
    base = (zoo / "p2_ri.s2p").read_bytes()
    (zoo / "bom.s2p").write_bytes(b"\xef\xbb\xbf" + base)
    (zoo / "latin1.s2p").write_bytes(b"! measured at 23\xb0C, 45 % RH\n" + base)
    (zoo / "cr.s2p").write_bytes(base.replace(b"\n", b"\r"))
    # reference impedance in the option line: one per port, and complex
    text = base.decode("latin-1")
    (zoo / "r_per_port.s2p").write_text(text.replace("R 50.0 ", "R 50 75"), encoding="latin-1")
    (zoo / "r_complex.s2p").write_text(text.replace("R 50.0 ", "R (10+10j)"), encoding="latin-1")
    files += ["bom.s2p", "latin1.s2p", "cr.s2p", "r_per_port.s2p", "r_complex.s2p"]

    # numbers as repr() strings: serde_json's default float parser is not correctly
    # rounded (off by an ulp now and then), Rust's str::parse::<f64> is
    def strs(a) -> list[str]:
        return [repr(float(x)) for x in np.asarray(a).ravel()]

    expected = {}
    for name in files:
        back = rf.Network(str(zoo / name))
        s = back.s.reshape(len(back.f), -1)
        expected[name] = {
            "ports": int(back.nports),
            "f": strs(back.f),
            "s_re": strs(s.real),
            "s_im": strs(s.imag),
            "z0_re": strs(np.real(back.z0)),
            "z0_im": strs(np.imag(back.z0)),
            "noise": bool(back.noisy),
        }
    (zoo / "zoo_expected.json").write_text(json.dumps(expected, indent=0) + "\n")
    print(f"wrote {len(files)} files and zoo_expected.json in {zoo} (skrf {rf.__version__})")


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
    write_zoo(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
