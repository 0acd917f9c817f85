#!/usr/bin/env python3
"""Speed against error: every fidelity on every scene, baseline and TTP, as a sweep manifest.
Usage: experiments.py MANIFEST [--size N] [--spp N] [--scenes a,b,...]"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
from scenes import SCENES  # noqa: E402

FIDELITIES = {  # id -> rtsim arguments
    "at": "--fidelity at",
    "lt_q100": "--fidelity lt --quantum 100",
    "lt_q1000": "--fidelity lt --quantum 1000",
    "lt_q10000": "--fidelity lt --quantum 10000",
    "at_s50": "--fidelity at --sample 0.5",
    "at_s25": "--fidelity at --sample 0.25",
    "at_s10": "--fidelity at --sample 0.1",
    "lt_s50": "--fidelity lt --sample 0.5",
    "lt_s25": "--fidelity lt --sample 0.25",
    "lt_s10": "--fidelity lt --sample 0.1",
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("manifest")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=2)
    ap.add_argument("--scenes", default=",".join(SCENES))
    a = ap.parse_args()
    scenes = [s for s in a.scenes.split(",") if s]
    with open(a.manifest + ".meta.json", "w") as f:
        json.dump({"size": a.size, "spp": a.spp, "scenes": scenes}, f)
    with open(a.manifest, "w") as f:
        f.write("id\targs\toutput\n")
        for fid, fargs in FIDELITIES.items():
            for pf, pargs in (("base", ""), ("ttp", "--prefetcher ttp")):
                for s in scenes:
                    args = f"{SCENES[s]} {fargs} --workload pt --width {a.size} --height {a.size} --spp {a.spp} {pargs}".strip()
                    f.write(f"{fid}_{pf}/{s}\t{args}\t{fid}_{pf}/{s}.json\n")


if __name__ == "__main__":
    main()
