#!/usr/bin/env python3
"""The README's accuracy table, computed from the error bounds rtsim compiles in
(platforms/configs/error_bounds.json, written by scripts/bench_error_grid.py): per frame size the
mean error of the grid and the bound, its worst error (with WIDEN, the larger worst of two grids;
with REPLACE, the fidelity's own rerun).
Usage: scripts/accuracy_table.py            print the table
       scripts/accuracy_table.py --check    exit 1 if README.md does not hold it verbatim
(ctest runs the check, so the README's figures cannot drift from the bounds)."""
import json
import os
import sys

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
d = json.load(open(os.path.join(root, "platforms", "configs", "error_bounds.json")))
b = d["bounds"]
# A fidelity's entry holds its workloads, and its commit where its grid was replaced (REPLACE).
sizes = sorted({int(s) for f in b.values() for w in f.values() if isinstance(w, dict) for s in w["by_size"]})
names = {"lt": "`lt` (any quantum)", "interval": "`interval`"}
workloads = {"primary": "primary rays", "pt": f"path tracing, {d['grid']['spp']} spp"}
lines = ["| fidelity | workload | " + " | ".join(f"{n}x{n}: mean / bound" if i == 0 else f"{n}x{n}" for i, n in enumerate(sizes)) + " |",
         "|---|---|" + "---|" * len(sizes)]
for fid in ("lt", "interval"):
    for wl in ("primary", "pt"):
        cells = []
        for n in sizes:
            c = b[fid][wl]["by_size"].get(str(n))
            cells.append(f"{100 * c['mean']:.1f} % / {100 * c['worst']:.1f} %" if c else "not run")
        lines.append(f"| {names[fid]} | {workloads[wl]} | " + " | ".join(cells) + " |")
table = "\n".join(lines) + "\n"
if "--check" in sys.argv:
    readme = open(os.path.join(root, "README.md")).read()
    if table in readme:
        sys.exit(0)
    print("README.md does not hold the accuracy table of platforms/configs/error_bounds.json; "
          "replace it with the output of scripts/accuracy_table.py:\n" + table, file=sys.stderr)
    sys.exit(1)
sys.stdout.write(table)
