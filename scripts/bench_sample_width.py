#!/usr/bin/env python3
"""--sample-width W against the full run on a grid of scenes, frame sizes, presets, widths and
sample seeds (docs/sampling.md, "A sample of a given width"): per run the pilot's half-width and
floor, the rate chosen, the half-width predicted for it and the one delivered, whether it reached
W, the estimate's error against the full run of the same fidelity, whether its interval holds the
full run, and its speed-up over the full run (time_s.run of each: the pilot's child run included);
or the refusal (before any pilot, after the first or the second). Then the summary: runs, refusals, reached, delivered / predicted, coverage, mean
|error|, speed-up. Resumable (a run with stats is not redone; use a new OUTDIR for a new rtsim).
Usage: scripts/bench_sample_width.py RTSIM OUTDIR SCENES   (SCENES: comma-separated, as
scripts/bench_sampling_grid.py takes them)
Environment: SIZES (512), PRESETS (mobile), WIDTHS (15,20,25: percent), SEEDS (3), FIRST_SEED (1),
FID (interval), WORKLOADS (pt), SHARED, JOBS (2)."""
import concurrent.futures as cf
import itertools
import json
import os
import re
import statistics
import sys

from bench_util import cell_name as cell, grid_env, run_stats, scene_args

rtsim, out, scenes = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
SC = scene_args()
sizes, presets, seeds, fid, workloads = grid_env("512", "mobile", "3", "interval")
widths = os.environ.get("WIDTHS", "15,20,25").split(",")
os.makedirs(out, exist_ok=True)

jobs = []
cells = list(itertools.product(scenes, workloads, sizes, presets))
for sc, wl, n, pre in cells:
    base = f"{SC[sc]} --workload {wl} --width {n} --height {n} --config {pre} --fidelity {fid} --threads 1"
    jobs.append((f"{cell(sc, wl)}_{n}_{pre}_full", base))
    for w, s in itertools.product(widths, seeds):
        jobs.append((f"{cell(sc, wl)}_{n}_{pre}_w{w}_{s}", base + f" --sample-width {w} --sample-seed {s}"))


def run(key, args):
    rc, err = run_stats(rtsim, f"{out}/{key}.json", args)
    if rc:  # a refusal is a result: its message is kept
        with open(f"{out}/{key}.refused", "w") as f:
            f.write(err)
    return key, rc, err


with cf.ThreadPoolExecutor(int(os.environ.get("JOBS", "2"))) as ex:
    list(ex.map(lambda j: run(*j), [j for j in jobs if not os.path.exists(f"{out}/{j[0]}.refused")]))

pct = lambda x: f"{100 * x:.1f}"
rows, refusals = [], []
print("| run | pilot: rate, h, floor | rate chosen | predicted h | delivered h | reached | error | holds | speed-up |")
print("|---|---|---|---|---|---|---|---|---|")
for sc, wl, n, pre in cells:
    name = f"{cell(sc, wl)}_{n}_{pre}"
    try:
        full = json.load(open(f"{out}/{name}_full.json"))
    except (OSError, ValueError):
        continue
    for w, s in itertools.product(widths, seeds):
        key = f"{name}_w{w}_{s}"
        if os.path.exists(f"{out}/{key}.refused"):
            msg = open(f"{out}/{key}.refused").read()
            floor = re.search(r"of which \+-([0-9.]+) % no (?:larger )?rate", msg)
            # Refused before any pilot (the bias bound), after the first (not even a model term
            # falling with the strata would reach W), after the second (its floor reaches W),
            # where the sampling term would need the whole frame or a sample of more than half of
            # it, or where the frame cannot be sampled at all (rtsim's other refusals).
            kind = ("bias bound" if "no rate narrows: ask" in msg else "first pilot" if "even were the model" in msg
                    else "whole frame" if "would need every one" in msg else "over half the frame" if "more than 50 %" in msg
                    else "second pilot" if floor else "not sampled")
            refusals.append((key, float(w) / 100, kind, float(floor.group(1)) / 100 if floor else None))
            print(f"| {key} | refused ({kind}{', floor ' + floor.group(1) + ' %' if floor else ''}) | | | | | | | |")
            continue
        try:
            d = json.load(open(f"{out}/{key}.json"))
        except (OSError, ValueError):
            continue
        sm = d["timing"]["sampling"]
        wd = sm["width"]
        est, truth = d["cycles"], full["cycles"]
        ci = sm["cycles_ci95"]
        r = {"key": key, "asked": wd["asked"], "predicted": wd["predicted"], "delivered": wd["delivered"], "reached": wd["reached"],
             "error": est / truth - 1, "holds": ci is not None and ci[0] <= truth <= ci[1],
             "speedup": full["time_s"]["run"] / d["time_s"]["run"], "rate": sm["rate"], "larger": sm["rate"] != wd["pilot_rate"]}
        rows.append(r)
        print(f"| {key} | {pct(wd['pilot_rate'])} %, {pct(wd['pilot_half_width'])} %, {pct(wd['floor'])} % | {pct(sm['rate'])} % | "
              f"{pct(wd['predicted'])} % | {pct(wd['delivered'])} % | {'yes' if wd['reached'] else 'no'} | {100 * r['error']:+.1f} % | "
              f"{'yes' if r['holds'] else 'NO'} | {r['speedup']:.2f}x |")
print()
if rows:
    ratio = sorted(r["delivered"] / r["predicted"] for r in rows)
    print(f"{len(rows) + len(refusals)} runs: {len(refusals)} refused" + ("" if not refusals else " (" + ", ".join(f"{k} {n}" for k in ("bias bound", "first pilot", "second pilot", "whole frame", "over half the frame", "not sampled")
                    for n in [sum(1 for x in refusals if x[2] == k)] if n) + ")") + f", {len(rows)} ran; "
          f"{sum(r['reached'] for r in rows)} of {len(rows)} reached the width asked; delivered / predicted median {statistics.median(ratio):.2f} "
          f"(range {ratio[0]:.2f}-{ratio[-1]:.2f}); {sum(r['holds'] for r in rows)} of {len(rows)} intervals hold the full run; "
          f"mean |error| {pct(statistics.mean(abs(r['error']) for r in rows))} %, worst {pct(max(abs(r['error']) for r in rows))} %; "
          f"speed-up over the full run median {statistics.median(r['speedup'] for r in rows):.2f}x "
          f"(range {min(r['speedup'] for r in rows):.2f}-{max(r['speedup'] for r in rows):.2f}x).")
    larger = [r for r in rows if r["larger"]]
    if larger:
        lr = sorted(r["delivered"] / r["predicted"] for r in larger)
        print(f"Where the pilot was not the run ({len(larger)} runs: a larger sample than the last pilot), {sum(r['reached'] for r in larger)} "
              f"reached the width asked; delivered / predicted median {statistics.median(lr):.2f} (" + ", ".join(f"{x:.2f}" for x in lr) + ").")
elif refusals:
    print(f"{len(refusals)} runs, every one refused.")
json.dump({"ran": rows, "refused": refusals,
           "grid": {"scenes": scenes, "sizes": sizes, "presets": presets, "widths": widths, "seeds": list(seeds), "fidelity": fid,
                    "workloads": workloads}}, open(f"{out}/summary.json", "w"), indent=1)
