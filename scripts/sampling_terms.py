#!/usr/bin/env python3
"""Where a sampled run's interval comes from (docs/sampling.md, "The interval"): per sampled run of
one or more folders of scripts/bench_sampling_grid.py, its error against the full run of the same
cell and the five terms of its 95 % half-width h, each as rtsim computed it:
  se  the work's sampling error times Student's t (what is left of h^2 by the other four),
  m   the schedule model's error, 1.96 x sqrt(2) x the root mean square of the per-SM misfits,
  g   the extrapolation gap (1.96 x it), f the first reads' gap, b the design's bias bound;
and, for the model term, the per-SM misfits' mean (a part common to every SM) and their standard
deviation. Then each term's mean share of h^2, the median h and the mean absolute error; and,
over the cells sampled at more than one rate (folder, scene, frame, preset), how each term moves
with the rate: the median over cells of its median at the highest rate / at the lowest.
Usage: scripts/sampling_terms.py DIR...   (prints Markdown)"""
import json
import math
import os
import statistics
import sys

from bench_util import sampling_grid_runs


def runs(folder):
    """(name, error, terms) of every sampled run in `folder` whose cell has a full run."""
    for path, full_path, (cell, size, preset, rate) in sampling_grid_runs(folder):
        name = os.path.basename(path)[:-5]
        run = json.load(open(path))
        s = run["timing"].get("sampling")
        if not s or "cycles_ci95" not in s:
            continue  # no interval (refused, or sampled without one)
        est = run["cycles"]
        h = (s["cycles_ci95"][1] - est) / est  # the high side: the low one may be cut
        per_sm = s["schedule_model_misfit_per_sm"]
        rms = math.sqrt(sum(x * x for x in per_sm) / len(per_sm)) if per_sm else s["schedule_model_misfit"]
        t = {"m": 1.96 * math.sqrt(2) * rms,
             "g": 1.96 * abs(s["work_estimate_residence_cycles"] / s["work_estimate_stratified_residence_cycles"] - 1),
             "f": s["first_reads"]["gap"], "b": s["design_bias"]}
        t["se"] = math.sqrt(max(0.0, h * h - sum(v * v for v in t.values())))
        t["h"] = h
        t["misfit_mean"] = statistics.mean(per_sm) if per_sm else 0.0
        t["misfit_sd"] = statistics.pstdev(per_sm) if len(per_sm) > 1 else 0.0
        # The same interval with the per-SM misfits' spread in place of their root mean square
        # (the part common to every SM taken as cancelled by the ratio of the two models), and
        # whether each holds the full run (the low end never below the cycles simulated).
        full = json.load(open(full_path))["cycles"]
        t["h_spread"] = math.sqrt(max(0.0, h * h - t["m"] ** 2 + (1.96 * math.sqrt(2) * t["misfit_sd"]) ** 2))
        t["holds"] = max(est * (1 - h), s["cycles_simulated"]) <= full <= est * (1 + h)
        t["holds_spread"] = max(est * (1 - t["h_spread"]), s["cycles_simulated"]) <= full <= est * (1 + t["h_spread"])
        t["cell"], t["rate"] = (folder, cell, size, preset), float(rate)
        yield name, est / full - 1, t


def main():
    rows = [r for folder in sys.argv[1:] for r in runs(folder)]
    if not rows:
        sys.exit("sampling_terms.py: no sampled run with an interval and a full run in " + " ".join(sys.argv[1:]))
    pct = lambda x: f"{100 * x:.1f}"
    print("| run | error % | h % | se % | m % | misfit mean / sd | g % | f % | b % |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, err, t in rows:
        print(f"| {name} | {100 * err:+.1f} | {pct(t['h'])} | {pct(t['se'])} | {pct(t['m'])} | "
              f"{t['misfit_mean']:+.3f} / {t['misfit_sd']:.3f} | {pct(t['g'])} | {pct(t['f'])} | {pct(t['b'])} |")
    shares = {k: statistics.mean(t[k] ** 2 / t["h"] ** 2 for _, _, t in rows) for k in ("se", "m", "g", "f", "b")}
    common = sum(abs(t["misfit_mean"]) > t["misfit_sd"] for _, _, t in rows)
    print()
    print(f"{len(rows)} runs: median h {pct(statistics.median(t['h'] for _, _, t in rows))} %, mean |error| "
          f"{pct(statistics.mean(abs(e) for _, e, _ in rows))} %, worst {pct(max(abs(e) for _, e, _ in rows))} %; "
          "mean share of h^2: " + ", ".join(f"{k} {100 * v:.0f} %" for k, v in shares.items()) +
          f"; the per-SM misfits' mean exceeds their spread in {common} of {len(rows)} runs.")
    print(f"With the per-SM misfits' spread in place of their root mean square, the median h would be "
          f"{pct(statistics.median(t['h_spread'] for _, _, t in rows))} % and hold the full run in "
          f"{sum(t['holds_spread'] for _, _, t in rows)} of {len(rows)} runs (as rtsim states it: {sum(t['holds'] for _, _, t in rows)}).")
    # How the terms move with the rate, cell by cell (the same frames sampled at several rates).
    by_cell = {}
    for _, _, t in rows:
        by_cell.setdefault(t["cell"], {}).setdefault(t["rate"], []).append(t)
    moves = {k: [] for k in ("se", "m", "h")}
    for rates in by_cell.values():
        if len(rates) < 2:
            continue
        lo, hi = rates[min(rates)], rates[max(rates)]
        for k in moves:
            a = statistics.median(t[k] for t in lo)
            if a > 0:
                moves[k].append(statistics.median(t[k] for t in hi) / a)
    if moves["h"]:
        print()
        print(f"Over {len(moves['h'])} cells sampled at two rates or more, from the lowest rate to the highest the median cell's "
              + ", ".join(f"{k} is {statistics.median(v):.2f} times" for k, v in moves.items())
              + f" what it was (m grew in {sum(v > 1 for v in moves['m'])} of them).")


if __name__ == "__main__":
    main()
