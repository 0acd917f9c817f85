#!/usr/bin/env python3
"""Checks that two sweep folders of one manifest hold the same results: every run's stats equal
in every statistic but what was measured of the host rather than simulated (wall-clock times, the
simulator's speed, our traversal's speed against Embree's, the process's peak memory: the keys
`rtsim --stats-schema` gives in s or per s, and the sections HOST), and results.csv equal in every
column but the wall-clock ones (wall_s, sim_s). Prints each difference.
Usage: same_results.py MANIFEST DIR_A DIR_B   (RTSIM: the rtsim binary, default build/rtsim)
Exit status: 0 the same, 1 different."""
import csv
import json
import os
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import manifest  # noqa: E402

WALL_CLOCK_COLUMNS = {"wall_s", "sim_s"}
HOST = ("time_s", "simulation_rate", "speed", "memory_mb.peak_resident", "provenance")


def host_keys():
    rtsim = os.environ.get("RTSIM", str(HERE.parent.parent / "build" / "rtsim"))
    out = subprocess.run([rtsim, "--stats-schema"], capture_output=True, text=True, check=True).stdout
    keys = set(HOST)
    for f in (line.split("\t") for line in out.splitlines()[1:]):
        if len(f) > 1 and (f[1] == "s" or f[1].endswith("/ s")):
            keys.add(f[0])
    return keys


def differences(x, y, path=""):
    if isinstance(x, dict) and isinstance(y, dict):
        for k in sorted(set(x) | set(y)):
            yield from differences(x.get(k), y.get(k), f"{path}.{k}" if path else k)
    elif x != y:
        yield f"{path}: {json.dumps(x)[:60]} against {json.dumps(y)[:60]}"


def strip(node, keys, path=""):
    if isinstance(node, dict):
        return {k: strip(v, keys, f"{path}.{k}" if path else k) for k, v in node.items()
                if (f"{path}.{k}" if path else k) not in keys}
    if isinstance(node, list):
        return [strip(v, keys, path + "[]") for v in node]
    return node


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    runs = manifest.read(sys.argv[1])
    a, b = pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
    host = host_keys()
    diffs = []
    for r in runs:
        fa, fb = a / r.output, b / r.output
        if not (manifest.finished(a, r) and manifest.finished(b, r)):
            diffs.append(f"{r.id}: stats missing in {fa if not manifest.finished(a, r) else fb}")
            continue
        ja, jb = (strip(json.loads(f.read_text()), host) for f in (fa, fb))
        if ja != jb:
            keys = list(differences(ja, jb))
            diffs.append(f"{r.id}: stats differ ({fa} against {fb}) in {len(keys)} keys: " + "; ".join(keys[:3]))
    rows = []
    for d in (a, b):
        with open(d / "results.csv") as f:
            rows.append([{k: v for k, v in row.items() if k not in WALL_CLOCK_COLUMNS} for row in csv.DictReader(f)])
    if rows[0] != rows[1]:
        diffs.append("results.csv differ beyond the wall-clock columns")
    for d in diffs:
        print("same_results:", d, file=sys.stderr)
    print(f"same_results: {len(runs)} runs, {len(diffs)} differences", file=sys.stderr)
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
