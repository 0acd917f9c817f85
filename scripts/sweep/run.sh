#!/usr/bin/env bash
# Runs every line of a sweep manifest with GNU parallel on this machine, resuming where a
# previous run stopped, then collects all stats into OUTDIR/results.csv.
# Usage: run.sh MANIFEST OUTDIR [JOBS]   (JOBS defaults to the number of cores)
set -euo pipefail
manifest=$1 outdir=$2 jobs=${3:-$(nproc)}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$outdir"
n=$(($(wc -l <"$manifest") - 1))
echo "sweep: $n runs from $manifest, $jobs at a time, into $outdir" >&2
seq 1 "$n" | parallel --will-cite -j "$jobs" --joblog "+$outdir/joblog" "$here/worker.sh" "$manifest" {} "$outdir" || true
/usr/bin/python3 "$here/collect.py" "$manifest" "$outdir"
