// What a run measured (RunRecord), and the one place that writes a run's statistics from it
// (write_stats; with a schema, stats_schema lists every key). Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "error_estimate.h"
#include "model/bvh_image.h"
#include "model/config.h"
#include "model/fidelity.h"
#include "model/stats.h"
#include "model/traversal.h"
#include "sampling/segments.h"
#include "sampling/width.h"
#include "timing_run.h"
#include "workloads/rays.h"
#include "workloads/verify.h"

namespace rtu {

const char* traversal_name(TraversalOrder o);

// What a run measured, for its statistics.
struct RunRecord {
    std::string scene, workload;
    Fidelity fidelity = Fidelity::Functional;
    TraversalOrder order = TraversalOrder::DFS;
    bool has_params = false;
    WorkloadParams params;
    uint64_t rays = 0, invalid = 0, hits = 0, nodes_visited = 0;
    uint32_t max_nodes = 0;
    BvhStats bvh;
    bool two_level = false;
    double load_s = 0, build_s = 0, run_s = 0;
    double scene_mb = 0, image_mb = 0, decoded_mb = 0, peak_mb = 0, estimate_mb = 0;
    const TimingResult* timing = nullptr;  // timing runs
    ErrorEstimate error;                   // timing runs
    const HwConfig* hw = nullptr;
    const Config* config = nullptr;
    const std::vector<std::string>* command_line = nullptr;  // the provenance's (none: not written)
    double sample_rate = 1.0;
    const SampleWidth* width = nullptr;  // --sample-width: what it planned
    const VerifyCounts* verify = nullptr;  // --verify
    const std::vector<uint64_t>* mismatch_rays = nullptr;
    bool has_speed = false;  // functional --verify: our traversal and Embree's on the same rays
    uint64_t speed_rays = 0;
    double ours_s = 0, embree_s = 0;
    bool interrupted = false;  // stopped by RunSpec::stop before the end
    bool snapshot = false;     // the statistics so far of a run that went on (SIGUSR1)
    // One segment of a split sample (--segment): its "segment" section instead of an estimate.
    const std::vector<IdentityKey>* segment_identity = nullptr;
    uint32_t segment = 0, segments = 0;
};

// Every statistic of a run: the one place that writes them, and (with a schema) lists them.
void write_stats(StatsOut& out, const RunRecord& r);

}  // namespace rtu
