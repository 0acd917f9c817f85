#!/usr/bin/env bash
# Runs the paper's Results section on our scenes and writes reports/paper/README.md with tables
# and PNG plots. Resumable: rerunning skips runs whose stats exist in the work folder.
# Usage: scripts/paper.sh [--size N] [--spp N] [--scenes a,b] [--no-256] [--jobs N] [--work DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
size=128 spp=2 scenes=wknd,cornell,ship,bunny,ref,bath,sprng jobs=$(nproc) work=out/paper-runs extra=()
while [ $# -gt 0 ]; do
  case $1 in
    --size) size=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --scenes) scenes=$2; shift 2 ;;
    --no-256) extra+=(--no-256); shift ;;
    --jobs) jobs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    *) echo "paper.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
scripts/setup.sh --reports
scripts/build.sh >/dev/null
mkdir -p "$work"
/usr/bin/python3 scripts/paper/experiments.py "$work/manifest.tsv" --size "$size" --spp "$spp" --scenes "$scenes" "${extra[@]}"
scripts/sweep/run.sh "$work/manifest.tsv" "$work" "$jobs"
/usr/bin/python3 scripts/paper/report.py "$work/results.csv" reports/paper
