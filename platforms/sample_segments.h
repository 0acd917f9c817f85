// A sampled run split into independent segments (docs/sampling.md, "Segments"), so that one frame's
// sample can run as many processes (Slurm array tasks, docs/sweeps.md) and be merged into one
// estimate: what a segment's run writes for the merge (the "segment" section of its statistics)
// and the merge itself. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "timing_run.h"

namespace rtu {

// One segment's run as the merge reads it back.
struct SegmentRun {
    uint32_t index = 0, count = 0;
    nlohmann::json identity;  // IdentityKey values by name
    uint64_t cycles_simulated = 0;
    std::vector<WarpRecord> warps;  // the simulated warps' records, in the segment's order
    HierarchyCounts counts;
    WorkloadDriver::RaySummary summary;
    uint64_t payloads_allocated = 0;
};

// One key of a segment's identity: what must be equal in every segment of one run.
struct IdentityKey {
    std::string name, value, what;
};

// The "segment" section of segment `index` of `count`: with the per-instance counters of the
// timing section, everything the merge needs, in JSON that reads back bit for bit (counters and
// cycles are integers; residences are whole cycles).
void write_segment(StatsOut& out, const TimingResult& r, uint32_t index, uint32_t count, const std::vector<IdentityKey>& identity);

// A sample plan (--sample-plan): the functional pre-pass of one frame (per shader warp, each
// trace's critical path), kept in a file so that the segments of a split sample and their merge,
// and every sampled run of a sweep over configurations, fidelities or samples of that frame,
// trace the frame once instead of once each. `identity`: what the pre-pass depends on
// (prepass_identity in simulation.h); a plan of another is refused. Binary, little-endian as the
// host: "RTUPLAN2", the identity's length (uint64) and text, the warps (uint64), the pre-pass's
// threads (uint32), per warp its traces (uint32) and their critical paths (uint32 each); then
// twice (in rounds, then warp by warp) a count (uint64: 0, or the warps) and per warp its first
// reads of nodes (uint32 each). A plan of version 1 ("RTUPLAN1", no first reads) is refused with
// a message to remove it.
// The file of a plan: `given` itself, or where `given` is a folder (it exists, or its name ends
// in '/'), `given`/plan-HASH.bin with HASH the 64-bit FNV-1a hash of `identity` in hex, so that
// one folder keeps the plans of a sweep over scenes and frames, one per frame. Empty: empty.
std::string plan_file(const std::string& given, const std::string& identity);
// 64-bit FNV-1a of `n` bytes, continued from `h` (the plans' identities and file names).
constexpr uint64_t kFnv1aBasis = 14695981039346656037ull;
uint64_t fnv1a(const void* data, size_t n, uint64_t h = kFnv1aBasis);
void write_plan(const std::string& file, const std::string& identity, const PrepassResult& p);
// nullopt if `file` does not exist; InputError naming it if it is not a plan of this frame.
std::optional<PrepassResult> read_plan(const std::string& file, const std::string& identity);

// Reads a segment's statistics file (written by rtsim --segment); InputError naming `file` if it
// is not one.
SegmentRun read_segment(const std::string& file);

// The frame's result from its segments (any order; each index 0..count-1 once, every identity
// equal to `identity`): counters and rays summed, cycles simulated summed, the estimate from every
// segment's records (WorkloadDriver::merge on a driver drawn with SamplingOptions::kNoSegment).
TimingResult merge_segments(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt,
                            std::vector<SegmentRun> segments, const std::vector<IdentityKey>& identity);

}  // namespace rtu
