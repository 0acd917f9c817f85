// A sampled run split into independent segments (docs/sampling.md, "Segments"), as the platform
// writes and reads them: a segment's statistics (its "segment" section: the sampling records of
// sampling/segments.h beside the per-instance counters) and the merge of the segments into one
// timing result. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sampling/segments.h"
#include "timing_run.h"

namespace rtu {

// One segment's run as the merge reads it back.
struct SegmentRun {
    SegmentHeader header;
    uint64_t cycles_simulated = 0;
    std::vector<WarpRecord> warps;  // the simulated warps' records, in the segment's order
    HierarchyCounts counts;
    WorkloadDriver::RaySummary summary;
    uint64_t payloads_allocated = 0;
};

// The "segment" section of segment `index` of `count`: with the per-instance counters of the
// timing section, everything the merge needs, in JSON that reads back bit for bit (counters and
// cycles are integers; residences are whole cycles).
void write_segment(StatsOut& out, const TimingResult& r, uint32_t index, uint32_t count, const std::vector<IdentityKey>& identity);

// Seals a segment's finished statistics: `segment.checksum` becomes the 64-bit FNV-1a of the
// document's compact JSON with that key empty and without the host's keys (time_s,
// simulation_rate, memory_mb) and the provenance, so that a file whose bytes are not the ones
// written is refused by the merge (a flipped digit in a counter or a residence changes the
// estimate silently otherwise). Nothing to do for a document without a "segment" section.
void seal_segment(nlohmann::ordered_json& stats);

// Reads a segment's statistics file (written by rtsim --segment); InputError naming `file` if it
// is not one, or if its checksum does not match its contents.
SegmentRun read_segment(const std::string& file);

// The frame's result from its segments (any order; each index 0..count-1 once, every identity
// equal to `identity`): counters and rays summed, cycles simulated summed, the estimate from every
// segment's records (FrameSample::merge on a sample drawn with SamplingOptions::kNoSegment).
TimingResult merge_segments(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt,
                            std::vector<SegmentRun> segments, const std::vector<IdentityKey>& identity);

}  // namespace rtu
