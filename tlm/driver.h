// Workload driver: the shader side of the GPU. Paths are packed into shader warps of 32
// neighbouring pixels, each warp bound to one SM; a warp issues one trace (one ray per thread
// that has one) to its SM's RT unit, waits for it, shades for a fixed latency, and issues the
// next bounce / AO / shadow rays. RT units pull traces when they have a free warp-buffer slot,
// which keeps their warp buffers full. Plain C++ with cycle numbers: it serves AT and LT alike.
#pragma once
#include <cstdint>
#include <deque>
#include <optional>
#include <set>
#include <vector>

#include "model/rt_unit_core.h"
#include "workloads/rays.h"

namespace rtu {

struct TracedRay {
    uint32_t path, seq;  // seq: order of the ray among its path's rays
    Ray ray;             // as the workload made it (not rescaled)
    Hit hit;
    uint32_t nodes_visited = 0;
    bool valid = true;
};

class WorkloadDriver {
public:
    // sample_rate < 1: sampled simulation. Clusters of `cluster` consecutive shader warps (groups
    // of warp_size neighbouring pixel samples) are split into round(clusters x rate) equal strata
    // in frame order; one cluster per stratum, chosen by `seed`, is simulated, and estimate()
    // extrapolates to the whole frame.
    // `capacity`: shader warps the GPU keeps in flight at once (for the estimator).
    WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency,
                   double sample_rate = 1.0, uint64_t seed = 1, uint32_t cluster = 1, uint32_t capacity = 32);

    // The next trace of one of this SM's warps that is ready by `now`, or nothing.
    std::optional<std::vector<WarpRay>> next_trace(uint32_t sm, uint64_t now);
    // Earliest cycle a trace of this SM becomes ready (~0: none waiting).
    uint64_t earliest_ready(uint32_t sm) const;
    // Rays of one trace came back at `now`.
    void retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now);

    bool finished() const { return live_warps_ == 0; }
    // Share of shader warps (pixel groups) whose paths have all ended.
    double fraction_done() const { return warps_.empty() ? 1.0 : 1.0 - double(live_warps_) / double(warps_.size()); }
    uint64_t rays_issued() const { return records_.size(); }
    uint64_t rays_retired() const { return retired_; }
    uint64_t last_progress() const { return last_progress_; }
    uint64_t invalid_rays() const { return invalid_; }
    // Every ray with its hit, in (path, seq) order.
    std::vector<TracedRay> results() const;
    // Which SM and shader warp the oldest trace in flight belongs to (for the watchdog).
    std::string oldest_in_flight() const;

    // Sampled simulation: a warp's work is the cycles its traces spent in an RT unit's warp buffer.
    struct Estimate {
        uint64_t warps_total = 0, warps_simulated = 0;
        double work_simulated = 0, work_estimate = 0;  // warp-buffer residence cycles
        double relative_se = 0;  // standard error of work_estimate / work_estimate
        // While at least `capacity` shader warps were unfinished the GPU ran full; after that
        // comes the tail. The frame's extra work runs at the full-GPU throughput, the tail
        // stays: cycles = simulated cycles + (work_estimate - work_simulated) / throughput.
        uint64_t saturated_until = 0;
        double work_saturated = 0;
        double scale() const { return work_simulated > 0 ? work_estimate / work_simulated : 1.0; }
        double throughput(double cycles_simulated) const {
            if (saturated_until > 0 && work_saturated > 0) return work_saturated / double(saturated_until);
            return cycles_simulated > 0 ? work_simulated / cycles_simulated : 1.0;
        }
        double cycles_estimate(double cycles_simulated) const {
            return cycles_simulated + (work_estimate - work_simulated) / throughput(cycles_simulated);
        }
    };
    Estimate estimate() const;
    bool sampled() const { return sampled_; }

private:
    struct Thread {
        uint32_t path;
        uint32_t next_seq = 0;
        std::deque<WorkRay> pending;
    };
    struct ShaderWarp {
        uint32_t sm = 0;
        double weight = 1.0;  // warps of the frame this one stands for (its stratum's size)
        double work = 0;      // cycles its traces spent in an RT unit so far
        uint32_t stratum = 0; // sampled: the stratum it was drawn for
        std::vector<Thread> threads;
        uint32_t in_flight = 0;  // rays of the current trace not yet retired
        uint64_t issued_at = 0;
    };
    struct Record {
        TracedRay r;
        WorkRay work;
        uint32_t warp;
        int scale;
    };
    void enqueue(uint32_t warp, uint64_t ready_at);

    Workload& workload_;
    uint32_t shade_;
    std::vector<ShaderWarp> warps_;
    std::vector<uint32_t> path_warp_;  // path -> shader warp
    std::vector<std::set<std::pair<uint64_t, uint32_t>>> ready_;  // per SM: (ready cycle, warp)
    std::vector<Record> records_;
    uint64_t live_warps_ = 0, retired_ = 0, last_progress_ = 0, invalid_ = 0;
    uint64_t warps_total_ = 0;
    bool sampled_ = false;
    uint32_t capacity_ = 32;
    double work_done_ = 0, work_saturated_ = 0;
    uint64_t saturated_until_ = 0;
};

}  // namespace rtu
