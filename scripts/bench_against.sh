#!/usr/bin/env bash
# Simulation speed of this build against another rtsim binary, interleaved in one run so that
# both see the same machine: bunny path tracing 64x64 in every fidelity (and sampled AT), each
# run REPS times alternating old and new (which one goes first alternates too); the fastest run
# of each is compared.
# Usage: scripts/bench_against.sh OLD_RTSIM [REPS]   (default 5; SHARED overrides ../shared/scenes)
# LARGE=1 runs the frames where the functional traversal dominates instead: ship path tracing
# 512x512 (functional; interval sampled at 10 %), the bunny's path tracing 512x512 sampled at 10 %
# and its primary rays 1024x1024 (functional), one thread each. PARTY=1 runs the large scene whose
# memory events dominate instead: party path tracing 128x128 under `paper`, interval and LT, with
# and without TTP, one thread each.
# Prints one line per run kind: old and new wall seconds (the simulation alone, time_s.run),
# new / old, and whether the two binaries wrote the same statistics (wall times aside). A change
# meant to keep the speed should stay within the spread of repeated runs.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1 reps=${2:-5}
shared=${SHARED:-../shared/scenes}
[ -d "$shared/bunny" ] || { echo "error: $shared/bunny not found (set SHARED to the scenes folder)" >&2; exit 2; }
scripts/build.sh >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bunny=(--scene bunny --assets "$shared/bunny" --workload pt --width 64 --height 64 -q)
kinds=("functional|${bunny[*]}" "at|${bunny[*]} --fidelity at" "lt|${bunny[*]} --fidelity lt" "interval|${bunny[*]} --fidelity interval"
       "at_ttp|${bunny[*]} --fidelity at --prefetcher ttp" "at_sample|${bunny[*]} --fidelity at --sample 0.25 --sample-unchecked --threads 1")
if [ "${LARGE:-0}" = 1 ]; then
  [ -d "$shared/ship" ] || { echo "error: $shared/ship not found (set SHARED to the scenes folder)" >&2; exit 2; }
  pt512="--workload pt --width 512 --height 512 --spp 2 -q --threads 1"
  kinds=("ship_pt512_functional|--scene ship --assets $shared/ship $pt512 --fidelity functional"
         "ship_pt512_interval_10pct|--scene ship --assets $shared/ship $pt512 --fidelity interval --sample 0.1"
         "bunny_pt512_interval_10pct|--scene bunny --assets $shared/bunny $pt512 --fidelity interval --sample 0.1"
         "bunny_primary1024_functional|--scene bunny --assets $shared/bunny --workload primary --width 1024 --height 1024 --spp 2 -q --threads 1 --fidelity functional")
fi
if [ "${PARTY:-0}" = 1 ]; then
  [ -d "$shared/party" ] || { echo "error: $shared/party not found (set SHARED to the scenes folder)" >&2; exit 2; }
  party="--scene party --assets $shared/party --workload pt --width 128 --height 128 --config paper -q --threads 1"
  kinds=("party_pt128_interval|$party --fidelity interval" "party_pt128_interval_ttp|$party --fidelity interval --prefetcher ttp"
         "party_pt128_lt|$party --fidelity lt" "party_pt128_lt_ttp|$party --fidelity lt --prefetcher ttp")
fi
for r in $(seq 1 "$reps"); do
  echo "repetition $r of $reps" >&2
  for k in "${kinds[@]}"; do
    name=${k%%|*} args=${k#*|}
    order="old new"; [ $((r % 2)) = 0 ] && order="new old"  # alternate which goes first
    for side in $order; do
      bin=$old; [ $side = new ] && bin=build/rtsim
      # shellcheck disable=SC2086
      "$bin" $args --stats "$out/$name.$side.$r.json"
    done
  done
done
python3 - "$out" "$reps" "${kinds[@]}" <<'PY'
import json, sys, pathlib
d, reps, kinds = pathlib.Path(sys.argv[1]), int(sys.argv[2]), [k.split("|")[0] for k in sys.argv[3:]]
print("| run | old s (fastest) | new s (fastest) | new / old | spread of old runs | same statistics |")
print("|---|---|---|---|---|---|")
def stats(k, side):  # the first repetition's statistics, wall times, host memory and provenance aside
    j = json.loads((d / f"{k}.{side}.1.json").read_text())
    for key in ("time_s", "simulation_rate", "memory_mb", "provenance"):
        j.pop(key, None)
    return j
for k in kinds:
    t = {side: [json.loads((d / f"{k}.{side}.{r}.json").read_text())["time_s"]["run"] for r in range(1, reps + 1)] for side in ("old", "new")}
    o, n = min(t["old"]), min(t["new"])
    same = "yes" if stats(k, "old") == stats(k, "new") else "NO"
    print(f"| {k} | {o:.3f} | {n:.3f} | {n / o:.3f} | {max(t['old']) / o:.2f}x | {same} |")
PY
