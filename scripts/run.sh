#!/usr/bin/env bash
# Sets up, builds and runs the main job: path tracing the built-in `wknd` scene (128x128, 2 spp)
# on the RT-unit model, checked ray by ray against Embree. Extra arguments go to rtsim and
# override the defaults, e.g. scripts/run.sh --scene cornell --workload ao
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh >/dev/null
mkdir -p out
exec build/rtsim --scene wknd --workload pt --verify --stats out/stats.json --image out/frame.png "$@"
