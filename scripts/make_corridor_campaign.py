#!/usr/bin/env python3
"""Write a campaign of N poses over the built-in corridor layout, for the benchmarks.

Usage: python3 scripts/make_corridor_campaign.py DIR N

Writes DIR/campaign.toml (the corridor manifest with 16 elements and N poses on a line
along the corridor, headings cycling), DIR/layout.geojson and DIR/model.toml (the
manifest's [clutter] section as a model file, for `pradar synth`).
Used by scripts/bench-memory and scripts/bench-scaling.
"""
import re
import shutil
import sys
from pathlib import Path

root = Path(__file__).resolve().parent.parent
d, n = sys.argv[1], int(sys.argv[2])
src = open(f"{root}/data/corridor/campaign.toml").read()
shutil.copy(f"{root}/data/corridor/layout.geojson", f"{d}/layout.geojson")
head = src.split("[[poses]]")[0].replace("elements = 400", "elements = 16")
tail = src[src.index("\n[scene]\n"):]
out = []
for i in range(n):
    x = -0.5 + 10.0 * i / max(n - 1, 1)
    out.append(f"[[poses]]\nx_m = {x:.4f}\ny_m = {-0.3 + 0.4 * (i % 3) / 2:.3f}\nheading_deg = {(i * 37) % 360 - 180:.1f}\n")
open(f"{d}/campaign.toml", "w").write(head + "\n".join(out) + "\n" + tail)
clutter = src[src.index("\n[clutter]\n") + 1:]
clutter = re.sub(r"\[clutter\.", "[", clutter).replace("[clutter]\n", "")
open(f"{d}/model.toml", "w").write(clutter)
