#!/usr/bin/env python3
"""The TTP paper's Results section as a sweep manifest: one line per run (scene, rtsim arguments,
output path). Usage: experiments.py MANIFEST [--size N] [--spp N] [--scenes a,b,...] [--no-256]"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
from scenes import arguments, write_manifest  # noqa: E402


def experiments(size, spp, with_256):
    """(experiment id, extra rtsim arguments). Every run is AT, path tracing, DFS unless stated."""
    e = [
        ("base", ""),
        ("ttp", "--prefetcher ttp"),
        ("perfect_up", "--prefetcher perfect-up"),
        ("perfect_down", "--prefetcher perfect-down"),
        ("l1_64_base", "--set l1.size_kb=64"),
        ("l1_64_ttp", "--set l1.size_kb=64 --prefetcher ttp"),
        ("l1_128_base", "--set l1.size_kb=128"),
        ("l1_128_ttp", "--set l1.size_kb=128 --prefetcher ttp"),
        ("desktop_base", "--config desktop"),
        ("desktop_ttp", "--config desktop --prefetcher ttp"),
        ("arb25", "--prefetcher ttp --set prefetch.priority_after=25"),
        ("arb50", "--prefetcher ttp --set prefetch.priority_after=50"),
        ("arb100", "--prefetcher ttp --set prefetch.priority_after=100"),
        ("int_1_1_1", "--prefetcher ttp --set prefetch.ttp_depth_s1=1 --set prefetch.ttp_depth_s2=1 --set prefetch.ttp_depth_s3=1"),
        ("int_1_2_4", "--prefetcher ttp --set prefetch.ttp_depth_s1=1 --set prefetch.ttp_depth_s2=2 --set prefetch.ttp_depth_s3=4"),
        ("int_2_4_8", "--prefetcher ttp --set prefetch.ttp_depth_s1=2 --set prefetch.ttp_depth_s2=4 --set prefetch.ttp_depth_s3=8"),
        ("int_4_8_16", "--prefetcher ttp --set prefetch.ttp_depth_s1=4 --set prefetch.ttp_depth_s2=8 --set prefetch.ttp_depth_s3=16"),
        ("bfs_base", "--traversal bfs"),
        ("bfs_ttp_n1", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=1"),
        ("bfs_ttp_n2", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=2"),
        ("bfs_ttp_n4", "--traversal bfs --prefetcher ttp --set prefetch.bfs_n=4"),
        ("park", "--prefetcher park"),
        ("ao_base", "--workload ao"),
        ("ao_ttp", "--workload ao --prefetcher ttp"),
        ("sh_base", "--workload sh"),
        ("sh_ttp", "--workload sh --prefetcher ttp"),
    ]
    runs = [(eid, f"--fidelity at --width {size} --height {size} --spp {spp} " + (a if "--workload" in a else "--workload pt " + a))
            for eid, a in e]
    runs.append(("treelet", f"--fidelity at --width {size} --height {size} --spp {spp} --workload pt --traversal treelet --prefetcher treelet"))
    runs.append(("treelet_trav", f"--fidelity at --width {size} --height {size} --spp {spp} --workload pt --traversal treelet"))
    for small in (32, 64):  # the paper's resolution study of Treelet against TTP
        for eid, extra in (("base", ""), ("ttp", "--prefetcher ttp"), ("treelet", "--traversal treelet --prefetcher treelet")):
            runs.append((f"res{small}_{eid}", f"--fidelity at --width {small} --height {small} --spp {spp} --workload pt {extra}".strip()))
    if with_256:
        runs += [("res256_base", f"--fidelity at --width 256 --height 256 --spp {spp} --workload pt"),
                 ("res256_ttp", f"--fidelity at --width 256 --height 256 --spp {spp} --workload pt --prefetcher ttp")]
    return runs


def main():
    a = arguments(__doc__, lambda ap: ap.add_argument("--no-256", action="store_true", help="skip the 256x256 runs (4x longer)"))
    write_manifest(a, experiments(a.size, a.spp, not a.no_256), with_256=not a.no_256)


if __name__ == "__main__":
    main()
