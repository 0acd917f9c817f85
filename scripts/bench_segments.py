#!/usr/bin/env python3
"""What splitting a sample into segments costs in accuracy (docs/sampling.md, "Segments"). Per case
and sample seed, the continuous sampled run (--sample RATE) and the same sample split into K
independent segments (--sample-segments K, each segment from cold caches warmed with the fetches
before it), all against the full run of the same fidelity. Writes per run OUTDIR/KEY.json
(resumable), then OUTDIR/table.md: per K, the mean and worst error against the full run, how
often the 95 % interval covers it, the median half-width, and how far the split estimate is from
the continuous one of the same draw.
Usage: scripts/bench_segments.py RTSIM OUTDIR
Environment: CASES (scene:workload:size:config[+prefetcher],...; default four scenes, path
tracing 256x256 mobile), RATE (0.25), SEEDS (1,2), SEGMENTS (2,4,8), FIDELITY (at), JOBS (1),
SHARED (../shared/scenes beside the repository)."""
import concurrent.futures as cf
import json
import os
import statistics
import sys

from bench_util import config_args, run_stats, scene_args

rtsim, out = sys.argv[1], sys.argv[2]
SC = scene_args()
cases = [tuple(c.split(":")) for c in os.environ.get("CASES", "wknd:pt:256:mobile,bunny:pt:256:mobile,ship:pt:256:mobile,"
                                                               "sprng:pt:256:mobile").split(",")]
rate = os.environ.get("RATE", "0.25")
seeds = [int(s) for s in os.environ.get("SEEDS", "1,2").split(",")]
ks = [int(k) for k in os.environ.get("SEGMENTS", "2,4,8").split(",")]
fid = os.environ.get("FIDELITY", "at")
os.makedirs(out, exist_ok=True)


def base(c):
    return f"{SC[c[0]]} --workload {c[1]} --width {c[2]} --height {c[2]} {config_args(c[3])} --fidelity {fid} --threads 1"


def name(c, seed=None, k=None):
    n = "_".join(c) + f"_{fid}"
    if seed is None:
        return n + "_full"
    return n + f"_r{rate}_s{seed}" + (f"_k{k}" if k else "")


jobs = []
for c in cases:
    jobs.append((name(c), base(c)))
    for seed in seeds:
        sample = f"{base(c)} --sample {rate} --sample-seed {seed}"
        jobs.append((name(c, seed), sample))
        for k in ks:
            jobs.append((name(c, seed, k), f"{sample} --sample-segments {k}"))
fails = {}
with cf.ThreadPoolExecutor(int(os.environ.get("JOBS", "1"))) as ex:
    for n, (rc, err) in zip([j[0] for j in jobs], ex.map(lambda j: run_stats(rtsim, f"{out}/{j[0]}.json", j[1]), jobs)):
        if rc:
            fails[n] = (rc, err)
for n, (rc, err) in fails.items():
    print(f"{n}: exit {rc}: {err}", file=sys.stderr)


def load(n):
    p = f"{out}/{n}.json"
    return json.load(open(p)) if os.path.exists(p) else None


rows = {}
for c in cases:
    full = load(name(c))
    if not full:
        continue
    truth = full["cycles"]
    for seed in seeds:
        cont = load(name(c, seed))
        for k in [0] + ks:
            j = load(name(c, seed, k)) if k else cont
            if not j:
                continue
            s = j["timing"]["sampling"]
            ci = s["cycles_ci95"]
            r = rows.setdefault(k, [])
            r.append({"case": name(c, seed, k), "err": j["cycles"] / truth - 1,
                      "covered": ci is not None and ci[0] <= truth <= ci[1],
                      "half": (ci[1] - ci[0]) / 2 / j["cycles"] if ci else None,
                      "vs_cont": j["cycles"] / cont["cycles"] - 1 if cont and k else 0.0})
lines = [f"# Split samples against the continuous sample and the full run\n",
         f"`scripts/bench_segments.py` ({fid}, --sample {rate}, sample seeds {','.join(map(str, seeds))}; cases: "
         + ", ".join(":".join(c) for c in cases) + "). K 1 is the continuous sample.\n",
         "| segments | runs | mean / worst error vs full | covered | median half-width | mean / worst distance from the continuous estimate |",
         "|---|---|---|---|---|---|"]
for k in [0] + ks:
    r = rows.get(k, [])
    if not r:
        continue
    errs = [abs(x["err"]) for x in r]
    halves = [x["half"] for x in r if x["half"] is not None]
    dist = [abs(x["vs_cont"]) for x in r]
    lines.append(f"| {k or 1} | {len(r)} | {100 * statistics.mean(errs):.1f} % / {100 * max(errs):.1f} % | "
                 f"{sum(x['covered'] for x in r)} of {len(r)} | {100 * statistics.median(halves) if halves else float('nan'):.1f} % | "
                 + (f"{100 * statistics.mean(dist):.1f} % / {100 * max(dist):.1f} % |" if k else "- |"))
lines.append("\nPer run (error against the full run, interval half-width):\n")
for k in [0] + ks:
    for x in rows.get(k, []):
        lines.append(f"- {x['case']}: {100 * x['err']:+.1f} %" + (f", +-{100 * x['half']:.1f} %" if x["half"] is not None else ", no interval")
                     + ("" if x["covered"] else " (missed)"))
open(f"{out}/table.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines[:4 + len(ks) + 1]))
sys.exit(1 if fails else 0)
