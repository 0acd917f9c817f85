#!/usr/bin/env bash
# The sweep definitions as rtsim sees them: every line of the paper and speed-vs-error manifests,
# written for the built-in wknd scene at a tiny frame, runs to exit 0 through the sweep worker and
# the collector finds every column it needs. A renamed option or key in an experiment list fails
# here rather than an hour into a sweep.
# Usage: sweep_manifests_test.sh RTSIM SOURCE_DIR
set -euo pipefail
export RTSIM=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
for exp in paper speed_error; do
  out=$work/$exp
  mkdir -p "$out"
  # The paper's runs on an 8x8 frame; the speed-vs-error ones sample down to 10 %, which needs
  # 10 strata beside the first wave, 105 clusters of 32 warps (a warp is 32 pixels): a 384x384
  # frame (144), at 1 spp to keep it short.
  if [ "$exp" = paper ]; then size=(--size 8 --spp 1 --no-256); else size=(--size 384 --spp 1); fi
  python3 "$src/scripts/$exp/experiments.py" "$out/manifest.tsv" "${size[@]}" --scenes wknd
  if [ "$exp" = speed_error ]; then
    # What is checked is that each line's options and keys are taken and its columns collected,
    # which neither the frame, the workload nor the sample's draw changes: the unsampled runs
    # take a 64x64 frame, the sample's extra draws (seeds 3-6; seed 2 stays) are left out, a
    # third of the test's time otherwise (AT and LT at 384x384 take 4-10 s a run), and the
    # sampled runs trace primary rays, a third of path tracing's rays (the test took 54 s).
    awk -F'\t' -v OFS='\t' 'NR > 1 && $2 ~ /--sample-seed [3-6] / { next }
      NR > 1 && $2 !~ /--sample / { gsub(/--width 384 --height 384/, "--width 64 --height 64", $2) }
      NR > 1 && $2 ~ /--sample / { gsub(/--workload pt /, "--workload primary ", $2) } { print }' \
      "$out/manifest.tsv" >"$out/manifest.small" && mv "$out/manifest.small" "$out/manifest.tsv"
  fi
  n=$(($(wc -l <"$out/manifest.tsv") - 1))
  failed=0
  for i in $(seq 1 "$n"); do
    if ! "$src/scripts/sweep/worker.sh" "$out/manifest.tsv" "$i" "$out" 2>/dev/null; then
      failed=$((failed + 1))
      line=$(awk -F'\t' -v i="$i" 'NR == i + 1 { print $1 ": " $2 }' "$out/manifest.tsv")
      echo "FAIL $exp line $i: $line" >&2
      sed 's/^/    /' "$out/$(awk -F'\t' -v i="$i" 'NR == i + 1 { print $3 }' "$out/manifest.tsv").err" >&2 || true
    fi
  done
  if ! python3 "$src/scripts/sweep/collect.py" "$out/manifest.tsv" "$out"; then failed=$((failed + 1)); fi
  echo "$exp: $n runs, $failed failed"
  [ "$failed" = 0 ] || status=1
done
exit $status
