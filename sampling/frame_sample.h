// A sampled run of one frame (docs/sampling.md), as the workload driver sees it: a warp selection
// (workloads/warp_selection.h) that draws the sample design, runs the functional pre-pass (or
// reads it from a sample plan), hands the driver the drawn clusters' warps, warms each SM's
// caches as it starts a simulated cluster, keeps the simulated warps' records, and estimates the
// frame from them; a split sample's merge draws the same design and estimates from every
// segment's records. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "design.h"
#include "estimator.h"
#include "options.h"
#include "prepass.h"
#include "workloads/warp_selection.h"

namespace rtu {

class FrameSample : public WarpSelection {
public:
    // `sms`, `timing`: the GPU the driver runs the frame on (as given to it); `opt.cluster` warps
    // make a cluster, `opt.capacity` are the RT units' warp-buffer slots.
    FrameSample(const SamplingOptions& opt, uint32_t sms, const ShaderTiming& timing);

    std::vector<uint64_t> select(const FrameWarps& frame) override;
    void trace_starts(uint32_t kept, uint32_t sm, uint32_t trace) override;
    void ray_retired(uint32_t kept, const RetiredRay& ray) override;
    void trace_done(uint32_t kept, uint32_t sm, uint64_t now, uint64_t residence) override;
    void warp_finished(uint64_t unfinished, uint64_t now) override;

    // Functional warming: called when an SM takes its first trace of a simulated cluster, with
    // that SM's share of the last node fetches of the clusters skipped before it, in order (with
    // a limit of resident warps: the first SM to start the cluster, with all). With every warp
    // resident (no limit) the frame runs in rounds, and the skipped warps' first traces warm the
    // SM at its first trace of the cluster, their later traces at its first later trace.
    std::function<void(const std::vector<WarmFetch>&)> on_warm;

    // The frame was sampled (a frame without warps never is).
    bool sampled() const { return sampled_; }
    // Host wall seconds select() took: the frame's pre-pass (its functional trace, or reading its
    // plan), the design, and tracing the warming fetches, all before the first simulated warp.
    double select_seconds() const { return select_s_; }
    // The estimate of the frame from the simulated warps.
    SampleEstimate estimate() const;
    // This run simulates one segment of a split sample (SamplingOptions::segments): its records
    // are the segment's part of the estimate.
    bool segment_run() const { return !segment_ends_.empty(); }
    const std::vector<WarpRecord>& warp_records() const { return records_; }
    // The frame's estimate from every segment's records (segments[s]: segment s's, in its
    // order), checked against this sample's design. Only on a sample drawn with
    // SamplingOptions::kNoSegment (the merge's).
    SampleEstimate merge(const std::vector<std::vector<WarpRecord>>& segments) const;

private:
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
    SamplingOptions opt_;
    uint32_t sms_, resident_;
    SampleEstimator estimator_;
    bool sampled_ = false;
    double select_s_ = 0.0;
    uint64_t warps_total_ = 0;
    SampleEstimate::Design design_;
    std::vector<WarpRecord> records_;      // per kept warp
    std::vector<uint32_t> cluster_of_;     // per kept warp: its simulated cluster (index into warm_)
    std::vector<std::vector<Warming>> warm_;  // per simulated cluster and SM (one for all SMs with a limit of resident warps)
    // Segments: where each segment ends among the design's warps (frame order); for the merge's
    // sample, those warps as drawn.
    std::vector<WarpRecord> merge_records_;
    std::vector<size_t> segment_ends_;
};

}  // namespace rtu
