#include "functional_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>

#include "model/on_threads.h"

namespace rtu {
namespace {
using Clock = std::chrono::steady_clock;

// Embree gets the same power-of-two-scaled ray as our traversal (an exact change of units), so
// tiny and huge directions stay within what Debian's Embree accepts (|component| <= 1.8e18).
bool embree_can_take(const Ray& scaled) {
    constexpr float kLarge = 1.0e18f;
    for (int i = 0; i < 3; ++i)
        if (std::fabs(scaled.org[i]) > kLarge || std::fabs(scaled.dir[i]) > kLarge) return false;
    return std::isfinite(scaled.tnear) && scaled.tnear >= 0.0f && !std::isnan(scaled.tfar);
}

Hit embree_trace_scaled(const EmbreeReference& ref, const Ray& ray, Query q) {
    Ray s = ray;
    s.query = q;
    const int k = scale_direction(s);
    Hit h = ref.trace(s);
    if (h.hit) h.t = std::ldexp(h.t, -k);
    return h;
}
}  // namespace

std::optional<Agreement> verify_ray(const Scene& scene, const EmbreeReference& reference, const Ray& ray, const Hit& hit) {
    Ray scaled = ray;
    scale_direction(scaled);
    if (!embree_can_take(scaled)) return std::nullopt;
    const Hit ref = embree_trace_scaled(reference, ray, ray.query);
    Hit ref_closest = ref;
    if (ray.query == Query::Any && ref.hit != hit.hit) ref_closest = embree_trace_scaled(reference, ray, Query::Closest);
    return classify(scene, ray, hit, ref, ref_closest);
}

FunctionalResult run_functional(const Scene& scene, const BvhImage& image, Workload& workload, const FunctionalOptions& opt,
                                const EmbreeReference* reference) {
    FunctionalResult res;
    std::vector<WorkRay> wave, next;
    workload.begin(wave);
    std::vector<uint32_t> next_seq;
    auto last_report = Clock::now();
    const auto start = Clock::now();
    // A wave is traced in batches: the batch's rays (and their checks against Embree) on
    // opt.threads threads, each into its own slot; then, on this thread and in the wave's order,
    // the results are recorded and handed to the workload, whose follow-up rays (random numbers
    // included) therefore come out the same for every thread count. A stop ends the run between
    // two batches.
    constexpr size_t kBatch = 16384;
    std::vector<TraceResult> traced;
    std::vector<std::optional<Agreement>> agreed;
    while (!wave.empty() && !res.interrupted) {
        next.clear();
        for (size_t b = 0; b < wave.size(); b += kBatch) {
            if (opt.stop.requested()) {  // a clean point: between two batches
                res.interrupted = true;
                break;
            }
            if (opt.snapshot && opt.stop.snapshot_requested()) opt.snapshot(res);
            const size_t n = std::min(kBatch, wave.size() - b);
            traced.assign(n, TraceResult{});
            agreed.assign(n, std::nullopt);
            for_each_index(opt.threads, n, [&](size_t i) {
                const Ray& ray = wave[b + i].ray;
                traced[i] = trace_ray(image, ray, opt.order, opt.treelets);
                if (reference && is_valid_ray(ray)) agreed[i] = verify_ray(scene, *reference, ray, traced[i].hit);
            });
            for (size_t i = 0; i < n; ++i) {
                const WorkRay& w = wave[b + i];
                const TraceResult& tr = traced[i];
                const uint64_t index = res.rays.size();
                const bool valid = is_valid_ray(w.ray);
                res.rays.push_back(w.ray);
                res.hits.push_back(tr.hit);
                if (next_seq.size() <= w.path) next_seq.resize(w.path + 1, 0);
                res.path.push_back(w.path);
                res.seq.push_back(next_seq[w.path]++);
                if (!valid) ++res.invalid_rays;
                res.nodes_visited += tr.nodes_visited;
                res.max_nodes_per_ray = std::max(res.max_nodes_per_ray, tr.nodes_visited);
                res.hit_count += tr.hit.hit;
                if (reference && valid) {
                    const std::optional<Agreement>& a = agreed[i];
                    if (!a) {
                        ++res.verify.skipped;
                    } else {
                        ++res.verify.by_class[size_t(*a)];
                        ++res.verify.rays;
                        if (*a == Agreement::Mismatch && res.mismatch_rays.size() < 100) res.mismatch_rays.push_back(index);
                    }
                }
                workload.complete(w, tr.hit, next);
            }
            if (opt.progress && seconds_since(last_report) > 2.0) {
                last_report = Clock::now();
                std::cerr << "\r  traced " << res.rays.size() << " rays (" << wave.size() << " in this wave), "
                          << uint64_t(res.rays.size() / std::max(1e-9, seconds_since(start))) << " rays/s   " << std::flush;
            }
        }
        wave.swap(next);
    }
    if (opt.progress && seconds_since(start) > 2.0) std::cerr << "\n";
    if (opt.measure_speed && !res.interrupted) {
        // Both traversals over the same recorded rays in tight loops, one after the other.
        uint64_t sink = 0;
        auto t0 = Clock::now();
        for (const Ray& r : res.rays) sink += trace_ray(image, r, opt.order, opt.treelets).hit.hit;
        res.trace_seconds = seconds_since(t0);
        if (reference) {
            t0 = Clock::now();
            for (const Ray& r : res.rays) {
                Ray s = r;
                scale_direction(s);
                if (is_valid_ray(r) && embree_can_take(s)) sink += reference->trace(s).hit;
            }
            res.embree_seconds = seconds_since(t0);
        }
        res.speed_checksum = sink;
    }
    return res;
}

}  // namespace rtu
