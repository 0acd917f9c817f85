// What the timing fidelities share at their entry: the options of a run and its result. AT and
// LT run on the SystemC platform (platforms/gpu_platform.h), the interval fidelity without a
// kernel (platforms/interval_run.h); both take and return these. Plain C++ (no SystemC).
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/bvh_image.h"
#include "model/config.h"
#include "model/fidelity.h"
#include "model/stop_request.h"
#include "model/traversal.h"
#include "timing_stats.h"
#include "sampling/frame_sample.h"
#include "workloads/workload_driver.h"

namespace rtu {

struct Treelets;
struct TimingResult;

struct TimingOptions {
    Fidelity fidelity = Fidelity::AT;  // run_timing dispatches on it (platforms/fidelity_run.h)
    TraversalOrder order = TraversalOrder::DFS;
    bool progress = false;
    std::string vcd;                  // VCD file (without the .vcd suffix SystemC adds)
    int trace_sm = -1, trace_warp = -1;  // one warp-buffer slot whose threads' stack depths are traced
    // --timeline (AT, LT): the threads of warp-buffer slot `timeline_slot` of SM `timeline_sm` as
    // Chrome trace events (platforms/timeline.h), in TimingResult::timeline.
    bool timeline = false;
    uint32_t timeline_sm = 0, timeline_slot = 0;
    bool check_protocol = false;      // AT: a base-protocol checker on every socket
    double sample_rate = 1.0;         // < 1: sampled simulation of this share of the frame's warps
    uint64_t sample_seed = 1;
    bool sample_unchecked = false;    // run a sample too small for an interval, and report none
    // Sampled runs: makes a fresh instance of the workload for the functional pre-pass and the
    // warming (docs/sampling.md), shared by their threads; empty: the plain stratified estimate.
    std::function<std::unique_ptr<Workload>()> sample_workload;
    unsigned threads = 1;  // --threads: the functional pass, --verify's checks and the sampling pre-pass
    // A sample split into independent segments (docs/sampling.md, "Segments"): this run simulates
    // segment `sample_segment` of `sample_segments` (SamplingOptions::segment).
    uint32_t sample_segments = 1;
    uint32_t sample_segment = SamplingOptions::kAllSegments;
    // --sample-plan: the pre-pass read from this file if it exists, else run and written to it;
    // `plan_identity` (prepass_identity, simulation.h) is what the plan must match.
    std::string sample_plan, plan_identity;
    // The frame's pre-pass, made already in this process (segments on threads,
    // platforms/segment_threads.h): taken instead of running it or reading a plan.
    std::shared_ptr<const PrepassResult> prepass;
    // The workload instance the pre-pass and the warming trace, shared by the segment threads
    // (SamplingOptions::shared_workload); null: the run makes its own.
    std::shared_ptr<PrepassWorkload> prepass_workload;
    // The run's workload has begun already, and these are its first rays (a split sample's
    // segments on threads share one workload: WorkloadDriver's `begun`); null: the run begins it.
    std::shared_ptr<const std::vector<WorkRay>> begun;
    // Keep every ray with its hit for TimingResult::rays (hits files, verification); without,
    // memory holds only the rays in flight.
    bool keep_rays = true;
    // Requested: the run ends at its next clean point with what it simulated so far
    // (TimingResult::interrupted; AT and LT at the monitor's next wake-up).
    StopRequest stop;
    // Called with the statistics so far when stop.snapshot_requested() (SIGUSR1), at the same
    // clean points; the run then goes on, its results unchanged (TimingResult::interrupted is set
    // in what it is given: the figures of what was simulated so far). Empty: not asked for.
    std::function<void(const TimingResult&)> snapshot;
};

struct TimingResult {
    std::vector<TracedRay> rays;    // with TimingOptions::keep_rays
    WorkloadDriver::RaySummary summary;  // always
    uint64_t cycles = 0;            // the frame's cycles (extrapolated when sampled)
    uint64_t cycles_simulated = 0;  // cycles of what was actually simulated
    bool stuck = false;
    std::string stuck_report;
    std::vector<std::string> invariant_failures;
    std::vector<std::string> protocol_violations;  // with check_protocol
    uint64_t protocol_transactions = 0;
    HierarchyCounts counts;         // per instance (platforms/timing_stats.h writes them)
    std::string timeline;           // with TimingOptions::timeline: the Chrome trace JSON
    bool sampled = false;
    SampleEstimate estimate;        // sampled runs
    // Sampled runs: host wall seconds before the first simulated warp, the frame's pre-pass
    // (FrameSample::select_seconds); a merge of segments: its own (reading the plan, or taking
    // the pre-pass its segments' threads made, whose time is added; each segment's own warming
    // is in the segments' time).
    double prepass_s = 0;
    std::vector<WarpRecord> segment_records;  // one segment of a split sample: its warps' records for the merge
    uint64_t payloads_allocated = 0;  // AT and LT: transaction payloads the pool made
    // Stopped by TimingOptions::stop before the frame ended: the statistics are those of the
    // cycles simulated so far; no estimate, no invariant checks.
    bool interrupted = false;
};

// Shader warps the RT units hold at once (SMs x warp-buffer slots): the slots of a sampled run's
// schedule model.
inline uint32_t gpu_warp_capacity(const HwConfig& c) { return c.sms * c.warp_buffer; }
// Shader warps a sampled run's cluster holds (docs/sampling.md, "Clusters"): the warps that run
// together on the GPU, so that a simulated cluster runs beside its neighbours in the frame. With a
// limit of resident warps (workload.resident_warps, `paper` and `desktop`) those are the warps
// resident on the SMs, SMs x the limit (or the warp buffer, if larger); a cluster of the warp
// buffers' warps alone ran beside other clusters' warps, resident with it, that in the frame lie
// far away: 10 % samples of primary rays at 1024x1024 (6 scenes, 3 draws, interval fidelity) ran
// 4.9 % from the full run on average under `paper`, 2.2 % with clusters of the resident warps
// (`desktop`, held out: 4.5 -> 3.4 %); path tracing at 512x512 and 25 % under `paper` 0.7 and
// 0.9 % (docs/sampling.md, "Clusters"). With every warp resident (`mobile`) an SM takes its warps'
// traces in rounds, and a cluster is what the warp buffers hold.
inline uint32_t sample_cluster_warps(const HwConfig& c) {
    return c.resident_warps ? c.sms * std::max(c.warp_buffer, c.resident_warps) : gpu_warp_capacity(c);
}

// A timing run's sample (docs/sampling.md), or null for a run of the whole frame: clusters of the
// warps that run together (sample_cluster_warps), the functional pre-pass on `image`, warming
// enough to refill every cache twice. `treelets` as for the run's traversal (may be null). The
// run's driver takes it as its warp selection; the run sets its on_warm.
std::unique_ptr<FrameSample> frame_sample(const HwConfig& cfg, const BvhImage& image, const TimingOptions& opt, const Treelets* treelets,
                                          const Workload& workload);
// Why a frame cannot be sampled on this hardware (its schedule model would leave out part of the
// shaders' time), or nothing: --sample and --check-error refuse such a frame.
std::optional<std::string> sample_refusal(const HwConfig& cfg, const BvhImage& image);
// The sampling options frame_sample uses (the merge of a split sample draws with them too).
SamplingOptions sampling_options(const HwConfig& cfg, const BvhImage& image, const TimingOptions& opt, const Treelets* treelets);
// Puts the sample's estimate into `r` (r.cycles_simulated and r.interrupted set): a sampled run's
// frame cycles, estimate and (one segment) records; a run of the whole frame gets an estimate of
// the frame's warps only.
void take_estimate(TimingResult& r, const FrameSample* sample, const WorkloadDriver& driver);

// The treelets a traversal order works on (AT, LT: treelet traversal and the Treelet prefetcher);
// null for the others.
std::unique_ptr<Treelets> traversal_treelets(const HwConfig& cfg, const BvhImage& image, TraversalOrder order);

}  // namespace rtu
