// What a sampled run is asked to do (docs/sampling.md): the rate, the seed, the pre-pass's
// workload and tracer, warming, segments and the plan kept between runs. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "model/stop_request.h"
#include "model/traversal.h"
#include "workloads/rays.h"

namespace rtu {

struct PrepassResult;    // sampling/prepass.h
class PrepassWorkload;  // sampling/prepass.h

// rate < 1 (docs/sampling.md): the frame's shader warps (groups of warp_size neighbouring pixel
// samples) are cut into clusters of `cluster` consecutive warps (as many as run together on the
// GPU, so that the warps running together are neighbours, as in the full frame; smaller clusters
// drew more strata but ran 5-80 % off, docs/sampling.md). The first wave (the first cluster that reads
// a BVH node, whose warps start together on cold caches) is always simulated;
// clusters whose traces read no BVH node are never simulated (their RT work is known: none); the
// rest are sorted by the functional pre-pass's work and split into equal strata, one cluster each
// drawn by `seed`, and the estimator extrapolates to the whole frame.
struct SamplingOptions {
    double rate = 1.0;
    uint64_t seed = 1;
    // false: a sample of fewer than kMinStrata drawn strata (and not every cluster) is refused with
    // an InputError naming the smallest rate and frame that work; true (--sample-unchecked): it
    // runs and reports no interval.
    bool unchecked = false;
    uint32_t capacity = 32;  // shader warps the RT units hold at once (SMs x warp-buffer slots)
    uint32_t cluster = 0;    // shader warps a cluster holds (0: `capacity`)
    // Functional pre-pass of the schedule estimator: a maker of a fresh instance of the run's
    // workload (the pre-pass's and the warming's threads share it) and a functional tracer that
    // may be called from several threads at once. Without them the clusters are stratified by
    // position and the estimator is the plain stratified one. `shared_workload`, if set, is that
    // instance already made by another run of the frame in this process (a split sample's segment
    // threads share one); else the run makes its own.
    std::function<std::unique_ptr<Workload>()> make_workload;
    std::shared_ptr<PrepassWorkload> shared_workload;
    std::function<TraceResult(const Ray&, std::vector<StackEntry>* fetched)> trace;
    unsigned threads = 1;  // pre-pass threads (results do not depend on the number)
    // Functional warming: before each simulated cluster, the last `warm_window` node fetches of
    // the clusters skipped before it are replayed into the caches (WorkloadDriver::on_warm).
    size_t warm_window = 0;
    // The BVH image's 64-byte blocks (every node starts on one): the pre-pass counts each warp's
    // first reads of a node over the frame in tables of this size (0: none counted).
    uint64_t node_blocks = 0;
    bool progress = false;  // report the pre-pass's progress on stderr every 2 s
    StopRequest stop;       // requested: the pre-pass throws Interrupted between warps
    // Segments (docs/sampling.md, "Segments"): > 1 splits the simulated clusters, in frame order,
    // into this many independent runs, each from cold caches warmed with the fetches before its
    // first cluster; `segment` is the one this run simulates, or kNoSegment for none (the merge's
    // own driver, which only draws the design and runs the pre-pass). With one segment, `segment`
    // is kAllSegments: the one continuous run.
    uint32_t segments = 1;
    uint32_t segment = kAllSegments;
    static constexpr uint32_t kAllSegments = ~0u, kNoSegment = ~0u - 1;
    // The pre-pass's result kept between runs of one frame (--sample-plan): `load_prepass` gives
    // it if it was kept (else nullopt: the pre-pass runs), `save_prepass` keeps it. Either may be
    // empty.
    std::function<std::optional<PrepassResult>()> load_prepass;
    std::function<void(const PrepassResult&)> save_prepass;
};

}  // namespace rtu
