#!/usr/bin/env bash
# Runs every line of a sweep manifest, resuming where a previous run stopped, then collects all
# stats into OUTDIR/results.csv. Results of another rtsim binary are first moved aside
# (manifest.py invalidate), so one results.csv never mixes two models.
# Engines (docs/sweeps.md):
#   local  GNU parallel on this machine, JOBS at a time (default: the number of cores)
#   slurm  Slurm job arrays (slurm.py; its options pass through: --max-parallel K, --partition P,
#          --account A, --qos Q, --sbatch-arg ARG, --time-per-run MIN, --mem-per-run MB,
#          --no-wait, --failed-only, --poll S)
# Usage: run.sh [--engine local|slurm] [--jobs N] [slurm options] MANIFEST OUTDIR [JOBS]
# Exit status: 0 done (local: failed runs are listed in results.csv with their exit status),
# 1 runs failed (slurm; listed), 2 bad usage, 75 submitted and not waited for (slurm --no-wait),
# 130 stopped before every run had run (no results.csv written).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
engine=local jobs=$(nproc) engine_args=() pos=()
while [ $# -gt 0 ]; do
  case $1 in
    --engine) engine=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --no-wait|--failed-only) engine_args+=("$1"); shift ;;
    --max-parallel|--partition|--account|--qos|--sbatch-arg|--time-per-run|--mem-per-run|--poll)
      engine_args+=("$1" "$2"); shift 2 ;;
    --*) echo "run.sh: unknown option $1" >&2; exit 2 ;;
    *) pos+=("$1"); shift ;;
  esac
done
if [ ${#pos[@]} -lt 2 ] || [ ${#pos[@]} -gt 3 ]; then
  echo "usage: run.sh [--engine local|slurm] [--jobs N] [slurm options] MANIFEST OUTDIR [JOBS]" >&2; exit 2
fi
manifest=${pos[0]} outdir=${pos[1]}
[ ${#pos[@]} -eq 3 ] && jobs=${pos[2]}
export RTSIM=${RTSIM:-$here/../../build/rtsim}
/usr/bin/python3 "$here/manifest.py" invalidate "$manifest" "$outdir" "$RTSIM"
n=$(($(wc -l <"$manifest") - 1))
status=0
case $engine in
  local)
    if [ ${#engine_args[@]} -gt 0 ]; then echo "run.sh: ${engine_args[*]}: options of the slurm engine" >&2; exit 2; fi
    echo "sweep: $n runs from $manifest, $jobs at a time, into $outdir" >&2
    # Failed runs are the collector's to list (parallel exits with their count). A sweep stopped
    # on the way (Ctrl-C, kill: parallel then starts no more runs and exits as usual) leaves
    # runs that never started, or that rtsim left with "interrupted": true: no results.csv then,
    # exit 130 (manifest.py not-run counts them; the worker runs them again).
    seq 1 "$n" | parallel --will-cite -j "$jobs" --joblog "+$outdir/joblog" "$here/worker.sh" "$manifest" {} "$outdir" || true
    not_run=$(/usr/bin/python3 "$here/manifest.py" not-run "$manifest" "$outdir")
    if [ "$not_run" -gt 0 ]; then
      echo "sweep: stopped with $not_run of $n runs not run; no results.csv written (the same command resumes)" >&2
      exit 130
    fi ;;
  slurm)
    echo "sweep: $n runs from $manifest as Slurm job arrays, into $outdir" >&2
    /usr/bin/python3 "$here/slurm.py" "$manifest" "$outdir" "${engine_args[@]}" || status=$?
    if [ $status -eq 75 ] || [ $status -eq 2 ]; then exit $status; fi ;;
  *) echo "run.sh: unknown engine '$engine' (local or slurm)" >&2; exit 2 ;;
esac
/usr/bin/python3 "$here/collect.py" "$manifest" "$outdir"
exit $status
