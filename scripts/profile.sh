#!/usr/bin/env bash
# Where each fidelity's time goes on one frame (docs/performance.md, "Where the time goes"): builds
# rtsim with symbols and frame pointers in build-prof/ (the Release flags plus -g
# -fno-omit-frame-pointer), records a run of each fidelity on one thread with `perf record` (self
# time, whole process: scene load and BVH build included), and prints the table of
# scripts/profile_groups.py and each fidelity's top functions.
# Usage: scripts/profile.sh OUT [FIDELITIES] -- RTSIM_ARGS...
#   FIDELITIES: comma-separated (default functional,interval,lt,at); OUT keeps the perf.data files
#   and each run's statistics. Example (the docs' figures):
#   scripts/profile.sh out/profile-party -- --scene party --assets ../shared/scenes/party \
#     --workload pt --width 256 --height 256 --config paper
# Needs perf (Debian: linux-perf); PERF_FREQ sets the sampling rate (default 499 Hz).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n '2,13p' "$0" >&2; exit 2; }
out=$1; shift
fids=functional,interval,lt,at
if [ "$1" != "--" ]; then fids=$1; shift; fi
[ "${1:-}" = "--" ] || { echo "profile: expected -- before rtsim's arguments" >&2; exit 2; }
shift
command -v perf >/dev/null || { echo "profile: perf not found (apt-get install linux-perf)" >&2; exit 2; }
cmake -S . -B build-prof -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="-g -fno-omit-frame-pointer" -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build build-prof -j"$(nproc)" --target rtsim >/dev/null
mkdir -p "$out"
labels=()
IFS=, read -r -a list <<<"$fids"
for f in "${list[@]}"; do
  echo "profile: $f" >&2
  perf record -q -F "${PERF_FREQ:-499}" -o "$out/$f.perf" build-prof/rtsim "$@" --fidelity "$f" --threads 1 -q \
    --stats "$out/$f.json" >/dev/null 2>"$out/$f.log" || { echo "profile: the $f run failed ($out/$f.log)" >&2; exit 1; }
  labels+=("$f=$out/$f.perf")
done
python3 scripts/profile_groups.py --top 6 "${labels[@]}"
