#!/usr/bin/env bash
# Speed against error: runs every fidelity (AT; LT at three quanta; sampled AT and LT at three
# rates) on our scenes with and without TTP, and writes reports/speed-vs-error/README.md with a
# Pareto plot. Resumable like scripts/paper.sh.
# Usage: scripts/speed_error.sh [--size N] [--spp N] [--scenes a,b] [--jobs N] [--work DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
size=128 spp=2 scenes=wknd,cornell,ship,bunny,ref,bath,sprng jobs=$(nproc) work=out/speed-error-runs
while [ $# -gt 0 ]; do
  case $1 in
    --size) size=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --scenes) scenes=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    *) echo "speed_error.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
scripts/setup.sh --reports
scripts/build.sh >/dev/null
mkdir -p "$work"
/usr/bin/python3 scripts/speed_error/experiments.py "$work/manifest.tsv" --size "$size" --spp "$spp" --scenes "$scenes"
scripts/sweep/run.sh "$work/manifest.tsv" "$work" "$jobs"
/usr/bin/python3 scripts/speed_error/report.py "$work/results.csv" reports/speed-vs-error
