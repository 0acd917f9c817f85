#include "timing_run.h"

#include <cmath>
#include <stdexcept>

#include "model/treelet.h"
#include "output.h"
#include "sampling/plan.h"

namespace rtu {

std::optional<std::string> sample_refusal(const HwConfig& c, const BvhImage& img) {
    // The sample's schedule model (sampling/schedule_model.h) puts a constant of shader code
    // between a warp's traces; the intersection loops that follow traces through procedural
    // leaves are not in it, so it cannot estimate such a frame.
    if (c.intersection_latency > 0 && img.stats.procedural_leaves > 0)
        return "this scene has " + std::to_string(img.stats.procedural_leaves) +
               " procedural leaves, and a sample's schedule model leaves out the shaders' intersection loops "
               "(workload.intersection_latency " + std::to_string(c.intersection_latency) +
               "): run the frame whole, or with --set workload.intersection_latency=0";
    // Without a limit of resident warps every warp of the frame is on its SM at once, and the
    // schedule model does not count which of them are in shader code.
    if (c.shader_contention > 0 && c.resident_warps == 0)
        return std::string("workload.shader_contention > 0 needs a limit of resident warps (workload.resident_warps is 0), which a sample's "
                           "schedule model counts the warps in shader code by: set workload.resident_warps, or run the frame whole");
    return std::nullopt;
}

SamplingOptions sampling_options(const HwConfig& c, const BvhImage& img, const TimingOptions& o, const Treelets* treelets) {
    if (const std::optional<std::string> why = sample_refusal(c, img)) throw InputError("--sample: " + *why);
    SamplingOptions s;
    s.rate = o.sample_rate;
    s.seed = o.sample_seed;
    s.unchecked = o.sample_unchecked;
    s.capacity = gpu_warp_capacity(c);
    s.cluster = sample_cluster_warps(c);
    s.node_blocks = (img.size() + kBlockBytes - 1) / kBlockBytes;
    s.make_workload = o.sample_workload;
    s.shared_workload = o.prepass_workload;
    s.threads = o.threads;
    s.segments = o.sample_segments;
    s.segment = o.sample_segment;
    if (!o.sample_plan.empty()) {
        s.load_prepass = [file = o.sample_plan, id = o.plan_identity] { return read_plan(file, id); };
        // Several segment tasks may write the same plan at once: whole files only.
        s.save_prepass = [file = o.sample_plan, id = o.plan_identity](const PrepassResult& p) { write_file_atomic(file, plan_bytes(id, p)); };
    }
    if (o.prepass) {
        s.load_prepass = [p = o.prepass] { return std::optional<PrepassResult>(*p); };
        s.save_prepass = nullptr;
    }
    s.progress = o.progress;
    s.stop = o.stop;
    // Enough fetches to refill every cache twice over.
    s.warm_window = 2 * (uint64_t(c.l2_slices) * c.l2.size_bytes + uint64_t(c.sms) * c.l1.size_bytes) / c.l1.sector;
    const TraversalOrder order = o.order;
    const bool next_node_register = c.next_node_register;
    s.trace = [&img, order, treelets, next_node_register](const Ray& r, std::vector<StackEntry>* fetched) {
        return trace_ray(img, r, order, treelets, fetched, next_node_register);
    };
    return s;
}

std::unique_ptr<FrameSample> frame_sample(const HwConfig& c, const BvhImage& img, const TimingOptions& o, const Treelets* treelets,
                                          const Workload& workload) {
    if (o.sample_rate >= 1.0) return nullptr;
    return std::make_unique<FrameSample>(sampling_options(c, img, o, treelets), c.sms, shader_timing(c, workload));
}

void take_estimate(TimingResult& r, const FrameSample* sample, const WorkloadDriver& driver) {
    if (!sample || !sample->sampled()) {
        r.estimate = SampleEstimate{};
        r.estimate.warps_total = r.estimate.warps_simulated = driver.warps_total();
        return;
    }
    r.sampled = true;
    r.estimate = sample->estimate();
    r.prepass_s = sample->select_seconds();
    if (!r.interrupted) r.cycles = uint64_t(std::llround(r.estimate.cycles_estimate(double(r.cycles_simulated))));
    if (sample->segment_run()) r.segment_records = sample->warp_records();
}

std::unique_ptr<Treelets> traversal_treelets(const HwConfig& c, const BvhImage& img, TraversalOrder order) {
    if (order != TraversalOrder::Treelet) return nullptr;
    auto t = std::make_unique<Treelets>(form_treelets(img, c.prefetch.treelet_budget, c.prefetch.treelet_contiguous, c.prefetch.treelet_stride));
    t->order = c.prefetch.treelet_order;
    return t;
}

}  // namespace rtu
