#!/usr/bin/env python3
"""Where a reference frame's cycles go, from the simulator's own log: per run, the RT unit's
traces against the shader code between them.

The authors' simulator prints, for every warp that enters or leaves the RT unit,
"SM s Warp w arrived cycle c" and "... completed cycle c", and "Issued cta i to sm s at cycle: c"
when a CTA starts. From these, per run:
  traces              warp traces (arrived/completed pairs)
  cta_first_issue     the cycle the first CTA was issued (the simulator's start-up before it)
  first_trace         the first trace's arrival: ray generation's code before its first call
  rt_residence_mean   mean cycles from a trace's arrival to its completion
  shader_gap_mean     mean cycles from a warp's trace completing to its next trace arriving
                      (the hit/miss and ray-generation shaders between two calls, intersection
                      shaders included), and its median
  rt_share            the traces' cycles over the traces' and the gaps' cycles: the share of a
                      warp's time between its first arrival and its last completion spent in the
                      RT unit
  last_completion     the last trace's completion; frame cycles after it are the shaders' tail
Usage: trace_stats.py OUT.csv LOG.gz... (logs as run_reference.py keeps them: <tag>.log.gz)"""
import csv
import gzip
import os
import re
import statistics
import sys

EVENT = re.compile(rb"SM (\d+) Warp (\d+) (arrived|completed) cycle (\d+)")
ISSUE = re.compile(rb"Issued cta \d+ to sm \d+ at cycle: (\d+)")
CYCLES = re.compile(rb"gpu_sim_cycle = (\d+)")
TAG = re.compile(r"(?P<scene>[a-z]+)-(?P<w>\d+)x(?P<h>\d+)-(?P<spp>\d+)spp-(?P<config>[a-z-]+)")

COLUMNS = ["scene", "width", "height", "spp", "config", "gpu_sim_cycle", "traces", "cta_first_issue", "first_trace",
           "rt_residence_mean", "shader_gap_mean", "shader_gap_median", "rt_share", "last_completion"]


def stats_of(path):
    events, first_issue, cycles = {}, None, None
    with gzip.open(path, "rb") as f:
        for line in f:
            m = EVENT.match(line)
            if m:
                key = (int(m.group(1)), int(m.group(2)))
                events.setdefault(key, []).append((int(m.group(4)), m.group(3) == b"arrived"))
                continue
            m = ISSUE.match(line)
            if m:
                c = int(m.group(1))
                first_issue = c if first_issue is None else min(first_issue, c)
                continue
            m = CYCLES.match(line)
            if m:
                cycles = int(m.group(1))
    residences, gaps, firsts, lasts = [], [], [], []
    for seq in events.values():
        # A warp slot is reused by later warps: pair each arrival with the next completion, and
        # count a gap only between a completion and the next arrival of the same slot.
        seq.sort(key=lambda e: (e[0], not e[1]))
        arrived, completed = None, None
        for c, is_arrival in seq:
            if is_arrival:
                if completed is not None:
                    gaps.append(c - completed)
                arrived = c
                firsts.append(c)
            elif arrived is not None:
                residences.append(c - arrived)
                lasts.append(c)
                completed, arrived = c, None
    if not residences:
        return None
    rt, gap = sum(residences), sum(gaps)
    return {"gpu_sim_cycle": cycles, "traces": len(residences), "cta_first_issue": first_issue,
            "first_trace": min(firsts), "rt_residence_mean": round(statistics.mean(residences), 1),
            "shader_gap_mean": round(statistics.mean(gaps), 1) if gaps else "",
            "shader_gap_median": statistics.median(gaps) if gaps else "",
            "rt_share": round(rt / (rt + gap), 4), "last_completion": max(lasts)}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    rows = []
    for path in sorted(sys.argv[2:]):
        name = os.path.basename(path)
        m = TAG.fullmatch(name[: -len(".log.gz")]) if name.endswith(".log.gz") else None
        if not m:  # an earlier attempt's log is <tag>.<stamp>.log.gz
            print(f"trace_stats: skipped {path} (not <scene>-<w>x<h>-<spp>spp-<config>[.stamp].log.gz)", file=sys.stderr)
            continue
        s = stats_of(path)
        if s is None:
            print(f"trace_stats: skipped {path} (no traces in the log)", file=sys.stderr)
            continue
        rows.append({"scene": m["scene"], "width": m["w"], "height": m["h"], "spp": m["spp"], "config": m["config"], **s})
    tmp = sys.argv[1] + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, sys.argv[1])
    print(f"trace_stats: {len(rows)} runs -> {sys.argv[1]}")


if __name__ == "__main__":
    main()
