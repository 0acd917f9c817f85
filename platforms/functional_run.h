// The functional fidelity: every ray traced to completion by our per-thread traversal over the
// BVH image, wave by wave (a workload's follow-up rays form the next wave), optionally checked
// ray by ray against Embree. Rays are traced on FunctionalOptions::threads threads; the rays,
// hits and counts are the same for every thread count.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "model/bvh_image.h"
#include "model/stop_request.h"
#include "model/traversal.h"
#include "workloads/embree_reference.h"
#include "workloads/rays.h"
#include "workloads/verify.h"

namespace rtu {

// Wall seconds from `t` to now: the runs' host times.
inline double seconds_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

struct FunctionalResult;

struct FunctionalOptions {
    TraversalOrder order = TraversalOrder::DFS;
    const Treelets* treelets = nullptr;  // required for TraversalOrder::Treelet
    unsigned threads = 1;         // threads tracing (and checking) each batch of a wave; results do not depend on it
    bool progress = false;        // rays done and rate on stderr every few seconds
    bool measure_speed = false;   // afterwards, re-trace all rays with ours (and Embree's, if given) for rays/s
    StopRequest stop;             // requested: the run ends between two batches of rays (FunctionalResult::interrupted)
    // Called with the result so far when stop.snapshot_requested() (SIGUSR1), between two
    // batches; the run then goes on. Empty: not asked for.
    std::function<void(const FunctionalResult&)> snapshot;
};

struct FunctionalResult {
    std::vector<Ray> rays;        // in trace order
    std::vector<Hit> hits;
    std::vector<uint32_t> path, seq;  // each ray's path and its order among that path's rays
    uint64_t invalid_rays = 0;
    uint64_t nodes_visited = 0;
    uint32_t max_nodes_per_ray = 0;
    uint64_t hit_count = 0;
    VerifyCounts verify;
    std::vector<uint64_t> mismatch_rays;  // indices of rays in class Mismatch (first 100)
    double trace_seconds = 0.0, embree_seconds = 0.0;  // measure_speed passes only
    uint64_t speed_checksum = 0;
    bool interrupted = false;     // stopped by FunctionalOptions::stop: the rays traced so far
};

// Checks one ray's hit against Embree: its class (Embree gets the same exactly-rescaled ray).
// Rays Debian's Embree cannot take return nullopt (counted as skipped).
std::optional<Agreement> verify_ray(const Scene& scene, const EmbreeReference& ref, const Ray& ray, const Hit& hit);

// `reference` may be null (no verification).
FunctionalResult run_functional(const Scene& scene, const BvhImage& image, Workload& workload, const FunctionalOptions& opt,
                                const EmbreeReference* reference);

}  // namespace rtu
