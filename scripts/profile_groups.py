#!/usr/bin/env python3
"""Where a run's time goes, by what the code models (docs/performance.md, "Where the time goes").

Reads perf.data files (`perf record` of rtsim runs, one per fidelity), takes each sample's
function (self time, no call graph needed) and puts it in a group by its name: traversal and
intersection tests, RT-unit logic, caches, DRAM, timestamp bookings, the event queue and the
SystemC/TLM kernel, allocation, scene load, BVH build and workload, the operating system.
Prints a markdown table (one column per file) and each file's top functions.

Usage: scripts/profile_groups.py [--top N] LABEL=perf.data ...
The perf.data files come from e.g. (a build with symbols, as scripts/profile.sh makes it):
  perf record -F 999 -o interval.perf build-prof/rtsim --scene party ... --fidelity interval
"""
import argparse
import re
import subprocess
import sys

# First match wins: the order puts the specific names before the catch-alls. Each pattern is
# searched in "dso symbol" (perf's --sort dso,sym).
GROUPS = [
    ("operating system (page faults, scheduling)", r"\[kernel|\[k\]|kallsyms"),
    ("allocation", r"\b(malloc|_int_malloc|_int_free|cfree|free|operator new|operator delete|tcache|malloc_consolidate|unlink_chunk)\b"),
    ("event queue, SystemC and TLM kernel",
     r"OrderedEvent|sc_core::|sc_dt::|tlm::|libsystemc|FifoPeq|fifo_peq|Crossbar|MemBridge|PayloadPool|RtExtension|ProtocolChecker|"
     r"get_extension|sc_time|sc_event|sc_simcontext|sc_method|sc_thread"),
    ("DRAM model", r"Dram|dram|AddressMap|RowBuffer|Bank"),
    ("timestamp bookings (calendars, heaps, the interval fidelity's event wheel)",
     r"Calendar|EventWheel|__adjust_heap|__push_heap|__pop_heap|priority_queue"),
    ("caches (tags, LRU, MSHRs, in-flight sectors)",
     r"SectorCache|CacheBookings|Cache::|Lru|Fifo::|Replacement|IntervalGpu::read|raw_hash_set|hash_internal|flat_hash|MixingHashState|"
     r"ipoly_index"),
    ("traversal and intersection tests",
     r"TraversalThread|child_hits|decode_|intersect_|moller|normal_to_world|trace_ray|robust|scale_direction|select_space|"
     r"BvhImage::|shader_sphere"),
    ("RT-unit logic (warp scheduler, threads, prefetcher, fetch events)",
     r"RtUnitCore|RtUnit::|RtComplex|IntervalGpu|RtThread|Prefetch|Ttp|Warp|FetchCoalescer|ResponseFifo|PopStreak|rt_math_latency|"
     r"ShaderLoads|run_interval|lt_run"),
    ("scene load, BVH build, workload, functional loop, pre-pass",
     r"embree|tbb|libassimp|tinyobj|load_obj|build_tree|ImageWriter|encode_|build_bvh|mesh_|split|lumibench|Workload|WorkRay|"
     r"Prepass|prepass|WarpTracer|FrameSample|warming|Scene|stbi|zlib|inflate|libz|functional_stage|run_functional|parse_number|"
     r"TracedRay|compute_smooth_normals"),
    ("C library (copies, fills)", r"libc\.so|memmove|memset|memcpy|libstdc"),
]


def samples(path):
    """(dso symbol) -> percentage of the file's samples, self time."""
    out = subprocess.run(["perf", "report", "-i", path, "--no-children", "--sort", "dso,sym", "--stdio", "-g", "none",
                          "--percent-limit", "0"], capture_output=True, text=True, check=True).stdout
    rows = []
    for line in out.splitlines():
        m = re.match(r"\s*([0-9.]+)%\s+(\S+)\s+\[[.k]\]\s+(.*)$", line)
        if m:
            rows.append((float(m.group(1)), m.group(2) + " " + m.group(3).strip()))
    if not rows:
        sys.exit(f"profile_groups: no samples read from {path} (perf report printed nothing usable)")
    return rows


def group_of(name):
    for g, pattern in GROUPS:
        if re.search(pattern, name):
            return g
    return "other"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--top", type=int, default=5, help="top functions listed per file (default 5)")
    ap.add_argument("files", nargs="+", help="LABEL=perf.data")
    a = ap.parse_args()
    cols = []
    for f in a.files:
        if "=" not in f:
            sys.exit(f"profile_groups: '{f}' is not LABEL=perf.data")
        label, path = f.split("=", 1)
        cols.append((label, samples(path)))
    names = [g for g, _ in GROUPS] + ["other"]
    shares = []
    for _, rows in cols:
        s = dict.fromkeys(names, 0.0)
        for pct, name in rows:
            s[group_of(name)] += pct
        shares.append(s)
    print("| share of samples (self time) | " + " | ".join(label for label, _ in cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for g in names:
        if all(s[g] < 0.5 for s in shares):
            continue
        print(f"| {g} | " + " | ".join(f"{s[g]:.0f} %" for s in shares) + " |")
    print()
    for label, rows in cols:
        top = sorted(rows, reverse=True)[:a.top]
        # The symbol without its arguments: "rtu::SectorCache::read(unsigned long, ...)" -> "rtu::SectorCache::read".
        # "(anonymous namespace)::" goes first, or the argument list's cut would take the whole name.
        short = [re.sub(r"\(.*$", "", name.split(" ", 1)[1].replace("(anonymous namespace)::", "")).replace("rtu::", "")
                 + f" {pct:.1f} %" for pct, name in top]
        print(f"- {label}: " + ", ".join(short))


if __name__ == "__main__":
    main()
