// Sampled simulation (docs/sampling.md), apart from the workload driver that runs it:
// - SampleDesign: which clusters of shader warps a sampled run simulates (one per stratum);
// - run_prepass: the functional pre-pass that traces the whole frame first (each trace's critical
//   path, and the node fetches that warm the caches before each simulated cluster);
// - SampleEstimator: the frame's cycles and shares estimated from the simulated warps' records,
//   which the driver hands to it.
// Plain C++ (no SystemC).
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "model/trace_schedule.h"
#include "model/traversal.h"
#include "ray_queue.h"
#include "rays.h"

namespace rtu {

// rate < 1: clusters of `cluster` consecutive shader warps (groups of warp_size neighbouring pixel
// samples) are split into round(clusters x rate) equal strata in frame order; one cluster per
// stratum, chosen by `seed`, is simulated, and the estimator extrapolates to the whole frame.
struct SamplingOptions {
    double rate = 1.0;
    uint64_t seed = 1;
    // false: a sample too small for a 95 % interval (fewer than 2 strata) is refused with an
    // InputError naming the smallest rate that works; true (--sample-unchecked): it runs and
    // reports no interval.
    bool unchecked = false;
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

// The stratified cluster sample of a frame of `warps` shader warps.
class SampleDesign {
public:
    SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed);
    uint64_t strata() const { return picks_.size(); }
    // Clusters in stratum h: the weight of its simulated cluster.
    double weight(uint64_t h) const { return double(hi(h) - lo(h)); }
    // The warps [first, end) of stratum h's simulated cluster.
    uint64_t first_warp(uint64_t h) const { return picks_[h] * cluster_; }
    uint64_t end_warp(uint64_t h) const;
    // Per warp of the frame, the stratum whose cluster its fetches warm (the warps between the
    // previous stratum's cluster and this one's); ~0 for simulated warps and those after the last.
    std::vector<uint32_t> feeds() const;

private:
    uint64_t lo(uint64_t h) const { return h * clusters_ / picks_.size(); }
    uint64_t hi(uint64_t h) const { return (h + 1) * clusters_ / picks_.size(); }
    uint64_t warps_, cluster_, clusters_;
    std::vector<uint64_t> picks_;  // the simulated cluster of each stratum
};

// The frame's shader warps as the pre-pass reads them (the workload driver implements it).
class FrameWarps {
public:
    virtual ~FrameWarps() = default;
    virtual size_t warps() const = 0;
    virtual uint32_t sm(size_t warp) const = 0;
    // The warp's threads' paths and first rays, in thread order (resized to its thread count).
    virtual void threads(size_t warp, std::vector<uint32_t>& paths, std::vector<RayQueue>& first) const = 0;
};

struct PrepassResult {
    std::vector<std::vector<uint32_t>> trace_nodes;  // per warp of the frame: per trace, the most nodes one of its rays visits
    double critical_nodes_total = 0;                 // their sum over the frame
    unsigned threads = 0;
    std::vector<std::vector<WarmFetch>> warm;        // per stratum: the fetches that warm the caches before its cluster
};

// Traces every path of the frame functionally, as the timing run will trace it (the same rays,
// because a workload's random numbers depend only on path and depth), warp by warp and trace by
// trace. `feeds` and `strata` as SampleDesign's; the last `opt.warm_window` fetches per stratum are
// kept. Needs opt.make_workload and opt.trace.
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, const std::vector<uint32_t>& feeds, size_t strata);

// What the estimator knows of one simulated shader warp.
struct WarpRecord {
    double weight = 1.0;   // warps of the frame this one stands for (its stratum's size)
    uint32_t stratum = 0;  // sampled: the stratum it was drawn for
    double work = 0;       // cycles its traces spent in an RT unit so far
    double nodes = 0, l1_miss_nodes = 0, dram_nodes = 0;  // over its retired rays
    std::vector<uint32_t> trace_nodes;  // pre-pass: per trace, the most nodes one of its rays visits
    double critical_nodes = 0;          // their sum
    uint32_t traces_done = 0;
};

// A sampled run's estimate of the frame. A warp's work is the cycles its traces spent in an RT
// unit's warp buffer. With the functional pre-pass (the schedule estimator):
// - each trace's residence is fitted as a + b x its critical path (the most nodes one of its
//   rays visits) over the simulated traces, and the frame's work is the fit summed over all
//   of the frame's traces;
// - cycles = simulated cycles x (schedule model of the frame / schedule model of the sample),
//   both models fed with the fitted durations (model/trace_schedule.h).
// Without it, the work is the stratified estimate and cycles come from the full-GPU throughput
// (cycles_estimate).
struct SampleEstimate {
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

class SampleEstimator {
public:
    // `shape`: the GPU the schedule model runs (SMs, warp-buffer slots per SM, shading cycles);
    // `capacity`: shader warps the GPU keeps in flight.
    SampleEstimator(const ScheduleShape& shape, uint64_t capacity) : shape_(shape), capacity_(capacity) {}
    void set_prepass(PrepassResult&& p);
    // A simulated trace of warp `w` left the RT unit after `residence` cycles in its warp buffer.
    void on_trace_done(WarpRecord& w, double residence);
    // A shader warp finished its last trace at cycle `now`, leaving `unfinished` warps.
    void on_warp_finished(uint64_t unfinished, uint64_t now);
    // `warps`: the simulated warps; `warps_total`: the frame's.
    SampleEstimate estimate(const std::vector<WarpRecord>& warps, uint64_t warps_total, bool sampled) const;

private:
    ScheduleShape shape_;
    uint64_t capacity_;
    std::vector<std::vector<uint32_t>> frame_traces_;  // pre-pass: every warp of the frame, in frame order
    double critical_nodes_total_ = 0;
    unsigned prepass_threads_ = 0;
    double fit_n_ = 0, fit_x_ = 0, fit_y_ = 0, fit_xx_ = 0, fit_xy_ = 0;  // least-squares sums over simulated traces
    double work_done_ = 0, work_saturated_ = 0;
    uint64_t saturated_until_ = 0;
};

}  // namespace rtu
