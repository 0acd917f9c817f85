#!/usr/bin/env bash
# ThreadSanitizer over the work rtsim runs on several host threads (docs/performance.md, "Threads"):
# builds rtsim with -fsanitize=thread in build-tsan/ (beside the Release build in build/; rtsim
# only, about 75 s on 2 cores) and runs each threaded path with more threads than this machine
# has cores, so that the threads interleave: the functional pass and --verify's checks against
# Embree (a built-in scene and a 20,000-triangle mesh written here, whose BVH Embree builds on
# TBB's threads), a timing run's --verify, the sampling pre-pass and warming (their threads share
# one workload instance), and a split sample's segments on threads of one process (the interval
# fidelity), sharing its scene, BVH image, pre-pass and workloads. A data race fails the run (exit
# status 66) with ThreadSanitizer's report. CI runs
# it after the fuzz smoke. Accesses from Debian's uninstrumented libraries (Embree, TBB, SystemC)
# are not checked (ignore_noninstrumented_modules); scripts/tsan.supp says what else is hidden
# and why. That the statistics are the same for every thread count is the Release suite's test
# (Rtsim.FunctionalThreadsChangeNoResult and the sampling tests), not this script's.
# Usage: scripts/test_threads_tsan.sh
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_UNITY_BUILD=ON -DRTU_SANITIZE=thread >/dev/null
cmake --build build-tsan -j"$(nproc)" --target rtsim
export TSAN_OPTIONS="halt_on_error=1 ignore_noninstrumented_modules=1 suppressions=$PWD/scripts/tsan.supp"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# A height field of 100 x 100 quads, two triangles each: large enough for Embree's builder to use
# its worker threads.
awk 'BEGIN { n = 100
  for (i = 0; i <= n; i++) for (j = 0; j <= n; j++) {
    x = i / n * 2 - 1; y = j / n * 2 - 1; printf "v %f %f %f\n", x, y, 0.3 * sin(6 * x) * cos(6 * y) }
  for (i = 0; i < n; i++) for (j = 0; j < n; j++) {
    a = i * (n + 1) + j + 1; c = a + n + 1; printf "f %d %d %d\nf %d %d %d\n", a, c, a + 1, a + 1, c, c + 1 } }' >"$out/grid.obj"
runs=(
  "--scene wknd --width 64 --height 64 --spp 2 --verify --threads 3"
  "--scene $out/grid.obj --width 64 --height 64 --spp 2 --verify --threads 3"
  "--scene wknd --width 64 --height 64 --spp 2 --fidelity interval --verify --threads 3"
  "--scene cornell --width 256 --height 256 --spp 1 --fidelity interval --sample 0.5 --threads 3"
  "--scene cornell --width 512 --height 256 --spp 1 --fidelity interval --sample 0.5 --sample-segments 3 --threads 3"
)
for args in "${runs[@]}"; do
  echo "tsan: rtsim $args"
  # shellcheck disable=SC2086  # the arguments are words
  build-tsan/rtsim $args -q --stats "$out/stats.json"
done
echo "tsan: ${#runs[@]} runs, no data race reported"
