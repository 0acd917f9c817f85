// Workload driver: the shader side of the GPU. Paths are packed into shader warps of 32
// neighbouring pixels, each warp bound to one SM; a warp issues one trace (one ray per thread
// that has one) to its SM's RT unit, waits for it, shades for a fixed latency, and issues the
// next bounce / AO / shadow rays. RT units pull traces when they have a free warp-buffer slot,
// which keeps their warp buffers full. Plain C++ with cycle numbers: it serves AT and LT alike.
#pragma once
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
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

// Sampled simulation (docs/sampling.md). rate < 1: clusters of `cluster` consecutive shader warps
// (groups of warp_size neighbouring pixel samples) are split into round(clusters x rate) equal
// strata in frame order; one cluster per stratum, chosen by `seed`, is simulated, and
// WorkloadDriver::estimate() extrapolates to the whole frame.
struct SamplingOptions {
    double rate = 1.0;
    uint64_t seed = 1;
    uint32_t cluster = 1;
    uint32_t capacity = 32;  // shader warps the GPU keeps in flight at once (for the estimator)
    // Functional pre-pass of the schedule estimator: a maker of fresh instances of the run's
    // workload (one per pre-pass thread) and a functional tracer that may be called from several
    // threads at once. Without them the estimator is the plain stratified one.
    std::function<std::unique_ptr<Workload>()> make_workload;
    std::function<TraceResult(const Ray&, std::vector<StackEntry>* fetched)> trace;
    unsigned threads = 1;  // pre-pass threads (results do not depend on the number)
    // Functional warming: before each simulated cluster, the last `warm_window` node fetches of
    // the clusters skipped before it are replayed into the caches (WorkloadDriver::on_warm).
    size_t warm_window = 0;
    bool progress = false;  // report the pre-pass's progress on stderr every 2 s
};

// A node fetch of the functional pre-pass, replayed into an SM's L1 and the L2 (functional
// warming) before a simulated cluster starts; `sm` is the SM that made it in the full frame.
struct WarmFetch {
    uint32_t sm;
    uint64_t addr;
    uint32_t bytes;
};

// A path's rays waiting for their trace, first in first out. A vector and a read position: one
// small allocation per path (a std::deque takes 512 B even for one ray, 270 MB for a 512x512
// frame at 2 spp).
class RayQueue {
public:
    bool empty() const { return head_ == rays_.size(); }
    const WorkRay& front() const { return rays_[head_]; }
    void pop_front() {
        if (++head_ == rays_.size()) rays_.clear(), head_ = 0;
    }
    void push_back(const WorkRay& r) { rays_.push_back(r); }

private:
    std::vector<WorkRay> rays_;
    size_t head_ = 0;
};

class WorkloadDriver {
public:
    WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency, const SamplingOptions& sampling = {});

    // The next trace of one of this SM's warps that is ready by `now`, or nothing.
    std::optional<std::vector<WarpRay>> next_trace(uint32_t sm, uint64_t now);
    // Earliest cycle a trace of this SM becomes ready (~0: none waiting).
    uint64_t earliest_ready(uint32_t sm) const;
    // Rays of one trace came back at `now`.
    void retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now);

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

    // Sampled simulation: a warp's work is the cycles its traces spent in an RT unit's warp buffer.
    // With the functional pre-pass (the schedule estimator):
    // - each trace's residence is fitted as a + b x its critical path (the most nodes one of its
    //   rays visits) over the simulated traces, and the frame's work is the fit summed over all
    //   of the frame's traces;
    // - cycles = simulated cycles x (schedule model of the frame / schedule model of the sample),
    //   both models fed with the fitted durations (model/trace_schedule.h).
    // Without it, the work is the stratified estimate and cycles come from the full-GPU
    // throughput (cycles_estimate).
    struct Estimate {
        uint64_t warps_total = 0, warps_simulated = 0;
        double work_simulated = 0, work_estimate = 0;  // warp-buffer residence cycles
        double work_estimate_stratified = 0;           // without the pre-pass
        bool schedule = false;                         // the schedule estimator is in use
        double critical_nodes_total = 0;               // of the frame (pre-pass)
        double fit_a = 0, fit_b = 0;                   // residence = a + b x critical-path nodes
        uint64_t fit_traces = 0;
        unsigned prepass_threads = 0;
        double model_frame = 0, model_sample = 0;      // schedule-model cycles
        double relative_se = 0;  // standard error of work_estimate / work_estimate
        uint32_t variance_pairs = 0;  // collapsed stratum pairs behind relative_se (degrees of freedom)
        // The frame's share of node fetches that missed L1 / went to DRAM: the stratified ratio
        // estimate and its 95 % interval (collapsed strata, Student's t).
        struct Share {
            double estimate = 0, lo = 0, hi = 0;
        };
        Share l1_miss_nodes, dram_nodes;
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
            if (schedule && model_sample > 0) return cycles_simulated * model_frame / model_sample;
            return cycles_simulated + (work_estimate - work_simulated) / throughput(cycles_simulated);
        }
        // How far the schedule model missed the simulated sample: |simulated / model - 1|.
        double model_misfit(double cycles_simulated) const {
            return schedule && model_sample > 0 ? std::fabs(cycles_simulated / model_sample - 1.0) : 0.0;
        }
        // Half-width of the 95 % interval of cycles_estimate, relative to it (docs/sampling.md):
        // the work's sampling error with Student's t for the collapsed pairs, and, with the
        // schedule estimator, the model's error, taken to be as large on the frame as on the
        // sample and independent of it (1.96 x sqrt(2) x the misfit).
        double relative_half_width(double cycles_simulated) const;
    };
    Estimate estimate() const;
    bool sampled() const { return sampled_; }
    // Sampled runs with the pre-pass: called when a simulated cluster starts, with the last node
    // fetches of the clusters skipped before it, in order.
    std::function<void(const std::vector<WarmFetch>&)> on_warm;

private:
    struct Thread {
        uint32_t path;
        uint32_t next_seq = 0;
        RayQueue pending;
    };
    struct ShaderWarp {
        uint32_t sm = 0;
        double weight = 1.0;  // warps of the frame this one stands for (its stratum's size)
        double work = 0;      // cycles its traces spent in an RT unit so far
        double nodes = 0, l1_miss_nodes = 0, dram_nodes = 0;  // over its retired rays
        std::vector<uint32_t> trace_nodes;  // pre-pass: per trace, the most nodes one of its rays visits
        double critical_nodes = 0;          // their sum
        uint32_t traces_done = 0;
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
    using TraceFn = std::function<TraceResult(const Ray&, std::vector<StackEntry>*)>;
    void prepass(const std::function<std::unique_ptr<Workload>()>& make_workload, const TraceFn& trace,
                 const std::vector<uint32_t>& feeds, size_t strata, size_t window, bool progress, unsigned threads);
    std::vector<std::vector<WarmFetch>> warm_;  // per stratum, until its cluster starts

    Workload& workload_;
    uint32_t shade_;
    std::vector<ShaderWarp> warps_;
    std::vector<uint32_t> path_warp_;  // path -> shader warp
    std::vector<std::set<std::pair<uint64_t, uint32_t>>> ready_;  // per SM: (ready cycle, warp)
    std::vector<Record> records_;
    std::vector<uint64_t> free_records_;
    bool keep_rays_ = true;
    uint64_t issued_ = 0;
    RaySummary summary_;
    uint64_t live_warps_ = 0, last_progress_ = 0;
    uint64_t warps_total_ = 0;
    bool sampled_ = false;
    uint32_t capacity_ = 32;
    double critical_nodes_total_ = 0;
    unsigned prepass_threads_ = 0;
    std::vector<std::vector<uint32_t>> frame_traces_;  // pre-pass: every warp of the frame, in frame order
    double fit_n_ = 0, fit_x_ = 0, fit_y_ = 0, fit_xx_ = 0, fit_xy_ = 0;  // least-squares sums over simulated traces
    uint32_t slots_ = 1;
    double work_done_ = 0, work_saturated_ = 0;
    uint64_t saturated_until_ = 0;
};

}  // namespace rtu
