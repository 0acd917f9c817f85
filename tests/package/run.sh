#!/usr/bin/env bash
# The installed package as a platform builder meets it (docs/peripheral.md, "Install"):
# installs the build into a temporary prefix, checks the files and what the library exports,
# builds the installed example platform out of tree with only CMAKE_PREFIX_PATH (as C++17, C++20
# and C++14, and with Embree, absl and assimp hidden from find_package), and through pkg-config,
# runs each and expects "N passed, 0 failed"; checks that a newer version than installed is
# refused; configures the source tree as another project's subproject; makes the Debian package
# (cpack -G DEB) and builds the example against its contents. Prints "N passed, M failed";
# exit 1 on a failure.
# Usage: tests/package/run.sh BUILD_DIR
set -uo pipefail
build=$(cd "$1" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
check() {  # check NAME COMMAND...: passes when the command succeeds
  local name=$1; shift
  if "$@" > "$tmp/out.txt" 2>&1; then passed=$((passed + 1)); echo "pass: $name"
  else failed=$((failed + 1)); echo "FAIL: $name"; tail -20 "$tmp/out.txt" | sed 's/^/    /'; fi
}
prefix=$tmp/prefix
check "cmake --install" cmake --install "$build" --prefix "$prefix"
# The library's folder: Debian's multiarch one (lib/x86_64-linux-gnu) where the compiler names one.
ma=$(gcc -print-multiarch 2>/dev/null)
lib=lib${ma:+/$ma}

# P1: the files, no build-tree paths, SystemC the only public dependency, the exports.
files_present() {
  for f in $lib/librtunit.so $lib/librtunit.so.0 include/rtunit/peripheral.h include/rtunit/job.h include/rtunit/rtu_regs.h \
           include/rtunit/export.h $lib/cmake/rtunit/rtunitConfig.cmake $lib/cmake/rtunit/rtunitConfigVersion.cmake \
           $lib/cmake/rtunit/rtunitTargets.cmake $lib/pkgconfig/rtunit.pc share/rtunit/examples/soc_vp/CMakeLists.txt \
           share/rtunit/examples/soc_vp/soc_vp.cpp share/rtunit/examples/soc_vp/soc_vp.h share/rtunit/data/cornell.rtubvh \
           share/rtunit/data/cornell.rays share/rtunit/data/cornell.hits; do
    [ -e "$prefix/$f" ] || { echo "missing: $f"; return 1; }
  done
}
check "installed files" files_present
no_build_paths() { ! grep -rlE "$build|$(cd "$build/.." && pwd)/(model|tlm|platforms|workloads)" "$prefix/$lib/cmake" "$prefix/$lib/pkgconfig"; }
check "no build-tree paths in the package files" no_build_paths
only_systemc() { grep -q 'INTERFACE_LINK_LIBRARIES "rtunit::systemc"' "$prefix/$lib/cmake/rtunit/rtunitTargets.cmake"; }
check "SystemC is the only public dependency" only_systemc
soname() { readelf -d "$prefix/$lib/librtunit.so" | grep -q 'SONAME.*librtunit.so.0'; }
check "SONAME librtunit.so.0" soname
# The scene importer is rtsim's: the library loads neither Assimp nor Draco (nor Embree).
no_importer() { ! readelf -d "$prefix/$lib/librtunit.so" | grep -E 'NEEDED.*(assimp|draco|embree)'; }
check "the library needs neither Assimp, Draco nor Embree" no_importer
exports() {
  local syms; syms=$(nm -D --defined-only "$prefix/$lib/librtunit.so" | c++filt)
  echo "$syms" | grep -q 'rtu::RtUnitPeripheral::RtUnitPeripheral' && echo "$syms" | grep -q 'rtu::reference_hits' &&
    ! echo "$syms" | grep -qE 'absl::|glm::|nlohmann|rtu::RtComplex|rtu::BvhImage'
}
check "exports the API and nothing of absl, glm or the model" exports
headers_alone() {
  for h in peripheral.h job.h rtu_regs.h export.h; do
    echo "#include <rtunit/$h>" | g++ -std=c++17 -DSC_CPLUSPLUS=201703L -I"$prefix/include" -x c++ -fsyntax-only - || return 1
    ! grep -qE '#include <(glm|absl|nlohmann)' "$prefix/include/rtunit/$h" || return 1
  done
}
check "each public header compiles alone, without glm, absl or nlohmann" headers_alone

# P2: the installed example, out of tree, with only CMAKE_PREFIX_PATH. Every build of it here, as
# its CMakeLists.txt documents, takes no build type: unoptimised, 4.4 s a compile against 7.8 s at
# -O2 (the simulation runs in the library, which is optimised).
cp -r "$prefix/share/rtunit/examples/soc_vp" "$tmp/vp"
consumer() {  # consumer STD [EXTRA CMAKE ARGS]
  local std=$1; shift
  local b="$tmp/vp-build-$std"
  cmake -S "$tmp/vp" -B "$b" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_STANDARD="$std" "$@" > "$b.log" 2>&1 &&
    cmake --build "$b" -j2 >> "$b.log" 2>&1 && "$b/soc_vp" | tee -a "$b.log" | grep -q ' passed, 0 failed' || { tail -20 "$b.log"; return 1; }
}
check "out-of-tree example, C++17" consumer 17
check "out-of-tree example, C++20 (SC_CPLUSPLUS from the package)" consumer 20 \
  -DCMAKE_DISABLE_FIND_PACKAGE_embree=ON -DCMAKE_DISABLE_FIND_PACKAGE_absl=ON -DCMAKE_DISABLE_FIND_PACKAGE_assimp=ON
check "out-of-tree example, C++14 (raised to 17 by the package)" consumer 14
# P3: pkg-config, as a Makefile-built platform would.
pkgconf() {
  g++ -std=c++17 -o "$tmp/vp-pc" "$tmp/vp/soc_vp.cpp" -DRTU_SOC_VP_DATA="\"$prefix/share/rtunit/data/cornell\"" \
      $(PKG_CONFIG_PATH="$prefix/$lib/pkgconfig" pkg-config --cflags --libs rtunit) &&
    LD_LIBRARY_PATH="$prefix/$lib" "$tmp/vp-pc" --fidelity at --data "$prefix/share/rtunit/data/wknd" | grep -q ' passed, 0 failed'
}
check "pkg-config consumer (AT, wknd's data)" pkgconf
# P5: a newer version than the one installed is refused at configure time.
newer() {
  mkdir -p "$tmp/newer" && printf 'cmake_minimum_required(VERSION 3.20)\nproject(n CXX)\nfind_package(rtunit 0.2 REQUIRED)\n' > "$tmp/newer/CMakeLists.txt" &&
    ! cmake -S "$tmp/newer" -B "$tmp/newer/b" -DCMAKE_PREFIX_PATH="$prefix" > "$tmp/newer.log" 2>&1 && grep -q '0.1.0' "$tmp/newer.log"
}
check "find_package(rtunit 0.2) is refused by 0.1" newer
# P6: the source tree as a subproject of a platform's own CMake project (add_subdirectory): its
# paths are the project's, not the top level's; configured, and the model library's one source
# that reads a generated header (model/config.cpp: config_presets.h) compiled, which takes less
# than half the time of the whole library. Makefiles, whose per-directory object targets name it.
source=$(cd "$(dirname "$0")/../.." && pwd)
super() {
  mkdir -p "$tmp/super" &&
    printf 'cmake_minimum_required(VERSION 3.20)\nproject(platform CXX)\nadd_subdirectory(%s rtunit)\n' "$source" > "$tmp/super/CMakeLists.txt" &&
    cmake -S "$tmp/super" -B "$tmp/super/b" -G "Unix Makefiles" -DBUILD_TESTING=OFF > "$tmp/super.log" 2>&1 &&
    make -C "$tmp/super/b/rtunit" model/config.cpp.o >> "$tmp/super.log" 2>&1 || { tail -20 "$tmp/super.log"; return 1; }
}
check "as a subproject (add_subdirectory): configures, and the model's generated header is found" super
# P7: the Debian package (cpack -G DEB): it depends on libsystemc-dev and the runtime libraries,
# holds the same files under /usr, and the installed example builds against its contents alone.
deb() {
  (cd "$build" && cpack -G DEB -B "$tmp/deb" > "$tmp/deb.log" 2>&1) || { tail -20 "$tmp/deb.log"; return 1; }
  local pkg; pkg=$(ls "$tmp"/deb/rtunit-dev_*_*.deb) || return 1
  dpkg-deb -f "$pkg" Depends | tee "$tmp/deb-depends.txt" | grep -q 'libsystemc-dev (>= 2.3.4)' || { cat "$tmp/deb-depends.txt"; return 1; }
  grep -q 'libabsl' "$tmp/deb-depends.txt" || return 1
  dpkg-deb -x "$pkg" "$tmp/debroot" || return 1
  for f in usr/$lib/librtunit.so.0 usr/include/rtunit/peripheral.h usr/$lib/cmake/rtunit/rtunitConfig.cmake usr/$lib/pkgconfig/rtunit.pc \
           usr/share/rtunit/examples/soc_vp/soc_vp.cpp usr/share/rtunit/data/cornell.rtubvh usr/bin/rtsim \
           usr/share/doc/rtunit-dev/copyright; do
    [ -e "$tmp/debroot/$f" ] || { echo "missing in the package: $f"; return 1; }
  done
  local b="$tmp/vp-build-deb"
  cp -r "$tmp/debroot/usr/share/rtunit/examples/soc_vp" "$tmp/vp-deb" &&
    cmake -S "$tmp/vp-deb" -B "$b" -DCMAKE_PREFIX_PATH="$tmp/debroot/usr" > "$b.log" 2>&1 &&
    cmake --build "$b" -j2 >> "$b.log" 2>&1 && LD_LIBRARY_PATH="$tmp/debroot/usr/$lib" "$b/soc_vp" | tee -a "$b.log" | grep -q ' passed, 0 failed' ||
    { tail -20 "$b.log"; return 1; }
}
check "Debian package (cpack -G DEB): dependencies, files, the example built against it" deb
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
