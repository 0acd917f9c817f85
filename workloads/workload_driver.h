// The workload driver: the shader side of the GPU, the design's "workload module making rays".
// Paths are packed into shader warps of 32 neighbouring pixels, each warp bound to one SM; a warp
// issues one trace (one ray per thread that has one) to its SM's RT unit, waits for it, shades for
// a latency (ShaderTiming: longer beside the SM's other warps in shader code), and issues the next
// bounce / AO / shadow rays. RT units pull traces when they have a free warp-buffer slot
// (TraceSource), which keeps their warp buffers full. A sampled run
// keeps only the warps its selection picks (workloads/warp_selection.h, sampling/frame_sample.h).
// Plain C++ with cycle numbers: it serves AT, LT and interval alike.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "model/config.h"
#include "model/trace_source.h"
#include "ray_queue.h"
#include "rays.h"
#include "warp_selection.h"

namespace rtu {

struct TracedRay {
    uint32_t path, seq;  // seq: order of the ray among its path's rays
    Ray ray;             // as the workload made it (not rescaled)
    Hit hit;
    uint32_t nodes_visited = 0;
    bool valid = true;
};

// The shader timing of `hw` for `workload` (no shader code for given rays: ShaderTiming::shaders).
ShaderTiming shader_timing(const HwConfig& hw, const Workload& workload);

class WorkloadDriver : public TraceSource {
public:
    // `timing`: the shader warps' time outside the RT unit (ShaderTiming). With a limit of
    // resident warps the first sms x resident warps go to the SMs round robin; a warp that
    // finishes gives its place to the next warp of the frame, on its SM, which then runs its
    // shader code before its first trace. `selection` (may be null: every warp runs) picks the
    // warps to simulate and is told what they do; it must outlive the driver. `begun` (may be
    // null: the driver calls workload.begin()): the workload has begun already, and these are
    // its first rays. Drivers that run disjoint warps of one frame may then share the workload
    // and its first rays, on threads of their own (a split sample's segments): each touches only
    // its own warps' paths.
    WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, const ShaderTiming& timing, WarpSelection* selection = nullptr,
                   const std::vector<WorkRay>* begun = nullptr);

    std::optional<std::vector<WarpRay>> next_trace(uint32_t sm, uint64_t now) override;
    uint64_t earliest_ready(uint32_t sm) const override;
    void retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now) override;

    bool finished() const { return live_warps_ == 0; }
    // Share of shader warps (pixel groups) whose paths have all ended.
    double fraction_done() const { return warps_.empty() ? 1.0 : 1.0 - double(live_warps_) / double(warps_.size()); }
    uint64_t rays_issued() const { return issued_; }
    uint64_t rays_retired() const { return summary_.rays; }
    uint64_t last_progress() const { return last_progress_; }
    // Every ray with its hit, in (path, seq) order; empty unless the driver keeps the rays.
    std::vector<TracedRay> results() const;
    // Totals over every retired ray (kept or not).
    struct RaySummary {
        uint64_t rays = 0, invalid = 0, hits = 0, nodes_visited = 0;
        uint64_t l1_miss_nodes = 0, dram_nodes = 0;  // node fetches not served by L1 / served by DRAM
        uint32_t max_nodes = 0;
    };
    const RaySummary& summary() const { return summary_; }
    // Without kept rays a ray's record is reused once it retires: memory for the rays in flight
    // only, not for every ray of the frame (about 160 B each). Call before the simulation.
    void keep_rays(bool keep) { keep_rays_ = keep; }
    // Which SM and shader warp the oldest trace in flight belongs to (for the watchdog).
    std::string oldest_in_flight() const;

    // Shader warps of the frame (simulated or not).
    uint64_t warps_total() const { return warps_total_; }

private:
    struct Thread {
        uint32_t path;
        uint32_t next_seq = 0;
        RayQueue pending;
    };
    struct ShaderWarp {
        uint32_t sm = 0;
        std::vector<Thread> threads;
        uint32_t in_flight = 0;  // rays of the current trace not yet retired
        uint64_t issued_at = 0;
        uint32_t traces_done = 0;
        uint32_t loop = 0;  // the current trace's most candidates of one ray: its intersection loop's iterations
    };
    struct Record {
        TracedRay r;
        WorkRay work;
        uint32_t warp;
        int scale;
    };
    class Frame;  // the warps as a selection reads them
    void enqueue(uint32_t warp, uint64_t ready_at);
    // The warp begins `cycles` of shader code (alone) at `now`: with contention it takes longer
    // (ShaderTiming::contended); its next trace is ready when the code ends.
    void shade(uint32_t warp, uint64_t now, uint64_t cycles);

    Workload& workload_;
    ShaderTiming timing_;
    std::vector<ShaderWarp> warps_;
    std::vector<std::set<std::pair<uint64_t, uint32_t>>> ready_;  // per SM: (ready cycle, warp)
    std::vector<ShaderCodeEnds<uint64_t>> shading_;  // per SM, with contention (else empty)
    std::vector<Record> records_;
    std::vector<uint64_t> free_records_;
    bool keep_rays_ = true;
    uint64_t issued_ = 0;
    RaySummary summary_;
    uint64_t live_warps_ = 0, last_progress_ = 0;
    size_t launched_ = 0;  // warps given a place on an SM so far (in frame order)
    uint64_t warps_total_ = 0;
    WarpSelection* selection_ = nullptr;
};

}  // namespace rtu
