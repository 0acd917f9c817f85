#!/usr/bin/env bash
# Runs line INDEX (1-based, after the header) of a sweep manifest and writes its stats.
# Free of local assumptions: the binary and the scene folder come from the environment, so the
# same manifest runs here under GNU parallel or elsewhere as a job array (INDEX = array index).
#   RTSIM   path of the rtsim binary (default: build/rtsim next to this script's project)
#   SHARED  folder of the shared scenes, substituted for {shared} in the manifest
# Usage: worker.sh MANIFEST INDEX OUTDIR
# Skips a run whose stats file exists (resume). Records exit status and wall time next to it.
set -uo pipefail
manifest=$1 index=$2 outdir=$3
here=$(cd "$(dirname "$0")/../.." && pwd)
rtsim=${RTSIM:-$here/build/rtsim}
shared=${SHARED:-$here/../shared/scenes}
line=$(awk -F'\t' -v i="$index" 'NR == i + 1' "$manifest")
if [ -z "$line" ]; then echo "worker: $manifest has no line $index" >&2; exit 2; fi
IFS=$'\t' read -r id args output <<<"$line"
stats="$outdir/$output"
[ -s "$stats" ] && exit 0
mkdir -p "$(dirname "$stats")"
args=${args//\{shared\}/$shared}
start=$(date +%s%N)
# shellcheck disable=SC2086  # args is a word list by design
"$rtsim" $args -q --stats "$stats" 2>"$stats.err"
rc=$?
end=$(date +%s%N)
wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", (b - a) / 1e9 }')
printf '{"id": "%s", "exit": %d, "wall_s": %s}\n' "$id" "$rc" "$wall" >"$stats.status"
exit $rc
