#include "simulation.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <iostream>

#include <sys/resource.h>

#include "functional_run.h"
#include "gpu_platform.h"
#include "interval_run.h"
#include "model/treelet.h"
#include "workloads/bvh_builder.h"
#include "workloads/embree_reference.h"
#include "workloads/input_error.h"
#include "workloads/scenes.h"

namespace rtu {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::vector<TracedRay> traced_from(const FunctionalResult& r) {
    std::vector<TracedRay> v(r.rays.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = TracedRay{r.path[i], r.seq[i], r.rays[i], r.hits[i], 0, is_valid_ray(r.rays[i])};
    std::stable_sort(v.begin(), v.end(), [](const TracedRay& a, const TracedRay& b) { return a.path != b.path ? a.path < b.path : a.seq < b.seq; });
    return v;
}

const char* traversal_name(TraversalOrder o) {
    switch (o) {
        case TraversalOrder::DFS: return "dfs";
        case TraversalOrder::BFS: return "bfs";
        case TraversalOrder::Treelet: return "treelet";
    }
    return "?";
}

}  // namespace

RunResult run_simulation(const RunSpec& spec, std::ostream* log) {
    const bool timing = is_timing(spec.fidelity);
    const WorkloadKind kind = spec.rays.empty() ? parse_workload(spec.workload) : WorkloadKind::RayFile;
    auto t0 = Clock::now();
    Scene scene = load_scene(spec.scene, spec.assets);
    scene.flatten = spec.flatten;
    const double load_s = seconds_since(t0);
    t0 = Clock::now();
    const BvhImage image = build_bvh_image(scene);
    const double build_s = seconds_since(t0);
    const BvhStats& bs = image.stats;
    if (log)
        *log << "scene " << scene.name << ": " << scene.meshes.size() << " meshes, " << scene.primitive_count()
             << " primitives, " << scene.instances.size() << " instances (" << (scene.two_level() ? "two-level" : "single-level")
             << " BVH), loaded in " << load_s << " s\n"
             << "BVH image: " << bs.image_bytes << " bytes, " << bs.internal_nodes << " internal nodes, "
             << bs.triangle_leaves << " triangle + " << bs.procedural_leaves << " procedural + " << bs.instance_leaves
             << " instance leaves, depth " << bs.depth << ", built in " << build_s << " s\n";

    std::vector<RayFileEntry> ray_entries;
    std::unique_ptr<Workload> workload;
    if (kind == WorkloadKind::RayFile) {
        ray_entries = read_ray_file(spec.rays);
        size_t warned = 0;
        for (const RayFileEntry& e : ray_entries)
            if (!e.valid && warned++ < 5) std::cerr << "warning: " << spec.rays << ":" << e.line << ": " << e.problem << " (reported as a miss)\n";
        if (warned > 5) std::cerr << "warning: " << warned << " invalid rays in all\n";
        workload = make_ray_file_workload(ray_entries);
    } else {
        workload = make_scene_workload(kind, scene, spec.params);
    }

    std::unique_ptr<EmbreeReference> reference;
    if (spec.verify) reference = std::make_unique<EmbreeReference>(scene);
    RunResult out;
    nlohmann::ordered_json& j = out.stats;
    j["scene"] = scene.name;
    j["workload"] = kind == WorkloadKind::RayFile ? "rays" : spec.workload;
    j["fidelity"] = fidelity_name(spec.fidelity);
    j["traversal"] = traversal_name(spec.order);
    if (kind != WorkloadKind::RayFile)
        j["params"] = {{"width", spec.params.width}, {"height", spec.params.height}, {"spp", spec.params.spp},
                       {"bounces", spec.params.bounces}, {"seed", spec.params.seed}};

    std::vector<TracedRay>& rays = out.rays;
    VerifyCounts verify;
    std::vector<uint64_t> mismatch_rays;
    double speed_ours = 0, speed_embree = 0;
    TimingResult timing_result;
    t0 = Clock::now();
    if (!timing) {
        FunctionalOptions fo;
        fo.order = spec.order;
        std::unique_ptr<Treelets> treelets;
        if (spec.order == TraversalOrder::Treelet) {
            treelets = std::make_unique<Treelets>(form_treelets(image, PrefetchConfig{}.treelet_budget));
            fo.treelets = treelets.get();
        }
        fo.progress = spec.progress;
        fo.measure_speed = spec.verify;
        const FunctionalResult r = run_functional(scene, image, *workload, fo, reference.get());
        rays = traced_from(r);
        verify = r.verify;
        mismatch_rays = r.mismatch_rays;
        speed_ours = r.trace_seconds;
        speed_embree = r.embree_seconds;
        j["nodes_visited"] = r.nodes_visited;
        j["max_nodes_per_ray"] = r.max_nodes_per_ray;
    } else {
        TimingOptions to;
        to.fidelity = spec.fidelity;
        to.order = spec.order;
        to.progress = spec.progress;
        to.vcd = spec.vcd;
        to.sample_rate = spec.sample_rate;
        to.sample_seed = spec.sample_seed;
        // A sampled run traces the whole frame functionally first, with fresh instances of the
        // workload (the run's own one accumulates the simulated image).
        if (spec.sample_rate < 1.0) {
            to.sample_workload = [&] {
                return kind == WorkloadKind::RayFile ? make_ray_file_workload(ray_entries) : make_scene_workload(kind, scene, spec.params);
            };
            to.sample_threads = spec.threads;
        }
        to.trace_sm = spec.trace_sm;
        to.trace_warp = spec.trace_warp;
        to.keep_rays = spec.keep_rays || spec.verify;  // else memory for the rays in flight only
        if (spec.fidelity == Fidelity::Interval) {
            try {
                timing_result = run_interval(spec.hw, image, *workload, to);
            } catch (const std::invalid_argument& e) {
                throw InputError(e.what());
            }
        } else {
            GpuPlatform platform(spec.hw, image, *workload, to);
            timing_result = platform.run();
        }
        rays = std::move(timing_result.rays);
        j["nodes_visited"] = timing_result.summary.nodes_visited;
        j["max_nodes_per_ray"] = timing_result.summary.max_nodes;
        if (reference) {
            for (size_t i = 0; i < rays.size(); ++i) {
                if (!rays[i].valid) continue;
                const auto cls = verify_ray(scene, *reference, rays[i].ray, rays[i].hit);
                if (!cls) {
                    ++verify.skipped;
                    continue;
                }
                ++verify.by_class[size_t(*cls)];
                ++verify.rays;
                if (*cls == Agreement::Mismatch && mismatch_rays.size() < 100) mismatch_rays.push_back(i);
            }
        }
    }
    const double run_s = seconds_since(t0);
    uint64_t invalid = 0, hits = 0, n_rays = rays.size();
    if (timing) {
        invalid = timing_result.summary.invalid;
        hits = timing_result.summary.hits;
        n_rays = timing_result.summary.rays;
    } else {
        for (const TracedRay& r : rays) {
            invalid += !r.valid;
            hits += r.hit.hit;
        }
    }
    const uint64_t valid_rays = n_rays - invalid;
    j["rays"] = n_rays;
    j["invalid_rays"] = invalid;
    j["hits"] = hits;
    j["nodes_per_ray"] = valid_rays ? double(j["nodes_visited"].get<uint64_t>()) / double(valid_rays) : 0.0;
    j["bvh"] = {{"two_level", scene.two_level()}, {"image_bytes", bs.image_bytes}, {"internal_nodes", bs.internal_nodes},
                {"triangle_leaves", bs.triangle_leaves}, {"procedural_leaves", bs.procedural_leaves},
                {"instance_leaves", bs.instance_leaves}, {"blas", bs.blas_count}, {"depth", bs.depth}, {"tlas_depth", bs.tlas_depth}};
    j["time_s"] = {{"load", load_s}, {"build", build_s}, {"run", run_s}};
    {
        // What the scene needs in memory against what the process holds at its peak.
        uint64_t scene_bytes = 0;
        for (const Mesh& m : scene.meshes)
            scene_bytes += m.vertices.size() * sizeof(glm::vec3) + m.triangles.size() * sizeof(glm::uvec3) +
                           m.spheres.size() * sizeof(Sphere) + m.material.size() * sizeof(uint32_t);
        struct rusage ru {};
        getrusage(RUSAGE_SELF, &ru);
        const double mb = 1.0 / (1024.0 * 1024.0);
        j["memory_mb"] = {{"scene", double(scene_bytes) * mb},
                          {"bvh_image", double(bs.image_bytes) * mb},
                          {"decoded_nodes", double(image.decoded_bytes()) * mb},  // host-side, within the peak
                          {"peak_resident", double(ru.ru_maxrss) / 1024.0},
                          {"target_1_5x_plus_200", 1.5 * double(scene_bytes + bs.image_bytes) * mb + 200.0}};
    }
    if (timing) {
        j["cycles"] = timing_result.cycles;
        j["timing"] = timing_result.stats;
        j["simulation_rate"] = {{"rays_per_s", run_s > 0 ? double(n_rays) / run_s : 0.0},
                                {"cycles_per_s", run_s > 0 ? double(timing_result.cycles) / run_s : 0.0}};
        j["config"] = spec.config.to_json();
    }
    if (spec.verify) {
        nlohmann::ordered_json classes;
        for (size_t c = 0; c < size_t(Agreement::Count); ++c) classes[agreement_name(Agreement(c))] = verify.by_class[c];
        j["verify"] = {{"rays", verify.rays}, {"skipped", verify.skipped}, {"mismatches", verify.mismatches()},
                       {"classes", classes}, {"mismatch_rays", mismatch_rays}};
        if (!timing)
            j["speed"] = {{"rays", rays.size()},
                          {"ours_s", speed_ours},
                          {"embree_s", speed_embree},
                          {"ours_rays_per_s", speed_ours > 0 ? double(rays.size()) / speed_ours : 0.0},
                          {"embree_rays_per_s", speed_embree > 0 ? double(rays.size()) / speed_embree : 0.0},
                          {"embree_over_ours", speed_ours > 0 && speed_embree > 0 ? speed_ours / speed_embree : 0.0}};
        out.mismatches = verify.mismatches();
        if (!mismatch_rays.empty()) out.first_mismatch = mismatch_rays.front();
    }
    if (timing && timing_result.stuck) out.stuck = timing_result.stuck_report;
    out.invariant_failures = timing_result.invariant_failures;
    if (kind != WorkloadKind::RayFile) {
        out.image = workload->image();
        out.width = spec.params.width;
        out.height = spec.params.height;
    }
    return out;
}

}  // namespace rtu
