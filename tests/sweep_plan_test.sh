#!/usr/bin/env bash
# A sweep's sampled runs of one frame share its sample plan (scripts/sweep/worker.sh): the first
# traces the frame and keeps the plan in OUTDIR/plans-<rtsim hash>/, the others (another
# prefetcher, SM count, sample seed and rate, another fidelity) read it; the results equal those
# of the same sweep with SWEEP_SAMPLE_PLAN=0 (every run tracing its frame itself), statistic by
# statistic. A manifest line with its own --sample-plan keeps it; runs that do not sample (or at
# --sample 1, the whole frame) get none.
# Usage: sweep_plan_test.sh RTSIM SOURCE_DIR
set -euo pipefail
export RTSIM=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# wknd at 256x256 and 2 spp: 128 clusters of 32 warps, so 25 % draws 31 strata.
frame="--scene wknd --workload pt --width 256 --height 256 --spp 2 --threads 1"
{
  printf 'id\targs\toutput\n'
  printf 'a/wknd\t%s --fidelity interval --sample 0.25\ta.json\n' "$frame"
  printf 'b/wknd\t%s --fidelity interval --sample 0.25 --prefetcher ttp\tb.json\n' "$frame"
  printf 'c/wknd\t%s --fidelity interval --sample 0.5 --sample-seed 2 --set gpu.sms=4\tc.json\n' "$frame"
  printf 'd/wknd\t%s --fidelity lt --sample 0.25 --sample-seed 3\td.json\n' "$frame"
  printf 'e/wknd\t%s --fidelity interval\te.json\n' "$frame"
  printf 'g/wknd\t%s --fidelity interval --sample 1\tg.json\n' "$frame"
  printf 'f/wknd\t%s --fidelity interval --sample 0.25 --sample-plan %s/own.bin\tf.json\n' "$frame" "$work"
} >"$work/m.tsv"
pass=0 fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass + 1)); else echo "FAIL $1"; fail=$((fail + 1)); fi; }

# Run by run, so that the plan's file can be watched: a run that reads it does not write it again
# (a write replaces the file: a new inode).
"$src/scripts/sweep/run.sh" --jobs 1 "$work/m.tsv" "$work/with" 2>/dev/null >/dev/null
plans=("$work"/with/plans-*/plan-*.bin)
check "one plan for the frame, in plans-<the binary's hash> (found: ${plans[*]##*/with/})" \
  '[ ${#plans[@]} = 1 ] && [ -s "${plans[0]}" ] && [ "$(basename "$(dirname "${plans[0]}")")" = "plans-$(cut -c1-12 "$work/with/rtsim.sha256")" ]'
inode=$(stat -c %i "${plans[0]}")
rm "$work/with/c.json"  # run c again alone: it reads the plan and leaves the file as it was
"$src/scripts/sweep/worker.sh" "$work/m.tsv" 3 "$work/with"
check "a later run reads the plan rather than writing it again" '[ "$(stat -c %i "${plans[0]}")" = "$inode" ] && [ -s "$work/with/c.json" ]'
check "a line with its own --sample-plan keeps it" '[ -s "$work/own.bin" ]'

SWEEP_SAMPLE_PLAN=0 "$src/scripts/sweep/run.sh" --jobs 1 "$work/m.tsv" "$work/without" 2>/dev/null >/dev/null
check "SWEEP_SAMPLE_PLAN=0 keeps no plans" '! ls -d "$work"/without/plans-* >/dev/null 2>&1'
check "every run's statistics equal those of the sweep without plans" \
  'python3 "$src/scripts/sweep/same_results.py" "$work/m.tsv" "$work/with" "$work/without"'
check "and every run succeeded" '[ "$(grep -c "\"exit\": 0" "$work"/with/*.status | awk -F: "{ s += \$2 } END { print s }")" = 7 ]'
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
