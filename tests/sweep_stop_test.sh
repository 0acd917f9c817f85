#!/usr/bin/env bash
# A local sweep stopped on the way (Ctrl-C or kill reaching GNU parallel, which then starts no
# more runs and exits as usual) writes no results.csv and exits 130, so that the experiment
# scripts write no report from part of the runs; the same command then resumes and collects all.
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
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
