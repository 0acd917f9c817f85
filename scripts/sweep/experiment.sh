#!/usr/bin/env bash
# Shared driver of the experiment scripts: sets up, builds, expands an experiment definition into
# a manifest, runs it (run.sh: resumable with the same rtsim binary; another binary runs
# everything again) on this machine or as Slurm job arrays, and writes the report.
# Usage: experiment.sh EXPERIMENTS_PY REPORT_PY REPORT_DIR DEFAULT_WORK [--size N] [--spp N]
#        [--scenes a,b] [--jobs N] [--work DIR] [--engine local|slurm] [slurm options of run.sh]
#        [other options for EXPERIMENTS_PY]
# With --engine slurm --no-wait it returns after submitting; the same command later waits for the
# runs still queued, submits nothing twice, and writes the report.
set -euo pipefail
cd "$(dirname "$0")/../.."
experiments=$1 report=$2 report_dir=$3 work=$4
shift 4
jobs=$(nproc) pass=() run_args=()
while [ $# -gt 0 ]; do
  case $1 in
    --size|--spp|--scenes) pass+=("$1" "$2"); shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --engine|--max-parallel|--partition|--account|--qos|--sbatch-arg|--time-per-run|--mem-per-run|--poll)
      run_args+=("$1" "$2"); shift 2 ;;
    --no-wait|--failed-only) run_args+=("$1"); shift ;;
    *) pass+=("$1"); shift ;;
  esac
done
scripts/setup.sh --reports
scripts/build.sh >/dev/null
mkdir -p "$work"
/usr/bin/python3 "$experiments" "$work/manifest.tsv" "${pass[@]}"
status=0
scripts/sweep/run.sh "${run_args[@]}" --jobs "$jobs" "$work/manifest.tsv" "$work" || status=$?
# No report from a sweep that was not run (75: submitted, not waited for; 2: bad usage) or was
# stopped (130, or killed: 128 + N): the report in the tree stays the last complete one.
if [ $status -eq 75 ] || [ $status -eq 2 ] || [ $status -ge 128 ]; then exit $status; fi
/usr/bin/python3 "$report" "$work/results.csv" "$report_dir"
exit $status
