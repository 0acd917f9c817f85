#!/usr/bin/env python3
"""Collects the stats of every run of a sweep manifest into OUTDIR/results.csv (one row per run,
in manifest order; a run without stats is listed with its exit status)."""
import csv
import json
import pathlib
import sys


def get(d, path, default=""):
    for k in path.split("."):
        if not isinstance(d, dict) or k not in d:
            return default
        d = d[k]
    return d


COLUMNS = [
    ("cycles", "cycles"), ("rays", "rays"), ("nodes_per_ray", "nodes_per_ray"), ("max_nodes_per_ray", "max_nodes_per_ray"),
    ("node_fetches", "timing.rt_unit.node_fetches"),
    ("l1_miss_rate", "timing.l1.demand.miss_rate"), ("l2_miss_rate", "timing.l2.demand.miss_rate"),
    ("l1_mpkf", "timing.l1.rt_misses_per_kilo_node_fetch"), ("l2_mpkf", "timing.l2.rt_misses_per_kilo_node_fetch"),
    ("l1_demand_misses", None), ("l2_demand_misses", None),
    ("dram_reads", "timing.dram.reads"), ("dram_bw", "timing.dram.bandwidth_utilisation"),
    ("pf_sent", "timing.prefetch.sent"),
    ("l1_pf_accuracy", "timing.prefetch.l1.accuracy"), ("l2_pf_accuracy", "timing.prefetch.l2.accuracy"),
    ("l1_pf_useful", "timing.prefetch.l1.useful"), ("l2_pf_useful", "timing.prefetch.l2.useful"),
    ("l1_pf_efficiency", "timing.prefetch.l1.efficiency"), ("l2_pf_efficiency", "timing.prefetch.l2.efficiency"),
    ("l1_pf_hit", "timing.prefetch.l1.response.hit"), ("l1_pf_mshr_hit", "timing.prefetch.l1.response.mshr_hit"),
    ("l1_pf_miss_free", "timing.prefetch.l1.response.mshr_miss_free_entry"), ("l1_pf_resfail", "timing.prefetch.l1.response.reservation_fail"),
    ("l2_pf_hit", "timing.prefetch.l2.response.hit"), ("l2_pf_mshr_hit", "timing.prefetch.l2.response.mshr_hit"),
    ("l2_pf_miss_free", "timing.prefetch.l2.response.mshr_miss_free_entry"), ("l2_pf_resfail", "timing.prefetch.l2.response.reservation_fail"),
    ("energy_j", "timing.energy.total_j"), ("power_w", "timing.energy.average_power_w"),
    ("sim_s", "time_s.run"),
    ("ci95_lo", None), ("ci95_hi", None),
]
STREAK = ["not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"]


def main():
    manifest, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    rows = []
    with open(manifest) as f:
        lines = f.read().splitlines()[1:]
    for line in lines:
        rid, args, output = line.split("\t")
        exp, scene = rid.split("/", 1)
        stats = outdir / output
        status = outdir / (output + ".status")
        row = {"id": rid, "experiment": exp, "scene": scene, "exit": "", "wall_s": ""}
        if status.exists():
            st = json.loads(status.read_text())
            row["exit"], row["wall_s"] = st["exit"], st["wall_s"]
        if stats.exists() and stats.stat().st_size:
            j = json.loads(stats.read_text())
            for name, path in COLUMNS:
                row[name] = get(j, path) if path else ""
            ci = get(j, "timing.sampling.cycles_ci95", [])
            if len(ci) == 2:
                row["ci95_lo"], row["ci95_hi"] = ci
            for lvl in ("l1", "l2"):
                d = get(j, f"timing.{lvl}.demand", {})
                if d:
                    row[f"{lvl}_demand_misses"] = d["sector_misses"] + d["line_misses"] + d["mshr_hits"]
            for i, entry in enumerate(get(j, "timing.pop_streak", []) or []):
                row[f"streak_{STREAK[i]}_fetches"] = entry["node_fetches"]
                row[f"streak_{STREAK[i]}_l1_misses"] = entry["l1_misses"]
                row[f"streak_{STREAK[i]}_dram_misses"] = entry["dram_misses"]
        rows.append(row)
    fields = ["id", "experiment", "scene", "exit", "wall_s"] + [c for c, _ in COLUMNS]
    fields += [f"streak_{s}_{k}" for s in STREAK for k in ("fetches", "l1_misses", "dram_misses")]
    with open(outdir / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    done = sum(1 for r in rows if r.get("cycles") != "" and "cycles" in r)
    print(f"collect: {done} of {len(rows)} runs have stats -> {outdir / 'results.csv'}", file=sys.stderr)


if __name__ == "__main__":
    main()
