// The workload driver: the shader side of the GPU, the design's "workload module making rays".
// Paths are packed into shader warps of 32 neighbouring pixels, each warp bound to one SM; a warp
// issues one trace (one ray per thread that has one) to its SM's RT unit, waits for it, shades for
// a fixed latency, and issues the next bounce / AO / shadow rays. RT units pull traces when they
// have a free warp-buffer slot (TraceSource), which keeps their warp buffers full. A sampled run
// (workloads/sampling.h) keeps only the drawn clusters of warps. Plain C++ with cycle numbers: it
// serves AT, LT and interval alike.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "model/trace_source.h"
#include "ray_queue.h"
#include "rays.h"
#include "sampling.h"

namespace rtu {

struct TracedRay {
    uint32_t path, seq;  // seq: order of the ray among its path's rays
    Ray ray;             // as the workload made it (not rescaled)
    Hit hit;
    uint32_t nodes_visited = 0;
    bool valid = true;
};

class WorkloadDriver : public TraceSource {
public:
    // `resident_warps`: shader warps an SM holds at once (workload.resident_warps; 0: every warp
    // of the frame from the start). The first sms x resident warps go to the SMs round robin; a
    // warp that finishes gives its place to the next warp of the frame, on its SM.
    WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency, uint32_t resident_warps = 0,
                   const SamplingOptions& sampling = {});

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

    // Sampled simulation: the estimate of the frame from the simulated warps (workloads/sampling.h).
    using Estimate = SampleEstimate;
    Estimate estimate() const;
    bool sampled() const { return sampled_; }
    // A sample split into segments (SamplingOptions::segments): this run simulates one of them
    // (or none: the merge's driver). Its records are the segment's part of the estimate.
    bool segment_run() const { return !segment_ends_.empty(); }
    const std::vector<WarpRecord>& warp_records() const { return records_of_warps_; }
    // The frame's estimate from every segment's records (segments[s]: segment s's, in its
    // order), checked against this sample's design. Only on a driver drawn with
    // SamplingOptions::kNoSegment (the merge's).
    Estimate merge(const std::vector<std::vector<WarpRecord>>& segments) const;
    // Sampled runs with the pre-pass: called when an SM takes its first trace of a simulated
    // cluster, with that SM's share of the last node fetches of the clusters skipped before it,
    // in order (with a limit of resident warps: the first SM to start the cluster, with all).
    // With every warp resident (no limit) the frame runs in rounds, and the skipped warps' first
    // traces warm the SM at its first trace of the cluster, their later traces at its first later
    // trace of the cluster (Warming).
    std::function<void(const std::vector<WarmFetch>&)> on_warm;

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
        uint32_t cluster = ~0u;  // sampled: its simulated cluster (index into warm_)
    };
    // What warms one SM for one simulated cluster: the skipped warps' fetches of their first
    // traces and of their later ones, each replayed once, in frame order, then let go. With every
    // warp ready at cycle 0 an SM takes the first traces of all its warps (in frame order) before
    // any second trace, so a cluster's first traces run where the frame's other warps have run
    // their first traces only; its later traces run in an order set by when the traces before
    // them ended, which mixes the frame. (With a limit of resident warps there are no rounds:
    // everything is in `first`.)
    struct Warming {
        std::vector<WarmFetch> first, later;
    };
    struct Record {
        TracedRay r;
        WorkRay work;
        uint32_t warp;
        int scale;
    };
    class Frame;  // the warps as the pre-pass reads them
    void enqueue(uint32_t warp, uint64_t ready_at);

    Workload& workload_;
    uint32_t shade_;
    std::vector<ShaderWarp> warps_;
    std::vector<WarpRecord> records_of_warps_;  // beside warps_: what the sampling estimator reads
    std::vector<uint32_t> path_warp_;  // path -> shader warp
    std::vector<std::set<std::pair<uint64_t, uint32_t>>> ready_;  // per SM: (ready cycle, warp)
    std::vector<Record> records_;
    std::vector<uint64_t> free_records_;
    std::vector<std::vector<Warming>> warm_;  // per simulated cluster and SM (one for all SMs with a limit of resident warps)
    bool keep_rays_ = true;
    uint64_t issued_ = 0;
    RaySummary summary_;
    uint64_t live_warps_ = 0, last_progress_ = 0;
    size_t launched_ = 0;  // warps given a place on an SM so far (in frame order)
    uint64_t warps_total_ = 0;
    bool sampled_ = false;
    SampleEstimate::Design design_;
    SampleEstimator estimator_;
    // Segments: where each segment ends among the design's warps (frame order); for the merge's
    // driver, those warps as drawn.
    std::vector<WarpRecord> merge_records_;
    std::vector<size_t> segment_ends_;
};

}  // namespace rtu
