#!/usr/bin/env python3
"""Speed against error: every fidelity (AT, LT, interval, sampled AT, LT and interval) on every scene, baseline and TTP, as a sweep manifest; and
the sampled AT baseline with five more draws of the sample (sample seeds 2-6) for the accuracy
and interval-coverage study.
Usage: experiments.py MANIFEST [--size N] [--spp N] [--scenes a,b,...]"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
from scenes import arguments, write_manifest  # noqa: E402

# Runs go two at a time on two cores: the sampling pre-pass gets one thread, like everything else,
# so that every speed-up is one core's against one core's.
ONE_CORE = "--threads 1"
FIDELITIES = {  # id -> rtsim arguments
    "at": "--fidelity at",
    "lt_q100": "--fidelity lt --quantum 100",
    "lt_q1000": "--fidelity lt --quantum 1000",
    "lt_q10000": "--fidelity lt --quantum 10000",
    "interval": "--fidelity interval",
    "at_s50": f"--fidelity at --sample 0.5 {ONE_CORE}",
    "at_s25": f"--fidelity at --sample 0.25 {ONE_CORE}",
    "at_s10": f"--fidelity at --sample 0.1 {ONE_CORE}",
    "lt_s50": f"--fidelity lt --sample 0.5 {ONE_CORE}",
    "lt_s25": f"--fidelity lt --sample 0.25 {ONE_CORE}",
    "lt_s10": f"--fidelity lt --sample 0.1 {ONE_CORE}",
    "iv_s50": f"--fidelity interval --sample 0.5 {ONE_CORE}",
    "iv_s25": f"--fidelity interval --sample 0.25 {ONE_CORE}",
    "iv_s10": f"--fidelity interval --sample 0.1 {ONE_CORE}",
}
SAMPLE_RATES = {"s50": "0.5", "s25": "0.25", "s10": "0.1"}
EXTRA_SEEDS = range(2, 7)  # seed 1 is the rtsim default (--seed 1), run above as at_sNN_base


def main():
    # 384x384 is 4,608 shader warps (a warp is 32 pixels; each thread traces its pixel's
    # samples, as LumiBench's), 144 clusters of the mobile GPU's 32 warps: a 10 % sample draws
    # the first wave and 13 strata, enough for an interval (a sample needs 10; docs/sampling.md).
    a = arguments(__doc__, size=384)
    runs = []
    for fid, fargs in FIDELITIES.items():
        for pf, pargs in (("base", ""), ("ttp", "--prefetcher ttp")):
            runs.append((f"{fid}_{pf}", f"{fargs} --workload pt --width {a.size} --height {a.size} --spp {a.spp} {pargs}"))
    for rid, rate in SAMPLE_RATES.items():
        for seed in EXTRA_SEEDS:
            runs.append((f"at_{rid}_seed{seed}_base", f"--fidelity at --sample {rate} --sample-seed {seed} {ONE_CORE} --workload pt "
                         f"--width {a.size} --height {a.size} --spp {a.spp}"))
    write_manifest(a, runs)


if __name__ == "__main__":
    main()
