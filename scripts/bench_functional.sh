#!/usr/bin/env bash
# Functional benchmark: per scene, BVH statistics and our traversal's rays/s against Embree's on
# the same rays (both traced in one run, one after the other; the ratio is what to compare).
# Usage: scripts/bench_functional.sh [WIDTH] [SPP]   (default 128x128, 2 spp, path tracing)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-128}
spp=${2:-2}
shared=${SHARED:-../shared/scenes}
scripts/build.sh >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {  # name assets: DFS with --verify (speed, agreement), then BFS (nodes per ray)
  local name=$1 assets=$2
  local args=(--scene "$name" --workload pt --width "$size" --height "$size" --spp "$spp" -q)
  [ -n "$assets" ] && args+=(--assets "$assets")
  if ! build/rtsim "${args[@]}" --verify --stats "$out/$name.json"; then echo "$name: rtsim failed" >&2; fi
  build/rtsim "${args[@]}" --traversal bfs --stats "$out/$name.bfs"
}
run wknd ""
run cornell ""
for s in ship bunny ref:dragon bath sprng; do
  name=${s%%:*}; dir=${s#*:}; [ "$dir" = "$s" ] && dir=$name
  [ -d "$shared/$dir" ] && run "$name" "$shared/$dir"
done
python3 - "$out" <<'PY'
import json, sys, pathlib
rows = []
bfs = {}
for f in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    j = json.loads(f.read_text())
    b, s, v = j["bvh"], j["speed"], j["verify"]
    rows.append((j["scene"], b["image_bytes"] / 2**20, b["internal_nodes"], b["triangle_leaves"] + b["procedural_leaves"],
                 b["instance_leaves"], b["depth"], j["rays"], j["nodes_per_ray"], j["max_nodes_per_ray"],
                 s["ours_rays_per_s"] / 1e6, s["embree_rays_per_s"] / 1e6, s["embree_over_ours"], v["mismatches"]))
print("| scene | image MB | internal | prim leaves | inst leaves | depth | rays | nodes/ray | max | ours Mrays/s | Embree Mrays/s | Embree/ours | mismatches |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print("| %s | %.2f | %d | %d | %d | %d | %d | %.1f | %d | %.2f | %.2f | %.1fx | %d |" % r)
print()
print("Nodes visited per ray, path tracing (paper Table 1); Diff > 0: BFS visits more")
print("| scene | DFS avg | BFS avg | diff | DFS max | BFS max | diff |")
print("|---|---|---|---|---|---|---|")
for f in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    d = json.loads(f.read_text()); b = json.loads(f.with_suffix(".bfs").read_text())
    print("| %s | %.1f | %.1f | %+.1f %% | %d | %d | %+.1f %% |" % (d["scene"], d["nodes_per_ray"], b["nodes_per_ray"],
          100 * (b["nodes_per_ray"] / d["nodes_per_ray"] - 1), d["max_nodes_per_ray"], b["max_nodes_per_ray"],
          100 * (b["max_nodes_per_ray"] / d["max_nodes_per_ray"] - 1)))
print()
print("Agreement with Embree per ray (DFS run), by class")
names = None
for f in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    d = json.loads(f.read_text()); c = d["verify"]["classes"]
    if names is None:
        names = list(c)
        print("| scene | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
    print("| %s | " % d["scene"] + " | ".join(str(c[n]) for n in names) + " |")
PY
