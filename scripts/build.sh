#!/usr/bin/env bash
# Configures and builds rtunit (Release) in build/: everything, or only the targets given (e.g.
# `scripts/build.sh rtsim`, what the main job runs).
# Usage: scripts/build.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
