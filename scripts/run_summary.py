#!/usr/bin/python3
"""The main job's summary (scripts/run.sh): a short table of the baseline and TTP runs and a
small PNG chart of the two. Every figure is read from the two stats files.
Usage: run_summary.py BASELINE.json TTP.json CHART.png"""
import json
import sys


def get(d, path):
    for k in path.split("."):
        d = d[k]
    return d


def main():
    base_path, ttp_path, chart = sys.argv[1:4]
    base, ttp = json.load(open(base_path)), json.load(open(ttp_path))

    def demand_misses(d):  # the baseline's L1 demand misses: sector, line and MSHR-hit misses
        return sum(get(d, f"timing.l1.demand.{k}") for k in ("sector_misses", "line_misses", "mshr_hits"))
    speedup = base["cycles"] / ttp["cycles"]
    coverage = get(ttp, "timing.l1.prefetched.useful") / demand_misses(base) if demand_misses(base) else float("nan")
    rows = [
        ("cycles", f"{base['cycles']:,}", f"{ttp['cycles']:,}"),
        ("TTP speed-up (baseline cycles / TTP cycles)", "", f"{speedup:.3f}x"),
        ("L1 demand miss rate", f"{100 * get(base, 'timing.l1.demand.miss_rate'):.1f} %",
         f"{100 * get(ttp, 'timing.l1.demand.miss_rate'):.1f} %"),
        ("L1 prefetch accuracy (prefetched sectors a demand read)", "", f"{100 * get(ttp, 'timing.prefetch.l1.accuracy'):.1f} %"),
        ("L1 prefetch coverage (of the baseline's L1 misses)", "", f"{100 * coverage:.1f} %"),
        ("simulated rays per second (this machine)", f"{base['rays'] / base['time_s']['run']:,.0f}",
         f"{ttp['rays'] / ttp['time_s']['run']:,.0f}"),
    ]
    w = max(len(r[0]) for r in rows)
    print(f"\n{'':{w}}  {'baseline':>12}  {'TTP':>12}")
    for name, a, b in rows:
        print(f"{name:{w}}  {a:>12}  {b:>12}")
    cfg = base.get("config", {})
    print(f"\n{base['rays']:,} rays, fidelity {base.get('fidelity', 'at')}, "
          f"{cfg.get('gpu', {}).get('sms', '?')} SMs, L1 {cfg.get('l1', {}).get('size_kb', '?')} KB"
          + (f"; Embree check: {base['verify']['mismatches']} mismatches in {base['verify']['rays']:,} rays" if "verify" in base else ""))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(no chart: python3-matplotlib is not installed; scripts/setup.sh --reports installs it)", file=sys.stderr)
        return
    labels = ["cycles", "L1 misses", "DRAM reads"]
    b = [base["cycles"], demand_misses(base), get(base, "timing.dram.reads")]
    t = [ttp["cycles"], demand_misses(ttp), get(ttp, "timing.dram.reads")]
    fig, ax = plt.subplots(figsize=(5, 2.8))
    xs = range(len(labels))
    ax.bar([x - 0.2 for x in xs], [1.0] * len(labels), 0.4, label="baseline")
    ax.bar([x + 0.2 for x in xs], [tv / bv if bv else 0 for tv, bv in zip(t, b)], 0.4, label="TTP")
    ax.set_xticks(list(xs))
    ax.set_xticklabels(labels)
    ax.set_ylabel("relative to baseline")
    ax.set_title(f"TTP against the baseline: {speedup:.2f}x speed-up")
    ax.set_ylim(0, 1.3)
    ax.legend(fontsize=8, ncol=2, loc="upper right")
    fig.tight_layout()
    fig.savefig(chart, dpi=100)


if __name__ == "__main__":
    main()
