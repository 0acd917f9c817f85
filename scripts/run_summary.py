#!/usr/bin/python3
"""The main job's summary (scripts/run.sh): a short table of the baseline and TTP runs and a
small PNG chart of the two. Every figure is read from the two stats files through
scripts/python/rtunit_stats; a statistic a file lacks (a file of another rtsim version) is shown
as "n/a", never an error.
Usage: run_summary.py BASELINE.json TTP.json CHART.png"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "python"))
from rtunit_stats import load, value  # noqa: E402


def main():
    base_path, ttp_path, chart = sys.argv[1:4]
    base, ttp = load(base_path).iloc[0], load(ttp_path).iloc[0]

    def demand_misses(d):  # L1 demand misses: sector, line and MSHR-hit misses (None: not in the file)
        parts = [value(d, f"timing.l1.demand.{k}") for k in ("sector_misses", "line_misses", "mshr_hits")]
        return None if None in parts else sum(parts)

    def ratio(a, b):
        return a / b if a is not None and b else None

    def fmt(v, spec, unit=""):
        return "n/a" if v is None else format(v, spec) + unit

    b_cycles, t_cycles = value(base, "cycles"), value(ttp, "cycles")
    speedup = ratio(b_cycles, t_cycles)
    coverage = ratio(value(ttp, "timing.l1.prefetched.useful"), demand_misses(base))
    pct = lambda v: None if v is None else 100 * v  # noqa: E731
    rate = lambda d: ratio(value(d, "rays"), value(d, "time_s.run"))  # noqa: E731
    rows = [
        ("cycles", fmt(b_cycles, ","), fmt(t_cycles, ",")),
        ("TTP speed-up (baseline cycles / TTP cycles)", "", fmt(speedup, ".3f", "x")),
        ("L1 demand miss rate", fmt(pct(value(base, "timing.l1.demand.miss_rate")), ".1f", " %"),
         fmt(pct(value(ttp, "timing.l1.demand.miss_rate")), ".1f", " %")),
        ("L1 prefetch accuracy (prefetched sectors a demand read)", "", fmt(pct(value(ttp, "timing.prefetch.l1.accuracy")), ".1f", " %")),
        ("L1 prefetch coverage (of the baseline's L1 misses)", "", fmt(pct(coverage), ".1f", " %")),
        ("simulated rays per second (this machine)", fmt(rate(base), ",.0f"), fmt(rate(ttp), ",.0f")),
    ]
    w = max(len(r[0]) for r in rows)
    print(f"\n{'':{w}}  {'baseline':>12}  {'TTP':>12}")
    for name, a, b in rows:
        print(f"{name:{w}}  {a:>12}  {b:>12}")
    check = ""
    if value(base, "verify.rays") is not None:
        check = f"; Embree check: {value(base, 'verify.mismatches', 'n/a')} mismatches in {value(base, 'verify.rays'):,} rays"
    print(f"\n{fmt(value(base, 'rays'), ',')} rays, fidelity {value(base, 'fidelity', 'at')}, "
          f"{value(base, 'config.gpu.sms', '?')} SMs, L1 {value(base, 'config.l1.size_kb', '?')} KB; "
          f"rtsim {value(base, 'provenance.version', '(version not recorded)')} "
          f"commit {value(base, 'provenance.commit', '(not recorded)')}" + check)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(no chart: python3-matplotlib is not installed; scripts/setup.sh --reports installs it)", file=sys.stderr)
        return
    labels = ["cycles", "L1 misses", "DRAM reads"]
    b = [b_cycles, demand_misses(base), value(base, "timing.dram.reads")]
    t = [t_cycles, demand_misses(ttp), value(ttp, "timing.dram.reads")]
    fig, ax = plt.subplots(figsize=(5, 2.8))
    xs = range(len(labels))
    ax.bar([x - 0.2 for x in xs], [1.0] * len(labels), 0.4, label="baseline")
    ax.bar([x + 0.2 for x in xs], [ratio(tv, bv) or 0 for tv, bv in zip(t, b)], 0.4, label="TTP")
    ax.set_xticks(list(xs))
    ax.set_xticklabels(labels)
    ax.set_ylabel("relative to baseline")
    ax.set_title(f"TTP against the baseline: {fmt(speedup, '.2f')}x speed-up")
    ax.set_ylim(0, 1.3)
    ax.legend(fontsize=8, ncol=2, loc="upper right")
    fig.tight_layout()
    fig.savefig(chart, dpi=100)


if __name__ == "__main__":
    main()
