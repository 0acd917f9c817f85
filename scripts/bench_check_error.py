#!/usr/bin/env python3
"""Does --check-error's stated error hold the true error, and what does it cost (docs/accuracy.md,
"--check-error")?

    scripts/bench_check_error.py RTSIM OUT SCENES
    env: FIDS=interval,lt  WORKLOADS=pt,primary  SIZES=256  PRESETS=mobile  SEEDS=3  N=10  JOBS=2

Per frame (scene, workload, size, preset): the full AT run, then per fidelity and seed
`rtsim --fidelity FID --check-error N --sample-seed SEED`, whose main run is the full frame in FID.
The true error is that run's cycles against AT's; the check states |difference| + its half-width.
OUT/summary.md (or SUMMARY=FILE): per check, the true error, the check's difference and interval, whether it holds
the true error, the check's wall time against the full AT run's, and the sample's own cycles
ratio (what the check stated before it paired the strata). Runs are resumable (bench_util)."""
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_util import config_args, run_stats, scene_args  # noqa: E402


def env_list(name, default):
    return [x for x in os.environ.get(name, default).split(",") if x]


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    rtsim, out, scenes = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
    fids = env_list("FIDS", "interval,lt")
    workloads = env_list("WORKLOADS", "pt,primary")
    sizes = [int(s) for s in env_list("SIZES", "256")]
    presets = env_list("PRESETS", "mobile")
    seeds = range(1, int(os.environ.get("SEEDS", "3")) + 1)
    n = int(os.environ.get("N", "10"))
    jobs = int(os.environ.get("JOBS", "2"))
    os.makedirs(out, exist_ok=True)
    sc = scene_args()
    frames = [(s, w, z, p) for s in scenes for w in workloads for z in sizes for p in presets]

    def frame_args(s, w, z, p):
        return f"{sc[s]} --workload {w} --width {z} --height {z} {config_args(p)} --threads 1"

    def timed(path, args):
        t = time.monotonic()
        rc, err = run_stats(rtsim, path, args)
        if rc == 0 and not os.path.exists(path + ".wall"):
            with open(path + ".wall", "w") as f:
                f.write(f"{time.monotonic() - t:.3f}\n")
        return path, rc, err

    tasks = []
    for s, w, z, p in frames:
        key = f"{s}_{w}_{z}_{p}"
        tasks.append((f"{out}/{key}_at.json", f"{frame_args(s, w, z, p)} --fidelity at"))
        for fid in fids:
            for seed in seeds:
                tasks.append((f"{out}/{key}_{fid}_check{n}_{seed}.json",
                              f"{frame_args(s, w, z, p)} --fidelity {fid} --check-error {n} --sample-seed {seed}"))
    with ThreadPoolExecutor(jobs) as pool:
        for path, rc, err in pool.map(lambda t: timed(*t), tasks):
            print(f"{os.path.basename(path)}: {'ok' if rc == 0 else f'exit {rc}: {err}'}", flush=True)

    def load(path):
        with open(path) as f:
            return json.load(f)

    def wall(path):
        with open(path + ".wall") as f:
            return float(f.read())

    rows = []
    for s, w, z, p in frames:
        key = f"{s}_{w}_{z}_{p}"
        at_path = f"{out}/{key}_at.json"
        if not os.path.exists(at_path):
            continue
        at = load(at_path)
        for fid in fids:
            for seed in seeds:
                path = f"{out}/{key}_{fid}_check{n}_{seed}.json"
                if not os.path.exists(path):
                    continue
                r = load(path)
                c = r["error_estimate"]["check"]
                true = r["cycles"] / at["cycles"] - 1
                if c is None:  # refused after the run (its sample cost half the run or more)
                    rows.append(dict(frame=f"{s} {w} {z} {p}", fid=fid, seed=seed, true=true, refused=True,
                                     ratio=at["time_s"]["run"] / r["time_s"]["run"]))
                    continue
                stated = abs(c["difference"]) + c["difference_half_width"]
                rows.append(dict(frame=f"{s} {w} {z} {p}", fid=fid, seed=seed, true=true, diff=c["difference"], half=c["difference_half_width"],
                                 held=abs(true) <= stated, inside=abs(true - c["difference"]) <= c["difference_half_width"],
                                 cost=c["wall_s"] / wall(at_path), sample=c["fidelity_cycles"] / c["at_cycles"] - 1, refused=False,
                                 ratio=at["time_s"]["run"] / r["time_s"]["run"]))
    if not rows:
        sys.exit("no checks with their AT run in " + out)
    lines = [f"# --check-error {n} against the full runs", "",
             f"`scripts/bench_check_error.py {rtsim} {out} {','.join(scenes)}` (FIDS={','.join(fids)} WORKLOADS={','.join(workloads)} "
             f"SIZES={','.join(map(str, sizes))} PRESETS={','.join(presets)} SEEDS={len(seeds)} N={n}).", ""]
    ran = [r for r in rows if not r["refused"]]
    refused = [r for r in rows if r["refused"]]
    if not ran:
        sys.exit(f"every one of the {len(rows)} checks in {out} was refused")
    held = sum(r["held"] for r in ran)
    inside = sum(r["inside"] for r in ran)
    costs = sorted(r["cost"] for r in ran)
    miss_sample = sum(abs(r["sample"] - r["true"]) for r in ran) / len(ran)
    miss_paired = sum(abs(r["diff"] - r["true"]) for r in ran) / len(ran)
    halves = sorted(r["half"] for r in ran)
    ratios = sorted(r["ratio"] for r in rows)
    lines += [f"- {len(ran)} {'check' if len(ran) == 1 else 'checks'} ran, {len(refused)} {'was' if len(refused) == 1 else 'were'} "
              "refused after the run (their sample cost half the run or more)"
              + (f": {', '.join(sorted(set(r['frame'] + ' ' + r['fid'] for r in refused)))}." if refused else "."),
              f"- The stated error (|difference| + half-width) holds the true error in {held} of {len(ran)} checks; the interval "
              f"(difference +- half-width) holds it in {inside}.",
              f"- The paired difference lies {100 * miss_paired:.2f} % from the true error on average; the sample's own cycles ratio "
              f"(what the check stated before) {100 * miss_sample:.2f} %.",
              f"- Median half-width {100 * halves[len(halves) // 2]:.2f} % (largest {100 * halves[-1]:.2f} %).",
              f"- A check's wall time is {costs[0]:.2f}-{costs[-1]:.2f} of the full AT run's (median {costs[len(costs) // 2]:.2f}).",
              f"- AT's full run took {ratios[0]:.2f}-{ratios[-1]:.2f} times the checked fidelity's (simulation time).", "",
              "| frame | fidelity | seed | true error | check: difference +- half-width | holds | sample's cycles ratio | check / full AT time |",
              "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["refused"]:
            lines.append(f"| {r['frame']} | {r['fid']} | {r['seed']} | {100 * r['true']:+.2f} % | refused | | | |")
            continue
        lines.append(f"| {r['frame']} | {r['fid']} | {r['seed']} | {100 * r['true']:+.2f} % | {100 * r['diff']:+.2f} +- {100 * r['half']:.2f} % | "
                     f"{'yes' if r['held'] else '**no**'}{'' if r['inside'] else ' (outside the interval)'} | {100 * r['sample']:+.2f} % | {r['cost']:.2f} |")
    with open(os.environ.get("SUMMARY", f"{out}/summary.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines[:10]))


if __name__ == "__main__":
    main()
