#!/usr/bin/env python3
"""How much of a fast fidelity's error is bias and how much is noise. AT, LT (default quantum) and
interval run on each case five times, with the L2 hit latency of the preset changed by -2, -1, 0,
+1 and +2 core cycles (a change far below any model's uncertainty about the hardware). Writes per
run OUTDIR/KEY.json (resumable), then OUTDIR/table.md:
  - AT's own spread: how far the perturbed AT runs are from the unperturbed one. Where a 1-cycle
    change moves AT by several per cent, the frame's cycle count is chaotic at that size (which
    warp goes to which SM, and when the last one ends, flips), and no single-run comparison
    against AT can resolve an error below that spread;
  - per fast fidelity: its error against AT at each perturbation, their mean (the bias: an error
    that stays whatever the perturbation) and their spread (the noise).
Usage: scripts/bench_sensitivity.py RTSIM OUTDIR
Environment: CASES (scene:workload:size:config[+prefetcher],...; default: the cases of the error
grid where LT or interval erred most, and two where they did not), JOBS (1), SHARED
(../shared/scenes beside the repository), COMMIT (the commit RTSIM was built from; default HEAD)."""
import concurrent.futures as cf
import json
import os
import statistics
import subprocess
import sys

from bench_util import config_args, run_stats, scene_args

rtsim, out = sys.argv[1], sys.argv[2]
SC = scene_args()
DEFAULT = ("sprng:primary:128:desktop,bunny:primary:256:desktop,ship:primary:64:desktop,party:primary:64:mobile,"
           "bath:primary:128:paper,mesh:primary:128:mobile,party:primary:64:paper+ttp,sprng:pt:128:paper+ttp,"
           "ship:primary:256:mobile,bath:pt:128:mobile")
cases = [tuple(c.split(":")) for c in os.environ.get("CASES", DEFAULT).split(",")]
DELTAS = [-2, -1, 0, 1, 2]
FIDS = ["at", "lt", "interval"]
os.makedirs(out, exist_ok=True)
REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def l2_latency(cfg):
    """The preset's L2 hit latency (platforms/configs/NAME.json)."""
    return json.load(open(os.path.join(REPO, "platforms", "configs", cfg.partition("+")[0] + ".json")))["l2"]["latency"]


def key(c, d, fid):
    return f"{c[0]}_{c[1]}_{c[2]}_{c[3]}_l2{d:+d}_{fid}"


def run(k, args):
    return (k,) + run_stats(rtsim, f"{out}/{k}.json", args)


jobs = []
for c in cases:
    base = f"{SC[c[0]]} --workload {c[1]} --width {c[2]} --height {c[2]} {config_args(c[3])}"
    for d in DELTAS:
        for fid in FIDS:
            jobs.append((key(c, d, fid), f"{base} --set l2.latency={l2_latency(c[3]) + d} --fidelity {fid}"))
fails = {}
with cf.ThreadPoolExecutor(int(os.environ.get("JOBS", "1"))) as ex:
    for i, (k, rc, err) in enumerate(ex.map(lambda j: run(*j), jobs), 1):
        if rc:
            fails[k] = (rc, err)
        if i % 15 == 0:
            print(f"{i}/{len(jobs)} runs", file=sys.stderr, flush=True)


def cycles(c, d, fid):
    f = f"{out}/{key(c, d, fid)}.json"
    return json.load(open(f))["cycles"] if os.path.exists(f) else None


def pct(x):
    return f"{x:+.1f} %"


commit = os.environ.get("COMMIT") or subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                                                    capture_output=True, text=True).stdout.strip()
lines = [
    f"Cases as `scene:workload:frame:config`; each run five times with `l2.latency` of the preset "
    f"{', '.join(f'{d:+d}' for d in DELTAS)} core cycles; rtsim at {commit}. "
    "AT's spread: the perturbed AT runs against the unperturbed one (min to max). "
    "Per fast fidelity: its error against AT at the same perturbation, as mean (bias) +- standard "
    "deviation (noise), and the unperturbed run's error (the one the error grid measures).", "",
    "| case | AT cycles | AT's spread | LT bias +- noise | LT at +0 | interval bias +- noise | interval at +0 |",
    "|---|---|---|---|---|---|---|"]
summary = {"at_spread": [], "lt": [], "interval": []}
for c in cases:
    at = {d: cycles(c, d, "at") for d in DELTAS}
    if any(v is None for v in at.values()):
        continue
    spread = [at[d] / at[0] - 1 for d in DELTAS if d != 0]
    summary["at_spread"].append(max(abs(s) for s in spread))
    cells = [":".join(c), f"{at[0]:,}", f"{100 * min(spread):+.1f} .. {100 * max(spread):+.1f} %"]
    for fid in ("lt", "interval"):
        got = {d: cycles(c, d, fid) for d in DELTAS}
        err = [got[d] / at[d] - 1 for d in DELTAS if got[d]]
        if len(err) < len(DELTAS):
            cells += ["-", "-"]
            continue
        mean, sd = statistics.mean(err), statistics.stdev(err)
        summary[fid].append((mean, sd, err[DELTAS.index(0)]))
        cells += [f"{100 * mean:+.1f} +- {100 * sd:.1f} %", pct(100 * err[DELTAS.index(0)])]
    lines.append("| " + " | ".join(cells) + " |")
lines.append("")
n = len(summary["at_spread"])
if n:
    chaotic = sum(1 for s in summary["at_spread"] if s > 0.01)
    lines.append(f"In {chaotic} of {n} cases a change of 1 or 2 cycles in the L2 latency moved AT by more than 1 % "
                 f"(up to {100 * max(summary['at_spread']):.1f} %).")
    for fid in ("lt", "interval"):
        s = summary[fid]
        if not s:
            continue
        biased = [m for m, sd, _ in s if abs(m) > 2 * sd / len(DELTAS) ** 0.5 and abs(m) > 0.01]
        noise = statistics.mean(sd for _, sd, _ in s)
        largest = f", the largest {100 * max(map(abs, biased)):.1f} %" if biased else ""
        lines.append(f"{fid}: a bias beyond 1 % and beyond twice its standard error in {len(biased)} of {len(s)} cases{largest} "
                     f"(the largest bias of all {100 * max(abs(m) for m, _, _ in s):.1f} %); mean noise {100 * noise:.1f} %.")
if fails:
    lines += ["", f"{len(fails)} runs failed: " + ", ".join(sorted(fails))]
open(f"{out}/table.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
sys.exit(1 if fails else 0)
