#!/usr/bin/env bash
# The sweeps' Slurm engine against a stand-in for Slurm's commands (no daemons, no root): `sbatch`
# runs an array's tasks at once, one after another, as Slurm would run them (SLURM_ARRAY_TASK_ID,
# the exported RTSIM, the output file); `squeue` shows nothing queued; `scontrol` gives
# MaxArraySize 3. Checks that 4 runs go as two arrays (3 and 1 tasks), that a second pass submits
# nothing, and that the results equal the local engine's. scripts/sweep/test_slurm.sh checks the
# engine on a real Slurm (CI).
# Usage: sweep_slurm_fake_test.sh RTSIM SOURCE_DIR
set -euo pipefail
export RTSIM=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/bin"
cat >"$work/bin/scontrol" <<'FAKE'
#!/usr/bin/env bash
echo "MaxArraySize            = 3"
FAKE
cat >"$work/bin/squeue" <<'FAKE'
#!/usr/bin/env bash
exit 0
FAKE
cat >"$work/bin/sbatch" <<'FAKE'
#!/usr/bin/env bash
# --parsable --array=0-N[%K] ... --output=PATTERN --export=ALL,RTSIM=X ... SCRIPT ARGS
job=$(( $(cat "$FAKE_SLURM_DIR/next_job" 2>/dev/null || echo 0) + 1 ))
echo "$job" >"$FAKE_SLURM_DIR/next_job"
while [ $# -gt 0 ]; do
  case $1 in
    --array=*) a=${1#--array=}; a=${a%%%*}; last=${a#0-} ;;
    --output=*) output=${1#--output=} ;;
    --export=*) e=${1#--export=ALL,}; export "${e?}" ;;
    --*) ;;
    *) break ;;
  esac
  shift
done
echo "$job $((last + 1))" >>"$FAKE_SLURM_DIR/arrays"
for t in $(seq 0 "$last"); do
  log=${output//%A/$job}; log=${log//%a/$t}
  SLURM_ARRAY_JOB_ID=$job SLURM_ARRAY_TASK_ID=$t bash "$@" >"$log" 2>&1 || true
done
echo "$job"
FAKE
chmod +x "$work/bin/"*
export FAKE_SLURM_DIR=$work PATH=$work/bin:$PATH
{
  printf 'id\targs\toutput\n'
  printf 'functional/wknd\t--scene wknd --width 16 --height 16\tfunctional/wknd.json\n'
  printf 'at/wknd\t--scene wknd --width 16 --height 16 --fidelity at\tat/wknd.json\n'
  printf 'lt/cornell\t--scene cornell --width 16 --height 16 --fidelity lt --workload primary\tlt/cornell.json\n'
  printf 'interval/wknd\t--scene wknd --width 16 --height 16 --fidelity interval --prefetcher ttp\tinterval/wknd.json\n'
} >"$work/manifest.tsv"
status=0
"$src/scripts/sweep/run.sh" --engine slurm --poll 0.1 "$work/manifest.tsv" "$work/slurm" 2>"$work/out1.txt" || status=1
if [ "$(cut -d' ' -f2 "$work/arrays" | tr '\n' ' ')" != "3 1 " ]; then
  echo "FAIL: arrays of $(cut -d' ' -f2 "$work/arrays" | tr '\n' ' ')tasks, expected 3 and 1 (MaxArraySize 3)"; status=1
fi
"$src/scripts/sweep/run.sh" --engine slurm --poll 0.1 "$work/manifest.tsv" "$work/slurm" 2>"$work/out2.txt" || status=1
grep -q "0 submitted now" "$work/out2.txt" || { echo "FAIL: the second pass submitted runs again"; status=1; }
"$src/scripts/sweep/run.sh" --engine local --jobs 2 "$work/manifest.tsv" "$work/local" 2>/dev/null
"$src/scripts/sweep/same_results.py" "$work/manifest.tsv" "$work/local" "$work/slurm" || status=1
[ $status -eq 0 ] || cat "$work/out1.txt" "$work/out2.txt"
exit $status
