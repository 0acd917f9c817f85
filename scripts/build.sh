#!/usr/bin/env bash
# Configures and builds rtunit (Release) in build/: everything, or only the targets given (e.g.
# `scripts/build.sh rtsim`, what the main job runs).
# Usage: scripts/build.sh [TARGET...]
# A unity build (CMake's CMAKE_UNITY_BUILD: a library's sources compiled a few to a unit): the
# templates that most files instantiate (nlohmann::json above all) are compiled once per unit, not
# once per file; a build from scratch took 230 s against 266 s here (2 cores, GCC 12). Rebuilding
# after a change to one file recompiles its unit: RTU_UNITY=OFF scripts/build.sh builds file by file.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD="${RTU_UNITY:-ON}" >/dev/null
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
