#!/usr/bin/env python3
"""The sample design's bias, measured: over sampled runs against the full run of the same frame
(the output folders of scripts/bench_sampling_grid.py and of scripts/speed_error.sh), per cell
(scene, workload, frame, preset, fidelity, rate) the mean error of its draws; a cell whose mean
lies beyond Student's 95 % quantile times its standard error carries a bias that no draw's
interval sees (docs/sampling.md, "The sample design's bias"). Per workload kind (primary rays,
and every other workload), the largest such mean is the bias bound that rtsim adds to each
sampled interval of that kind, in quadrature (platforms/configs/sampling_bias.json, compiled in).
Usage: scripts/sampling_bias.py OUT.json DIR...   (COMMIT: the rtsim the runs were made with;
default the repository's HEAD). DIR=FOLDER:SCENE,SCENE takes only those scenes of the folder (a
speed_error folder of an older rtsim whose other scenes' statistics have changed since). Prints
every cell with a bias, largest first."""
import datetime, glob, json, os, re, statistics, subprocess, sys

from bench_util import sampling_grid_runs

# Student's t, two-sided 95 %, by degrees of freedom (draws - 1); beyond 10: 2.2 (conservative to 30).
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228}


def frame_of(d):
    """A speed_error folder's frame size, from its manifest's --width."""
    with open(f"{d}/manifest.tsv") as f:
        m = re.search(r"--width (\d+)", f.read())
    return m.group(1) if m else "?"


def split(arg):
    """DIR or DIR:SCENE,SCENE -> (folder, scenes taken or None for all)."""
    d, _, only = arg.partition(":")
    return d, (set(only.split(",")) if only else None)


def runs_of(d, only=None):
    """(cell, error) per sampled run with a stored full run of its frame (of the scenes `only`, if given)."""
    def cycles(path):
        try:
            with open(path) as f:
                return json.load(f)["cycles"]
        except (OSError, ValueError, KeyError):
            return None
    out = []
    if os.path.exists(f"{d}/manifest.tsv"):  # scripts/speed_error.sh: at_s25_seed3_base/ship.json against at_base/ship.json
        size = frame_of(d)
        for f in glob.glob(f"{d}/*_s*_*/*.json"):
            m = re.match(r"(at|iv)_s(\d+)(?:_seed\d+)?_(base|ttp)$", os.path.basename(os.path.dirname(f)))
            if not m:
                continue
            fid, pct, pf = m.groups()
            full = f"{d}/{'at' if fid == 'at' else 'interval'}_{pf}/{os.path.basename(f)}"
            est, truth = cycles(f), cycles(full)
            scene = os.path.basename(f)[:-5]
            if est and truth and (only is None or scene in only):
                out.append(((scene, "pt", size, "mobile" + ("+ttp" if pf == "ttp" else ""), "at" if fid == "at" else "interval",
                             f"{int(pct) / 100:g}"), est / truth - 1))
        return out
    with open(f"{d}/summary.json") as f:  # scripts/bench_sampling_grid.py
        fid = json.load(f)["grid"]["fidelity"]
    for f, full, (name, size, preset, rate) in sampling_grid_runs(d):
        scene, _, wl = name.partition("-")
        est, truth = cycles(f), cycles(full)
        if est and truth and (only is None or scene in only):
            out.append(((scene, wl or "pt", size, preset, fid, f"{float(rate):g}"), est / truth - 1))
    return out


def grid_of(d, only=None):
    """What a folder holds: bench_sampling_grid's grid, or speed_error's sampled runs."""
    if os.path.exists(f"{d}/manifest.tsv"):
        scenes = sorted(scenes_all(d) & only if only else scenes_all(d))
        n = frame_of(d)
        return f"scripts/speed_error.sh: path tracing {n}x{n}, mobile, {','.join(scenes)}, AT and interval, 10/25/50 %"
    with open(f"{d}/summary.json") as f:
        g = json.load(f)["grid"]
    scenes = [s for s in g["scenes"] if only is None or s in only]
    return (f"scripts/bench_sampling_grid.py: {g['fidelity']}, {','.join(g['workloads'])}, {','.join(map(str, g['sizes']))}, "
            f"{','.join(g['presets'])}, {','.join(scenes)}, rates {','.join(g['rates'])}, {g['seeds']} seeds")


def scenes_all(d):
    """The scenes of a speed_error folder's sampled runs."""
    return {os.path.basename(f)[:-5] for f in glob.glob(f"{d}/*_s*_*/*.json")}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    cells = {}
    for arg in sys.argv[2:]:
        for cell, e in runs_of(*split(arg)):
            cells.setdefault(cell, []).append(e)
    biased = []
    for cell, errs in cells.items():
        if len(errs) < 3:
            continue
        m, se = statistics.mean(errs), statistics.stdev(errs) / len(errs) ** 0.5
        if abs(m) > T95.get(len(errs) - 1, 2.2) * se:
            biased.append((abs(m), m, se, len(errs), cell))
    biased.sort(reverse=True)
    kind = lambda wl: "primary" if wl == "primary" else "other"
    bias = {}
    for k in ("primary", "other"):
        mine = [b for b in biased if kind(b[4][1]) == k]
        tested = [c for c in cells if kind(c[1]) == k and len(cells[c]) >= 3]
        if not tested:
            continue
        top = mine[0] if mine else None
        bias[k] = {"value": top[0] if top else 0.0,
                   "cell": " ".join(top[4]) if top else None,
                   "cells": len(tested), "runs": sum(len(cells[c]) for c in tested), "biased_cells": len(mine)}
    commit = os.environ.get("COMMIT") or subprocess.run("git rev-parse --short HEAD", shell=True, capture_output=True, text=True,
                                                        cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
    doc = {"measured_on": commit, "date": datetime.date.today().isoformat(),
           "command": "scripts/sampling_bias.py OUT DIR...",
           "grids": [grid_of(*split(arg)) for arg in sys.argv[2:]],
           "rule": "per workload kind, the largest |mean error of a cell's draws| among the cells (3 draws or more) whose mean lies "
                   "beyond Student's 95 % quantile times its standard error; cell: scene workload frame preset fidelity rate",
           "bias": bias}
    with open(sys.argv[1] + ".tmp", "w") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    os.replace(sys.argv[1] + ".tmp", sys.argv[1])
    print(f"{len(cells)} cells, {sum(len(v) for v in cells.values())} runs; cells with a bias beyond their noise:")
    for a, m, se, n, cell in biased:
        print(f"  {' '.join(cell):45s} {100 * m:+.2f} % (standard error {100 * se:.2f} %, {n} draws)")
    for k, b in bias.items():
        print(f"bias bound, {k}: {100 * b['value']:.2f} % ({b['cell']}; {b['biased_cells']} of {b['cells']} cells biased)")


if __name__ == "__main__":
    main()
