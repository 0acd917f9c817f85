#!/usr/bin/env python3
"""Sampled AT against full AT on a grid of scenes, frame sizes, presets, rates and sample seeds:
per cell the error of each draw, whether its 95 % interval covers the full run (! where it does
not) and its half-width; then coverage, misses of intervals narrower than +-10 %, refusals and
errors. Resumable (a run with stats is not redone; use a new OUTDIR for a new rtsim).
Usage: scripts/bench_sampling_grid.py RTSIM OUTDIR [SCENES]   (SCENES: comma-separated, from
mesh, bunny, cornell, sprng, ship; default mesh,bunny,cornell)
Environment: SIZES (default 64,128), PRESETS (mobile,desktop), RATES (0.1,0.25), SEEDS (4),
FID (at), WORKLOADS (pt; also primary, ao, sh), FIRST_SEED (1: the sample seeds are FIRST_SEED,
FIRST_SEED + 1, ...), SHARED (../shared/scenes beside the repository),
JOBS (runs at a time, 2).
The grids of docs/sampling.md:
  SIZES=128,256 RATES=0.25,0.5 scripts/bench_sampling_grid.py build/rtsim out/grid
  SIZES=256 RATES=0.1,0.25 PRESETS=mobile,paper scripts/bench_sampling_grid.py build/rtsim out/heldout ship,sprng"""
import json, os, sys, itertools, concurrent.futures as cf
from bench_util import cell_name as cell, grid_env, run_stats, scene_args
rtsim, out = sys.argv[1], sys.argv[2]
SC = scene_args()
scenes = sys.argv[3].split(",") if len(sys.argv) > 3 else ["mesh", "bunny", "cornell"]
sizes, presets, seeds, fid, workloads = grid_env("64,128", "mobile,desktop", "4", "at")
rates = os.environ.get("RATES", "0.1,0.25").split(",")
os.makedirs(out, exist_ok=True)
def run(key, args):
    return (key,) + run_stats(rtsim, f"{out}/{key}.json", args)
jobs = []
for sc, wl, n, pre in itertools.product(scenes, workloads, sizes, presets):
    base = f"{SC[sc]} --workload {wl} --width {n} --height {n} --config {pre} --fidelity {fid}"
    jobs.append((f"{cell(sc, wl)}_{n}_{pre}_full", base))
    for r, s in itertools.product(rates, seeds):
        jobs.append((f"{cell(sc, wl)}_{n}_{pre}_{r}_{s}", base + f" --sample {r} --sample-seed {s} --threads 1"))
fails = {}
with cf.ThreadPoolExecutor(int(os.environ.get("JOBS", "2"))) as ex:
    for key, rc, err in ex.map(lambda j: run(*j), jobs):
        if rc: fails[key] = (rc, err)
# analyse
cov = n = narrow_miss = refused = 0; errs = []; halfwidths = []; misses = []
few = [0, 0]  # intervals over 10-29 drawn strata: runs, covered ("How many strata" in docs/sampling.md)
for sc, sz, pre in itertools.product([cell(sc, wl) for sc in scenes for wl in workloads], sizes, presets):
    try: truth = json.load(open(f"{out}/{sc}_{sz}_{pre}_full.json"))["cycles"]
    except Exception: continue
    for r in rates:
        line = []; sm = {}
        for s in seeds:
            k = f"{sc}_{sz}_{pre}_{r}_{s}"
            if k in fails: refused += 1; line.append("refused"); continue
            d = json.load(open(f"{out}/{k}.json")); est = d["cycles"]; sm = d["timing"]["sampling"]; ci = sm["cycles_ci95"]
            e = est / truth - 1; errs.append(abs(e))
            if ci is None: line.append(f"{100*e:+.1f}(noci)"); continue
            n += 1; c = ci[0] <= truth <= ci[1]; cov += c
            hw = (ci[1] - ci[0]) / 2 / est; halfwidths.append(hw)
            if sm.get("strata", 30) < 30: few[0] += 1; few[1] += c
            if not c:
                misses.append(f"{k}: {100*e:+.1f} % with +-{100*hw:.1f} %")
                if hw < 0.10: narrow_miss += 1
            line.append(f"{100*e:+.1f}{'' if c else '!'}±{100*hw:.0f}")
        print(f"{sc:13s} {sz:4d} {pre:8s} r={r:5s} strata={sm.get('strata', '?')} rate_sim={sm.get('rate_simulated', 0):.3f}  " + "  ".join(line))
errs.sort(); halfwidths.sort()
summary = {"runs_with_interval": n, "covered": cov, "narrow_misses": narrow_miss, "refused": refused,
           "estimates": len(errs), "mean_abs_error": sum(errs) / max(1, len(errs)), "worst_abs_error": max(errs or [0]),
           "median_halfwidth": halfwidths[len(halfwidths) // 2] if halfwidths else None,
           "runs_10_29_strata": few[0], "covered_10_29_strata": few[1], "misses": misses,
           "grid": {"scenes": scenes, "sizes": sizes, "presets": presets, "rates": rates, "seeds": len(seeds),
                    "fidelity": fid, "workloads": workloads}}
with open(f"{out}/summary.json", "w") as f:
    json.dump(summary, f, indent=1)
print(f"coverage {cov}/{n} intervals, narrow(<10%) misses {narrow_miss}, refused {refused}, mean|err| {100*sum(errs)/max(1,len(errs)):.2f}%, worst {100*max(errs or [0]):.1f}%"
      + (f", median half-width {100*summary['median_halfwidth']:.1f}%" if halfwidths else "")
      + f"; 10-29 strata: {few[1]}/{few[0]} covered")
for m in misses: print("miss", m)
for k, v in fails.items(): print("FAIL", k, v[0], v[1][:200])
