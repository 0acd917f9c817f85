#!/usr/bin/env bash
# Speed against error: runs every fidelity (AT; LT at three quanta; sampled AT and LT at three
# rates) on our scenes with and without TTP, and writes reports/speed-vs-error/README.md with a
# Pareto plot. Resumable like scripts/paper.sh.
# Usage: scripts/speed_error.sh [--size N (default 256)] [--spp N] [--scenes a,b] [--jobs N] [--work DIR]
#        [--engine local|slurm] [Slurm options: docs/sweeps.md]
# Each sampled run is timed from scratch, its own functional pre-pass included: no sample plan
# shared between the runs of a frame (scripts/sweep/worker.sh), which would time the sweep's reuse.
export SWEEP_SAMPLE_PLAN=0
exec "$(dirname "$0")/sweep/experiment.sh" scripts/speed_error/experiments.py scripts/speed_error/report.py reports/speed-vs-error out/speed-error-runs "$@"
