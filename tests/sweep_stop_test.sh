#!/usr/bin/env bash
# A local sweep stopped on the way (Ctrl-C or kill reaching GNU parallel, which then starts no
# more runs and exits as usual) writes no results.csv and exits 130, so that the experiment
# scripts write no report from part of the runs; the same command then resumes and collects all.
# A run whose rtsim was stopped by a signal left its statistics so far ("interrupted": true) and
# exit 143: that run is not finished, and the next resume runs it again rather than collecting it.
# The stop is made deterministic by a stand-in for rtsim that, on the second run, sends SIGTERM to
# the parallel above it, then runs the real rtsim.
# Usage: sweep_stop_test.sh RTSIM SOURCE_DIR
set -euo pipefail
real=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat >"$work/rtsim" <<'STUB'
#!/usr/bin/env bash
case " $* " in
  *" --seed 2 "*)
    if [ -f "$STOP_ONCE" ]; then
      rm -f "$STOP_ONCE"
      p=$PPID
      while [ "${p:-1}" -gt 1 ]; do
        if ps -o args= -p "$p" | grep -q "parallel --will-cite"; then kill -TERM "$p"; break; fi
        p=$(ps -o ppid= -p "$p" | tr -d ' ')
      done
    fi ;;
esac
exec "$REAL_RTSIM" "$@"
STUB
chmod +x "$work/rtsim"
export REAL_RTSIM=$real RTSIM=$work/rtsim STOP_ONCE=$work/stop
printf 'id\targs\toutput\n' >"$work/m.tsv"
for i in 1 2 3 4; do printf 't/r%d\t--scene cornell --fidelity functional --width 16 --height 16 --seed %d\tt/r%d.json\n' "$i" "$i" "$i" >>"$work/m.tsv"; done
touch "$work/stop"
pass=0 fail=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass + 1)); else echo "FAIL $1"; fail=$((fail + 1)); fi; }
rc=0
"$src/scripts/sweep/run.sh" --jobs 1 "$work/m.tsv" "$work/out" 2>"$work/err1" || rc=$?
check "a stopped sweep exits 130 (got $rc)" '[ "$rc" = 130 ]'
check "and writes no results.csv" '[ ! -e "$work/out/results.csv" ]'
check "and says how many runs did not run" 'grep -q "runs not run" "$work/err1"'
rc=0
"$src/scripts/sweep/run.sh" --jobs 1 "$work/m.tsv" "$work/out" 2>"$work/err2" || rc=$?
check "the same command resumes and exits 0 (got $rc)" '[ "$rc" = 0 ]'
check "with every run in results.csv" '[ "$(tail -n +2 "$work/out/results.csv" | wc -l)" = 4 ]'
# Two states a kill can leave: r3 as rtsim leaves a run it was stopped in (its statistics so far,
# "interrupted": true, exit 143); r4 whole but without .status (its worker killed after rtsim ended).
/usr/bin/python3 - "$work/out/t" <<'PY'
import json, pathlib, sys
d = pathlib.Path(sys.argv[1])
j = json.loads((d / "r3.json").read_text())
j["interrupted"] = True
(d / "r3.json").write_text(json.dumps(j, indent=2) + "\n")
(d / "r3.json.status").write_text('{"id": "t/r3", "exit": 143, "wall_s": 0.1}\n')
(d / "r4.json.status").unlink()
PY
m="$src/scripts/sweep/manifest.py"
check "the interrupted run counts as not run, the one without .status but whole stats does not" \
  '[ "$(/usr/bin/python3 "$m" not-run "$work/m.tsv" "$work/out")" = 1 ]'
check "the interrupted run is not finished" '! /usr/bin/python3 "$m" finished "$work/m.tsv" "$work/out" 3'
check "the whole one is" '/usr/bin/python3 "$m" finished "$work/m.tsv" "$work/out" 4'
rc=0
rm "$work/out/results.csv"
"$src/scripts/sweep/run.sh" --jobs 1 "$work/m.tsv" "$work/out" 2>"$work/err3" || rc=$?
check "resuming runs the interrupted run again and exits 0 (got $rc)" '[ "$rc" = 0 ]'
check "whose stats are now whole" '! grep -q "\"interrupted\": true" "$work/out/t/r3.json"'
check "results.csv has the swept key, the seed, as a column after the run's id" 'head -1 "$work/out/results.csv" | grep -q "^id,experiment,scene,params.seed,exit,"'
check "and r3 with its seed and exit 0" 'grep -q "^t/r3,t,r3,3,0," "$work/out/results.csv"'
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
