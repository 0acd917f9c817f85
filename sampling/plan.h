// A sample plan (--sample-plan): the functional pre-pass of one frame (per shader warp, each
// trace's critical path; per warp its first reads of nodes), kept in a file so that the segments
// of a split sample and their merge, and every sampled run of a sweep over configurations,
// fidelities or samples of that frame, trace the frame once instead of once each. `identity`:
// what the pre-pass depends on (prepass_identity, platforms/simulation.h); a plan of another is
// refused. Binary, little-endian as the host: "RTUPLAN3", the identity's length (uint64) and
// text, the warps (uint64), the pre-pass's threads (uint32), per warp its traces (uint32) and
// their critical paths (uint32 each); then twice (in rounds, then warp by warp) a count (uint64:
// 0, or the warps) and per warp its first reads of nodes (uint32 each); last, a 64-bit FNV-1a
// checksum of every byte before it, so that a damaged plan is refused rather than believed.
// Plans of versions 1 ("RTUPLAN1", no first reads) and 2 (no checksum) are refused with a
// message to remove them. Plain C++ (no SystemC).
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "prepass.h"

namespace rtu {

// The file of a plan: `given` itself, or where `given` is a folder (it exists, or its name ends
// in '/'), `given`/plan-HASH.bin with HASH the 64-bit FNV-1a hash of `identity` in hex, so that
// one folder keeps the plans of a sweep over scenes and frames, one per frame. Empty: empty.
std::string plan_file(const std::string& given, const std::string& identity);
// 64-bit FNV-1a of `n` bytes, continued from `h` (the plans' identities and file names).
constexpr uint64_t kFnv1aBasis = 14695981039346656037ull;
uint64_t fnv1a(const void* data, size_t n, uint64_t h = kFnv1aBasis);
// The plan's bytes (the caller writes them whole: several segment tasks may write one plan at once).
std::string plan_bytes(const std::string& identity, const PrepassResult& p);
// nullopt if `file` does not exist; InputError naming it if it is not a plan of this frame.
std::optional<PrepassResult> read_plan(const std::string& file, const std::string& identity);

}  // namespace rtu
