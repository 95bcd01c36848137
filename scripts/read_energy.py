#!/usr/bin/env python3
"""Check an energy Parquet table written by ``pradar energy`` (or energy_numpy.py).

Usage: python3 scripts/read_energy.py PATH

Checks, reading with pandas (pyarrow engine) and pyarrow:
  * the columns are exactly position, direction, angle_rel_deg,
    angle_global_deg, bin, delay_ns, energy (names and order);
    position/direction/bin are int32, the others float64;
  * no NaN anywhere, energy >= 0;
  * one row per (position, direction, bin) and a full grid;
  * the file-level key-value metadata has the keys schema_version,
    bin_width_ns, pulses, n0, enbw, array.

Prints ``ok rows=N positions=P directions=D bins=B bin_width_ns=X`` and
exits 0, or prints one ``error: ...`` line and exits 1.
"""

from __future__ import annotations

import sys

COLUMNS = ["position", "direction", "angle_rel_deg", "angle_global_deg", "bin", "delay_ns", "energy"]
INT_COLUMNS = ("position", "direction", "bin")
META_KEYS = ["schema_version", "bin_width_ns", "pulses", "n0", "enbw", "array"]


class CheckError(Exception):
    pass


def check(path: str) -> str:
    import pandas as pd
    import pyarrow.parquet as pq

    meta = pq.ParquetFile(path).metadata.metadata or {}
    meta = {k.decode(): v.decode() for k, v in meta.items()}
    missing = [k for k in META_KEYS if k not in meta]
    if missing:
        raise CheckError(f"metadata keys missing: {', '.join(missing)}")

    df = pd.read_parquet(path, engine="pyarrow")
    cols = list(df.columns)
    if cols != COLUMNS:
        absent = [c for c in COLUMNS if c not in cols]
        extra = [c for c in cols if c not in COLUMNS]
        if absent or extra:
            raise CheckError(f"columns mismatch: missing={absent} extra={extra}")
        raise CheckError(f"columns out of order: {cols}")
    for c in COLUMNS:
        want = "int32" if c in INT_COLUMNS else "float64"
        if str(df[c].dtype) != want:
            raise CheckError(f"column {c} has dtype {df[c].dtype}, expected {want}")
    nan_cols = [c for c in COLUMNS if df[c].isna().any()]
    if nan_cols:
        raise CheckError(f"NaN in columns: {', '.join(nan_cols)}")
    if (df["energy"] < 0).any():
        n_neg = int((df["energy"] < 0).sum())
        raise CheckError(f"{n_neg} rows with energy < 0 (min {float(df['energy'].min())!r})")

    rows = len(df)
    n_pos = df["position"].nunique()
    n_dir = df["direction"].nunique()
    n_bin = df["bin"].nunique()
    if df.duplicated(["position", "direction", "bin"]).any():
        raise CheckError("duplicate (position, direction, bin) rows")
    if rows != n_pos * n_dir * n_bin:
        raise CheckError(f"incomplete grid: rows={rows} != {n_pos}*{n_dir}*{n_bin}")
    return (f"ok rows={rows} positions={n_pos} directions={n_dir} bins={n_bin} "
            f"bin_width_ns={meta['bin_width_ns']}")


def main(argv: list[str]) -> int:
    if len(argv) == 2 and argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if len(argv) != 2:
        print("error: usage: read_energy.py PATH")
        return 1
    try:
        print(check(argv[1]))
        return 0
    except CheckError as e:
        print(f"error: {argv[1]}: {e}")
    except Exception as e:  # unreadable file, not Parquet, ...
        print(f"error: {argv[1]}: {type(e).__name__}: {e}")
    return 1


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
