#!/usr/bin/env python3
"""Lab-style campaign folders from a simulated campaign, and the checks of scripts/lab-campaign.

Usage:
  lab_folders.py make SIM_MANIFEST OUT
  lab_folders.py check OUT

``make`` reads the simulated campaign SIM_MANIFEST (written by ``pradar simulate``, one
Touchstone file per sweep) and rewrites it as two labs would have left it on disk, with
scikit-rf (``skrf.Network`` / ``write_touchstone``), frequencies in GHz:

  OUT/lab-keysight/   raw/P03_az-45.s2p ...  dB / angle, a Keysight N5227A header and a date
  OUT/lab-rs/         raw/P03_az-45.s2p ...  magnitude / angle, a Rohde & Schwarz ZVA67 header

File names: position labels P01..P12 in the manifest's pose order, then the steering angle in
signed whole degrees (``f"az{angle:+03d}"``: az-90, az-05, az+00, az+45). Numbers are written
at full precision (skrf's default ``'{}'`` format specs, the shortest repr of each double);
every rewritten sweep is read back with skrf and must equal the simulated one within 1e-12 of
its largest magnitude. Each folder also gets

  poses.csv     ``Pos,X [m],Y [m],Heading [deg]`` then ``P01,0.5,-0.3,0`` ... (the manifest's
                [[poses]])
  <layout>      the simulated campaign's layout, copied
  base.toml     name (lab-<sim name>-keysight / -rs), the simulated seed, [array] as simulated, [processing] with
                every field the simulated manifest has (noise_from_ns always written), and
                [sweeps] parameter = "S21"

and prints one line per folder. It refuses a campaign with more than one pulse, non-integer
steering angles, or any [sweeps] other than Touchstone files.

``check`` compares what scripts/lab-campaign made in OUT (see that script), printing the
figures and exiting 1 when a check fails:

  (i)   OUT/lab-*/report/work/energy.parquet equals OUT/sim/energy.parquet: the same
        (position, direction, bin) rows, and energy within 1e-9 relative, as
        max|a - b| / max|b| and per row on the rows above the noise (b > 10 N0 TW, the
        table's metadata); its n0 too;
  (ii)  OUT/lab-*/report/table1.csv equals OUT/sim-report/table1.csv in every column the
        lab's table has (numbers within 1e-9 relative, text exactly), and the lab's has no
        truth column;
  (iii) the lab's report page (index.html) and table1.md carry the campaign's name in the
        title and Table 1's title, and the position labels P01.. appear on the page.
"""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

LABS = {
    # folder: (name suffix, Touchstone form, header comment lines (skrf prefixes each with "!"))
    "lab-keysight": (
        "keysight",
        "db",
        [
            "Keysight Technologies,N5227A,MY54321098,A.13.95.09",
            "Date: Tuesday, May 21, 2024 {time}",
            "Correction: S11(Full 2 Port(1,2)) S21(Full 2 Port(1,2)) S12(Full 2 Port(1,2)) S22(Full 2 Port(1,2))",
            "S2P File: Measurements: S11, S21, S12, S22:",
        ],
    ),
    "lab-rs": (
        "rs",
        "ma",
        [
            " Rohde & Schwarz ZVA67  1312.7008K67/101832",
            " Firmware 4.20",
            " Created {date_rs}",
            "",
        ],
    ),
}
ROUND_TRIP_TOL = 1e-12
ENERGY_TOL = 1e-9
TABLE_TOL = 1e-9


class CheckFailed(Exception):
    pass


def load_toml(path: Path) -> dict:
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError:  # pragma: no cover - older Pythons
        import tomli as tomllib  # type: ignore[no-redef]
    with open(path, "rb") as f:
        return tomllib.load(f)


def num(x) -> str:
    """A number as a lab writes it: shortest round-trip form, no trailing `.0`."""
    if isinstance(x, bool):
        raise TypeError(x)
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"cannot write {v!r} to TOML")


def label(i: int) -> str:
    return f"P{i + 1:02d}"


def angles(m: dict) -> list[int]:
    d = m["directions"]
    start, stop, step = float(d["start_deg"]), float(d["stop_deg"]), float(d["step_deg"])
    n = int(round((stop - start) / step)) + 1
    out = []
    for j in range(n):
        a = start + j * step
        if abs(a - round(a)) > 1e-9:
            raise SystemExit(f"error: direction {j} is {a} deg: this helper names whole degrees only")
        out.append(int(round(a)))
    return out


def sweep_paths(m: dict, root: Path, npos: int, ndir: int) -> dict[tuple[int, int], Path]:
    s = m.get("sweeps") or {}
    if s.get("format", "touchstone") != "touchstone":
        raise SystemExit("error: the simulated sweeps must be Touchstone files (pradar simulate's default)")
    if int(m.get("pulses", 1)) != 1:
        raise SystemExit("error: this helper writes one sweep per (position, direction): pulses must be 1")
    if s.get("files"):
        return {(int(f["position"]), int(f["direction"])): root / f["path"] for f in s["files"]}
    pat = s.get("pattern")
    if not pat:
        raise SystemExit("error: the manifest's [sweeps] has neither files nor pattern")
    return {
        (p, d): root / pat.format(position=p, direction=d, pulse=0)
        for p in range(npos)
        for d in range(ndir)
    }


def make(sim_manifest: Path, out: Path) -> None:
    import numpy as np
    import skrf

    m = load_toml(sim_manifest)
    root = sim_manifest.parent
    poses = m["poses"]
    ang = angles(m)
    paths = sweep_paths(m, root, len(poses), len(ang))
    layout_src = root / m["layout"]
    layout_name = Path(m["layout"]).name
    proc = dict(m.get("processing") or {})
    proc.setdefault("noise_from_ns", 80.0)  # written explicitly (pradar's default)
    # fields in pradar's order
    order = ["window", "oversample", "coupling", "gate_ns", "max_delay_ns", "noise_from_ns"]
    proc_keys = [k for k in order if k in proc] + [k for k in proc if k not in order]

    for folder, (suffix, form, header) in LABS.items():
        d = out / folder
        raw = d / "raw"
        raw.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(layout_src, d / layout_name)
        with open(d / "poses.csv", "w", newline="\n") as f:
            f.write("Pos,X [m],Y [m],Heading [deg]\n")
            for i, q in enumerate(poses):
                f.write(f"{label(i)},{num(q['x_m'])},{num(q['y_m'])},{num(q['heading_deg'])}\n")
        base = [
            "# What the sweep files cannot tell pradar import (scripts/lab_folders.py).",
            "name = " + toml_value(f"lab-{m['name']}-{suffix}"),
            # the simulated campaign's seed: the report's seeded steps (the check's draws)
            # then draw what the simulated report drew
            "seed = " + toml_value(m["seed"]),
            "",
            "[array]",
        ]
        base += [f"{k} = {toml_value(v)}" for k, v in m["array"].items()]
        base += ["", "[processing]"]
        base += [f"{k} = {toml_value(proc[k])}" for k in proc_keys]
        base += ["", "[sweeps]", 'parameter = "S21"', ""]
        (d / "base.toml").write_text("\n".join(base))

        worst = 0.0
        count = 0
        for (p, j), src in sorted(paths.items()):
            n = skrf.Network(str(src))
            s0 = n.s.copy()
            n.frequency.unit = "ghz"
            k = p * len(ang) + j  # one sweep every 20 s from 10:00:00
            sec = 10 * 3600 + 20 * k
            hh, mm, ss = sec // 3600, sec // 60 % 60, sec % 60
            time = f"{hh:02d}:{mm:02d}:{ss:02d}"
            date_rs = f"5/21/2024 {hh % 12 or 12}:{mm:02d}:{ss:02d} {'AM' if hh < 12 else 'PM'}"
            n.comments = "\n".join(h.format(time=time, date_rs=date_rs) for h in header)
            name = f"{label(p)}_az{ang[j]:+03d}.s2p"
            dst = raw / name
            with np.errstate(divide="ignore"):  # |S11| = 0 is written -inf dB, as skrf does
                n.write_touchstone(str(dst), form=form, skrf_comment=False)
            back = skrf.Network(str(dst))
            peak = float(np.max(np.abs(s0)))
            err = float(np.max(np.abs(back.s - s0))) / peak if peak > 0 else 0.0
            if not np.allclose(back.f, n.f, rtol=1e-14, atol=0):
                raise SystemExit(f"error: {dst}: frequencies do not round-trip")
            worst = max(worst, err)
            count += 1
        if worst > ROUND_TRIP_TOL:
            raise SystemExit(
                f"error: {folder}: a rewritten sweep differs from the simulated one by {worst:.2e} of its largest |S|"
            )
        print(
            f"{folder}: {count} files ({form.upper()}, GHz) in {raw}, poses.csv, base.toml, {layout_name}; "
            f"worst round trip {worst:.1e} of the largest |S|"
        )


def check_energy(sim: Path, lab: Path) -> list[str]:
    import numpy as np
    import pandas as pd
    import pyarrow.parquet as pq

    a = pd.read_parquet(lab)
    b = pd.read_parquet(sim)
    key = ["position", "direction", "bin"]
    a = a.sort_values(key).reset_index(drop=True)
    b = b.sort_values(key).reset_index(drop=True)
    fails = []
    if len(a) != len(b) or not (a[key].to_numpy() == b[key].to_numpy()).all():
        return [f"rows differ: {len(a)} vs {len(b)}"]
    for c in ("angle_rel_deg", "angle_global_deg", "delay_ns"):
        if c in a and not np.allclose(a[c], b[c], rtol=1e-12, atol=1e-12):
            fails.append(f"column {c} differs")
    ea, eb = a["energy"].to_numpy(), b["energy"].to_numpy()
    meta = lambda p: {k.decode(): v.decode() for k, v in (pq.ParquetFile(p).metadata.metadata or {}).items()}
    ma, mb = meta(lab), meta(sim)
    n0a, n0b = float(ma["n0"]), float(mb["n0"])
    tw = float(mb.get("tw", "1"))
    floor = 10.0 * n0b * tw
    above = eb > floor
    glob = float(np.max(np.abs(ea - eb)) / np.max(np.abs(eb)))
    per_row = float(np.max(np.abs(ea[above] - eb[above]) / eb[above])) if above.any() else 0.0
    n0_rel = abs(n0a - n0b) / abs(n0b)
    print(
        f"    energy: {len(a)} rows, max|a-b|/max|b| = {glob:.2e}; "
        f"{int(above.sum())} rows above 10 N0 TW: max relative {per_row:.2e}; n0 relative {n0_rel:.2e}"
    )
    if not glob <= ENERGY_TOL:
        fails.append(f"energy max|a-b|/max|b| = {glob:.2e} > {ENERGY_TOL}")
    if not per_row <= ENERGY_TOL:
        fails.append(f"energy per-row relative {per_row:.2e} > {ENERGY_TOL}")
    if not above.any():
        fails.append("no rows above the noise")
    if not n0_rel <= ENERGY_TOL:
        fails.append(f"n0 relative {n0_rel:.2e} > {ENERGY_TOL}")
    return fails


def read_table(path: Path) -> tuple[list[str], list[list[str]]]:
    import csv

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def as_float(s: str):
    try:
        return float(s)
    except ValueError:
        return None


def check_table(sim: Path, lab: Path) -> list[str]:
    hs, rs = read_table(sim)
    hl, rl = read_table(lab)
    fails = []
    truth = [h for h in hl if "truth" in h.lower()]
    if truth:
        fails.append(f"the lab's Table 1 has a truth column: {truth}")
    missing = [h for h in hl if h not in hs]
    if missing:
        fails.append(f"columns not in the simulated campaign's Table 1: {missing}")
        return fails
    if len(rs) != len(rl):
        return fails + [f"{len(rl)} rows vs {len(rs)}"]
    worst, numbers, texts = 0.0, 0, 0
    for r_s, r_l in zip(rs, rl):
        for c, h in enumerate(hl):
            vs, vl = r_s[hs.index(h)], r_l[c]
            fs, fl = as_float(vs), as_float(vl)
            if fs is not None and fl is not None:
                numbers += 1
                if math.isnan(fs) and math.isnan(fl):
                    continue
                d = abs(fs - fl) / max(abs(fs), 1e-300) if fs != fl else 0.0
                worst = max(worst, d)
                if not d <= TABLE_TOL:
                    fails.append(f"{r_l[0]} / {h}: {vl} vs {vs}")
            else:
                texts += 1
                if vs != vl:
                    fails.append(f"{r_l[0]} / {h}: `{vl}` vs `{vs}`")
    print(
        f"    Table 1: {len(rl)} rows x {len(hl)} columns ({numbers} numbers, worst relative "
        f"{worst:.1e}; {texts} text cells); simulated columns not in the lab's: "
        f"{[h for h in hs if h not in hl]}"
    )
    return fails


def check_page(report: Path, name: str, labels: list[str]) -> list[str]:
    import re

    page = (report / "index.html").read_text(encoding="utf-8")
    md = (report / "table1.md").read_text(encoding="utf-8")
    fails = []
    t = re.search(r"<title>(.*?)</title>", page, re.S)
    title = t.group(1).strip() if t else ""
    if name not in title:
        fails.append(f"page title `{title}` lacks `{name}`")
    heads = [re.sub(r"<[^>]+>", "", h).strip() for h in re.findall(r"<h[1-6][^>]*>(.*?)</h[1-6]>", page, re.S)]
    t1 = [h for h in heads if "Table 1" in h]
    if not any(name in h for h in t1):
        fails.append(f"no Table 1 heading with `{name}` on the page (Table 1 headings: {t1})")
    first = md.splitlines()[0] if md else ""
    if name not in first:
        fails.append(f"table1.md title `{first}` lacks `{name}`")
    seen = [lab for lab in labels if re.search(rf"\b{re.escape(lab)}\b", page)]
    print(
        f"    page: title `{title}`; Table 1 heading `{t1[0] if t1 else ''}`; "
        f"position labels on the page: {len(seen)} of {len(labels)}"
    )
    if len(seen) != len(labels):
        fails.append(f"position labels missing from the page: {[x for x in labels if x not in seen]}")
    return fails


def check(out: Path) -> int:
    sim_energy = out / "sim" / "energy.parquet"
    sim_table = out / "sim-report" / "table1.csv"
    failed = False
    for folder in LABS:
        d = out / folder
        manifest = load_toml(d / "work" / "campaign.toml")
        name = manifest["name"]
        labels = [label(i) for i in range(len(manifest["poses"]))]
        report = d / "report"
        print(f"{folder} ({name}):")
        fails = []
        fails += check_energy(sim_energy, report / "work" / "energy.parquet")
        fails += check_table(sim_table, report / "table1.csv")
        fails += check_page(report, name, labels)
        for f in fails:
            print(f"    FAIL: {f}")
        print(f"    {'ok' if not fails else 'FAILED'}")
        failed |= bool(fails)
    return 1 if failed else 0


def main(argv: list[str]) -> int:
    if len(argv) >= 2 and argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if len(argv) == 4 and argv[1] == "make":
        make(Path(argv[2]), Path(argv[3]))
        return 0
    if len(argv) == 3 and argv[1] == "check":
        return check(Path(argv[2]))
    print("usage: lab_folders.py make SIM_MANIFEST OUT | lab_folders.py check OUT", file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
