// A sample split into independent segments (docs/sampling.md, "Segments"), so that one frame's
// sample can run as many processes (Slurm array tasks, docs/sweeps.md) and be merged into one
// estimate: the sampling side of a segment's file (its simulated warps' records, what must be
// equal in every segment) and the checked order of the segments for the merge. The file's
// counters and the merge of a timing run are the platform's (platforms/sample_segments.h).
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "estimator.h"

namespace rtu {

// One key of a segment's identity: what must be equal in every segment of one run.
struct IdentityKey {
    std::string name, value, what;
};

// Per simulated warp: its index in the frame, its rays' node reads (and of them those that missed
// L1 / went to DRAM), each trace's residence in whole cycles, its SM and when its last trace
// left, so that the file reads back bit for bit. The rest (stratum, weight, critical paths) the
// merge draws again.
nlohmann::ordered_json segment_warps_json(const std::vector<WarpRecord>& warps);
extern const char* const kSegmentWarpsNote;
// The records back; InputError for anything that is not one.
std::vector<WarpRecord> segment_warps_from_json(const nlohmann::json& warps);

// A whole number in [0, max] (nlohmann's get<uint64_t> of a negative or fractional number, or of
// one beyond the type, would wrap or be undefined), or a number; any other value is bad input.
uint64_t json_whole(const nlohmann::json& j, uint64_t max = UINT64_MAX);
double json_real(const nlohmann::json& j);

// One segment as the merge orders it: its index, count and identity.
struct SegmentHeader {
    uint32_t index = 0, count = 0;
    nlohmann::json identity;  // IdentityKey values by name
};
// Checks that `segments` (sorted by index) are segments 0..count-1 of one run whose identity is
// `identity`; InputError naming the first that is not.
void check_segment_set(const std::vector<SegmentHeader>& segments, uint32_t count, const std::vector<IdentityKey>& identity);

}  // namespace rtu
