#!/usr/bin/env bash
# Fuzzes rtsim's input readers with libFuzzer (fuzz/: meshes, ray files, camera files, the
# configuration; and the peripheral's BVH images and ray records from untrusted memory), built with clang, AddressSanitizer and UBSan in build-fuzz/. Each harness starts
# from its seed corpus (fuzz/corpus/NAME), with its dictionary (fuzz/dict/NAME.dict) where there
# is one, for SECONDS seconds; what it learns is kept in out/fuzz/corpus/NAME for the next run.
# A finding (crash, sanitizer report, an exception other than bad input, a timeout of 10 s, or
# more than 2 GB) is written to out/fuzz/findings/. Prints executions and findings per harness.
# Harnesses run side by side, as many at once as there are cores, each for its own SECONDS.
# Usage: scripts/fuzz.sh [SECONDS (default 60)] [HARNESS...]   Exit status: 1 if anything was found.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(mesh assimp importer rays camera config image descriptor segment)
scripts/setup.sh --fuzz
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=OFF -DRTU_FUZZ=ON \
  -DRTU_SANITIZE=address,undefined,fuzzer-no-link >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target "${harnesses[@]/#/fuzz_}" >/dev/null
mkdir -p out/fuzz/findings
# Assimp's child process (workloads/mesh_io.cpp) runs without its address-space limit under ASan:
# an allocation beyond 2 GB ends it (reported as bad input); in the harness itself it is a finding
# (ASan's limit, 2048 MB, trips before libFuzzer's -malloc_limit_mb).
export ASAN_OPTIONS=${ASAN_OPTIONS:-max_allocation_size_mb=2048}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Every harness gets `seconds` of its own; they run side by side, as many at once as there are
# cores, and are reported in order.
fuzz_one() {
  local h=$1 corpus=out/fuzz/corpus/$1 dict=() rc=0
  mkdir -p "$corpus"
  [ -f "fuzz/dict/$h.dict" ] && dict=(-dict="fuzz/dict/$h.dict")
  build-fuzz/fuzz/fuzz_$h "$corpus" "fuzz/corpus/$h" "${dict[@]}" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -malloc_limit_mb=4096 -print_final_stats=1 -artifact_prefix="out/fuzz/findings/$h-" >"out/fuzz/$h.log" 2>&1 || rc=$?
  echo "$rc" >"out/fuzz/$h.rc"
}
declare -A before
for h in "${harnesses[@]}"; do before[$h]=$(find out/fuzz/findings -name "$h-*" | wc -l); done
for h in "${harnesses[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  fuzz_one "$h" &
done
wait
status=0
printf '%-8s %12s %10s  %s\n' harness executions findings corpus
for h in "${harnesses[@]}"; do
  corpus=out/fuzz/corpus/$h
  log=out/fuzz/$h.log
  rc=$(cat "out/fuzz/$h.rc")
  runs=$(awk '/stat::number_of_executed_units/ {n = $2} END {print n}' "$log")
  found=$(($(find out/fuzz/findings -name "$h-*" | wc -l) - before[$h]))
  printf '%-8s %12s %10s  %s\n' "$h" "${runs:-?}" "$found" "$(find "$corpus" -type f | wc -l) inputs"
  if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
    status=1
    echo "  finding: see $log and out/fuzz/findings/$h-*; reproduce: build-fuzz/fuzz/fuzz_$h FILE" >&2
    grep -m3 -E "ERROR|runtime error|uncaught|deadly|==[0-9]+==" "$log" | sed 's/^/    /' >&2 || true
  fi
done
exit $status
