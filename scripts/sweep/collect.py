#!/usr/bin/env python3
"""Collects the stats of every run of a sweep manifest into OUTDIR/results.csv (one row per run,
in manifest order; a run without stats is listed with its exit status). After the run's id come
the swept keys, one column each: every configuration key (as `config.l1.size_kb` is written,
`l1.size_kb`), frame parameter (`params.width`) and run option (`fidelity`, `traversal`,
`workload`) whose value differs between the sweep's finished runs, read from their statistics
files, so that results group by parameter without the manifest.

Every column names a statistic by its key in `rtsim --stats-schema` (RTSIM: the rtsim binary,
default build/rtsim). The collector stops with status 1 if a column's key is not in the schema (a
renamed statistic would otherwise leave a column silently empty) or if a finished run lacks a
statistic it must have.
Usage: collect.py MANIFEST OUTDIR"""
import csv
import json
import os
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import manifest  # noqa: E402
STREAK = ["not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"]
THREAD_STATUS = ["waiting_to_be_scheduled", "waiting_on_memory", "in_math", "done_waiting_for_warp"]

# (column, statistic); every timing run has these.
TIMING = [
    ("cycles", "cycles"),
    ("error_bound", "error_estimate.value"),  # the run's own stated error (null: none stated)
    ("node_fetches", "timing.rt_unit.node_fetches"),
    ("l1_miss_rate", "timing.l1.demand.miss_rate"), ("l2_miss_rate", "timing.l2.demand.miss_rate"),
    ("l1_mpkf", "timing.l1.rt_misses_per_kilo_node_fetch"), ("l2_mpkf", "timing.l2.rt_misses_per_kilo_node_fetch"),
    ("dram_reads", "timing.dram.reads"), ("dram_bytes", "timing.dram.bytes"), ("dram_bw", "timing.dram.bandwidth_utilisation"),
    ("pf_sent", "timing.rt_unit.prefetch_queue.sent"),
    ("l1_pf_accuracy", "timing.prefetch.l1.accuracy"), ("l2_pf_accuracy", "timing.prefetch.l2.accuracy"),
    ("l1_pf_useful", "timing.l1.prefetched.useful"), ("l2_pf_useful", "timing.l2.prefetched.useful"),
    ("l1_pf_efficiency", "timing.prefetch.l1.efficiency"), ("l2_pf_efficiency", "timing.prefetch.l2.efficiency"),
    ("energy_j", "timing.energy.total_j"), ("power_w", "timing.energy.average_power_w"),
    ("pf_generated", "timing.rt_unit.prefetch_queue.generated"),
    ("pf_window_dropped", "timing.rt_unit.prefetch_queue.window_dropped"),
    ("pf_removed_by_demand", "timing.rt_unit.prefetch_queue.removed_by_demand"),
    ("l1_misses_with_next_queued_share", "timing.rt_unit.l1_misses_with_next_queued_share"),
] + [(f"{lvl}_pf_authors_{k}", f"timing.prefetch.{lvl}.authors_{k}") for lvl in ("l1", "l2") for k in ("accuracy", "coverage")] \
  + [(f"status_{k}", f"timing.rt_unit.thread_status.{k}") for k in THREAD_STATUS] \
  + [(f"{lvl}_pf_{name}", f"timing.{lvl}.prefetch.{key}") for lvl in ("l1", "l2")
     for name, key in (("hit", "hits"), ("mshr_hit", "mshr_hits"), ("resfail", "reservation_fails"),
                       ("sector_miss", "sector_misses"), ("line_miss", "line_misses"))] \
  + [(f"{lvl}_demand_{name}", f"timing.{lvl}.demand.{name}") for lvl in ("l1", "l2")
     for name in ("sector_misses", "line_misses", "mshr_hits")] \
  + [(f"streak_{c}_{k}", f"timing.rt_unit.pop_streak.{c}.{k}") for c in STREAK for k in ("node_fetches", "l1_misses", "dram_misses")]
# Every run has these.
ALWAYS = [("rays", "rays"), ("nodes_per_ray", "nodes_per_ray"), ("max_nodes_per_ray", "max_nodes_per_ray"), ("sim_s", "time_s.run")]
# Sampled runs only.
SAMPLED = [("cycles_simulated", "timing.sampling.cycles_simulated"), ("rate_simulated", "timing.sampling.rate_simulated"),
           ("ci95", "timing.sampling.cycles_ci95")]
# Columns computed from others.
DERIVED = ["l1_demand_misses", "l2_demand_misses", "l1_pf_miss_free", "l2_pf_miss_free", "ci95_lo", "ci95_hi"]


def get(d, path):
    for k in path.split("."):
        if not isinstance(d, dict) or k not in d:
            raise KeyError(path)
        d = d[k]
    return d


def settings(j):
    """A run's settings, by key: its fidelity, traversal and workload, its frame parameters and
    every configuration key."""
    out = {k: j.get(k) for k in ("fidelity", "traversal", "workload")}
    out.update({f"params.{k}": v for k, v in j.get("params", {}).items()})

    def walk(d, prefix):
        for k, v in d.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{k}.")
            else:
                out[f"{prefix}{k}"] = json.dumps(v) if isinstance(v, list) else v
    walk(j.get("config", {}), "")
    return out


def swept(all_settings):
    """The keys whose value is not the same in every run that has settings (in first-seen order)."""
    keys = list(dict.fromkeys(k for s in all_settings for k in s))
    return [k for k in keys if len({json.dumps(s.get(k)) for s in all_settings}) > 1]


def schema_keys():
    rtsim = os.environ.get("RTSIM", str(HERE.parent.parent / "build" / "rtsim"))
    out = subprocess.run([rtsim, "--stats-schema"], capture_output=True, text=True, check=True).stdout
    return {line.split("\t")[0] for line in out.splitlines()[1:]}


def main():
    manifest_path, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    keys = schema_keys()
    unknown = [path for _, path in ALWAYS + TIMING + SAMPLED if path not in keys]
    if unknown:
        sys.exit(f"collect: statistics not in rtsim --stats-schema: {', '.join(unknown)}")
    rows, missing, run_settings = [], [], []
    for run in manifest.read(manifest_path):
        rid = run.id
        exp, scene = rid.split("/", 1)
        stats, status, _ = manifest.outputs(outdir, run)
        row = {"id": rid, "experiment": exp, "scene": scene, "exit": "", "wall_s": ""}
        if status.exists():
            st = json.loads(status.read_text())
            row["exit"], row["wall_s"] = st["exit"], st["wall_s"]
        if manifest.finished(outdir, run):
            j = json.loads(stats.read_text())
            row["_settings"] = settings(j)
            run_settings.append(row["_settings"])
            wanted = ALWAYS + (TIMING if "timing" in j else []) + (SAMPLED if "sampling" in j.get("timing", {}) else [])
            for name, path in wanted:
                try:
                    row[name] = get(j, path)
                except KeyError:
                    missing.append(f"{rid}: {path}")
            if "ci95" in row:  # null: a --sample-unchecked run without an interval
                row["ci95_lo"], row["ci95_hi"] = row.pop("ci95") or ("", "")
            for lvl in ("l1", "l2"):
                if f"{lvl}_demand_sector_misses" in row:
                    row[f"{lvl}_demand_misses"] = sum(row[f"{lvl}_demand_{k}"] for k in ("sector_misses", "line_misses", "mshr_hits"))
                    row[f"{lvl}_pf_miss_free"] = row[f"{lvl}_pf_sector_miss"] + row[f"{lvl}_pf_line_miss"]
        rows.append(row)
    if missing:
        sys.exit("collect: runs lack statistics they must have:\n  " + "\n  ".join(missing[:20]))
    sweep_keys = swept(run_settings)
    for r in rows:
        r.update({k: r.get("_settings", {}).get(k, "") for k in sweep_keys})
        r.pop("_settings", None)
    fields = ["id", "experiment", "scene"] + sweep_keys + ["exit", "wall_s"] + [c for c, _ in ALWAYS + TIMING] + \
             ["cycles_simulated", "rate_simulated"] + DERIVED
    with open(outdir / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    done = sum(1 for r in rows if r.get("rays", "") != "")
    print(f"collect: {done} of {len(rows)} runs have stats -> {outdir / 'results.csv'}", file=sys.stderr)


if __name__ == "__main__":
    main()
