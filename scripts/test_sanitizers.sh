#!/usr/bin/env bash
# Builds the project with AddressSanitizer and UndefinedBehaviorSanitizer in build-asan/ (beside
# the Release build in build/) and runs the test suite there: a heap overflow, a use after free,
# a leak, a signed overflow or an invalid shift fails the test that hits it. CI runs it after the
# Release suite. Extra arguments go to ctest (e.g. -R Rtsim).
#
# Sweeps.* is left to the Release suite: it drives rtsim through the sweep shell scripts and runs
# no rtsim code that other tests do not, and it is among the suite's longest groups; CI must stay
# under 20 minutes. So is RtsimSampling.IntervalCoversTheFullRun,
# the suite's longest test under ASan (about 100 s): a statistical check of sampled intervals
# over many draws, whose code (sampled interval runs) the other RtsimSampling tests run here.
# The tests are built with RTU_SANITIZED=1 (tests/test_util.h kSanitized): the longest of the
# rest check a smaller frame or fewer cases here, each saying which (SIGUSR1 and the stop signals,
# segments, sample plans, every key of every preset, the sampled interval fidelity against AT).
# The build is -O1 -g1 (CMakeLists.txt: line tables for the reports, half the compile time).
# (Package.* is not built here at all: tests/CMakeLists.txt.) Tests run one more at a time than
# there are cores: many of them wait on rtsim child processes or poll for a signal's answer.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRTU_SANITIZE=address,undefined >/dev/null
cmake --build build-asan -j"$(nproc)"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd build-asan
ctest --output-on-failure -j"$(($(nproc) + 1))" -E '^(Sweeps\.|RtsimSampling\.IntervalCoversTheFullRun$)' "$@"
