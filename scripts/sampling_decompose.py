#!/usr/bin/env python3
"""Where a sampled run's error comes from: the frame's work, or the cycles per unit of it.
A sampled run estimates the frame's cycles as its simulated cycles x model(frame) / model(sample)
(docs/sampling.md, "The schedule estimator"); its work estimate W^ is the frame model's durations
summed. Against the frame, the error splits into two factors,

    estimate / full cycles = (W^ / W) x (estimate / W^) / (full cycles / W)

  work: W^ / W - 1, how far the sample's cost per critical-path node, carried to the frame, is
        from the frame's own (what runs beside a sampled trace, the warming, the draw);
  rate: the rest, how far the sample's cycles per unit of work (the schedule model's carry of
        occupancy, ramps and tails) are from the frame's.
W, the frame's work, comes from a 99 % sample of the same frame (its fit is taken on the traces of
all but one to three clusters, and a least-squares fit sums to the residences it is fitted on), run
once per cell with the full run's command line and written beside it as CELL_near99.json.
Per cell (scene, frame, preset, rate) the draws' mean error, mean work part and mean rate part;
then, over every run, the mean |error| and the mean |part| of each.
Usage: scripts/sampling_decompose.py RTSIM DIR...   (DIR: folders of bench_sampling_grid.py;
prints Markdown)"""
import functools
import json
import os
import statistics
import subprocess
import sys

from bench_util import sampling_grid_runs


@functools.lru_cache(maxsize=None)
def near_full(rtsim, full_path):
    """The 99 % sample's work of a full run's frame (run once, kept beside it; read once per cell)."""
    path = full_path[:-len("_full.json")] + "_near99.json"
    if not os.path.exists(path):
        argv = json.load(open(full_path))["provenance"]["command_line"]
        args, skip = [], False
        for a in argv[1:]:
            if skip:
                skip = False
            elif a == "--stats":
                skip = True
            else:
                args.append(a)
        subprocess.run([rtsim] + args + ["--sample", "0.99", "--threads", "1", "--stats", path + ".tmp"], check=True,
                       stdout=subprocess.DEVNULL)
        os.replace(path + ".tmp", path)
    return json.load(open(path))["timing"]["sampling"]["work_estimate_residence_cycles"]


@functools.lru_cache(maxsize=None)
def full_cycles(full_path):
    return json.load(open(full_path))["cycles"]


def main():
    rtsim, folders = sys.argv[1], sys.argv[2:]
    cells = {}
    for folder in folders:
        for path, full_path, (name, size, preset, rate) in sampling_grid_runs(folder):
            run = json.load(open(path))
            s = run["timing"].get("sampling")
            if not s:
                continue
            cycles = full_cycles(full_path)
            work = near_full(rtsim, full_path)
            total = run["cycles"] / cycles
            part = s["work_estimate_residence_cycles"] / work
            cells.setdefault((os.path.basename(folder), name, size, preset, rate), []).append((total - 1, part - 1, total / part - 1))
    print("| folder | cell | draws | error | work part | rate part |")
    print("|---|---|---|---|---|---|")
    everything = []
    for (folder, name, size, preset, rate), runs in sorted(cells.items()):
        everything += runs
        mean = [statistics.mean(r[i] for r in runs) for i in range(3)]
        print(f"| {folder} | {name} {size} {preset} {rate} | {len(runs)} | " + " | ".join(f"{100 * m:+.1f} %" for m in mean) + " |")
    if everything:
        mean_abs = [statistics.mean(abs(r[i]) for r in everything) for i in range(3)]
        print(f"\n{len(everything)} runs: mean |error| {100 * mean_abs[0]:.2f} %, mean |work part| {100 * mean_abs[1]:.2f} %, "
              f"mean |rate part| {100 * mean_abs[2]:.2f} %")


if __name__ == "__main__":
    main()
