#!/usr/bin/env bash
# Sets up, builds and runs the test suite (GoogleTest under CTest, one process per test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
cd build
ctest --output-on-failure -j"$(nproc)" "$@"
