#!/usr/bin/env bash
# Timing-model benchmark: path tracing at SIZE x SIZE (default 64) on bunny and ship. Prints, from
# one run of each fidelity on the same rays: wall time of the simulation, rays/s, and the ratio to
# Embree's time on those rays (measured inside the functional run); then LT's error against AT
# at three quanta. Machines here are shared and noisy: compare the ratios.
# Usage: scripts/bench_timing.sh [SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-64}
shared=${SHARED:-../shared/scenes}
scripts/build.sh >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in bunny ship; do
  common=(--scene "$scene" --assets "$shared/$scene" --workload pt --width "$size" --height "$size" -q)
  build/rtsim "${common[@]}" --verify --stats "$out/$scene.functional.json"
  build/rtsim "${common[@]}" --fidelity at --stats "$out/$scene.at.json"
  for q in 100 1000 10000; do
    build/rtsim "${common[@]}" --fidelity lt --quantum "$q" --stats "$out/$scene.lt$q.json"
  done
done
python3 - "$out" <<'PY'
import json, sys, pathlib
d = pathlib.Path(sys.argv[1])
print("| scene | fidelity | rays | wall s | rays/s | x Embree time | cycles | L1 miss | L2 miss |")
print("|---|---|---|---|---|---|---|---|---|")
for scene in ("bunny", "ship"):
    f = json.loads((d / f"{scene}.functional.json").read_text())
    embree_s = f["speed"]["embree_s"]
    rows = [("embree", f["rays"], embree_s, None), ("functional", f["rays"], f["speed"]["ours_s"], None)]
    for name in ("lt10000", "lt1000", "lt100", "at"):
        j = json.loads((d / f"{scene}.{name}.json").read_text())
        rows.append((name.replace("lt", "lt q=") if name.startswith("lt") else name, j["rays"], j["time_s"]["run"], j))
    for name, rays, wall, j in rows:
        cyc = j["cycles"] if j else ""
        l1 = "%.3f" % j["timing"]["l1"]["demand"]["miss_rate"] if j else ""
        l2 = "%.3f" % j["timing"]["l2"]["demand"]["miss_rate"] if j else ""
        print("| %s | %s | %d | %.3f | %d | %.1fx | %s | %s | %s |" % (scene, name, rays, wall, rays / wall, wall / embree_s, cyc, l1, l2))
print()
print("LT against AT (same rays): error in total cycles and L1 miss rate")
print("| scene | quantum | cycles | error | L1 miss rate | error (points) | speed-up over AT |")
print("|---|---|---|---|---|---|---|")
for scene in ("bunny", "ship"):
    at = json.loads((d / f"{scene}.at.json").read_text())
    for q in (100, 1000, 10000):
        lt = json.loads((d / f"{scene}.lt{q}.json").read_text())
        e = 100.0 * (lt["cycles"] - at["cycles"]) / at["cycles"]
        m_at, m_lt = at["timing"]["l1"]["demand"]["miss_rate"], lt["timing"]["l1"]["demand"]["miss_rate"]
        print("| %s | %d | %d (AT %d) | %+.2f %% | %.4f (AT %.4f) | %+.2f | %.2fx |" % (scene, q, lt["cycles"], at["cycles"], e, m_lt, m_at,
              100 * (m_lt - m_at), at["time_s"]["run"] / lt["time_s"]["run"]))
PY
