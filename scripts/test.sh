#!/usr/bin/env bash
# Sets up, builds and runs the test suite (GoogleTest under CTest, one process per test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
shared=$(cd .. && pwd)/shared/scenes
cd build
ctest --output-on-failure -j"$(nproc)" "$@"
# The tests skipped above say why in their own output; ctest's summary lists only their names.
if [ ! -d "$shared" ]; then
  echo "test: the tests listed as skipped need the real scenes in $shared (ship, bunny, dragon, bath,"
  echo "test: sprng, party; not part of this repository: see the README's Credits for their sources);"
  echo "test: every other test ran."
fi
