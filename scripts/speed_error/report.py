#!/usr/bin/python3
"""Writes reports/speed-vs-error/README.md and a Pareto plot from a speed-vs-error sweep."""
import datetime
import math
import pathlib
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "sweep"))
from experiments import EXTRA_SEEDS, FIDELITIES, SAMPLE_RATES  # noqa: E402
from report_util import load, number  # noqa: E402

SCENES = ["wknd", "cornell", "ship", "bunny", "ref", "bath", "sprng", "party"]
LABEL = {"at": "AT (reference)", "lt_q100": "LT, quantum 100", "lt_q1000": "LT, quantum 1000", "lt_q10000": "LT, quantum 10000",
         "interval": "interval",
         "at_s50": "AT, sample 50 %", "at_s25": "AT, sample 25 %", "at_s10": "AT, sample 10 %",
         "lt_s50": "LT q1000, sample 50 %", "lt_s25": "LT q1000, sample 25 %", "lt_s10": "LT q1000, sample 10 %",
         "iv_s50": "interval, sample 50 %", "iv_s25": "interval, sample 25 %", "iv_s10": "interval, sample 10 %"}


def main():
    results, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    outdir.mkdir(parents=True, exist_ok=True)
    d, meta = load(results)

    def v(exp, scene, col):
        return number(d, exp, scene, col)

    lines = []
    p = lines.append
    wall_sum = sum(float(r["wall_s"] or 0) for r in d.values())
    p("# Speed against error")
    p("")
    p(f"Generated {datetime.date.today()} by `scripts/speed_error.sh`: path tracing {meta['size']}x{meta['size']}, "
      f"{meta['spp']} spp, DFS, mobile preset, each fidelity with and without TTP, and the sampled AT baseline with "
      f"{len(EXTRA_SEEDS)} more draws of the sample; {len(d)} runs, two at a time, each on one core (the sampling "
      f"pre-pass with `--threads 1`), {wall_sum / 60:.1f} "
      "minutes of simulation summed. Wall time is the simulation alone (scene loading and BVH build excluded; the "
      "sampled runs' functional pre-pass included), of the baseline run; the speed-up over AT is the geometric mean "
      "of the baseline's and TTP's, each against AT's run in the same configuration (the machine is shared: "
      "compare speeds within one run of this script). Errors "
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
            # Speed-up: the geometric mean of the baseline's and TTP's (each against AT in the
            # same configuration), so that one slow or fast run moves it less.
            su = at_w / w
            at_tw, tw = v("at_ttp", s, "sim_s"), v(f"{fid}_ttp", s, "sim_s")
            if at_tw and tw:
                su = math.sqrt(su * at_tw / tw)
            err = 100 * (c - at_c) / at_c
            tt = c / tc if tc else float("nan")
            summary.setdefault(fid, []).append((su, abs(err), abs(100 * (tt - at_tt) / at_tt)))
            p(f"| {LABEL[fid]} | {w:.2f} | {su:.2f}x | {c:.0f} | {err:+.2f} % | {tt:.3f}x | {100 * (tt - at_tt) / at_tt:+.2f} % | "
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
        # The error the baseline runs state (error_estimate.value, %), median over the scenes
        # that state one; None where none does (outside the validated regime).
        stated = sorted(100 * e for e in (v(f"{fid}_base", s, "error_bound") for s in SCENES) if e is not None)
        pts.append((fid, gm, me, statistics.median(stated) if stated else None))
        p(f"| {LABEL[fid]} | {gm:.2f}x | {me:.2f} % | {mx:.2f} % | {mt:.2f} % |")
    p("")
    fig, ax = plt.subplots(figsize=(7.5, 4))
    # One colour per fidelity, one marker per sampling rate; legends beside the axes, no labels
    # on the points (the LT quanta and some sampled rates land on top of each other).
    colours = {"at": "tab:blue", "lt": "tab:orange", "interval": "tab:green"}
    markers = {"": "o", "s50": "s", "s25": "^", "s10": "v"}
    for fid, gm, me, stated in pts:
        family = "at" if fid.startswith("at") else "lt" if fid.startswith("lt") else "interval"
        ax.scatter(gm, me, s=34, color=colours[family], marker=markers.get(fid[-3:], "o"), alpha=0.85, zorder=3)
        if stated:  # the error the runs state, as a bar from 0 behind the point
            ax.vlines(gm, 0, stated, color=colours[family], linewidth=5, alpha=0.25, zorder=2)
    lt_quanta = sorted({int(f.split("_q")[1].split("_")[0]) for f, _, _, _ in pts if f.startswith("lt_q")})
    fidelities = [Line2D([], [], color=colours["at"], marker="o", linestyle="", label="AT"),
                  Line2D([], [], color=colours["lt"], marker="o", linestyle="",
                         label="LT" + (f" (quanta {', '.join(map(str, lt_quanta))})" if lt_quanta else "")),
                  Line2D([], [], color=colours["interval"], marker="o", linestyle="", label="interval")]
    rates = [Line2D([], [], color="grey", marker=m, linestyle="", label=l)
             for l, m in (("whole frame", "o"), ("sample 50 %", "s"), ("sample 25 %", "^"), ("sample 10 %", "v"))]
    rates.append(Line2D([], [], color="grey", linewidth=5, alpha=0.25, label="bar: median error the\nruns state (none: none)"))
    first = ax.legend(handles=fidelities, title="fidelity", fontsize=7, title_fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.add_artist(first)
    ax.legend(handles=rates, title="simulated", fontsize=7, title_fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 0.55))
    ax.set_xscale("log")
    top = max(gm for _, gm, _, _ in pts)
    ticks = [t for t in (1, 2, 3, 5, 10, 20, 50, 100, 200) if t <= top * 1.5]
    ax.set_xlim(0.9, max(ticks[-1], top) * 1.2)  # every point inside the last tick's decade, with room
    ax.set_xticks(ticks)
    ax.set_xticklabels([f"{t}x" for t in ticks])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("speed-up over AT (geomean over scenes)")
    ax.set_ylabel("mean |error| in total cycles (%)")
    ax.set_title("Speed against error")
    ax.grid(True, which="both", linewidth=0.3)
    fig.tight_layout()
    fig.savefig(outdir / "pareto.png", dpi=110, bbox_inches="tight", bbox_extra_artists=[first])  # the legends beside the axes
    p("![Pareto: speed-up against cycle error](pareto.png)")
    p("")
    bars = [f"{LABEL[f]} {st:.1f} %" for f, _, _, st in pts if st]
    silent = [LABEL[f] for f, _, _, st in pts if st is None]
    p("The bars are the error the runs state (`error_estimate.value`, median over the scenes): "
      + ("; ".join(bars) if bars else "none states one") + "."
      + (f" These state none (outside what was validated): {'; '.join(silent)}." if silent else ""))
    p("")
    def row(fid):
        rows = summary.get(fid, [])
        if not rows:
            return None
        return (math.exp(sum(math.log(r[0]) for r in rows) / len(rows)), sum(r[1] for r in rows) / len(rows),
                max(r[1] for r in rows), sum(r[2] for r in rows) / len(rows))

    # Sampled AT over several draws of the sample: accuracy and coverage of the 95 % interval.
    study = {}  # rate id -> list of (scene, seed, error %, covered, half-width %, speed-up)
    for rid in SAMPLE_RATES:
        for s in SCENES:
            at_c, at_w = v("at_base", s, "cycles"), v("at_base", s, "sim_s")
            if not at_c:
                continue
            for seed, exp in [(1, f"at_{rid}_base")] + [(k, f"at_{rid}_seed{k}_base") for k in EXTRA_SEEDS]:
                c, lo, hi, w = v(exp, s, "cycles"), v(exp, s, "ci95_lo"), v(exp, s, "ci95_hi"), v(exp, s, "sim_s")
                if c and lo is not None and hi is not None and w:
                    study.setdefault(rid, []).append((s, seed, 100 * (c - at_c) / at_c, lo <= at_c <= hi, 100 * (hi - lo) / 2 / c, at_w / w))
    if study:
        n_seeds = 1 + len(EXTRA_SEEDS)
        p(f"## Sampled AT: accuracy and interval over {n_seeds} draws of the sample")
        p("")
        p(f"Each scene's frame sampled with sample seeds 1-{n_seeds} (`--sample-seed`; the rays stay the same), baseline "
          "configuration, against the full AT run. The interval is the run's own 95 % interval (`cycles_ci95`); "
          "coverage counts the runs whose interval holds the full run's cycles.")
        p("")
        p("| sample | runs | speed-up over AT (geomean) | mean abs. error | RMS error | max abs. error | interval covers | median half-width |")
        p("|---|---|---|---|---|---|---|---|")
        for rid in SAMPLE_RATES:
            rows = study.get(rid, [])
            if not rows:
                continue
            errs = [r[2] for r in rows]
            hws = sorted(r[4] for r in rows)
            gm = math.exp(sum(math.log(r[5]) for r in rows) / len(rows))
            p(f"| {float(SAMPLE_RATES[rid]) * 100:.0f} % | {len(rows)} | {gm:.1f}x | {sum(map(abs, errs)) / len(errs):.1f} % | "
              f"{math.sqrt(sum(e * e for e in errs) / len(errs)):.1f} % | {max(map(abs, errs)):.1f} % | "
              f"{sum(r[3] for r in rows)} of {len(rows)} | {hws[len(hws) // 2]:.1f} % |")
        p("")
        p("Per scene, mean error (bias) and its spread over the draws:")
        p("")
        p("| scene | " + " | ".join(f"{float(SAMPLE_RATES[r]) * 100:.0f} %: bias / SD" for r in SAMPLE_RATES) + " |")
        p("|---|" + "---|" * len(SAMPLE_RATES))
        for s in SCENES:
            cells = []
            for rid in SAMPLE_RATES:
                e = [r[2] for r in study.get(rid, []) if r[0] == s]
                if len(e) > 1:
                    m = sum(e) / len(e)
                    sd = math.sqrt(sum((x - m) ** 2 for x in e) / (len(e) - 1))
                    cells.append(f"{m:+.1f} % / {sd:.1f} %")
                else:
                    cells.append("-")
            p(f"| {s} | " + " | ".join(cells) + " |")
        p("")
        misses = [r for rid in SAMPLE_RATES for r in study.get(rid, []) if not r[3]]
        narrow = [r for r in misses if r[4] < 10]
        if misses:
            p(f"The {len(misses)} misses: " + ", ".join(f"{r[0]} seed {r[1]} ({r[2]:+.1f} % with +-{r[4]:.1f} %)" for r in misses) +
              f"; {len(narrow)} of them with an interval narrower than +-10 %.")
            p("")

    # Every fast run states its error (error_estimate.value); how often the measured error is within it.
    p("## The error each run stated, against the error measured")
    p("")
    p("Every LT, interval and sampled run writes `error_estimate` (docs/accuracy.md): a bound validated on the error "
      "grid, a sampling interval, or none where the run lies outside what was validated. Here each is set against "
      "its measured cycle error (against AT on the same scene and configuration).")
    p("")
    p("| fidelity | configuration | runs | stated an error | measured error within it | worst measured / stated |")
    p("|---|---|---|---|---|---|")
    for fid in FIDELITIES:
        if fid == "at":
            continue
        for pf, name in (("base", "baseline"), ("ttp", "TTP")):
            stated = within = runs = 0
            worst = 0.0
            for s in SCENES:
                c, at_c, bound = v(f"{fid}_{pf}", s, "cycles"), v(f"at_{pf}", s, "cycles"), v(f"{fid}_{pf}", s, "error_bound")
                if not c or not at_c:
                    continue
                runs += 1
                if bound is None:
                    continue
                stated += 1
                err = abs(c / at_c - 1)
                within += err <= bound
                if bound > 0:
                    worst = max(worst, err / bound)
            if runs:
                p(f"| {LABEL[fid]} | {name} | {runs} | {stated} | {within} of {stated} | "
                  f"{f'{worst:.2f}' if stated else '-'} |")
    p("")

    p("## Which fidelity for which question")
    p("")
    p("Each line below is computed from the tables above (mean and worst absolute cycle error over the scenes, "
      "speed-up as the geometric mean).")
    p("")
    p("- **Functional** (not in the table: it has no time) answers what the rays hit and how many nodes they visit "
      "(docs/foundation.md). Use it for BVH and traversal-order studies (nodes per ray, the paper's Table 1).")
    p("- **AT** is the reference: cycles, every cache and DRAM statistic, waveforms; final numbers and anything about "
      "queueing (reservation fails, DRAM bandwidth, arbitration).")
    lts = {q: row(f"lt_q{q}") for q in (100, 1000, 10000)}
    if all(lts.values()):
        best = min(lts, key=lambda q: lts[q][1])
        fastest = max(lts, key=lambda q: lts[q][0])
        same_error = len({tuple(round(x, 9) for x in lts[q][1:]) for q in lts}) == 1
        p("- **LT**: " + "; ".join(f"quantum {q:,}: {lts[q][0]:.2f}x faster than AT, cycles within {lts[q][1]:.2f} % on average "
                                  f"(worst {lts[q][2]:.2f} %), TTP speed-up within {lts[q][3]:.2f} %" for q in lts) +
          (f". The error is the same at every quantum (LT's statistics do not depend on it); the highest speed is at "
           f"quantum {fastest:,}." if same_error else
           f". The smallest error is at quantum {best:,}, the highest speed at quantum {fastest:,}" +
           (f" ({lts[fastest][0] / lts[best][0]:.2f}x the speed of quantum {best:,} for {lts[fastest][1] - lts[best][1]:+.2f} points "
            "of mean cycle error)." if fastest != best else ".")))
    iv = row("interval")
    if iv:
        lt_best = min((r for r in lts.values() if r), key=lambda r: r[1], default=None)
        cmp = ""
        if lt_best:
            faster = iv[0] > lt_best[0]
            closer = iv[1] < lt_best[1]
            cmp = (f" Against LT's most accurate quantum it is {'faster' if faster else 'slower'} "
                   f"({iv[0]:.2f}x against {lt_best[0]:.2f}x) and {'closer to' if closer else 'further from'} AT "
                   f"({iv[1]:.2f} % against {lt_best[1]:.2f} %).")
        p(f"- **Interval** (docs/interval.md): {iv[0]:.2f}x faster than AT, cycles within {iv[1]:.2f} % on average "
          f"(worst {iv[2]:.2f} %), TTP speed-up within {iv[3]:.2f} %.{cmp} It has no waveforms, no FR-FCFS DRAM queue, "
          "and models the prefetchers none and TTP only.")
    def study_line(rid):
        rows = study.get(rid, [])
        if not rows:
            return ""
        errs = [abs(r[2]) for r in rows]
        return (f"over {len(rows)} draws its cycles are off by {sum(errs) / len(errs):.1f} % on average (worst "
                f"{max(errs):.1f} %) and its 95 % interval holds the full run's cycles in {sum(r[3] for r in rows)} of {len(rows)}")
    for rid, rate in SAMPLE_RATES.items():
        r = row(f"at_{rid}")
        if r:
            p(f"- **Sampled AT at {float(rate) * 100:.0f} %**: {r[0]:.1f}x faster than AT (functional pre-pass included); "
              f"{study_line(rid)}; TTP speed-up within {r[3]:.1f} % of AT's.")
    ivs = {rid: row(f"iv_{rid}") for rid in SAMPLE_RATES}
    if all(ivs.values()):
        p("- **Sampled interval** at " + " / ".join(f"{float(SAMPLE_RATES[k]) * 100:.0f} %" for k in ivs) + ": " +
          " / ".join(f"{ivs[k][0]:.1f}x" for k in ivs) + " faster than AT, cycles within " +
          " / ".join(f"{ivs[k][1]:.1f} %" for k in ivs) + " on average.")
    zatel = [(LABEL[f], r) for f in FIDELITIES for r in [row(f)] if r and r[0] >= 10 and r[1] < 1.0]
    p(f"- Zatel's mark (< 1 % cycle error at 10x): " + (", ".join(f"met by {name} ({r[0]:.1f}x, {r[1]:.2f} %)" for name, r in zatel)
      if zatel else f"not met by any fidelity at {meta['size']}x{meta['size']} (docs/sampling.md has larger frames)") + ".")
    p("")
    (outdir / "README.md").write_text("\n".join(lines) + "\n")
    print(f"report: {outdir / 'README.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
