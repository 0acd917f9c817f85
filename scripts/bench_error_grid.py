#!/usr/bin/env python3
"""The fast fidelities (LT at its default quantum, interval) against AT, full frames, on a grid of
scenes, frame sizes, presets, prefetchers and workloads. Writes per run OUTDIR/KEY.json (resumable:
a run with stats is not redone; use a new OUTDIR for a new rtsim), then
  OUTDIR/table.md          error per cell and per fidelity x workload (mean, worst, runs);
  OUTDIR/error_bounds.json the validated bounds rtsim reports as error_estimate (copy it to
                           platforms/configs/error_bounds.json to make them the build's).
Usage: scripts/bench_error_grid.py RTSIM OUTDIR [SCENES]
  SCENES: comma-separated from mesh (the Stanford bunny as a bare mesh, automatic camera), bunny,
  ship, bath, sprng, party, cornell, wknd; default mesh,bunny,ship,bath,sprng,party.
Environment: PRIMARY_SIZES (64,128,256,512), PT_SIZES (64,128,256), CONFIGS (mobile,paper,
paper+ttp,desktop,mobile+ttp; NAME+PREFETCHER), SEED (1), JOBS (2), SHARED (../shared/scenes beside the
repository), ANALYSE_ONLY (1: no runs, tables from the runs already in OUTDIR), COMMIT (the
commit RTSIM was built from; default: the repository's HEAD), EXTEND (a bounds file, e.g.
platforms/configs/error_bounds.json: OUTDIR/error_bounds.json is then that file with this grid's
frame sizes added, each size's entry naming its own scenes and commit; the configurations must be
the file's, and a size it already has is refused), WIDEN (a bounds file of the whole grid, e.g.
platforms/configs/error_bounds.json: this grid reruns some of its configurations after a change
that leaves the others bit-identical; OUTDIR/error_bounds.json is then that file with each frame
size's worst raised to this grid's where larger, and its commit naming the rerun), FIDS (the fast
fidelities to run beside AT: lt,interval), REPLACE (a bounds file of the whole grid, e.g.
platforms/configs/error_bounds.json: this grid reruns every configuration, scene and frame size
of the FIDS fidelities after a change to them alone; OUTDIR/error_bounds.json is then that file
with those fidelities' bounds replaced by this grid's, each naming the commit it was measured on)."""
import concurrent.futures as cf
import datetime
import itertools
import json
import os
import subprocess
import sys

from bench_util import config_args, run_stats, scene_args

rtsim, out = sys.argv[1], sys.argv[2]
SC = scene_args()
scenes = sys.argv[3].split(",") if len(sys.argv) > 3 else ["mesh", "bunny", "ship", "bath", "sprng", "party"]
sizes = {"primary": [int(x) for x in os.environ.get("PRIMARY_SIZES", "64,128,256,512").split(",") if x],
         "pt": [int(x) for x in os.environ.get("PT_SIZES", "64,128,256").split(",") if x]}
configs = os.environ.get("CONFIGS", "mobile,paper,paper+ttp,desktop,mobile+ttp").split(",")
seed = int(os.environ.get("SEED", "1"))
fast = [f for f in os.environ.get("FIDS", "lt,interval").split(",") if f]
if not fast or not set(fast) <= {"lt", "interval"}:
    sys.exit(f"FIDS: comma-separated from lt and interval, not {os.environ['FIDS']!r}")
fids = ["at"] + fast
os.makedirs(out, exist_ok=True)


def run(key, args):
    return (key,) + run_stats(rtsim, f"{out}/{key}.json", args, skip=os.environ.get("ANALYSE_ONLY") == "1")


cases = []  # (scene, workload, size, config)
for wl in ("primary", "pt"):
    for sc, n, cfg in itertools.product(scenes, sizes[wl], configs):
        cases.append((sc, wl, n, cfg))
cases.sort(key=lambda c: c[2])  # small frames first: a partial grid already reads


def key(c, fid):
    return f"{c[0]}_{c[1]}_{c[2]}_{c[3]}_{fid}"


jobs = []
for c in cases:
    base = f"{SC[c[0]]} --workload {c[1]} --width {c[2]} --height {c[2]} --seed {seed} {config_args(c[3])}"
    for fid in fids:
        jobs.append((key(c, fid), base + f" --fidelity {fid}"))
fails = {}
done = 0
with cf.ThreadPoolExecutor(int(os.environ.get("JOBS", "2"))) as ex:
    for k, rc, err in ex.map(lambda j: run(*j), jobs):
        done += 1
        if rc:
            fails[k] = (rc, err)
        if done % 20 == 0:
            print(f"{done}/{len(jobs)} runs", file=sys.stderr, flush=True)

# Per case, each fast fidelity's error against AT and its wall-time speed-up.
rows = []
for c in cases:
    try:
        at = json.load(open(f"{out}/{key(c, 'at')}.json"))
    except OSError:
        continue
    for fid in ("lt", "interval"):
        try:
            d = json.load(open(f"{out}/{key(c, fid)}.json"))
        except OSError:
            continue
        rows.append({"scene": c[0], "workload": c[1], "size": c[2], "config": c[3], "fidelity": fid,
                     "at_cycles": at["cycles"], "cycles": d["cycles"], "error": d["cycles"] / at["cycles"] - 1})


def summary(sel):
    e = [abs(r["error"]) for r in sel]
    return {"runs": len(e), "mean": sum(e) / max(1, len(e)), "worst": max(e or [0.0])}


def extend(base, new):
    """`base` with `new`'s frame sizes added. Each added size's entry names the scenes and the commit
    it was measured on (rtsim states them in the bound's basis); the whole-grid summary of each
    fidelity and workload is recomputed from the sizes (runs summed, mean weighted by runs)."""
    if new["grid"]["configs"] != base["grid"]["configs"]:
        sys.exit(f"EXTEND: configurations {new['grid']['configs']} are not the file's {base['grid']['configs']}")
    for wl in ("primary", "pt"):
        both = set(base["grid"][f"{wl}_sizes"]) & set(new["grid"][f"{wl}_sizes"])
        if both:
            sys.exit(f"EXTEND: {wl} at {sorted(both)} is in the file already (measure other sizes, or a whole new grid)")
        base["grid"][f"{wl}_sizes"] = sorted(base["grid"][f"{wl}_sizes"] + new["grid"][f"{wl}_sizes"])
    base.setdefault("extended", []).append({k: new[k] for k in ("measured_on", "date", "command")} |
                                           {"scenes": new["grid"]["scenes"], "seed": new["grid"]["seed"],
                                            "primary_sizes": new["grid"]["primary_sizes"], "pt_sizes": new["grid"]["pt_sizes"]})
    for fid, wls in new["bounds"].items():
        for wl, b in wls.items():
            into = base["bounds"][fid][wl]
            for n, cell in b["by_size"].items():
                into["by_size"][n] = cell | {"scenes": new["grid"]["scenes"], "measured_on": new["measured_on"]}
            cells = list(into["by_size"].values())
            into["runs"] = sum(c["runs"] for c in cells)
            into["mean"] = sum(c["runs"] * c["mean"] for c in cells) / max(1, into["runs"])
            into["worst"] = max(c["worst"] for c in cells)
    return base


def widen(base, new):
    """`base` (the whole grid's bounds) with each frame size's worst raised to `new`'s where larger:
    `new` reruns some of the grid's configurations after a change that leaves the others
    bit-identical. The replaced runs stay in `base`'s worst, so a bound is at least each grid's
    worst (never below either); runs and means stay `base`'s."""
    if not set(new["grid"]["configs"]) <= set(base["grid"]["configs"]) or new["grid"]["scenes"] != base["grid"]["scenes"]:
        sys.exit(f"WIDEN: scenes {new['grid']['scenes']} and configurations {new['grid']['configs']} are not the file's")
    for wl in ("primary", "pt"):
        if new["grid"][f"{wl}_sizes"] != base["grid"][f"{wl}_sizes"]:
            sys.exit(f"WIDEN: {wl} at {new['grid'][f'{wl}_sizes']}, the file at {base['grid'][f'{wl}_sizes']}")
    for fid, wls in new["bounds"].items():
        for wl, b in wls.items():
            into = base["bounds"][fid][wl]
            for n, cell in b["by_size"].items():
                into["by_size"][n]["worst"] = max(into["by_size"][n]["worst"], cell["worst"])
            into["worst"] = max(c["worst"] for c in into["by_size"].values())
    base["measured_on"] += f"; {', '.join(new['grid']['configs'])} rerun at {new['measured_on']}, the larger worst"
    base.setdefault("widened", []).append({k: new[k] for k in ("measured_on", "date", "command")} | {"configs": new["grid"]["configs"]})
    return base


def replace(base, new):
    """`base` (the whole grid's bounds) with the bounds of the fidelities `new` ran replaced by
    `new`'s: a change to those fidelities alone, whose whole grid was run again (every scene,
    configuration and frame size of `base`). Each replaced fidelity names its own commit
    (`measured_on`, which rtsim states in the bound's basis); the others keep the file's, and
    `replaced` lists the reruns."""
    for k in ("scenes", "configs", "primary_sizes", "pt_sizes", "seed"):
        if new["grid"][k] != base["grid"][k]:
            sys.exit(f"REPLACE: the grid's {k} {new['grid'][k]} are not the file's {base['grid'][k]} (run the whole grid)")
    for fid, b in new["bounds"].items():
        base["bounds"][fid] = b | {"measured_on": new["measured_on"]}
    base.setdefault("replaced", []).append({k: new[k] for k in ("measured_on", "date", "command")} | {"fidelities": list(new["bounds"])})
    return base


def command():
    """How to make this grid again: the settings that shape it, and the scenes; RTSIM and OUTDIR
    as placeholders (the paths of one machine say nothing elsewhere)."""
    env = [f"{k}={os.environ[k]}" for k in ("PRIMARY_SIZES", "PT_SIZES", "CONFIGS", "SEED", "FIDS") if k in os.environ]
    return " ".join(env + ["scripts/bench_error_grid.py RTSIM OUTDIR"] + sys.argv[3:4])


commit = os.environ.get("COMMIT") or subprocess.run("git rev-parse --short HEAD", shell=True, capture_output=True, text=True,
                        cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
# The regime rtsim claims: only the frame sizes with runs in (a partial grid claims less).
measured = {wl: [n for n in sizes[wl] if any(r["workload"] == wl and r["size"] == n for r in rows)] for wl in sizes}
grid = {"scenes": scenes, "primary_sizes": measured["primary"], "pt_sizes": measured["pt"], "spp": 2, "configs": configs, "seed": seed}
bounds = {"measured_on": commit, "date": datetime.date.today().isoformat(),
          "command": command(), "grid": grid, "bounds": {}}
# Per fidelity and workload: over the whole grid and per frame size (rtsim takes the worst of the
# grid's frame sizes on either side of a run's frame).
for fid in fast:
    bounds["bounds"][fid] = {}
    for wl in ("primary", "pt"):
        sel = [r for r in rows if r["fidelity"] == fid and r["workload"] == wl]
        b = summary(sel)
        b["by_size"] = {str(n): summary([r for r in sel if r["size"] == n]) for n in measured[wl]}
        bounds["bounds"][fid][wl] = b
if os.environ.get("EXTEND"):
    bounds = extend(json.load(open(os.environ["EXTEND"])), bounds)
if os.environ.get("WIDEN"):
    bounds = widen(json.load(open(os.environ["WIDEN"])), bounds)
if os.environ.get("REPLACE"):
    bounds = replace(json.load(open(os.environ["REPLACE"])), bounds)
with open(f"{out}/error_bounds.json", "w") as f:
    json.dump(bounds, f, indent=2)
    f.write("\n")

pct = lambda x: f"{100 * x:+.1f} %"
lines = [f"Grid: scenes {', '.join(scenes)}; primary rays at {sizes['primary']}, path tracing (2 spp) at {sizes['pt']} "
         f"(square frames); configurations {', '.join(configs)}; seed {seed}; rtsim at {commit}. "
         f"{len(rows)} fast runs against AT, {len(fails)} failed runs.", "",
         "| fidelity | workload | frame | runs | mean abs. error | worst abs. error | worst case |",
         "|---|---|---|---|---|---|---|"]
for fid, wl in itertools.product(("lt", "interval"), ("primary", "pt")):
    for n in sizes[wl] + ["all"]:
        sel = [r for r in rows if r["fidelity"] == fid and r["workload"] == wl and (n == "all" or r["size"] == n)]
        if not sel:
            continue
        s = summary(sel)
        w = max(sel, key=lambda r: abs(r["error"]))
        lines.append(f"| {fid} | {wl} | {n} | {s['runs']} | {100 * s['mean']:.2f} % | {100 * s['worst']:.2f} % | "
                     f"{w['scene']} {w['size']} {w['config']} ({pct(w['error'])}) |")
within = sum(abs(r["error"]) <= 0.01 for r in rows)
lines += ["", f"{within} of {len(rows)} fast runs are within 1 % of AT.", "",
          "Per case (error against AT; LT / interval):", "",
          "| scene | workload | frame | config | AT cycles | LT | interval |", "|---|---|---|---|---|---|---|"]
by = {}
for r in rows:
    by.setdefault((r["scene"], r["workload"], r["size"], r["config"]), {})[r["fidelity"]] = r
for (sc, wl, n, cfg), d in sorted(by.items(), key=lambda x: (x[0][1], x[0][0], x[0][2], x[0][3])):
    at = next(iter(d.values()))["at_cycles"]
    lines.append(f"| {sc} | {wl} | {n} | {cfg} | {at} | " + " | ".join(pct(d[f]["error"]) if f in d else "-" for f in ("lt", "interval")) + " |")
for k, v in fails.items():
    lines.append(f"\nFAILED {k}: exit {v[0]}: {v[1][:200]}")
with open(f"{out}/table.md", "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines[:6 + 2 * sum(len(v) + 1 for v in sizes.values()) + 2]))
