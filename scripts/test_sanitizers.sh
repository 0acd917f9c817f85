#!/usr/bin/env bash
# Builds the project with AddressSanitizer and UndefinedBehaviorSanitizer in build-asan/ (beside
# the Release build in build/) and runs the test suite there: a heap overflow, a use after free,
# a leak, a signed overflow or an invalid shift fails the test that hits it. CI runs it after the
# Release suite. Usage: scripts/test_sanitizers.sh [--all] [CTEST ARGUMENTS...] (e.g. -R Rtsim);
# --all: also the tests left to the Release suite (below).
#
# Left to the Release suite (CI must stay under 20 minutes; the sanitizers find faults in code that
# runs, and each of these runs only code that tests kept here run too):
# - Sweeps.*: rtsim driven through the sweep shell scripts;
# - checks of accuracy or speed on whole frames, whose runs (AT, LT, interval, sampled interval,
#   --check-error) other RtsimSampling, RtsimError and RtsimTiming tests run here:
#   RtsimSampling.IntervalCoversTheFullRun (the suite's longest under ASan, about 100 s),
#   RtsimSampling.IntervalCarriesTheDesignBias, RtsimSampling.IntervalFidelitySampledAsAt,
#   RtsimSampling.PrimaryRaysOfASparseFrame (37-48 s under ASan; the per-SM warming it checks
#   the estimate of runs here in SampleWarming.EachSmIsWarmedWhenItStartsTheCluster),
#   RtsimSampling.SampleWidthPlansItsRateFromAPilot (36 s under ASan; a width's pilot that is
#   the run, and its statistics, run here in RtsimStats.SchemaListsEveryKeyWrittenAndNothingElse;
#   the child pilots of AT and LT run in the Release suite only),
#   RtsimTiming.IntervalIsWithinTheStatedBoundOfAt, RtsimTiming.IntervalShaderReadsKeepAtsPace (the
#   shaders' reads in every fidelity run here in RtsimTiming.ShaderReadsGoThroughL1L2AndDram),
#   RtsimPresets.TtpSpeedsUpPathTracingOnEveryPreset
#   RtsimError.EveryTimingRunStatesItsError (every timing run writes its error statement)
#   and RtsimError.CheckErrorPairsTheSameClustersInAt (--check-error's children and its pairing
#   run here in RtsimError.CheckErrorRefusesWhatCostsAsMuchAsAt and RtsimStats.SchemaListsEveryKey...);
# - checks that observing changes no statistic: RtsimTiming.TracingChangesNoStatistic and
#   RtsimTiming.TimelineChangesNoStatistic (the VCD and timeline writers run here in
#   RtsimTiming.VcdHasTheDocumentedSignals, RtsimTiming.TraceWindowSetsTheWaveformSamplingOnly and
#   RtsimTiming.MergingReadsInFlightChangesNoHitInAnyFidelity).
# Together about a fifth of the suite's test-seconds here. `scripts/test_sanitizers.sh --all`
# runs them too.
# The tests are built with RTU_SANITIZED=1 (tests/test_util.h kSanitized): the longest of the rest
# check a smaller frame, primary rays or fewer cases here, each saying which (SIGUSR1 and the stop
# signals, segments, sample plans, every key of every preset (one preset, primary rays), the
# full-frame sample (primary rays), the sampled interval fidelity against AT).
# The build is -O1 -g1 (CMakeLists.txt: line tables for the reports, half the compile time), a
# unity build as scripts/build.sh's, and leaves three of UBSan's checks to the fuzz build
# (scripts/fuzz.sh, clang, every UBSan check): vptr (dynamic types), alignment and null. They made
# GCC's instrumented build 1.3x as long (474 s against 362 s from scratch here, file by file;
# platforms/segment_file.cpp 31-36 s against 18-20 s; with the unity build too, 302 s), and where
# they matter most, in the readers of untrusted files and memory (misaligned records, casts of
# what a file claims), the fuzz harnesses run them; a null dereference is still a fault under
# AddressSanitizer (SEGV).
# (Package.* is not built here at all: tests/CMakeLists.txt.) Tests run one more at a time than
# there are cores: many of them wait on rtsim child processes or poll for a signal's answer.
set -euo pipefail
cd "$(dirname "$0")/.."
left='^(Sweeps\.|RtsimSampling\.(IntervalCoversTheFullRun|IntervalCarriesTheDesignBias|IntervalFidelitySampledAsAt|PrimaryRaysOfASparseFrame|SampleWidthPlansItsRateFromAPilot)$|RtsimTiming\.(IntervalIsWithinTheStatedBoundOfAt|IntervalShaderReadsKeepAtsPace|TracingChangesNoStatistic|TimelineChangesNoStatistic)$|RtsimPresets\.TtpSpeedsUpPathTracingOnEveryPreset$|RtsimError\.(EveryTimingRunStatesItsError|CheckErrorPairsTheSameClustersInAt)$)'
if [ "${1:-}" = "--all" ]; then left='^$'; shift; fi
scripts/setup.sh
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_UNITY_BUILD=ON -DRTU_SANITIZE=address,undefined \
  -DRTU_NO_SANITIZE=vptr,alignment,null >/dev/null
cmake --build build-asan -j"$(nproc)"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd build-asan
ctest --output-on-failure -j"$(($(nproc) + 1))" -E "$left" "$@"
