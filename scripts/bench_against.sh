#!/usr/bin/env bash
# Simulation speed of this build against another rtsim binary, interleaved in one run so that
# both see the same machine: bunny path tracing 64x64 in every fidelity (and sampled AT), each
# run REPS times alternating old and new (which one goes first alternates too); the fastest run
# of each is compared.
# Usage: scripts/bench_against.sh OLD_RTSIM [REPS]   (default 5; SHARED overrides ../shared/scenes)
# Prints one line per run kind: old and new wall seconds (the simulation alone, time_s.run) and
# new / old. A change meant to keep the speed should stay within the spread of repeated runs.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1 reps=${2:-5}
shared=${SHARED:-../shared/scenes}
[ -d "$shared/bunny" ] || { echo "error: $shared/bunny not found (set SHARED to the scenes folder)" >&2; exit 2; }
scripts/build.sh >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bunny=(--scene bunny --assets "$shared/bunny" --workload pt --width 64 --height 64 -q)
kinds=("functional|" "at|--fidelity at" "lt|--fidelity lt" "interval|--fidelity interval" "at_ttp|--fidelity at --prefetcher ttp"
       "at_sample|--fidelity at --sample 0.25 --sample-unchecked --threads 1")
for r in $(seq 1 "$reps"); do
  echo "repetition $r of $reps" >&2
  for k in "${kinds[@]}"; do
    name=${k%%|*} args=${k#*|}
    order="old new"; [ $((r % 2)) = 0 ] && order="new old"  # alternate which goes first
    for side in $order; do
      bin=$old; [ $side = new ] && bin=build/rtsim
      # shellcheck disable=SC2086
      "$bin" "${bunny[@]}" $args --stats "$out/$name.$side.$r.json"
    done
  done
done
python3 - "$out" "$reps" "${kinds[@]}" <<'PY'
import json, sys, pathlib
d, reps, kinds = pathlib.Path(sys.argv[1]), int(sys.argv[2]), [k.split("|")[0] for k in sys.argv[3:]]
print("| run (bunny pt 64x64) | old s (fastest) | new s (fastest) | new / old | spread of old runs |")
print("|---|---|---|---|---|")
for k in kinds:
    t = {side: [json.loads((d / f"{k}.{side}.{r}.json").read_text())["time_s"]["run"] for r in range(1, reps + 1)] for side in ("old", "new")}
    o, n = min(t["old"]), min(t["new"])
    print(f"| {k} | {o:.3f} | {n:.3f} | {n / o:.3f} | {max(t['old']) / o:.2f}x |")
PY
