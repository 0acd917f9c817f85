// The estimate of a sampled frame (docs/sampling.md): the frame's cycles and shares from the
// simulated warps' records, with its 95 % interval. Plain C++ (no SystemC).
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "design.h"
#include "prepass.h"
#include "schedule_model.h"

namespace rtu {

// Student's t for a two-sided 95 % interval; one pair (or none) leaves one degree of freedom at the least.
double t95(double degrees);

// The 95 % interval's relative half-width from its five terms (docs/sampling.md, "The interval"),
// in quadrature: the sampling term (t x the work's relative standard error) as it is; the
// schedule model's error on both sides, the frame's and the sample's, taken independent (1.96 x
// sqrt(2) x it); the extrapolation gap (1.96 x it); the first reads' gap (a bias estimate) and the
// design's bias bound (already a 95 % figure) as they are. SampleEstimate::relative_half_width
// and --sample-width's prediction (sampling/width.h) both take it.
double interval_half_width(double sampling, double model_error, double extrapolation_gap, double first_reads_gap, double design_bias);

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

// The residence of a sample's clusters per stratum: what two runs of the same draw (--check-error:
// a fast fidelity and AT) are paired by.
struct StrataWork {
    double first_wave = 0;       // the first wave's residence (simulated whole, weight 1)
    std::vector<double> work;    // per drawn stratum: its cluster's residence x the stratum's weight
    std::vector<double> weight;  // per drawn stratum: the clusters it stands for
};

// The frame's residence in one run of a draw against another run of the same draw, as a ratio
// estimate over the strata (the fast run's weighted residence over the reference's), minus 1,
// with its 95 % half-width: Student's t over the collapsed stratum pairs of the residuals
// W_fast,h - R W_ref,h (as SampleEstimate::relative_se takes the work's), divided by the
// reference's total, with Satterthwaite's degrees of freedom for pairs of unequal variance. The pairing takes out what both runs share (which clusters were drawn,
// how much work they hold); what is left is how differently the two fidelities time the same
// clusters, stratum by stratum. Throws std::invalid_argument if the two are not of one draw
// (other strata or weights).
struct PairedDifference {
    double difference = 0, half_width = 0;
    uint32_t pairs = 0;   // collapsed stratum pairs
    double degrees = 0;   // of Student's t: (sum of the pairs' variances)^2 / sum of their squares
};
PairedDifference paired_work_difference(const StrataWork& fast, const StrataWork& reference);

// A sampled run's estimate of the frame. A warp's work is the cycles its traces spent in an RT
// unit's warp buffer. With the functional pre-pass (the schedule estimator):
// - each trace's residence is fitted as a + b x its critical path (the most nodes one of its
//   rays visits) over the drawn clusters' traces;
// - cycles = simulated cycles x (schedule model of the frame / schedule model of the sample)
//   (sampling/schedule_model.h), both models fed with the simulated traces' own residences and,
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
    StrataWork strata_work;  // the simulated residence by stratum (paired_work_difference)
    double relative_se = 0;  // standard error of work_estimate / work_estimate
    uint32_t variance_pairs = 0;  // collapsed stratum pairs behind relative_se
    // Student's t's degrees of freedom for relative_se: Satterthwaite's, (sum of the pairs'
    // variances)^2 / sum of their squares, between 1 and variance_pairs (0 without pairs).
    double variance_degrees = 0;
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
