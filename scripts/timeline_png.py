#!/usr/bin/python3
"""Draws a timeline that rtsim wrote (--timeline FILE.json: Chrome trace events, docs/usage.md) as
a PNG, as Perfetto or chrome://tracing would show it: a row per thread of the traced warp-buffer
slot, a bar per span coloured by its status (schedule, fetch served by L1 / L1 miss / DRAM,
test), a tick per prefetch TTP picked. For a picture in the docs where no browser is at hand.
Usage: timeline_png.py TRACE.json OUT.png [--start CYCLE] [--cycles N]
  --start  the first cycle drawn (default: the first event's)
  --cycles how many cycles (default 3000)"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

COLOURS = {"schedule": "tab:grey", "fetch: L1 hit": "tab:green", "fetch: L1 miss": "tab:orange",
           "fetch: DRAM": "tab:red", "test": "tab:blue"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trace")
    ap.add_argument("out")
    ap.add_argument("--start", type=int)
    ap.add_argument("--cycles", type=int, default=3000)
    a = ap.parse_args()
    try:
        with open(a.trace) as f:
            doc = json.load(f)
        events = doc["traceEvents"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"timeline_png: {a.trace}: not a timeline rtsim wrote ({e})")
    spans = [e for e in events if e.get("ph") == "X"]
    if not spans:
        sys.exit(f"timeline_png: {a.trace}: no spans")
    start = a.start if a.start is not None else min(e["ts"] for e in spans)
    end = start + a.cycles
    title = next((e["args"]["name"] for e in events if e.get("ph") == "M" and e.get("name") == "process_name"), "RT unit")
    threads = sorted({e["tid"] for e in spans})
    fig, ax = plt.subplots(figsize=(11, 0.18 * len(threads) + 1.4))
    for name, colour in COLOURS.items():
        for tid in threads:
            bars = [(max(e["ts"], start), min(e["ts"] + e["dur"], end) - max(e["ts"], start)) for e in spans
                    if e["tid"] == tid and e["name"] == name and e["ts"] < end and e["ts"] + e["dur"] > start]
            if bars:
                ax.broken_barh(bars, (tid - 0.4, 0.8), facecolors=colour, linewidth=0)
    picks = [(e["ts"], e["tid"]) for e in events if e.get("ph") == "i" and start <= e["ts"] < end]
    if picks:
        ax.scatter([p[0] for p in picks], [p[1] for p in picks], marker="|", s=30, color="black", linewidths=0.8)
    ax.set_xlim(start, end)
    ax.set_ylim(max(threads) + 0.6, min(threads) - 0.6)
    ax.set_yticks(threads[::4])
    ax.set_ylabel("thread")
    ax.set_xlabel("core cycle")
    ax.set_title(f"{title}: cycles {start:,} to {end:,}")
    handles = [Patch(color=c, label=n) for n, c in COLOURS.items()] + \
              [Line2D([], [], color="black", marker="|", linestyle="", label="prefetch picked")]
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.savefig(a.out, dpi=110, bbox_inches="tight")
    print(f"timeline_png: {len(threads)} threads, cycles {start}-{end} -> {a.out}")


if __name__ == "__main__":
    main()
