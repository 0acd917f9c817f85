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
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/stop_request.h"
#include "model/trace_schedule.h"
#include "model/traversal.h"
#include "ray_queue.h"
#include "rays.h"

namespace rtu {

struct PrepassResult;  // below

// rate < 1 (docs/sampling.md): the frame's shader warps (groups of warp_size neighbouring pixel
// samples) are cut into clusters of `capacity` consecutive warps (as many as the GPU holds, so
// that the warps running together are neighbours, as in the full frame; smaller clusters drew
// more strata but ran 5-80 % off, docs/sampling.md). The first wave (the first cluster that reads
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
    uint32_t capacity = 32;  // shader warps the GPU keeps in flight at once (SMs x warp-buffer slots)
    // Functional pre-pass of the schedule estimator: a maker of fresh instances of the run's
    // workload (one per pre-pass thread) and a functional tracer that may be called from several
    // threads at once. Without them the clusters are stratified by position and the estimator is
    // the plain stratified one.
    std::function<std::unique_ptr<Workload>()> make_workload;
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

// Drawn strata a sample needs for its interval (collapsed pairs: 5 pairs, Student's t with 5
// degrees of freedom, 2.57).
constexpr uint64_t kMinStrata = 10;

// Drawn strata below which a run's error estimate says its interval rests on few strata and names
// the rate that draws this many. 30 is the aim (a normal-theory interval from fewer draws
// leans on the clusters' costs being near normal). Measured after it was set (docs/sampling.md,
// "How many strata"): over 384 sampled runs of five grids, intervals of 10-29 strata covered 96 %
// with 4 misses narrower than +-10 %, those of 30 or more 99 % with 1.
constexpr uint64_t kAimStrata = 30;

// The smallest rate, rounded up to 0.1 %, at which a frame of `clusters` clusters (the first wave
// among them; `candidates` of them neither the first wave nor empty) draws `strata` strata, or
// none where it has fewer candidates than that. A design simulates round(clusters x rate)
// clusters, the first wave one of them (SampleDesign).
std::optional<double> rate_for_strata(uint64_t clusters, uint64_t candidates, uint64_t strata);

// Simulated clusters a segment of a split sample needs for its interval: each segment pays its own
// start and drain, which the schedule model carries only in part. Measured (docs/sampling.md,
// "Segments"): with 16 or more per segment the split estimate erred as the continuous one did
// (mean 2.2-3.5 %, every interval covering); with 8, 4.4 % and 7 of 8 covering; with 4, 7.4 %
// and 5 of 8.
constexpr uint64_t kMinSegmentClusters = 16;

// A node fetch of the functional pre-pass, replayed into an SM's L1 and the L2 (functional
// warming) before a simulated cluster starts; `sm` is the SM that made it in the full frame.
struct WarmFetch {
    uint32_t sm;
    uint64_t addr;
    uint32_t bytes;
    uint32_t trace = 0;  // which trace of its warp fetched it (0: the first)
};

// One simulated cluster of a sample.
struct SampledCluster {
    uint64_t cluster;  // its index in the frame
    uint32_t stratum;  // the drawn stratum it stands for; kCertain for the first wave
    double weight;     // clusters of the frame it stands for
    static constexpr uint32_t kCertain = ~0u;
};

// The sample of a frame of `warps` shader warps in clusters of `cluster`, the first of them with
// work the first wave. `work`: per cluster, the pre-pass's critical-path node reads (empty: no
// pre-pass, or not run yet; strata by position, no cluster is known to be empty, and cluster 0
// is the first wave).
class SampleDesign {
public:
    SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed, const std::vector<double>& work = {});
    // Drawn strata (the first wave and the empty clusters are not strata).
    uint64_t strata() const { return strata_; }
    uint64_t clusters() const { return clusters_; }
    uint64_t empty_clusters() const { return empty_; }
    uint64_t first_wave_clusters() const { return certain_; }
    // Every cluster is simulated or known to be empty: the sample is the frame.
    bool census() const { return strata_ == candidates_; }
    // The simulated clusters in frame order.
    const std::vector<SampledCluster>& simulated() const { return sim_; }
    uint64_t first_warp(size_t i) const { return sim_[i].cluster * cluster_; }
    uint64_t end_warp(size_t i) const { return std::min(warps_, (sim_[i].cluster + 1) * cluster_); }
    // Per warp of the frame, the simulated cluster (index into simulated()) whose start its
    // fetches warm: the warps between the previous simulated cluster and it; ~0 otherwise.
    std::vector<uint32_t> feeds() const;
    // Splits the simulated clusters, in frame order, into `k` segments of consecutive ones
    // (sizes differing by one at most; the first wave in segment 0). Needs 1 <= k <= simulated().size().
    void split(uint32_t k);
    uint32_t segments() const { return segments_; }
    uint32_t segment_of(size_t i) const { return uint32_t(i * segments_ / sim_.size()); }
    // The first simulated cluster of its segment: its segment runs from cold caches, so it is
    // warmed from the frame's first warp on (the clusters simulated in earlier segments included).
    bool starts_segment(size_t i) const { return i == 0 || segment_of(i) != segment_of(i - 1); }
    // The first warp whose fetches warm simulated cluster i.
    uint64_t warm_from(size_t i) const { return starts_segment(i) ? 0 : end_warp(i - 1); }

private:
    uint64_t warps_, cluster_, clusters_, certain_ = 0, empty_ = 0, candidates_ = 0, strata_ = 0;
    uint32_t segments_ = 1;
    std::vector<SampledCluster> sim_;
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

// Fresh instances of the run's workload (opt.make_workload), one per pre-pass thread, made on the
// thread's first use and kept for the warming pass. Each thread touches only its own.
class PrepassWorkloads {
public:
    explicit PrepassWorkloads(const SamplingOptions& opt);
    Workload& of_thread(unsigned t);

private:
    const SamplingOptions& opt_;
    std::vector<std::unique_ptr<Workload>> made_;
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
    // second one, docs/sampling.md "Warming the first traces apart"), and warp by warp. Both
    // are kept, so that a sample plan serves either. Empty: not counted (no node_blocks).
    std::vector<uint32_t> first_reads_in_rounds, first_reads_by_warp;
    const std::vector<uint32_t>& first_reads(bool rounds) const { return rounds ? first_reads_in_rounds : first_reads_by_warp; }
    unsigned threads = 0;
};
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, PrepassWorkloads& workloads);
// The sum of first reads over the frame's warps.
double first_reads_total(const std::vector<uint32_t>& first_reads);
// The sum of every trace's critical path, in frame order (the one order, so that a pre-pass read
// back from a sample plan sums to the same double as the one that ran).
double critical_nodes_total(const std::vector<std::vector<uint32_t>>& trace_nodes);

// Per simulated cluster of `design`, the last opt.warm_window node fetches of the warps it feeds
// (the clusters skipped before it), in frame order: traced again, backwards from the cluster,
// until the window is full.
std::vector<std::vector<WarmFetch>> warming_fetches(const FrameWarps& frame, const SamplingOptions& opt, const SampleDesign& design,
                                                    PrepassWorkloads& workloads);

// What the estimator knows of one simulated shader warp.
struct WarpRecord {
    double weight = 1.0;   // warps of the frame this one stands for (its stratum's size)
    uint32_t stratum = 0;  // sampled: the stratum it was drawn for (SampledCluster::kCertain: the first wave)
    uint64_t frame_warp = 0;  // its index in the frame
    double work = 0;       // cycles its traces spent in an RT unit so far
    double nodes = 0, l1_miss_nodes = 0, dram_nodes = 0;  // over its retired rays
    std::vector<uint32_t> trace_nodes;  // pre-pass: per trace, the most nodes one of its rays visits
    double critical_nodes = 0;          // their sum
    double first_reads = 0;             // pre-pass: the nodes the frame reads first in this warp
    std::vector<double> residences;     // per trace simulated so far, its residence
    uint32_t traces_done = 0;
    uint32_t sm = 0;        // the SM its simulated traces ran on
    double last_done = -1;  // the cycle its latest simulated trace left the RT unit (of its segment's run; -1: not known)
};

// A sampled run's estimate of the frame. A warp's work is the cycles its traces spent in an RT
// unit's warp buffer. With the functional pre-pass (the schedule estimator):
// - each trace's residence is fitted as a + b x its critical path (the most nodes one of its
//   rays visits) over the drawn clusters' traces;
// - cycles = simulated cycles x (schedule model of the frame / schedule model of the sample)
//   (model/trace_schedule.h), both models fed with the simulated traces' own residences and,
//   for the frame's other traces, the fit; the frame's work is the frame model's durations summed.
// Without it, the work is the stratified estimate and cycles come from the full-GPU throughput
// (cycles_estimate).
struct SampleEstimate {
    uint64_t warps_total = 0, warps_simulated = 0;
    double work_simulated = 0, work_estimate = 0;  // warp-buffer residence cycles
    double work_estimate_stratified = 0;           // stratified (ratio to critical-path nodes with the pre-pass)
    bool schedule = false;                         // the schedule estimator is in use
    double critical_nodes_total = 0;               // of the frame (pre-pass)
    double fit_a = 0, fit_b = 0;                   // residence = a + b x critical-path nodes
    uint64_t fit_traces = 0;
    unsigned prepass_threads = 0;
    double model_frame = 0, model_sample = 0;      // schedule-model cycles
    // Per SM with traces in both: the cycle its last simulated trace left / the same in the
    // schedule model of the sample - 1 (with segments, each side summed over the segments).
    std::vector<double> misfit_per_sm;
    double relative_se = 0;  // standard error of work_estimate / work_estimate
    uint32_t variance_pairs = 0;  // collapsed stratum pairs behind relative_se (degrees of freedom)
    // The design, as the workload driver drew it: warps per cluster, drawn strata, clusters of the
    // first wave (simulated whole) and empty clusters (no node read; not simulated); whether the
    // sample carries an interval (false: too few strata, --sample-unchecked).
    struct Design {
        uint64_t cluster_warps = 0, strata = 0, first_wave_clusters = 0, empty_clusters = 0;
        bool has_interval = true;
    } design;
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
    // How far the fit's work (summed over the frame) is from the stratified ratio estimate, which
    // the design makes unbiased: a measured bound for the extrapolation's own error.
    double extrapolation_gap() const {
        return schedule && work_estimate_stratified > 0 ? std::fabs(work_estimate / work_estimate_stratified - 1.0) : 0.0;
    }
    // How far the schedule model missed the simulated sample: |simulated / model - 1|.
    double model_misfit(double cycles_simulated) const {
        return schedule && model_sample > 0 ? std::fabs(cycles_simulated / model_sample - 1.0) : 0.0;
    }
    // The scale of the schedule model's error, as the interval takes it: the root mean square of
    // the per-SM misfits where they were measured, else the whole run's misfit. The run's misfit
    // is one draw (the SM that ended last) and is near zero by chance in some runs; the SMs' are
    // one draw each of the same error, on the part of the sample each SM ran (docs/sampling.md,
    // "The model's error from every SM").
    double model_error(double cycles_simulated) const {
        if (!schedule || misfit_per_sm.empty()) return model_misfit(cycles_simulated);
        double sq = 0;
        for (double m : misfit_per_sm) sq += m * m;
        return std::sqrt(sq / double(misfit_per_sm.size()));
    }
    // The sample design's bias bound, relative: how far the sample's context (what runs beside
    // its traces) can carry its estimate from the frame's cycles beyond every term above. Not
    // measured in the run; the platform sets it from the grids (platforms/configs/
    // sampling_bias.json, docs/sampling.md "The sample design's bias"); 0 until set.
    double design_bias = 0;
    // The first reads of BVH nodes (pre-pass): a first read is a compulsory miss of the L2 that
    // the draw either took or left. The frame's first reads outside the first wave, and the
    // sample's ratio estimate of them (per critical-path node, as the work is estimated); their
    // price in slot-cycles beyond the fit, from the drawn clusters, or from the first wave where
    // the drawn clusters hold none (first_read_cost_of_first_wave). Where the draw holds more or
    // fewer than its share (a small BVH first read by a few clusters: cornell's primary rays),
    // the work is off by about their difference at that price, and no other term sees it: the
    // sampling variance comes from the drawn strata, and where none of them holds a first read it
    // holds nothing of them (docs/sampling.md, "First reads").
    double first_reads_rest = 0, first_reads_estimate = 0, first_read_cost = 0;
    bool first_read_cost_of_first_wave = false;
    double first_reads_gap() const {
        return work_estimate > 0 ? first_read_cost * std::fabs(first_reads_rest - first_reads_estimate) / work_estimate : 0.0;
    }
    // Half-width of the 95 % interval of cycles_estimate, relative to it (docs/sampling.md),
    // five parts in quadrature: the work's sampling error with Student's t for the collapsed
    // pairs; with the schedule estimator the model's error, taken to be as large on the frame as
    // on the sample and independent of it (1.96 x sqrt(2) x model_error), the extrapolation
    // gap (1.96 x it) and the first reads' gap (a bias estimate, taken as it is); and the
    // design's bias bound (already a 95 % figure: the largest bias the grids measured, so taken
    // as it is).
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
    // `warps`: the simulated warps; `warps_total`: the frame's. `segment_ends`: empty for one
    // continuous run; else the warps are those of independent segments in frame order, segment s
    // ending before warps[segment_ends[s]]: the sample's schedule model is then the sum of the
    // segments' (each ran alone), and the fit is taken from the records in frame order, so that
    // the estimate depends on the records only, not on the order the segments ran in.
    SampleEstimate estimate(const std::vector<WarpRecord>& warps, uint64_t warps_total, bool sampled,
                            const std::vector<size_t>& segment_ends = {}) const;

private:
    ScheduleShape shape_;
    uint64_t capacity_;
    std::vector<std::vector<uint32_t>> frame_traces_;  // pre-pass: every warp of the frame, in frame order
    double critical_nodes_total_ = 0;
    double first_reads_total_ = 0;  // pre-pass: the frame's first reads of nodes (0: not counted)
    unsigned prepass_threads_ = 0;
    // Least-squares sums of residence = a + b x critical path, over the drawn clusters' traces.
    struct FitSums {
        double n = 0, x = 0, y = 0, xx = 0, xy = 0;
        void add(double cx, double cy) { n += 1, x += cx, y += cy, xx += cx * cx, xy += cx * cy; }
    };
    FitSums fit_;  // as the traces left the RT units
    double work_done_ = 0, work_saturated_ = 0;
    uint64_t saturated_until_ = 0;
};

}  // namespace rtu
