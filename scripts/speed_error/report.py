#!/usr/bin/python3
"""Writes reports/speed-vs-error/README.md and a Pareto plot from a speed-vs-error sweep."""
import csv
import datetime
import json
import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from experiments import FIDELITIES  # noqa: E402

SCENES = ["wknd", "cornell", "ship", "bunny", "ref", "bath", "sprng"]
LABEL = {"at": "AT (reference)", "lt_q100": "LT, quantum 100", "lt_q1000": "LT, quantum 1000", "lt_q10000": "LT, quantum 10000",
         "at_s50": "AT, sample 50 %", "at_s25": "AT, sample 25 %", "at_s10": "AT, sample 10 %",
         "lt_s50": "LT q1000, sample 50 %", "lt_s25": "LT q1000, sample 25 %", "lt_s10": "LT q1000, sample 10 %"}


def main():
    results, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    outdir.mkdir(parents=True, exist_ok=True)
    d = {}
    with open(results) as f:
        for r in csv.DictReader(f):
            d[(r["experiment"], r["scene"])] = r
    meta_file = results.parent / "manifest.tsv.meta.json"
    meta = json.loads(meta_file.read_text()) if meta_file.exists() else {"size": 128, "spp": 2}

    def v(exp, scene, col):
        r = d.get((exp, scene))
        return float(r[col]) if r and r.get(col) not in ("", None) else None

    lines = []
    p = lines.append
    wall_sum = sum(float(r["wall_s"] or 0) for r in d.values())
    p("# Speed against error")
    p("")
    p(f"Generated {datetime.date.today()} by `scripts/speed_error.sh`: path tracing {meta['size']}x{meta['size']}, "
      f"{meta['spp']} spp, DFS, mobile preset, each fidelity with and without TTP; {len(d)} runs, {wall_sum / 60:.1f} "
      "minutes of simulation summed. Wall time is the simulation alone (scene loading and BVH build excluded). Errors "
      "are against AT on the same scene: total cycles (baseline run), TTP speed-up (baseline / TTP cycles) and L1 "
      "demand miss rate.")
    p("")
    summary = {}
    for s in SCENES:
        if not v("at_base", s, "cycles"):
            continue
        p(f"## {s}")
        p("")
        p("| fidelity | wall s | speed-up over AT | cycles | error | TTP speed-up | error | L1 miss rate | error (points) |")
        p("|---|---|---|---|---|---|---|---|---|")
        at_c, at_w = v("at_base", s, "cycles"), v("at_base", s, "sim_s")
        at_tt = at_c / v("at_ttp", s, "cycles")
        at_m = v("at_base", s, "l1_miss_rate")
        for fid in FIDELITIES:
            c, w, tc, m = v(f"{fid}_base", s, "cycles"), v(f"{fid}_base", s, "sim_s"), v(f"{fid}_ttp", s, "cycles"), v(f"{fid}_base", s, "l1_miss_rate")
            if not c or not w:
                continue
            err = 100 * (c - at_c) / at_c
            tt = c / tc if tc else float("nan")
            summary.setdefault(fid, []).append((at_w / w, abs(err), abs(100 * (tt - at_tt) / at_tt)))
            p(f"| {LABEL[fid]} | {w:.2f} | {at_w / w:.2f}x | {c:.0f} | {err:+.2f} % | {tt:.3f}x | {100 * (tt - at_tt) / at_tt:+.2f} % | "
              f"{m:.4f} | {100 * (m - at_m):+.2f} |")
        p("")
    p("## All scenes: speed-up and error")
    p("")
    p("| fidelity | speed-up over AT (geomean) | mean abs. cycle error | max abs. cycle error | mean abs. TTP speed-up error |")
    p("|---|---|---|---|---|")
    pts = []
    for fid, rows in summary.items():
        gm = math.exp(sum(math.log(r[0]) for r in rows) / len(rows))
        me = sum(r[1] for r in rows) / len(rows)
        mx = max(r[1] for r in rows)
        mt = sum(r[2] for r in rows) / len(rows)
        pts.append((fid, gm, me))
        p(f"| {LABEL[fid]} | {gm:.2f}x | {me:.2f} % | {mx:.2f} % | {mt:.2f} % |")
    p("")
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for fid, gm, me in pts:
        ax.scatter(gm, me, s=30)
        ax.annotate(LABEL[fid], (gm, me), fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_xlabel("speed-up over AT (geomean over scenes)")
    ax.set_ylabel("mean |error| in total cycles (%)")
    ax.set_title("Speed against error")
    ax.grid(True, which="both", linewidth=0.3)
    fig.tight_layout()
    fig.savefig(outdir / "pareto.png", dpi=110)
    p("![Pareto: speed-up against cycle error](pareto.png)")
    p("")
    p("## Which fidelity for which question")
    p("")
    p("- **Functional** (not in the table: no time at all) answers what the rays hit and how many nodes they visit, "
      "3-7x slower than Embree; use it for BVH and traversal-order studies (nodes per ray, Table 1).")
    p("- **AT** is the reference: cycles, every cache and DRAM statistic, waveforms. Use it for final numbers and for "
      "anything about queueing (reservation fails, DRAM bandwidth, arbitration).")
    p("- **LT at a quantum of 100-1,000 cycles** keeps miss rates within about a point and the TTP speed-up close to "
      "AT's, with cycles within a few percent; today it is not faster than AT (see the table), so it only pays where AT "
      "is impossible (none yet). Avoid quanta of 10,000: cycles drift by 15-25 %.")
    p("- **Sampling** cuts wall time in proportion to the share simulated. At 50 % the cycle error stays within about 2 % "
      "and ratios such as the TTP speed-up hold better than absolute cycles, since both runs share the sample; at 10 % "
      "the error reaches 10 % on some scenes. Use it for design-space sweeps that compare configurations, then confirm "
      "the chosen points in full AT. Its printed interval covers only the sampling error of the work, not of the "
      "throughput (docs/sampling.md).")
    (outdir / "README.md").write_text("\n".join(lines) + "\n")
    print(f"report: {outdir / 'README.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
