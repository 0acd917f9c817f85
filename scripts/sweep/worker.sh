#!/usr/bin/env bash
# Runs line INDEX (1-based, after the header) of a sweep manifest and writes its stats.
# Free of local assumptions: the binary and the scene folder come from the environment, so the
# same manifest runs here under GNU parallel or elsewhere as a job array (INDEX = array index).
#   RTSIM   path of the rtsim binary (default: build/rtsim next to this script's project)
#   SHARED  folder of the shared scenes, substituted for {shared} in the manifest
#   SWEEP_SAMPLE_PLAN  0: each sampled run traces its frame itself (runs timed from scratch, as
#           scripts/speed_error.sh does); else (the default) a sampled run (rate below 1) without its own
#           --sample-plan keeps and reads its frame's pre-pass in OUTDIR/plans-<rtsim hash>/, so
#           that only the first sampled run of each frame traces the frame and every other
#           configuration of it reads the plan (docs/sampling.md, "Sample plan": the same
#           statistics, bit for bit). The folder is per binary: another rtsim makes its own plans.
# Usage: worker.sh MANIFEST INDEX OUTDIR
# Skips a finished run (resume): its stats file exists and is not of a run stopped by a signal
# ("interrupted": true; manifest.py finished). Records exit status and wall time next to it.
set -uo pipefail
manifest=$1 index=$2 outdir=$3
here=$(cd "$(dirname "$0")/../.." && pwd)
rtsim=${RTSIM:-$here/build/rtsim}
shared=${SHARED:-$here/../shared/scenes}
line=$(awk -F'\t' -v i="$index" 'NR == i + 1' "$manifest")
if [ -z "$line" ]; then echo "worker: $manifest has no line $index" >&2; exit 2; fi
IFS=$'\t' read -r id args output <<<"$line"
stats="$outdir/$output"
if [ -e "$stats" ]; then
  /usr/bin/python3 "$here/scripts/sweep/manifest.py" finished "$manifest" "$outdir" "$index" && exit 0
  # Stopped on the way last time: its statistics so far are not the run's; run it again.
  rm -f "$stats" "$stats.status" "$stats.err"
fi
mkdir -p "$(dirname "$stats")"
args=${args//\{shared\}/$shared}
# The rate after --sample (given once: rtsim refuses more); a plan is for rates below 1.
rate=$(awk '{ for (i = 1; i < NF; ++i) if ($i == "--sample") r = $(i + 1) } END { print r }' <<<"$args")
if [ "${SWEEP_SAMPLE_PLAN:-1}" != 0 ] && [ -n "$rate" ] && awk -v r="$rate" 'BEGIN { exit !(r + 0 > 0 && r + 0 < 1) }' &&
  [[ " $args " != *" --sample-plan "* ]]; then
  # OUTDIR/rtsim.sha256 is written by manifest.py invalidate before any run (both engines); a
  # worker run by hand without it hashes the binary itself.
  if [ -s "$outdir/rtsim.sha256" ]; then hash=$(cut -c1-12 "$outdir/rtsim.sha256"); else hash=$(sha256sum "$rtsim" | cut -c1-12); fi
  mkdir -p "$outdir/plans-$hash"
  args="$args --sample-plan $outdir/plans-$hash/"
fi
start=$(date +%s%N)
# shellcheck disable=SC2086  # args is a word list by design
"$rtsim" $args -q --stats "$stats" 2>"$stats.err"
rc=$?
end=$(date +%s%N)
wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", (b - a) / 1e9 }')
printf '{"id": "%s", "exit": %d, "wall_s": %s}\n' "$id" "$rc" "$wall" >"$stats.status"
exit $rc
