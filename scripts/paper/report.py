#!/usr/bin/python3
"""Writes reports/paper/README.md and its PNG plots from a sweep's results.csv (scripts/paper.sh).

Every figure of ours stands next to the paper's, and every comparison (direction, rank order,
share of the paper's gain) is computed from the data: the paper's figures are the constants in
PAPER below, each with the place in the paper it comes from."""
import datetime
import math
import os
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
from report_util import Markdown, direction, geomean, load, mean, number, order, pct, share_words, times  # noqa: E402

SCENES = ["wknd", "cornell", "ship", "bunny", "ref", "bath", "sprng", "party"]
PAPER_SCENES = [s for s in SCENES if s != "cornell"]  # geometric means that compare with the paper's

# The paper's figures (ISCA 2026, ../shared/paper/ttp-isca2026.tex), in one place.
PAPER = {
    "ttp": 1.48, "ttp_max": 1.89, "power": 1.35, "energy": 0.91,           # Section 6.1, Figure 'dfsspeeduppowerenergy_pt'
    "perfect_up": 1.79, "perfect_down": 1.35,                               # Figure 'perfectpref'
    "l1_64": 1.44, "l1_128": 1.44,                                          # Figure 'largedcache'
    "l1_mpki_drop": 0.2828, "l2_mpki_drop": 0.4001,                         # Figure 'mpki'
    "l1_accuracy": 0.9892, "l2_accuracy": 0.8981,                           # Figure 'dfs_accuracy'
    "l1_coverage": 0.3154, "l2_coverage": 0.3346,
    "l1_efficiency": 0.5856, "l2_efficiency": 0.6485,                       # Figure 'cache_response_breakdown'
    "res256": 1.44,                                                         # Figure 'highres'
    "desktop": 1.50, "desktop_max": 1.93,                                   # Figure 'desktop_speedup'
    "bfs_n1": 1.85, "bfs_n2": 2.05, "bfs_n4": 2.20,                         # Figure 'bfsspeedup_pt' (over BFS)
    "bfs_ttp_over_dfs": 1.61,                                               # Figure 'bfsvsdfs' (BFS+TTP over DFS)
    "treelet_32": 1.14, "treelet_64": 1.00, "treelet_128": 1.00,           # Figure 'treeletres'
    "ttp_32": 1.44, "ttp_64": 1.49, "ttp_128": 1.48,
    "treelet_dram": 1.38,                                                   # Figure 'treelet_dram_reads'
    "park": 1.04, "park_max": 1.11,                                         # Figure 'parketal'
    "ao": 1.22, "sh": 1.18,                                                 # Figure 'speedupaosh'
    # Table 1: DFS / BFS nodes per ray.
    "nodes": {"wknd": (13.3, 13.3), "ship": (43.3, 46.6), "bunny": (11.3, 12.5), "ref": (11.3, 12.7), "bath": (18.4, 21.1),
              "party": (34.8, 37.4), "sprng": (31.4, 38.7)},
}


class Report(Markdown):
    def __init__(self, data, outdir):
        super().__init__()
        self.d = data
        self.out = outdir

    def val(self, exp, scene, col):
        return number(self.d, exp, scene, col)

    def scenes_with(self, *exps):
        return [s for s in SCENES if all(self.val(e, s, "cycles") for e in exps)]

    def speedup(self, exp, base, scene):
        b, e = self.val(base, scene, "cycles"), self.val(exp, scene, "cycles")
        return b / e if b and e else None

    def gm(self, series):
        """Geometric mean over the paper's scenes only (cornell is not one)."""
        return geomean([v for s, v in series.items() if s in PAPER_SCENES])

    def bars(self, name, title, series, ylabel="speed-up over baseline", hline=1.0):
        scenes = [s for s in SCENES if any(v.get(s) for v in series.values())]
        if not scenes:
            return
        fig, ax = plt.subplots(figsize=(8, 3.2))
        w = 0.8 / max(1, len(series))
        for i, (label, vals) in enumerate(series.items()):
            ax.bar([j + i * w for j in range(len(scenes))], [vals.get(s) or 0 for s in scenes], w, label=label)
        ax.set_xticks([j + w * (len(series) - 1) / 2 for j in range(len(scenes))])
        ax.set_xticklabels(scenes)
        if hline is not None:
            ax.axhline(hline, color="black", linewidth=0.8)
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.legend(fontsize=8, ncol=min(4, len(series)))
        fig.tight_layout()
        fig.savefig(self.out / f"{name}.png", dpi=110)
        plt.close(fig)
        self.p(f"![{title}]({name}.png)")
        self.p()

    def speedups(self, title, exps, base, paper=None, plot=None):
        """exps: {label: experiment}; per-scene speed-ups over `base` and their geomeans; with
        `paper` ({label: the paper's geomean}), the direction of each and the rank order."""
        self.p(f"## {title}")
        self.p()
        scenes = self.scenes_with(base, *exps.values())
        series = {lbl: {s: self.speedup(e, base, s) for s in scenes} for lbl, e in exps.items()}
        rows = [[s] + [times(series[l][s]) for l in exps] for s in scenes]
        gms = {l: self.gm(series[l]) for l in exps}
        rows.append(["**geomean**"] + [f"**{times(gms[l])}**" for l in exps])
        if paper:
            rows.append(["paper"] + [times(paper.get(l)) if l in paper else "-" for l in exps])
        self.table(["scene"] + list(exps), rows)
        if plot:
            self.bars(plot, title, series)
        if paper:
            dirs = [f"{l}: {direction(gms[l], paper[l])}" for l in exps if l in paper]
            self.p("Direction against the paper (above or below 1x): " + "; ".join(dirs) + ".")
            if len([l for l in exps if l in paper]) > 1:
                self.p(f"Rank order of the variants: {order(gms, paper)} (ours: {' > '.join(sorted(gms, key=lambda k: -gms[k]))}; "
                       f"paper: {' > '.join(sorted(paper, key=lambda k: -paper[k]))}).")
            self.p()
        return series, gms


def main():
    results, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    outdir.mkdir(parents=True, exist_ok=True)
    data, meta = load(results)
    R = Report(data, outdir)
    d = R.d
    size = f"{meta['size']}x{meta['size']}"
    failed = [k for k, r in d.items() if r["exit"] not in ("0", 0, "")]
    missing = [k for k, r in d.items() if r["exit"] == ""]
    wall = sum(float(r["wall_s"] or 0) for r in d.values())
    scenes_run = sorted({s for (_, s) in d}, key=SCENES.index)
    R.p("# The TTP paper's experiments, reproduced on rtunit")
    R.p()
    R.p(f"Generated {datetime.date.today()} by `scripts/paper.sh` from `{results.name}`: {len(d)} runs ({len(failed)} failed, "
        f"{len(missing)} not run), {wall / 60:.1f} minutes of simulation summed. AT fidelity, {meta.get('config', 'mobile')} "
        f"preset unless stated, path tracing {size}, {meta['spp']} spp, DFS, seed 1. Scenes: {', '.join(scenes_run)}. "
        "Geometric means are over the paper's scenes among them (cornell is not one). Speed-up = baseline cycles / cycles.")
    R.p()
    if failed:
        R.p("Failed runs (see their .err files): " + ", ".join("/".join(k) for k in failed))
        R.p()
    if missing:
        R.p("Not run (yet): " + ", ".join("/".join(k) for k in missing) + ". Rerun scripts/paper.sh to resume.")
        R.p()

    # 1. Overall.
    R.p("## Speed-up, power and energy of TTP (paper Figure 'dfsspeeduppowerenergy_pt')")
    R.p()
    scenes = R.scenes_with("base", "ttp")
    sp = {s: R.speedup("ttp", "base", s) for s in scenes}
    pw = {s: R.val("ttp", s, "power_w") / R.val("base", s, "power_w") for s in scenes}
    en = {s: R.val("ttp", s, "energy_j") / R.val("base", s, "energy_j") for s in scenes}
    rows = [[s, times(sp[s]), times(pw[s]), times(en[s]), f"{R.val('base', s, 'cycles'):.0f}", f"{R.val('ttp', s, 'cycles'):.0f}"]
            for s in scenes]
    g_sp, g_pw, g_en = R.gm(sp), R.gm(pw), R.gm(en)
    rows.append(["**geomean**", f"**{times(g_sp)}**", f"**{times(g_pw)}**", f"**{times(g_en)}**", "", ""])
    rows.append(["paper", times(PAPER["ttp"]), times(PAPER["power"]), times(PAPER["energy"]), "", ""])
    R.table(["scene", "speed-up", "power", "energy", "baseline cycles", "TTP cycles"], rows)
    R.bars("overall", "TTP speed-up, power and energy (normalised to baseline)", {"speed-up": sp, "power": pw, "energy": en}, ylabel="x baseline")
    peak_scene = max((s for s in sp if s in PAPER_SCENES), key=lambda s: sp[s], default=None)
    low_scene = min((s for s in sp if s in PAPER_SCENES), key=lambda s: sp[s], default=None)
    pu = R.gm({s: R.speedup("perfect_up", "base", s) for s in R.scenes_with("base", "perfect_up")})
    R.p(f"Ours: {times(g_sp, 2)} geomean, peak {times(sp.get(peak_scene), 2)} ({peak_scene}), least {times(sp.get(low_scene), 2)} "
        f"({low_scene}); paper: {times(PAPER['ttp'], 2)}, peak {times(PAPER['ttp_max'], 2)}, wknd least. Direction: speed-up "
        f"{direction(g_sp, PAPER['ttp'])}, power {direction(g_pw, PAPER['power'])}, energy {direction(g_en, PAPER['energy'])}. "
        f"Our TTP gain ({pct(g_sp - 1)}) is {share_words(g_sp - 1, PAPER['ttp'] - 1)} of the paper's ({pct(PAPER['ttp'] - 1)}); "
        f"the perfect-upward limit, which bounds it, is {times(pu, 2)} here against the paper's {times(PAPER['perfect_up'], 2)}, "
        f"and TTP reaches {share_words(g_sp - 1, pu - 1)} of it (paper: {share_words(PAPER['ttp'] - 1, PAPER['perfect_up'] - 1)}).")
    R.p()

    # 2. Limit studies.
    R.speedups("Perfect upward and downward traversal (paper Figure 'perfectpref')",
               {"perfect-up": "perfect_up", "perfect-down": "perfect_down", "TTP": "ttp"}, "base",
               {"perfect-up": PAPER["perfect_up"], "perfect-down": PAPER["perfect_down"], "TTP": PAPER["ttp"]}, plot="perfect")

    # 3. Larger L1.
    R.p("## Larger L1 caches (paper Figure 'largedcache')")
    R.p()
    sc = R.scenes_with("l1_64_base", "l1_64_ttp", "l1_128_base", "l1_128_ttp", "base", "ttp")
    s32 = {s: R.speedup("ttp", "base", s) for s in sc}
    s64 = {s: R.speedup("l1_64_ttp", "l1_64_base", s) for s in sc}
    s128 = {s: R.speedup("l1_128_ttp", "l1_128_base", s) for s in sc}
    rows = [[s, times(s32[s]), times(s64[s]), times(s128[s])] for s in sc]
    rows.append(["**geomean**", f"**{times(R.gm(s32))}**", f"**{times(R.gm(s64))}**", f"**{times(R.gm(s128))}**"])
    rows.append(["paper", times(PAPER["ttp"]), times(PAPER["l1_64"]), times(PAPER["l1_128"])])
    R.table(["scene", "TTP, 32 KB L1", "TTP, 64 KB L1 (vs 64 KB baseline)", "TTP, 128 KB L1 (vs 128 KB baseline)"], rows)
    if sc:
        R.p(f"The paper's speed-up hardly changes with L1 size ({times(PAPER['ttp'], 2)}, {times(PAPER['l1_64'], 2)}, "
            f"{times(PAPER['l1_128'], 2)}); ours goes {times(R.gm(s32), 2)} -> {times(R.gm(s64), 2)} -> {times(R.gm(s128), 2)} "
            f"({100 * (R.gm(s128) / R.gm(s32) - 1):+.1f} % from 32 to 128 KB). Direction at 64 and 128 KB: "
            f"{direction(R.gm(s64), PAPER['l1_64'])}, {direction(R.gm(s128), PAPER['l1_128'])}.")
        R.p()

    # 4. MPKI.
    R.p("## RT-read misses per kilo node fetch (paper Figure 'mpki', per kilo-instruction there)")
    R.p()
    rows, r1, r2 = [], {}, {}
    for s in R.scenes_with("base", "ttp"):
        a1, b1 = R.val("base", s, "l1_mpkf"), R.val("ttp", s, "l1_mpkf")
        a2, b2 = R.val("base", s, "l2_mpkf"), R.val("ttp", s, "l2_mpkf")
        r1[s] = b1 / a1 if a1 else None
        r2[s] = b2 / a2 if a2 else None
        rows.append([s, f"{a1:.1f} -> {b1:.1f}", times(r1[s]), f"{a2:.1f} -> {b2:.1f}", times(r2[s])])
    R.table(["scene", "L1 misses / 1000 node fetches", "ratio", "L2", "ratio"], rows)
    drop1 = 1 - mean([v for s, v in r1.items() if s in PAPER_SCENES])
    drop2 = 1 - mean([v for s, v in r2.items() if s in PAPER_SCENES])
    R.p(f"Mean fall (1 - mean of the ratios): L1 {pct(drop1, 2)}, L2 {pct(drop2, 2)}; paper {pct(PAPER['l1_mpki_drop'], 2)} and "
        f"{pct(PAPER['l2_mpki_drop'], 2)}. Direction: L1 {direction(1 - drop1, 1 - PAPER['l1_mpki_drop'])}, L2 "
        f"{direction(1 - drop2, 1 - PAPER['l2_mpki_drop'])}; ours is {share_words(drop1, PAPER['l1_mpki_drop'])} of the "
        f"paper's fall at L1 and {share_words(drop2, PAPER['l2_mpki_drop'])} at L2. We count per node fetch, not per "
        "instruction (the RT unit is all we simulate); the ratio to the baseline does not depend on the unit.")
    R.p()

    # 5. Accuracy and coverage.
    R.p("## Accuracy and coverage (paper Figure 'dfs_accuracy')")
    R.p()
    rows, acc, cov = [], {"l1": {}, "l2": {}}, {"l1": {}, "l2": {}}
    for s in R.scenes_with("base", "ttp"):
        for lvl in ("l1", "l2"):
            acc[lvl][s] = R.val("ttp", s, f"{lvl}_pf_accuracy")
            m = R.val("base", s, f"{lvl}_demand_misses")
            cov[lvl][s] = R.val("ttp", s, f"{lvl}_pf_useful") / m if m else None
        rows.append([s, pct(acc["l1"][s]), pct(acc["l2"][s]), pct(cov["l1"][s]), pct(cov["l2"][s])])
    m_acc = {lvl: mean([v for s, v in acc[lvl].items() if s in PAPER_SCENES]) for lvl in acc}
    m_cov = {lvl: mean([v for s, v in cov[lvl].items() if s in PAPER_SCENES]) for lvl in cov}
    rows.append(["**mean**", f"**{pct(m_acc['l1'])}**", f"**{pct(m_acc['l2'])}**", f"**{pct(m_cov['l1'])}**", f"**{pct(m_cov['l2'])}**"])
    rows.append(["paper", pct(PAPER["l1_accuracy"]), pct(PAPER["l2_accuracy"]), pct(PAPER["l1_coverage"]), pct(PAPER["l2_coverage"])])
    R.table(["scene", "L1 accuracy", "L2 accuracy", "L1 coverage", "L2 coverage"], rows)
    R.p("Definitions: accuracy = prefetched sectors later read by a demand request / sectors brought in by prefetches; "
        "coverage = useful prefetches / baseline demand misses (sector, line and MSHR-hit misses) of the same cache.")
    R.p()
    R.p("Ours against the paper: " + "; ".join(
        f"{lvl.upper()} accuracy {pct(m_acc[lvl])} ({'within' if abs(m_acc[lvl] - PAPER[lvl + '_accuracy']) <= 0.02 else 'outside'} "
        f"2 points of {pct(PAPER[lvl + '_accuracy'])}), coverage {share_words(m_cov[lvl], PAPER[lvl + '_coverage'])} of the paper's"
        for lvl in ("l1", "l2")) + ".")
    R.p()

    # 6. Response breakdown.
    R.p("## Cache responses to prefetches (paper Figure 'cache_response_breakdown')")
    R.p()
    rows, eff = [], {"l1": {}, "l2": {}}
    for s in R.scenes_with("ttp"):
        for lvl in ("l1", "l2"):
            parts = [R.val("ttp", s, f"{lvl}_pf_{k}") or 0 for k in ("hit", "mshr_hit", "miss_free", "resfail")]
            tot = sum(parts)
            if not tot:
                continue
            rows.append([s, lvl.upper()] + [pct(x / tot) for x in parts])
            eff[lvl][s] = parts[2] / tot
    R.table(["scene", "cache", "hit", "MSHR hit", "MSHR miss, free entry (efficiency)", "reservation fail"], rows)
    m_eff = {lvl: mean([v for s, v in eff[lvl].items() if s in PAPER_SCENES]) for lvl in eff}
    R.p(f"Efficiency (the share of prefetches that missed with an MSHR free), mean: L1 {pct(m_eff['l1'])} (paper "
        f"{pct(PAPER['l1_efficiency'])}), L2 {pct(m_eff['l2'])} (paper {pct(PAPER['l2_efficiency'])}); ours is "
        f"{share_words(m_eff['l1'], PAPER['l1_efficiency'])} of the paper's at L1 and {share_words(m_eff['l2'], PAPER['l2_efficiency'])} "
        "at L2.")
    R.p()

    # 7-8. 256x256, desktop.
    if R.scenes_with("res256_base", "res256_ttp"):
        _, g = R.speedups("256x256 (paper Figure 'highres')", {"TTP at 256x256": "res256_ttp"}, "res256_base",
                          {"TTP at 256x256": PAPER["res256"]})
        R.p(f"Our speed-up at 256x256 is {100 * (g['TTP at 256x256'] / g_sp - 1):+.1f} % from our {size} figure; the paper's is "
            f"{100 * (PAPER['res256'] / PAPER['ttp'] - 1):+.1f} % from its 128x128 figure.")
        R.p()
    _, g = R.speedups("Larger GPU: the desktop preset (paper Figure 'desktop_speedup')", {"TTP, desktop": "desktop_ttp"}, "desktop_base",
                      {"TTP, desktop": PAPER["desktop"]})
    R.p(f"Desktop against mobile: ours {times(g['TTP, desktop'], 2)} against {times(g_sp, 2)} "
        f"({'above' if g['TTP, desktop'] > g_sp else 'below'}); paper {times(PAPER['desktop'], 2)} against {times(PAPER['ttp'], 2)} "
        f"({'above' if PAPER['desktop'] > PAPER['ttp'] else 'below'}): {'agrees' if (g['TTP, desktop'] > g_sp) == (PAPER['desktop'] > PAPER['ttp']) else 'differs'}.")
    R.p()

    # 9-10. Arbitration and intensity.
    _, g = R.speedups("Prefetch arbitration (paper Figure 'arbitration')",
                      {"free cycles only": "ttp", "X=25": "arb25", "X=50": "arb50", "X=100": "arb100"}, "base", plot="arbitration")
    spread = max(g.values()) / min(g.values()) - 1 if g else float("nan")
    R.p(f"The paper: 'on average, arbitration makes little to no difference'. Ours: the geomeans differ by {pct(spread)} "
        f"between the best and the worst setting ({'within' if spread <= 0.02 else 'beyond'} 2 %).")
    R.p()
    _, g = R.speedups("Prefetch intensity: depths of S1-S2-S3 (paper Figure 'dfs_aggressiveness')",
                      {"1-1-1": "int_1_1_1", "1-2-4": "int_1_2_4", "1-2-16": "ttp", "2-4-8": "int_2_4_8", "4-8-16": "int_4_8_16"},
                      "base", plot="intensity")
    spread = max(g.values()) / min(g.values()) - 1 if g else float("nan")
    R.p(f"The paper: 'TTP is not sensitive to this parameter'. Ours: {pct(spread)} between the best "
        f"({max(g, key=g.get)}) and the worst ({min(g, key=g.get)}) setting.")
    R.p()

    # 11-12. BFS.
    R.speedups("TTP with BFS, N = 1, 2, 4 (paper Figure 'bfsspeedup_pt'), over BFS without TTP",
               {"N=1": "bfs_ttp_n1", "N=2": "bfs_ttp_n2", "N=4": "bfs_ttp_n4"}, "bfs_base",
               {"N=1": PAPER["bfs_n1"], "N=2": PAPER["bfs_n2"], "N=4": PAPER["bfs_n4"]}, plot="bfs")
    series, g = R.speedups("BFS against DFS, with and without TTP (paper Figure 'bfsvsdfs'), normalised to DFS without TTP",
                           {"DFS+TTP": "ttp", "BFS": "bfs_base", "BFS+TTP N=4": "bfs_ttp_n4"}, "base")
    paper_scenes = [s for s in series["BFS"] if s in PAPER_SCENES]
    slower = [s for s in paper_scenes if series["BFS"][s] and series["BFS"][s] < 1]
    wins = [s for s in paper_scenes if series["BFS+TTP N=4"][s] and series["DFS+TTP"][s] and series["BFS+TTP N=4"][s] > series["DFS+TTP"][s]]
    R.p(f"The paper: without prefetching BFS is slower than DFS on every scene; with TTP, BFS beats DFS on average "
        f"({times(PAPER['bfs_ttp_over_dfs'], 2)}). Ours: BFS alone is slower on {len(slower)} of {len(paper_scenes)} of the paper's scenes; "
        f"BFS+TTP over DFS {times(g['BFS+TTP N=4'], 2)} (direction {direction(g['BFS+TTP N=4'], PAPER['bfs_ttp_over_dfs'])}), "
        f"and above DFS+TTP on {', '.join(wins) or 'no scene'} (geomean {times(g['BFS+TTP N=4'], 2)} against "
        f"{times(g['DFS+TTP'], 2)}: {'above' if g['BFS+TTP N=4'] > g['DFS+TTP'] else 'below'}).")
    R.p()

    # 13. Treelet.
    R.p("## Treelet prefetcher against TTP (paper Figures 'treeletvs_pt', 'treeletres', 'treelet_dram_reads')")
    R.p()
    R.p("Treelet = treelet traversal (two stacks) with whole-treelet prefetching, 512 B treelets, threshold 0.75, "
        "normalised to the DFS baseline at the same resolution, as in the paper.")
    R.p()
    rows, ser = [], {}
    for label, key, (tl, ttp, base) in (("32x32", "32", ("res32_treelet", "res32_ttp", "res32_base")),
                                         ("64x64", "64", ("res64_treelet", "res64_ttp", "res64_base")),
                                         (size, "128", ("treelet", "ttp", "base"))):
        sc = R.scenes_with(tl, ttp, base)
        if not sc:
            continue
        t_sp = {x: R.speedup(tl, base, x) for x in sc}
        p_sp = {x: R.speedup(ttp, base, x) for x in sc}
        dram = {x: R.val(tl, x, "dram_reads") / R.val(base, x, "dram_reads") for x in sc if R.val(base, x, "dram_reads")}
        ser[f"Treelet {label}"], ser[f"TTP {label}"] = t_sp, p_sp
        ours = {"Treelet": R.gm(t_sp), "TTP": R.gm(p_sp)}
        paper = {"Treelet": PAPER[f"treelet_{key}"], "TTP": PAPER[f"ttp_{key}"]}
        rows.append([label, times(ours["Treelet"]), times(paper["Treelet"]), times(ours["TTP"]), times(paper["TTP"]),
                     times(R.gm(dram), 2), order(ours, paper)])
    R.table(["resolution", "Treelet (ours)", "Treelet (paper)", "TTP (ours)", "TTP (paper)", "Treelet DRAM reads vs baseline",
             "TTP above Treelet, as in the paper"], rows)
    R.bars("treelet", "Treelet and TTP speed-ups by resolution", ser)
    sc = R.scenes_with("treelet_trav", "base")
    if sc:
        R.p(f"Treelet traversal alone (no prefetching) runs at {times(R.gm({x: R.speedup('treelet_trav', 'base', x) for x in sc}))} "
            "of the DFS baseline.")
        R.p()
    R.p(f"Paper: Treelet raises DRAM reads {times(PAPER['treelet_dram'], 2)}.")
    R.p()

    # 14. Park.
    _, g = R.speedups("Park et al. (paper Figure 'parketal')", {"Park": "park", "TTP": "ttp"}, "base",
                      {"Park": PAPER["park"], "TTP": PAPER["ttp"]}, plot="park")
    R.p(f"The paper has Park far below TTP ({share_words(PAPER['park'] - 1, PAPER['ttp'] - 1)} of TTP's gain); ours: "
        f"{share_words(g['Park'] - 1, g['TTP'] - 1)}.")
    R.p()

    # 15. AO and SH.
    _, g_ao = R.speedups("Ambient occlusion (paper Figure 'speedupaosh')", {"AO": "ao_ttp"}, "ao_base", {"AO": PAPER["ao"]})
    _, g_sh = R.speedups("Shadow rays (paper Figure 'speedupaosh')", {"SH": "sh_ttp"}, "sh_base", {"SH": PAPER["sh"]})
    R.p(f"The paper's AO and SH gains are below path tracing's ({times(PAPER['ao'], 2)}, {times(PAPER['sh'], 2)} against "
        f"{times(PAPER['ttp'], 2)}); ours: {times(g_ao['AO'], 2)}, {times(g_sh['SH'], 2)} against {times(g_sp, 2)}: "
        f"{'agrees' if max(g_ao['AO'], g_sh['SH']) < g_sp else 'differs'}.")
    R.p()

    # 16. Pop streaks.
    R.p("## Pop-streak analysis (paper Figure 'pop_miss_rates'), baseline DFS")
    R.p()
    rows, largest, later_share = [], {}, {}
    classes = ["not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"]
    for s in R.scenes_with("base"):
        fetch = [R.val("base", s, f"streak_{c}_node_fetches") or 0 for c in classes]
        dram = [R.val("base", s, f"streak_{c}_dram_misses") or 0 for c in classes]
        pops, dpop = sum(fetch[1:]), sum(dram[1:])
        rows.append([s] + [pct(x / pops) if pops else "-" for x in fetch[1:]] + [pct(x / dpop) if dpop else "-" for x in dram[1:]])
        if pops and dpop and s in PAPER_SCENES:
            largest[s] = max(range(1, 5), key=lambda i: fetch[i])
            later_share[s] = sum(dram[2:]) / dpop
    R.table(["scene", "pops: 1st", "2nd", "3rd", "4th+", "DRAM misses of pops: 1st", "2nd", "3rd", "4th+"], rows)
    first_largest = [s for s, c in largest.items() if c == 1]
    R.p("The paper: single pops make up most of the stack activity, longer streaks a large share of the misses. Ours: the "
        f"first pop is the largest class on {len(first_largest)} of {len(largest)} of the paper's scenes"
        f"{' (not on ' + ', '.join(s for s in largest if s not in first_largest) + ')' if len(first_largest) < len(largest) else ''}; "
        f"second and later pops carry {pct(min(later_share.values()) if later_share else None, 0)} to "
        f"{pct(max(later_share.values()) if later_share else None, 0)} of the pops' DRAM misses.")
    R.p()

    # 17. Table 1.
    R.p("## DFS and BFS nodes per ray (paper Table 1)")
    R.p()
    rows, more = [], []
    for s in R.scenes_with("base", "bfs_base"):
        a, b = R.val("base", s, "nodes_per_ray"), R.val("bfs_base", s, "nodes_per_ray")
        ma, mb = R.val("base", s, "max_nodes_per_ray"), R.val("bfs_base", s, "max_nodes_per_ray")
        pp = PAPER["nodes"].get(s)
        if s in PAPER_SCENES:
            more.append(b >= a)
        rows.append([s, f"{a:.1f}", f"{b:.1f}", f"{100 * (b / a - 1):+.1f} %", f"{ma:.0f}", f"{mb:.0f}",
                     f"{pp[0]} / {pp[1]}" if pp else "-", f"{100 * (a / pp[0] - 1):+.0f} %" if pp else "-"])
    R.table(["scene", "DFS avg", "BFS avg", "diff", "DFS max", "BFS max", "paper DFS / BFS avg", "our DFS vs paper's"], rows)
    R.p(f"BFS visits at least as many nodes as DFS on {sum(more)} of {len(more)} of the paper's scenes (the paper: on every scene).")
    R.p()
    (outdir / "README.md").write_text(R.text())
    print(f"report: {outdir / 'README.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
