// A segment's statistics file as the merge reads it back (docs/sampling.md, "Segments"): its
// checksum, and its "segment" section beside the per-instance counters of its timing section.
// Plain C++ on model/ and sampling/ alone (no SystemC, no simulation): the libFuzzer harness
// fuzz/fuzz_segment.cpp links it without the platform.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sampling/segments.h"
#include "timing_stats.h"

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

// Seals a segment's finished statistics: `segment.checksum` becomes the 64-bit FNV-1a of the
// document's compact JSON with that key empty and without the host's keys (time_s,
// simulation_rate, memory_mb) and the provenance, so that a file whose bytes are not the ones
// written is refused by the merge (a flipped digit in a counter or a residence changes the
// estimate silently otherwise). Nothing to do for a document without a "segment" section.
void seal_segment(nlohmann::ordered_json& stats);

// Reads a segment's statistics file (written by rtsim --segment); InputError naming `file` if it
// is not one, or if its checksum does not match its contents.
SegmentRun read_segment(const std::string& file);

}  // namespace rtu
