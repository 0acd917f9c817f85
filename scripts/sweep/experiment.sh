#!/usr/bin/env bash
# Shared driver of the experiment scripts: sets up, builds, expands an experiment definition into
# a manifest, runs it (resumable with the same rtsim binary; another binary runs everything again)
# and writes the report.
# Usage: experiment.sh EXPERIMENTS_PY REPORT_PY REPORT_DIR DEFAULT_WORK [--size N] [--spp N]
#        [--scenes a,b] [--jobs N] [--work DIR] [other options for EXPERIMENTS_PY]
set -euo pipefail
cd "$(dirname "$0")/../.."
experiments=$1 report=$2 report_dir=$3 work=$4
shift 4
jobs=$(nproc) pass=()
while [ $# -gt 0 ]; do
  case $1 in
    --size|--spp|--scenes) pass+=("$1" "$2"); shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    *) pass+=("$1"); shift ;;
  esac
done
scripts/setup.sh --reports
scripts/build.sh >/dev/null
# Resuming is for the same rtsim: runs made by another build would mix two models in one report,
# so they are moved aside and everything runs again.
binary=$(sha256sum build/rtsim | cut -d' ' -f1)
if [ -d "$work" ] && [ "$(cat "$work/rtsim.sha256" 2>/dev/null)" != "$binary" ] && [ -n "$(ls -A "$work")" ]; then
  rm -rf "$work.previous"
  mv "$work" "$work.previous"
  echo "rtsim has changed since the runs in $work: running all again (the old runs are in $work.previous)" >&2
fi
mkdir -p "$work"
echo "$binary" >"$work/rtsim.sha256"
/usr/bin/python3 "$experiments" "$work/manifest.tsv" "${pass[@]}"
scripts/sweep/run.sh "$work/manifest.tsv" "$work" "$jobs"
/usr/bin/python3 "$report" "$work/results.csv" "$report_dir"
