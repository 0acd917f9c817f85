#!/usr/bin/env python3
"""The TTP paper's Results section as a sweep manifest: one line per run (scene, rtsim arguments,
output path). Every run uses the `paper` preset (the TTP authors' MOBILE setup, docs/paper-preset.md)
unless its id starts with `desktop_` (the authors' RTX 2060 setup), `mobile_` (the paper's
Table 2 alone, for the report's second column) or `without_` (the `paper` preset without the keys
by which it follows the authors' RT unit and application beyond their configuration file:
scripts/reference/paper_keys.py).
Usage: experiments.py MANIFEST [--size N] [--spp N] [--scenes a,b,...] [--no-256]"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
from paper_keys import set_arguments  # noqa: E402
from scenes import arguments, write_manifest  # noqa: E402

TTP_DEPTHS = "--set prefetch.ttp_depth_s1={} --set prefetch.ttp_depth_s2={} --set prefetch.ttp_depth_s3={}"
TREELET = "--traversal treelet --prefetcher treelet"
CONTIGUOUS = "--set prefetch.treelet_layout=contiguous"

# (experiment id, rtsim arguments after the preset) for the experiments at the sweep's frame size.
MAIN = [
    ("base", ""),
    ("ttp", "--prefetcher ttp"),
    ("perfect_up", "--prefetcher perfect-up"),
    ("perfect_down", "--prefetcher perfect-down"),
    ("l1_64_base", "--set l1.size_kb=64"),
    ("l1_64_ttp", "--set l1.size_kb=64 --prefetcher ttp"),
    ("l1_128_base", "--set l1.size_kb=128"),
    ("l1_128_ttp", "--set l1.size_kb=128 --prefetcher ttp"),
    ("arb25", "--prefetcher ttp --set prefetch.priority_after=25"),
    ("arb50", "--prefetcher ttp --set prefetch.priority_after=50"),
    ("arb100", "--prefetcher ttp --set prefetch.priority_after=100"),
    ("int_1_1_1", "--prefetcher ttp " + TTP_DEPTHS.format(1, 1, 1)),
    ("int_1_2_4", "--prefetcher ttp " + TTP_DEPTHS.format(1, 2, 4)),
    ("int_2_4_8", "--prefetcher ttp " + TTP_DEPTHS.format(2, 4, 8)),
    ("int_4_8_16", "--prefetcher ttp " + TTP_DEPTHS.format(4, 8, 16)),
    ("bfs_base", "--traversal bfs"),
    ("bfs_ttp_n1", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=1"),
    ("bfs_ttp_n2", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=2"),
    ("bfs_ttp_n4", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=4"),
    ("park", "--prefetcher park"),
    ("ao_base", "--workload ao"),
    ("ao_ttp", "--workload ao --prefetcher ttp"),
    ("sh_base", "--workload sh"),
    ("sh_ttp", "--workload sh --prefetcher ttp"),
    ("treelet", TREELET),
    ("treelet_contiguous", f"{TREELET} {CONTIGUOUS}"),
    ("treelet_trav", "--traversal treelet"),
    ("treelet_first", f"{TREELET} --set prefetch.treelet_order=treelets"),
    # The spread over ray seeds: the speed-up of one frame is one draw of the rays' paths.
    ("seed2_base", "--seed 2"), ("seed2_ttp", "--seed 2 --prefetcher ttp"),
    ("seed3_base", "--seed 3"), ("seed3_ttp", "--seed 3 --prefetcher ttp"),
    # Figure 1 (thread status) is at 1 sample per pixel.
    ("spp1_base", "--spp 1"), ("spp1_ttp", "--spp 1 --prefetcher ttp"),
]
# The same experiments on other presets: desktop (paper Figure 'desktop_speedup') and mobile (the
# paper's Table 2 alone), which shows what the authors' simulator details weigh.
OTHER_PRESETS = {
    "desktop": ["base", "ttp"],
    "mobile": ["base", "ttp", "perfect_up", "perfect_down", "park", "bfs_base", "bfs_ttp_n4", "treelet"],
}
# The `paper` preset without the authors' in-flight merging and shader reads (paper_keys.py): what
# they do to the figures the reference issue names.
WITHOUT = ["base", "ttp", "perfect_up", "perfect_down", "park", "treelet"]


def experiments(size, spp, with_256):
    """(experiment id, rtsim arguments). Every run is AT, path tracing, DFS unless stated."""
    def run(preset, frame, extra):
        workload = "" if "--workload" in extra else "--workload pt "
        spp_arg = "" if "--spp" in extra else f"--spp {spp} "
        return f"--config {preset} --fidelity at --width {frame} --height {frame} {spp_arg}{workload}{extra}".strip()

    main = dict(MAIN)
    runs = [(eid, run("paper", size, a)) for eid, a in MAIN]
    for preset, eids in OTHER_PRESETS.items():
        runs += [(f"{preset}_{eid}", run(preset, size, main[eid])) for eid in eids]
    keys = " ".join(set_arguments())
    runs += [(f"without_{eid}", run("paper", size, f"{keys} {main[eid]}".strip())) for eid in WITHOUT]
    for small in (32, 64):  # the paper's resolution study of Treelet against TTP
        for eid in ("base", "ttp", "treelet", "treelet_contiguous"):
            runs.append((f"res{small}_{eid}", run("paper", small, main[eid])))
    if with_256:
        runs += [(f"res256_{eid}", run("paper", 256, main[eid])) for eid in ("base", "ttp")]
    return runs


def main():
    a = arguments(__doc__, lambda ap: ap.add_argument("--no-256", action="store_true", help="skip the 256x256 runs (4x longer)"))
    write_manifest(a, experiments(a.size, a.spp, not a.no_256), with_256=not a.no_256, config="paper")


if __name__ == "__main__":
    main()
