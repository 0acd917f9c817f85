#!/usr/bin/env bash
# The Slurm engine on a real Slurm (Debian 12's 22.05): installs slurmctld, slurmd and the client if
# missing, starts a throw-away single-node cluster on 127.0.0.1 (local_cluster.sh) with its whole
# configuration and state in a temporary folder (MaxArraySize 5, so 8 runs need two arrays), and
# checks:
#   1. a manifest of 8 short runs goes through the Slurm engine in two arrays; the one run that
#      cannot succeed yet (its configuration file does not exist) is reported with its Slurm log;
#   2. --failed-only submits that run alone, and it finishes;
#   3. the results equal the local engine's, bit for bit but wall-clock times;
#   4. a second pass submits nothing; --no-wait after a changed rtsim returns at once with every run
#      submitted again, and the same command then waits, collects, and gives the same results;
#   5. one sampled frame split into 4 segments as array tasks (split_frame.sh: segment 0, which
#      keeps the pre-pass in a plan file, then the other 3) merges into the same statistics as
#      rtsim --sample-segments 4 in one process.
# Stops the two daemons it started (local_cluster.sh, by their process ids) and removes the
# folder, whatever happens.
# Prints `N passed, M failed`; exit status 0 if none failed.
# Usage: scripts/sweep/test_slurm.sh [RTSIM]   (default build/rtsim, built if missing)
set -uo pipefail
cd "$(dirname "$0")/../.."
passed=0 failed=0
check() {  # check NAME COMMAND...: one named check
  local name=$1
  shift
  if "$@"; then passed=$((passed + 1)); echo "ok   $name"; else failed=$((failed + 1)); echo "FAIL $name"; fi
}
if [ "$(id -u)" -ne 0 ]; then
  echo "test_slurm: needs root (slurmd launches the tasks; the packages may need installing)" >&2
  echo "0 passed, 1 failed"
  exit 1
fi
scripts/setup.sh --slurm || { echo "test_slurm: installing Slurm failed"; echo "0 passed, 1 failed"; exit 1; }
rtsim=${1:-build/rtsim}
[ -x "$rtsim" ] || scripts/build.sh >/dev/null
rtsim=$(readlink -f "$rtsim")

tmp=$(mktemp -d /tmp/rtu-slurm.XXXXXX)
teardown() {
  scripts/sweep/local_cluster.sh stop "$tmp/cluster"
  rm -rf "$tmp"
}
trap teardown EXIT
if ! scripts/sweep/local_cluster.sh start "$tmp/cluster" 5; then echo "0 passed, 1 failed"; exit 1; fi
export SLURM_CONF=$tmp/cluster/slurm.conf
echo "test_slurm: MaxArraySize $(scontrol show config | awk '/^MaxArraySize/ {print $3}')"

# --- the sweep ----------------------------------------------------------------------------------
manifest=$tmp/manifest.tsv
late=$tmp/late.json  # the configuration of the run that fails until it exists
small="--width 32 --height 32"
{
  printf 'id\targs\toutput\n'
  printf 'functional/wknd\t--scene wknd %s\tfunctional/wknd.json\n' "$small"
  printf 'at/wknd\t--scene wknd %s --fidelity at\tat/wknd.json\n' "$small"
  printf 'at_ttp/wknd\t--scene wknd %s --fidelity at --prefetcher ttp\tat_ttp/wknd.json\n' "$small"
  printf 'lt/wknd\t--scene wknd %s --fidelity lt\tlt/wknd.json\n' "$small"
  printf 'interval/wknd\t--scene wknd %s --fidelity interval\tinterval/wknd.json\n' "$small"
  printf 'at/cornell\t--scene cornell %s --fidelity at --workload primary\tat/cornell.json\n' "$small"
  printf 'interval_paper/cornell\t--scene cornell %s --fidelity interval --config paper\tinterval_paper/cornell.json\n' "$small"
  printf 'late/wknd\t--scene wknd %s --fidelity interval --config %s\tlate/wknd.json\n' "$small" "$late"
} >"$manifest"
export RTSIM=$rtsim
sweep() { scripts/sweep/run.sh --engine slurm --poll 1 "$@" >"$tmp/out.txt" 2>&1; }
out_has() { grep -q -e "$1" "$tmp/out.txt"; }

rc=0; sweep "$manifest" "$tmp/slurm" || rc=$?
cat "$tmp/out.txt"
check "a failed run makes the sweep exit 1" [ $rc -eq 1 ]
check "8 runs in two arrays of at most MaxArraySize (5 and 3 tasks)" \
  bash -c "grep -q 'job [0-9]*: 5 tasks' '$tmp/out.txt' && grep -q 'job [0-9]*: 3 tasks' '$tmp/out.txt'"
check "the failed run is reported with its exit status and Slurm log" \
  bash -c "grep -q 'late/wknd: rtsim exit 2' '$tmp/out.txt' && log=\$(grep -o 'Slurm log: .*' '$tmp/out.txt' | head -1 | cut -d' ' -f3) && [ -s \"\$log\" ]"
check "the other 7 runs have stats" bash -c "[ \$(find '$tmp/slurm' -name '*.json' -size +0 | wc -l) -eq 7 ]"

echo '{"l1": {"size_kb": 64}}' >"$late"
rc=0; sweep --failed-only "$manifest" "$tmp/slurm" || rc=$?
cat "$tmp/out.txt"
check "--failed-only submits the failed run alone, and it finishes" bash -c "[ $rc -eq 0 ] && grep -q '1 submitted now' '$tmp/out.txt'"

scripts/sweep/run.sh --engine local --jobs 2 "$manifest" "$tmp/local" 2>"$tmp/local.txt" >/dev/null
check "the Slurm engine's results equal the local engine's" scripts/sweep/same_results.py "$manifest" "$tmp/local" "$tmp/slurm"

rc=0; sweep "$manifest" "$tmp/slurm" || rc=$?
check "a second pass submits nothing" bash -c "[ $rc -eq 0 ] && grep -q '0 submitted now' '$tmp/out.txt'"

# Another binary (the same program and one more byte) invalidates every result.
cp "$rtsim" "$tmp/rtsim-changed" && printf '\0' >>"$tmp/rtsim-changed"
rc=0; RTSIM=$tmp/rtsim-changed sweep --no-wait "$manifest" "$tmp/slurm" || rc=$?
cat "$tmp/out.txt"
check "--no-wait after a changed rtsim submits all 8 again and returns 75" \
  bash -c "[ $rc -eq 75 ] && grep -q '8 submitted now' '$tmp/out.txt' && ls -d '$tmp'/slurm/previous-* >/dev/null"
rc=0; RTSIM=$tmp/rtsim-changed sweep "$manifest" "$tmp/slurm" || rc=$?
cat "$tmp/out.txt"
check "the same command then waits without submitting twice, and collects" \
  bash -c "[ $rc -eq 0 ] && grep -q '0 submitted now' '$tmp/out.txt' && [ -s '$tmp/slurm/results.csv' ]"
check "and its results equal the local engine's" scripts/sweep/same_results.py "$manifest" "$tmp/local" "$tmp/slurm"

# --- one sampled frame across array tasks ------------------------------------------------------
frame="--scene cornell --fidelity at --width 256 --height 512 --sample 0.5 --threads 1"  # 64 clusters simulated, 16 per segment
rc=0; scripts/sweep/split_frame.sh --engine slurm --poll 1 --segments 4 "$tmp/frame" -- $frame >"$tmp/out.txt" 2>&1 || rc=$?
cat "$tmp/out.txt"
# shellcheck disable=SC2086
"$rtsim" $frame --sample-segments 4 -q --stats "$tmp/frame-single.json"
same_frame() {
  /usr/bin/python3 - "$tmp/frame/frame.json" "$tmp/frame-single.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for j in (a, b):
    for k in ("time_s", "simulation_rate", "memory_mb", "provenance"):  # the host's, and the command line
        j.pop(k)
sys.exit(0 if a == b and a["timing"]["sampling"]["cycles_ci95"] else 1)
PY
}
same=1; same_frame && same=0
check "a sampled frame split over 4 array tasks (segment 0, then 3 reading its plan) merges into the single-process estimate, bit for bit" \
  bash -c "[ $rc -eq 0 ] && [ $same -eq 0 ] && grep -q 'job [0-9]*: 1 tasks' '$tmp/out.txt' && grep -q 'job [0-9]*: 3 tasks' '$tmp/out.txt' && [ -s '$tmp/frame/plan.bin' ]"

# Nothing of ours left running but the two daemons (an exited slurmstepd is a zombie for a moment).
strays=$(ps -eo pid=,stat=,args= | awk -v t="$tmp" '$2 !~ /^Z/ && index($0, t) && $0 !~ /slurmctld|slurmd -D|awk/' | wc -l)
check "no task processes left behind" [ "$strays" -eq 0 ]

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
