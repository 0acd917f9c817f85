// The functional pre-pass of a sampled run (docs/sampling.md): the whole frame traced first,
// warp by warp, for each trace's critical path and each warp's first reads of BVH nodes; and
// functional warming, the node fetches replayed into the caches before each simulated cluster.
// Plain C++ (no SystemC).
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "design.h"
#include "options.h"
#include "workloads/warp_selection.h"

namespace rtu {

// A node fetch of the functional pre-pass, replayed into an SM's L1 and the L2 (functional
// warming) before a simulated cluster starts; `sm` is the SM that made it in the full frame.
struct WarmFetch {
    uint32_t sm;
    uint64_t addr;
    uint32_t bytes;
    uint32_t trace = 0;  // which trace of its warp fetched it (0: the first)
};

// A fresh instance of the run's workload (SamplingOptions::make_workload) for the pre-pass and the
// warming pass, made on first use and shared by their threads, and by a split sample's segment
// threads (SamplingOptions::shared_workload). A workload keeps its state per path and WarpTracer
// restarts every path of a warp before tracing it, so the threads share it safely as long as no
// two trace the same warp at once: a warp is traced holding its own flag (a byte per warp; a
// lock shared by several warps made threads walking the frame in step wait on each other:
// 1.07x the wall time on party 512x512). The pre-pass's threads take disjoint ranges of warps;
// the warming's windows of different segments may overlap, and there a thread waits. One
// instance instead of one per thread: at 1920x1080 an instance is about 140 MB (a pixel's state
// and its image value).
class PrepassWorkload {
public:
    explicit PrepassWorkload(std::function<std::unique_ptr<Workload>()> make) : make_(std::move(make)) {}
    // The instance, made on the first call, for a frame of `warps` shader warps (the same in
    // every call). Thread-safe.
    Workload& get(uint64_t warps);
    // Holds warp `warp` (< warps) for the caller's thread while it lives.
    class Hold {
    public:
        Hold(PrepassWorkload& w, uint64_t warp);
        ~Hold();
        Hold(const Hold&) = delete;
        Hold& operator=(const Hold&) = delete;

    private:
        std::atomic<bool>& busy_;
    };

private:
    std::atomic<bool>& busy(uint64_t warp);
    std::function<std::unique_ptr<Workload>()> make_;
    std::once_flag made_once_;
    std::unique_ptr<Workload> made_;
    uint64_t warps_ = 0;
    std::unique_ptr<std::atomic<bool>[]> busy_;  // per warp: traced now
};

// The functional pre-pass traces every path of the frame as the timing run will trace it (the
// same rays, because a workload's random numbers depend only on path and depth), warp by warp and
// trace by trace, and returns per warp of the frame, per trace, the most nodes one of its rays
// visits (the trace's critical path). Needs opt.make_workload and opt.trace.
struct PrepassResult {
    std::vector<std::vector<uint32_t>> trace_nodes;  // per warp of the frame: per trace, its critical path
    double critical_nodes_total = 0;                 // their sum over the frame
    // Per warp of the frame: the BVH nodes it reads before any other warp of the frame does (the
    // frame's compulsory misses of the L2, each counted at the warp that pays it), in either
    // order the GPU may run the traces: in rounds, where every warp is resident at once
    // (workload.resident_warps 0: an SM takes the first traces of all its warps before any
    // second one, docs/sampling.md "Warming"), and warp by warp. Both
    // are kept, so that a sample plan serves either. Empty: not counted (no node_blocks).
    std::vector<uint32_t> first_reads_in_rounds, first_reads_by_warp;
    const std::vector<uint32_t>& first_reads(bool rounds) const { return rounds ? first_reads_in_rounds : first_reads_by_warp; }
    unsigned threads = 0;
};
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, PrepassWorkload& shared);
// The sum of first reads over the frame's warps.
double first_reads_total(const std::vector<uint32_t>& first_reads);
// The sum of every trace's critical path, in frame order (the one order, so that a pre-pass read
// back from a sample plan sums to the same double as the one that ran).
double critical_nodes_total(const std::vector<std::vector<uint32_t>>& trace_nodes);

// Per simulated cluster of `design`, the last opt.warm_window node fetches of the warps it feeds
// (the clusters skipped before it), in frame order: traced again, backwards from the cluster,
// until the window is full.
std::vector<std::vector<WarmFetch>> warming_fetches(const FrameWarps& frame, const SamplingOptions& opt, const SampleDesign& design,
                                                    PrepassWorkload& shared);

}  // namespace rtu
