// A sampled run split into independent segments (docs/sampling.md, "Segments"), as the platform
// writes and merges them: a segment's statistics (its "segment" section: the sampling records of
// sampling/segments.h beside the per-instance counters) and the merge of the segments into one
// timing result; segment_file.h reads them back. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sampling/segments.h"
#include "segment_file.h"
#include "timing_run.h"

namespace rtu {

// The "segment" section of segment `index` of `count`: with the per-instance counters of the
// timing section, everything the merge needs, in JSON that reads back bit for bit (counters and
// cycles are integers; residences are whole cycles).
void write_segment(StatsOut& out, const TimingResult& r, uint32_t index, uint32_t count, const std::vector<IdentityKey>& identity);

// The frame's result from its segments (any order; each index 0..count-1 once, every identity
// equal to `identity`): counters and rays summed, cycles simulated summed, the estimate from every
// segment's records (FrameSample::merge on a sample drawn with SamplingOptions::kNoSegment).
TimingResult merge_segments(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt,
                            std::vector<SegmentRun> segments, const std::vector<IdentityKey>& identity);

}  // namespace rtu
