#include "simulation.h"

#include <rtunit/job.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <set>
#include <iostream>

#include <sys/resource.h>

#include "functional_run.h"
#include "host_memory.h"
#include "model/memory_estimate.h"
#include "model/stats.h"
#include "timing_stats.h"
#include "gpu_platform.h"
#include "interval_run.h"
#include "model/treelet.h"
#include "workloads/bvh_builder.h"
#include "workloads/embree_reference.h"
#include "workloads/input_error.h"
#include "workloads/scenes.h"
#include "sampling/bias.h"
#include "sampling/plan.h"

namespace rtu {
namespace {

// The rays a peripheral job would trace, as its 48-byte records: a ray file's rays (an invalid
// line as a NaN origin, never traced), or a workload's first rays (camera rays: later bounces
// depend on shading); `user` is the ray's index.
std::vector<rtu_ray> ray_records(const std::vector<RayFileEntry>& entries) {
    std::vector<rtu_ray> out;
    for (const RayFileEntry& e : entries) {
        const float o[3] = {e.ray.org.x, e.ray.org.y, e.ray.org.z}, d[3] = {e.ray.dir.x, e.ray.dir.y, e.ray.dir.z};
        out.push_back(make_ray_record(o, d, e.ray.tnear, e.ray.tfar, e.ray.query == Query::Any, uint32_t(out.size())));
    }
    return out;
}

std::vector<rtu_ray> ray_records(Workload& w) {
    std::vector<WorkRay> first;
    w.begin(first);
    if (first.size() > UINT32_MAX) throw InputError("--dump-rays: more than 2^32 rays");
    std::vector<RayFileEntry> entries(first.size());
    for (size_t i = 0; i < first.size(); ++i) entries[i].ray = first[i].ray;
    return ray_records(entries);
}

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

// What a run measured, for its statistics.
struct RunRecord {
    std::string scene, workload;
    Fidelity fidelity = Fidelity::Functional;
    TraversalOrder order = TraversalOrder::DFS;
    bool has_params = false;
    WorkloadParams params;
    uint64_t rays = 0, invalid = 0, hits = 0, nodes_visited = 0;
    uint32_t max_nodes = 0;
    BvhStats bvh;
    bool two_level = false;
    double load_s = 0, build_s = 0, run_s = 0;
    double scene_mb = 0, image_mb = 0, decoded_mb = 0, peak_mb = 0, estimate_mb = 0;
    const TimingResult* timing = nullptr;  // timing runs
    ErrorEstimate error;                   // timing runs
    const HwConfig* hw = nullptr;
    const Config* config = nullptr;
    double sample_rate = 1.0;
    const VerifyCounts* verify = nullptr;  // --verify
    const std::vector<uint64_t>* mismatch_rays = nullptr;
    bool has_speed = false;  // functional --verify: our traversal and Embree's on the same rays
    uint64_t speed_rays = 0;
    double ours_s = 0, embree_s = 0;
    bool interrupted = false;  // stopped by RunSpec::stop before the end
    // One segment of a split sample (--segment): its "segment" section instead of an estimate.
    const std::vector<IdentityKey>* segment_identity = nullptr;
    uint32_t segment = 0, segments = 0;
};

void write_error_estimate(StatsOut& out, const ErrorEstimate& e) {
    StatsOut o = out.child("error_estimate", "the run's error against the AT reference (docs/accuracy.md)");
    o.value("value", e.value ? nlohmann::ordered_json(*e.value) : nlohmann::ordered_json(), "ratio",
            "relative error bound on cycles (0.02: within +-2 %); null: no estimate (see basis)");
    o.value("kind", e.kind, "",
            "reference (AT), interval (sampling), validated bound (the error grid), measured (--check-error), their sums, or none");
    o.value("basis", e.basis, "", "what the value rests on");
    StatsOut c = o.child("check", "--check-error N: the same clusters simulated in this fidelity and in AT (null without)");
    if (!e.check) {
        o.json()["check"] = nullptr;
        return;
    }
    c.value("clusters", e.check->clusters, "clusters", "simulated in both, the first wave included");
    c.value("share", e.check->share, "ratio", "of the frame's shader warps");
    c.value("fidelity_cycles", e.check->fidelity_cycles, "cycles", "simulated in this run's fidelity");
    c.value("at_cycles", e.check->at_cycles, "cycles", "simulated in AT");
    c.value("difference", e.check->difference(), "ratio", "fidelity_cycles / at_cycles - 1");
    c.value("fidelity_s", e.check->fidelity_s, "s", "the fidelity's simulation time");
    c.value("at_s", e.check->at_s, "s", "AT's simulation time");
}

// Every statistic of a run: the one place that writes them, and (with a schema) lists them.
void write_stats(StatsOut& out, const RunRecord& r) {
    out.value("scene", r.scene, "", "the scene's name");
    out.value("workload", r.workload, "", "primary, pt, ao, sh, or rays (a ray file)");
    out.value("fidelity", fidelity_name(r.fidelity), "", "functional, at, lt or interval");
    out.value("traversal", traversal_name(r.order), "", "dfs, bfs or treelet");
    out.value("interrupted", r.interrupted, "",
              "stopped by SIGINT or SIGTERM before the end: every figure is of what was simulated so far, and cycles are the "
              "cycles simulated, not the frame's (docs/robustness.md)");
    if (r.has_params) {
        StatsOut p = out.child("params", "the scene workload's parameters");
        p.value("width", r.params.width, "pixels", "frame width");
        p.value("height", r.params.height, "pixels", "frame height");
        p.value("spp", r.params.spp, "samples", "samples per pixel");
        p.value("bounces", r.params.bounces, "rays", "path tracing: at most this many rays per path");
        p.value("seed", r.params.seed, "", "random seed of the rays");
    }
    out.value("nodes_visited", r.nodes_visited, "node reads", "nodes the rays' traversals read (simulated rays of a sampled run)");
    out.value("max_nodes_per_ray", r.max_nodes, "node reads", "the most one ray read");
    out.value("rays", r.rays, "rays", "rays traced (simulated rays of a sampled run), invalid ones included");
    out.value("invalid_rays", r.invalid, "rays", "rays that do not parse or are not valid (misses; never sent to the RT unit)");
    out.value("hits", r.hits, "rays", "rays that hit");
    out.value("nodes_per_ray", r.rays > r.invalid ? double(r.nodes_visited) / double(r.rays - r.invalid) : 0.0, "node reads / ray",
              "nodes_visited per valid ray");
    {
        StatsOut b = out.child("bvh", "the BVH image (DESIGN.md section 6)");
        b.value("two_level", r.two_level, "", "a TLAS over instanced BLASes (false: one single-level BVH)");
        b.value("image_bytes", r.bvh.image_bytes, "bytes", "the BVH image in simulated memory");
        b.value("internal_nodes", r.bvh.internal_nodes, "nodes", "64 B internal nodes");
        b.value("triangle_leaves", r.bvh.triangle_leaves, "nodes", "64 B triangle leaves");
        b.value("procedural_leaves", r.bvh.procedural_leaves, "nodes", "64 B procedural (sphere) leaves");
        b.value("instance_leaves", r.bvh.instance_leaves, "nodes", "128 B instance leaves");
        b.value("blas", r.bvh.blas_count, "BVHs", "bottom-level BVHs");
        b.value("depth", r.bvh.depth, "nodes", "nodes on the longest root-to-leaf path, leaves included (the paper's Table 2)");
        b.value("tlas_depth", r.bvh.tlas_depth, "nodes", "internal levels of the TLAS (0: single-level)");
    }
    {
        StatsOut t = out.child("time_s", "wall-clock time of this run's phases");
        t.value("load", r.load_s, "s", "loading the scene");
        t.value("build", r.build_s, "s", "building the BVH image with Embree");
        t.value("run", r.run_s, "s", "tracing or simulating (the sampling pre-pass included)");
    }
    {
        StatsOut m = out.child("memory_mb", "host memory");
        m.value("scene", r.scene_mb, "MiB", "the scene's vertices, triangles, spheres and materials");
        m.value("bvh_image", r.image_mb, "MiB", "the BVH image");
        m.value("decoded_nodes", r.decoded_mb, "MiB", "internal nodes decoded up front for traversal (within the peak)");
        m.value("peak_resident", r.peak_mb, "MiB", "the process's peak resident memory");
        m.value("model_estimate", r.estimate_mb, "MiB",
                "timing runs: what the model (caches, RT units, threads in flight, the frame's paths) was estimated to need "
                "before it was elaborated, checked against the memory available (model/memory_estimate.h); 0: functional");
        m.value("target_1_5x_plus_200", 1.5 * (r.scene_mb + r.image_mb) + 200.0, "MiB", "1.5 x (scene + BVH image) + 200: the resident-memory target");
    }
    if (r.timing) {
        const TimingResult& t = *r.timing;
        out.value("cycles", t.cycles, "core cycles", "the frame's cycles (a sampled run's estimate; simulated cycles under timing.sampling)");
        write_error_estimate(out, r.error);
        StatsOut tm = out.child("timing", "the timing model's statistics");
        if (t.sampled && !t.interrupted && !r.segment_identity) write_sampling(tm, t.estimate, r.sample_rate, t.cycles, t.cycles_simulated);
        write_hierarchy(tm, *r.hw, t.counts, t.summary, t.estimate.scale());
        if (r.fidelity != Fidelity::Interval)
            tm.value("payloads_allocated", t.payloads_allocated, "payloads", "TLM payloads the pool made (AT, LT)");
        if (r.segment_identity) write_segment(out, t, r.segment, r.segments, *r.segment_identity);
        StatsOut rate = out.child("simulation_rate", "the simulator's speed");
        rate.value("rays_per_s", r.run_s > 0 ? double(r.rays) / r.run_s : 0.0, "rays / s", "rays over time_s.run");
        rate.value("cycles_per_s", r.run_s > 0 ? double(t.cycles) / r.run_s : 0.0, "cycles / s", "cycles over time_s.run");
        out.json()["config"] = r.config->to_json();
        out.note("config", "", "the effective configuration (platforms/configs/*.json keys)");
        std::set<std::string> groups;
        for (const Config::KeyInfo& k : Config::keys()) {
            for (size_t dot = k.name.find('.'); dot != std::string::npos; dot = k.name.find('.', dot + 1))
                if (groups.insert(k.name.substr(0, dot)).second) out.note(("config." + k.name.substr(0, dot)).c_str(), "", "configuration keys");
            out.note(("config." + k.name).c_str(), k.unit, k.what);
        }
    }
    if (r.verify) {
        const VerifyCounts& v = *r.verify;
        StatsOut vo = out.child("verify", "every valid ray against Embree's robust mode (docs/verification.md)");
        vo.value("rays", v.rays, "rays", "compared");
        vo.value("skipped", v.skipped, "rays", "not handed to Embree (|component| > 1.8e18)");
        vo.value("mismatches", v.mismatches(), "rays", "outside the documented classes (exit status 1)");
        StatsOut classes = vo.child("classes", "rays per agreement class");
        for (size_t c = 0; c < size_t(Agreement::Count); ++c) classes.value(agreement_name(Agreement(c)), v.by_class[c], "rays", "docs/verification.md");
        vo.value("mismatch_rays", *r.mismatch_rays, "ray indices", "the first 100 mismatching rays");
    }
    if (r.has_speed) {
        StatsOut sp = out.child("speed", "our traversal and Embree's on the same rays, timed after the run");
        sp.value("rays", r.speed_rays, "rays", "traced by each");
        sp.value("ours_s", r.ours_s, "s", "our traversal");
        sp.value("embree_s", r.embree_s, "s", "Embree");
        sp.value("ours_rays_per_s", r.ours_s > 0 ? double(r.speed_rays) / r.ours_s : 0.0, "rays / s", "rays over ours_s");
        sp.value("embree_rays_per_s", r.embree_s > 0 ? double(r.speed_rays) / r.embree_s : 0.0, "rays / s", "rays over embree_s");
        sp.value("embree_over_ours", r.ours_s > 0 && r.embree_s > 0 ? r.ours_s / r.embree_s : 0.0, "ratio", "our time / Embree's");
    }
}

}  // namespace

std::vector<StatKey> stats_schema() {
    // A record with every section present: what a sampled timing run with --verify writes, and
    // the functional run's speed.
    std::vector<StatKey> schema;
    RunRecord r;
    r.has_params = true;
    TimingResult t;
    t.sampled = true;
    r.error.check = ErrorCheck{};
    const Config config = Config::load("mobile");
    const HwConfig hw = config.resolve();
    r.timing = &t;
    r.hw = &hw;
    r.config = &config;
    const VerifyCounts v;
    const std::vector<uint64_t> none;
    r.verify = &v;
    r.mismatch_rays = &none;
    r.has_speed = true;
    nlohmann::ordered_json j;
    StatsOut out(j, &schema);
    write_stats(out, r);
    RunSpec spec;
    spec.fidelity = Fidelity::AT;
    spec.config = config;
    write_segment(out, t, 0, 2, segment_identity(spec, ""));
    return schema;
}

std::vector<IdentityKey> segment_identity(const RunSpec& spec, const std::string& scene) {
    char sample[64];
    std::snprintf(sample, sizeof sample, "%.17g seed %llu", spec.sample_rate, static_cast<unsigned long long>(spec.sample_seed));
    const WorkloadParams& p = spec.params;
    return {{"scene", scene + (spec.flatten ? " (--flatten)" : ""), "the scene's name, and whether it was flattened"},
            {"workload", spec.rays.empty() ? spec.workload : "rays " + spec.rays, "the workload, or the ray file"},
            {"frame", std::to_string(p.width) + "x" + std::to_string(p.height) + " spp " + std::to_string(p.spp) + " bounces " +
                          std::to_string(p.bounces) + " seed " + std::to_string(p.seed),
             "the frame's size, samples, bounces and ray seed"},
            {"fidelity", fidelity_name(spec.fidelity), "at, lt or interval"},
            {"traversal", traversal_name(spec.order), "dfs, bfs or treelet"},
            {"sample", sample, "--sample and --sample-seed"},
            {"segments", std::to_string(spec.sample_segments), "--sample-segments"},
            {"config", spec.config.to_json().dump(), "the effective configuration"}};
}

std::string prepass_identity(const RunSpec& spec, const std::string& scene, const HwConfig& hw, const BvhImage& image,
                             const std::vector<RayFileEntry>& ray_file) {
    std::string id;
    for (const IdentityKey& k : segment_identity(spec, scene))
        if (k.name == "scene" || k.name == "workload" || k.name == "frame" || k.name == "traversal") id += k.name + "=" + k.value + "\n";
    // The BVH itself, not its scene's name: a mesh file rewritten, or a LumiBench scene's other
    // assets, are other frames. FNV-1a over the image's bytes (about 50 ms for sprng's 53 MB,
    // against seconds of pre-pass). A ray file likewise by its rays, not its name.
    char line[96];
    std::snprintf(line, sizeof line, "bvh=%zu bytes, FNV-1a %016llx\n", image.size(),
                  static_cast<unsigned long long>(fnv1a(image.data(), image.size())));
    id += line;
    if (!spec.rays.empty()) {
        uint64_t h = kFnv1aBasis;
        for (const RayFileEntry& e : ray_file) {  // field by field: a struct's padding is not data
            const Ray& r = e.ray;
            const float f[8] = {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar};
            const uint8_t q[2] = {uint8_t(r.query), uint8_t(e.valid)};
            h = fnv1a(q, sizeof q, fnv1a(f, sizeof f, h));
        }
        std::snprintf(line, sizeof line, "rays=%zu, FNV-1a %016llx\n", ray_file.size(), static_cast<unsigned long long>(h));
        id += line;
    }
    id += "rt.warp_size=" + std::to_string(hw.warp_size) + "\n";
    id += std::string("rt.next_node_register=") + (hw.next_node_register ? "true" : "false") + "\n";
    if (spec.order == TraversalOrder::Treelet)  // the treelets the traversal keeps to (traversal_treelets)
        id += "prefetch.treelet_budget=" + std::to_string(hw.prefetch.treelet_budget) +
              "\nprefetch.treelet_contiguous=" + (hw.prefetch.treelet_contiguous ? "true" : "false") +
              "\nprefetch.treelet_stride=" + std::to_string(hw.prefetch.treelet_stride) + "\n";
    return id;
}

RunResult run_simulation(const RunSpec& spec, std::ostream* log) {
    const bool timing = is_timing(spec.fidelity);
    const WorkloadKind kind = spec.rays.empty() ? parse_workload(spec.workload) : WorkloadKind::RayFile;
    auto t0 = Clock::now();
    Scene scene = load_scene(spec.scene, spec.assets);
    scene.flatten = spec.flatten;
    const double load_s = seconds_since(t0);
    // Loading and building are not cut short; a stop requested meanwhile ends the run here, before
    // anything is simulated or written.
    const auto stop_here = [&spec] {
        if (spec.stop.requested()) throw Interrupted{spec.stop.signal()};
    };
    stop_here();
    t0 = Clock::now();
    const BvhImage image = build_bvh_image(scene);
    const double build_s = seconds_since(t0);
    stop_here();
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
    if (!spec.dump_bvh.empty()) out.files.emplace_back(spec.dump_bvh, std::string(reinterpret_cast<const char*>(image.data()), image.size()));
    if (!spec.dump_rays.empty() || !spec.dump_hits.empty()) {
        const std::vector<rtu_ray> records =
            kind == WorkloadKind::RayFile ? ray_records(ray_entries) : ray_records(*make_scene_workload(kind, scene, spec.params));
        const auto bytes = [](const auto& v) { return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0])); };
        if (!spec.dump_rays.empty()) out.files.emplace_back(spec.dump_rays, bytes(records));
        if (!spec.dump_hits.empty()) {
            if (spec.order == TraversalOrder::Treelet) throw InputError("--dump-hits: the peripheral traverses dfs or bfs, not treelet");
            out.files.emplace_back(spec.dump_hits, bytes(reference_hits(image.data(), image.size(), reinterpret_cast<const uint8_t*>(records.data()),
                                                                        uint32_t(records.size()), sizeof(rtu_ray),
                                                                        spec.order == TraversalOrder::BFS ? RecordTraversal::Bfs : RecordTraversal::Dfs)));
        }
    }
    RunRecord rec;
    if (timing) {
        // Refused before elaboration if it cannot fit: a configuration of maximal sizes would
        // otherwise exhaust the machine.
        const uint64_t paths = kind == WorkloadKind::RayFile ? ray_entries.size()
                                                             : uint64_t(spec.params.width) * uint64_t(spec.params.height) * uint64_t(spec.params.spp);
        const MemoryEstimate need = estimate_memory(spec.hw, spec.fidelity, paths, bs.image_bytes);
        const HostMemory host = host_memory_available();
        if (need.total() > host.available)
            throw InputError("this configuration and frame need about " + format_bytes(need.total()) + " of host memory for the timing model (" +
                             need.largest() + "), more than the " + format_bytes(host.available) + " left by " + host.limit +
                             "; make the largest of these smaller (the keys in parentheses), or run on a larger machine");
        rec.estimate_mb = double(need.total()) / (1024.0 * 1024.0);
    }
    rec.scene = scene.name;
    rec.workload = kind == WorkloadKind::RayFile ? "rays" : spec.workload;
    rec.fidelity = spec.fidelity;
    rec.order = spec.order;
    rec.has_params = kind != WorkloadKind::RayFile;
    rec.params = spec.params;
    rec.bvh = bs;
    rec.two_level = scene.two_level();
    rec.load_s = load_s;
    rec.build_s = build_s;

    std::vector<TracedRay>& rays = out.rays;
    VerifyCounts verify;
    std::vector<uint64_t> mismatch_rays;
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
        fo.stop = spec.stop;
        const FunctionalResult r = run_functional(scene, image, *workload, fo, reference.get());
        rays = traced_from(r);
        verify = r.verify;
        mismatch_rays = r.mismatch_rays;
        rec.has_speed = spec.verify;
        rec.speed_rays = rays.size();
        rec.ours_s = r.trace_seconds;
        rec.embree_s = r.embree_seconds;
        rec.nodes_visited = r.nodes_visited;
        rec.max_nodes = r.max_nodes_per_ray;
        rec.interrupted = r.interrupted;
    } else {
        TimingOptions to;
        to.fidelity = spec.fidelity;
        to.order = spec.order;
        to.progress = spec.progress;
        to.vcd = spec.vcd;
        to.sample_rate = spec.sample_rate;
        to.sample_seed = spec.sample_seed;
        to.sample_unchecked = spec.sample_unchecked;
        to.sample_segments = spec.sample_segments;
        to.sample_segment = spec.segment;
        if (!spec.sample_plan.empty()) {  // hashing the image costs tens of ms on large scenes: only for a plan
            to.plan_identity = prepass_identity(spec, scene.name, spec.hw, image, ray_entries);
            to.sample_plan = plan_file(spec.sample_plan, to.plan_identity);
        }
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
        to.stop = spec.stop;
        const bool merge = spec.sample_segments > 1 && spec.segment >= spec.sample_segments;
        if (merge) {
            // The segments ran elsewhere (files) or as child processes: merged into one estimate.
            std::vector<SegmentRun> segments;
            if (!spec.merge_segments.empty()) {
                for (const std::string& f : spec.merge_segments) segments.push_back(read_segment(f));
            } else if (spec.run_segments) {
                segments = spec.run_segments();
            }
            timing_result = merge_segments(spec.hw, image, *workload, to, std::move(segments), segment_identity(spec, scene.name));
        } else if (spec.fidelity == Fidelity::Interval) {
            try {
                timing_result = run_interval(spec.hw, image, *workload, to);
            } catch (const std::invalid_argument& e) {
                throw InputError(e.what());
            }
        } else {
            GpuPlatform platform(spec.hw, image, *workload, to);
            timing_result = platform.run();
        }
        // The sample design's bias bound, measured on the grids, widens the interval.
        if (timing_result.sampled) timing_result.estimate.design_bias = SamplingBias::built_in().value(spec.rays.empty() ? spec.workload : "");
        if (!merge && spec.sample_segments > 1 && !timing_result.interrupted) {
            // One segment: its own cycles; the frame's estimate is the merge's.
            timing_result.cycles = timing_result.cycles_simulated;
            rec.segment = spec.segment;
            rec.segments = spec.sample_segments;
        }
        rays = std::move(timing_result.rays);
        rec.nodes_visited = timing_result.summary.nodes_visited;
        rec.max_nodes = timing_result.summary.max_nodes;
        rec.timing = &timing_result;
        rec.hw = &spec.hw;
        rec.config = &spec.config;
        rec.sample_rate = spec.sample_rate;
        rec.interrupted = timing_result.interrupted;
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
    rec.run_s = seconds_since(t0);
    if (timing) {
        // After the run's own time: --check-error's child runs are not this run's speed.
        std::optional<ErrorCheck> check;
        if (spec.check_error && spec.run_check && !rec.interrupted) {
            // N drawn clusters and the first wave: a sample at (N + 1) / clusters, or the whole frame.
            const uint64_t capacity = gpu_warp_capacity(spec.hw);
            const uint64_t clusters = (timing_result.estimate.warps_total + capacity - 1) / capacity;
            const double rate = clusters <= spec.check_error + 1 ? 1.0 : double(spec.check_error + 1) / double(clusters);
            try {
                check = spec.run_check(rate);
                if (rate == 1.0) check->clusters = clusters;
            } catch (...) {
                // The check's child runs got the same signal: the run itself is whole; it is
                // written without its check.
                if (!spec.stop.requested()) throw;
                rec.interrupted = true;
            }
        }
        if (rec.interrupted) {
            rec.error.kind = "none";
            rec.error.basis = "interrupted: the cycles simulated before the stop, not the frame's";
        } else if (rec.segments) {
            rec.error.kind = "none";
            rec.error.basis = "one segment of a split sample: its cycles simulated; --merge-segments gives the frame's estimate and error";
        } else {
            rec.error = estimate_error(spec, timing_result, check);
        }
        rec.invalid = timing_result.summary.invalid;
        rec.hits = timing_result.summary.hits;
        rec.rays = timing_result.summary.rays;
    } else {
        rec.rays = rays.size();
        for (const TracedRay& r : rays) {
            rec.invalid += !r.valid;
            rec.hits += r.hit.hit;
        }
    }
    // A frame of nothing but invalid rays is all misses and would look like an empty scene (a
    // camera near the float limit does it); a ray file warns per line already.
    if (kind != WorkloadKind::RayFile && rec.rays > 0 && rec.invalid == rec.rays)
        std::cerr << "warning: every one of the " << rec.rays
                  << " rays is invalid (an origin or direction out of range): check the camera (eye, look-at) and the scene's "
                     "coordinates; the frame is all misses\n";
    // What the scene needs in memory against what the process holds at its peak.
    uint64_t scene_bytes = 0;
    for (const Mesh& m : scene.meshes)
        scene_bytes += m.vertices.size() * sizeof(glm::vec3) + m.triangles.size() * sizeof(glm::uvec3) +
                       m.spheres.size() * sizeof(Sphere) + m.material.size() * sizeof(uint32_t);
    struct rusage ru {};
    getrusage(RUSAGE_SELF, &ru);
    const double mb = 1.0 / (1024.0 * 1024.0);
    rec.scene_mb = double(scene_bytes) * mb;
    rec.image_mb = double(bs.image_bytes) * mb;
    rec.decoded_mb = double(image.decoded_bytes()) * mb;
    rec.peak_mb = double(ru.ru_maxrss) / 1024.0;
    if (spec.verify) {
        rec.verify = &verify;
        rec.mismatch_rays = &mismatch_rays;
        out.mismatches = verify.mismatches();
        if (!mismatch_rays.empty()) out.first_mismatch = mismatch_rays.front();
    }
    std::vector<IdentityKey> identity;  // a segment's, for the merge
    if (rec.segments) {
        identity = segment_identity(spec, scene.name);
        rec.segment_identity = &identity;
    }
    StatsOut stats(out.stats);
    write_stats(stats, rec);
    if (timing && timing_result.stuck) out.stuck = timing_result.stuck_report;
    out.interrupted = rec.interrupted;
    out.invariant_failures = timing_result.invariant_failures;
    if (kind != WorkloadKind::RayFile) {
        out.image = workload->image();
        out.width = spec.params.width;
        out.height = spec.params.height;
    }
    return out;
}

}  // namespace rtu
