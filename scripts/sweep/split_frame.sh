#!/usr/bin/env bash
# One large sampled frame across many processes or cluster nodes (docs/sweeps.md, "One frame on
# many nodes"): the sample's drawn clusters split into K independent segments (rtsim
# --sample-segments K --segment I, docs/sampling.md "Segments"), run as a manifest of K runs through
# the local engine or as Slurm array tasks (run.sh: resumable, a changed rtsim reruns them), then
# merged into the frame's estimate and interval: OUTDIR/frame.json, the same statistics, bit for
# bit, as `rtsim RTSIM_ARGS --sample-segments K` in one process. Segment 0 runs first and keeps the
# frame's functional pre-pass in OUTDIR/plan.bin (--sample-plan); the other K - 1 and the merge
# read it.
# Usage: split_frame.sh [--engine local|slurm] [--jobs N] [slurm options of run.sh] --segments K
#                       OUTDIR -- RTSIM_ARGS...
#   RTSIM_ARGS: the frame, fidelity and --sample RATE [--sample-seed S] (no --stats: the segments'
#   go to OUTDIR/segments/, the frame's to OUTDIR/frame.json); {shared} stands for $SHARED, as in
#   a manifest. Environment: RTSIM (default build/rtsim), SHARED (default ../shared/scenes).
# Exit status: 0 merged; 1 a segment failed (listed) or the merge failed; 2 bad usage; 75 submitted
# and not waited for (--no-wait: the same command later waits, or merges at once if all are done).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
run_args=() segments="" outdir=""
while [ $# -gt 0 ]; do
  case $1 in
    --segments) segments=$2; shift 2 ;;
    --engine|--jobs|--max-parallel|--partition|--account|--qos|--sbatch-arg|--time-per-run|--mem-per-run|--poll)
      run_args+=("$1" "$2"); shift 2 ;;
    --no-wait|--failed-only) run_args+=("$1"); shift ;;
    --) shift; break ;;
    --*) echo "split_frame.sh: unknown option $1" >&2; exit 2 ;;
    *) [ -z "$outdir" ] || { echo "split_frame.sh: one OUTDIR, then -- and rtsim's arguments" >&2; exit 2; }
       outdir=$1; shift ;;
  esac
done
usage="usage: split_frame.sh [--engine local|slurm] [options] --segments K OUTDIR -- RTSIM_ARGS..."
if [ -z "$outdir" ] || [ $# -eq 0 ]; then echo "$usage" >&2; exit 2; fi
if ! [[ $segments =~ ^[0-9]+$ ]] || [ "$segments" -lt 2 ]; then
  echo "split_frame.sh: --segments '$segments': 2 or more segments (one is a plain sampled run)" >&2; exit 2
fi
for a in "$@"; do
  case $a in
    --stats|--sample-segments|--segment|--merge-segments|--sample-plan) echo "split_frame.sh: $a is split_frame.sh's to give, not in RTSIM_ARGS" >&2; exit 2 ;;
    *$'\t'*) echo "split_frame.sh: an argument with a tab cannot go into a manifest" >&2; exit 2 ;;
  esac
done
case " $* " in *" --sample "*) ;; *) echo "split_frame.sh: RTSIM_ARGS need --sample RATE (below 1): only a sample splits" >&2; exit 2 ;; esac
export RTSIM=${RTSIM:-$here/../../build/rtsim}
shared=${SHARED:-$here/../../../shared/scenes}
mkdir -p "$outdir"
args="$* --sample-segments $segments --sample-plan $(readlink -f "$outdir")/plan.bin"
manifest=$outdir/manifest.tsv
{
  printf 'id\targs\toutput\n'
  for ((i = 0; i < segments; i++)); do printf 'segments/%d\t%s --segment %d\tsegments/segment%d.json\n' "$i" "$args" "$i" "$i"; done
} >"$manifest.tmp"
# A different frame or K in the same folder would mix segments of two samples: refused.
if [ -f "$manifest" ] && ! cmp -s "$manifest" "$manifest.tmp"; then
  rm -f "$manifest.tmp"
  echo "split_frame.sh: $outdir holds the segments of another frame or K (its manifest.tsv differs); use another OUTDIR" >&2; exit 2
fi
mv "$manifest.tmp" "$manifest"
# The plan (the frame's functional pre-pass) of another rtsim binary is not this one's.
sha=$(sha256sum "$RTSIM" | cut -d' ' -f1)
if [ -f "$outdir/plan.sha256" ] && [ "$(cat "$outdir/plan.sha256")" != "$sha" ]; then rm -f "$outdir/plan.bin"; fi
echo "$sha" >"$outdir/plan.sha256"
# Segment 0 first, alone: it writes the plan, which the other segments and the merge then read
# instead of tracing the whole frame again each.
head -2 "$manifest" >"$outdir/first.tsv"
status=0
"$here/run.sh" "${run_args[@]}" "$outdir/first.tsv" "$outdir" || status=$?
[ $status -eq 0 ] && { "$here/run.sh" "${run_args[@]}" "$manifest" "$outdir" || status=$?; }
if [ $status -ne 0 ]; then
  [ $status -eq 75 ] && echo "split_frame.sh: submitted; run the same command again to wait and go on (segment 0 first, then the rest, then the merge)" >&2
  exit $status
fi
# The local engine lists failed runs in results.csv and exits 0: a failed segment ends it here.
files=()
for ((i = 0; i < segments; i++)); do
  f=$outdir/segments/segment$i.json
  if [ ! -s "$f" ]; then echo "split_frame.sh: segment $i failed: see $f.err" >&2; status=1; fi
  files+=("$f")
done
[ $status -eq 0 ] || exit 1
# shellcheck disable=SC2086  # the arguments are a word list, as in a manifest
if ! "$RTSIM" ${args//\{shared\}/$shared} --merge-segments "${files[@]}" -q --stats "$outdir/frame.json" 2>"$outdir/frame.err"; then
  echo "split_frame.sh: the merge failed: $(cat "$outdir/frame.err")" >&2; exit 1
fi
summary=$(/usr/bin/python3 -c '
import json, sys
j = json.load(open(sys.argv[1]))
ci = j["timing"]["sampling"]["cycles_ci95"]
print(str(j["cycles"]) + " cycles" + (" (95 %% interval %.0f..%.0f)" % (ci[0], ci[1]) if ci else " (no interval)"))' "$outdir/frame.json")
echo "split_frame.sh: $segments segments merged into $outdir/frame.json: $summary" >&2
