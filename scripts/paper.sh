#!/usr/bin/env bash
# Runs the paper's Results section on our scenes and writes reports/paper/README.md with tables
# and PNG plots. Resumable: rerunning skips runs whose stats exist in the work folder.
# Usage: scripts/paper.sh [--size N] [--spp N] [--scenes a,b] [--no-256] [--jobs N] [--work DIR]
#        [--engine local|slurm] [Slurm options: docs/sweeps.md]
exec "$(dirname "$0")/sweep/experiment.sh" scripts/paper/experiments.py scripts/paper/report.py reports/paper out/paper-runs "$@"
