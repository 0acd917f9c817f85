#include "simulation.h"

#include <rtunit/job.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <iostream>
#include <optional>

#include <sys/resource.h>

#include "fidelity_run.h"
#include "functional_run.h"
#include "host_memory.h"
#include "model/memory_estimate.h"
#include "model/on_threads.h"
#include "model/stats.h"
#include "model/treelet.h"
#include "run_record.h"
#include "sample_segments.h"
#include "segment_threads.h"
#include "workloads/bvh_builder.h"
#include "workloads/embree_reference.h"
#include "workloads/input_error.h"
#include "workloads/scenes.h"
#include "sampling/bias.h"
#include "sampling/plan.h"
#include "sampling/width.h"

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

std::vector<TracedRay> traced_from(const FunctionalResult& r) {
    std::vector<TracedRay> v(r.rays.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = TracedRay{r.path[i], r.seq[i], r.rays[i], r.hits[i], 0, is_valid_ray(r.rays[i])};
    std::stable_sort(v.begin(), v.end(), [](const TracedRay& a, const TracedRay& b) { return a.path != b.path ? a.path < b.path : a.seq < b.seq; });
    return v;
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
    const SampleWidth width;
    r.width = &width;
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
    spec.run.fidelity = Fidelity::AT;
    spec.config = config;
    write_segment(out, t, 0, 2, segment_identity(spec, ""));
    return schema;
}

std::vector<IdentityKey> segment_identity(const RunSpec& spec, const std::string& scene) {
    char sample[64];
    std::snprintf(sample, sizeof sample, "%.17g seed %llu", spec.run.sample_rate, static_cast<unsigned long long>(spec.run.sample_seed));
    const WorkloadParams& p = spec.params;
    return {{"scene", scene + (spec.flatten ? " (--flatten)" : ""), "the scene's name, and whether it was flattened"},
            {"workload", spec.rays.empty() ? spec.workload : "rays " + spec.rays, "the workload, or the ray file"},
            {"frame", std::to_string(p.width) + "x" + std::to_string(p.height) + " spp " + std::to_string(p.spp) + " bounces " +
                          std::to_string(p.bounces) + " seed " + std::to_string(p.seed),
             "the frame's size, samples, bounces and ray seed"},
            {"fidelity", fidelity_name(spec.run.fidelity), "at, lt or interval"},
            {"traversal", traversal_name(spec.run.order), "dfs, bfs or treelet"},
            {"sample", sample, "--sample and --sample-seed"},
            {"segments", std::to_string(spec.run.sample_segments), "--sample-segments"},
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
    if (spec.run.order == TraversalOrder::Treelet)  // the treelets the traversal keeps to (traversal_treelets)
        id += "prefetch.treelet_budget=" + std::to_string(hw.prefetch.treelet_budget) +
              "\nprefetch.treelet_contiguous=" + (hw.prefetch.treelet_contiguous ? "true" : "false") +
              "\nprefetch.treelet_stride=" + std::to_string(hw.prefetch.treelet_stride) +
              "\nprefetch.treelet_order=" + (hw.prefetch.treelet_order == TreeletOrder::Treelets ? "treelets" : "root-then-dfs") + "\n";
    return id;
}

namespace {

// The stages of a run, in order: parse (rtsim: platforms/command_line.h), load the scene, build
// its BVH image, make the workload, run the chosen fidelity, write the outputs. Loading and
// building are not cut short; a stop requested meanwhile ends the run before anything is
// simulated or written.
void stop_here(const RunSpec& spec) {
    if (spec.run.stop.requested()) throw Interrupted{spec.run.stop.signal()};
}

// Load: the scene, as named.
Scene load_stage(const RunSpec& spec, RunRecord& rec) {
    const auto t0 = Clock::now();
    Scene scene = load_scene(spec.scene, spec.assets);
    scene.flatten = spec.flatten;
    rec.load_s = seconds_since(t0);
    rec.scene = scene.name;
    rec.two_level = scene.two_level();
    stop_here(spec);
    return scene;
}

// Build: the scene's BVH image.
BvhImage build_stage(const RunSpec& spec, const Scene& scene, RunRecord& rec, std::ostream* log) {
    const auto t0 = Clock::now();
    BvhImage image = build_bvh_image(scene);
    rec.build_s = seconds_since(t0);
    rec.bvh = image.stats;
    stop_here(spec);
    const BvhStats& bs = image.stats;
    if (log)
        *log << "scene " << scene.name << ": " << scene.meshes.size() << " meshes, " << scene.primitive_count()
             << " primitives, " << scene.instances.size() << " instances (" << (scene.two_level() ? "two-level" : "single-level")
             << " BVH), loaded in " << rec.load_s << " s\n"
             << "BVH image: " << bs.image_bytes << " bytes, " << bs.internal_nodes << " internal nodes, "
             << bs.triangle_leaves << " triangle + " << bs.procedural_leaves << " procedural + " << bs.instance_leaves
             << " instance leaves, depth " << bs.depth << ", built in " << rec.build_s << " s\n";
    return image;
}

// Make the workload: a ray file's rays or the scene's workload; fresh() makes another instance
// of it (the sampling pre-pass's, the dumps').
struct WorkloadStage {
    const RunSpec& spec;
    const Scene& scene;
    WorkloadKind kind;
    std::vector<RayFileEntry> ray_file;
    std::unique_ptr<Workload> workload;
    std::unique_ptr<Workload> fresh() const {
        return kind == WorkloadKind::RayFile ? make_ray_file_workload(ray_file) : make_scene_workload(kind, scene, spec.params);
    }
    uint64_t paths() const {
        return kind == WorkloadKind::RayFile ? ray_file.size() : uint64_t(spec.params.width) * uint64_t(spec.params.height) * uint64_t(spec.params.spp);
    }
};

void memory_stage(const WorkloadStage& w, const BvhStats& bs, RunRecord& rec) {
    if (w.kind != WorkloadKind::RayFile) check_workload_params(w.spec.params);  // a frame that cannot be made is said as such
    const bool timing = is_timing(w.spec.run.fidelity);
    const MemoryEstimate need = timing ? estimate_memory(w.spec.hw, w.spec.run.fidelity, w.paths(), bs.image_bytes)
                                       : estimate_functional_memory(w.paths());
    const HostMemory host = host_memory_available();
    if (need.total() > host.available)
        throw InputError("this frame needs about " + format_bytes(need.total()) + " of host memory" +
                         (timing ? " for the timing model (" : " (") + need.largest() + "), more than the " + format_bytes(host.available) +
                         " left by " + host.limit +
                         (timing ? "; make the largest of these smaller (the keys in parentheses), or run on a larger machine"
                                 : "; make the frame smaller (--width, --height, --spp), or run on a larger machine"));
    if (timing) rec.estimate_mb = double(need.total()) / (1024.0 * 1024.0);
}

void make_workload_stage(WorkloadStage& w, const BvhStats& bs, RunRecord& rec) {
    if (w.kind == WorkloadKind::RayFile) {
        w.ray_file = read_ray_file(w.spec.rays);
        size_t warned = 0;
        for (const RayFileEntry& e : w.ray_file)
            if (!e.valid && warned++ < 5) std::cerr << "warning: " << w.spec.rays << ":" << e.line << ": " << e.problem << " (reported as a miss)\n";
        if (warned > 5) std::cerr << "warning: " << warned << " invalid rays in all\n";
    }
    // The memory the frame needs, before the workload allocates any of it (its per-path state).
    memory_stage(w, bs, rec);
    w.workload = w.fresh();
    rec.workload = w.kind == WorkloadKind::RayFile ? "rays" : w.spec.workload;
    rec.has_params = w.kind != WorkloadKind::RayFile;
    rec.params = w.spec.params;
}

// The SoC peripheral's inputs (--dump-bvh, --dump-rays, --dump-hits), written with the outputs.
void dump_stage(const WorkloadStage& w, const BvhImage& image, RunResult& out) {
    const RunSpec& spec = w.spec;
    if (!spec.dump_bvh.empty()) out.files.emplace_back(spec.dump_bvh, std::string(reinterpret_cast<const char*>(image.data()), image.size()));
    if (spec.dump_rays.empty() && spec.dump_hits.empty()) return;
    const std::vector<rtu_ray> records = w.kind == WorkloadKind::RayFile ? ray_records(w.ray_file) : ray_records(*w.fresh());
    const auto bytes = [](const auto& v) { return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0])); };
    if (!spec.dump_rays.empty()) out.files.emplace_back(spec.dump_rays, bytes(records));
    if (spec.dump_hits.empty()) return;
    if (spec.run.order == TraversalOrder::Treelet) throw InputError("--dump-hits: the peripheral traverses dfs or bfs, not treelet");
    out.files.emplace_back(spec.dump_hits, bytes(reference_hits(image.data(), image.size(), reinterpret_cast<const uint8_t*>(records.data()),
                                                                uint32_t(records.size()), sizeof(rtu_ray),
                                                                spec.run.order == TraversalOrder::BFS ? RecordTraversal::Bfs : RecordTraversal::Dfs)));
}

// A timing run is refused before elaboration if it cannot fit: a configuration of maximal sizes
// would otherwise exhaust the machine.
// What the fidelity stage leaves behind, for the record.
struct Ran {
    TimingResult timing;
    VerifyCounts verify;
    std::vector<uint64_t> mismatch_rays;
    std::vector<IdentityKey> identity;  // one segment's, for the merge
};

// SIGUSR1: a run's statistics so far, `snap` (a copy of the run's record with what was simulated
// so far), handed to RunSpec::write_snapshot with `what` says how far the run is.
void write_snapshot(const RunSpec& spec, RunRecord snap, const std::string& what) {
    snap.interrupted = snap.snapshot = true;
    nlohmann::ordered_json j;
    StatsOut out(j);
    write_stats(out, snap);
    spec.write_snapshot(j.dump(2) + "\n", what);
}

// A functional result's figures into the record; `verify`: with its checks so far.
void record_functional(RunRecord& rec, const FunctionalResult& r, bool verify) {
    rec.nodes_visited = r.nodes_visited;
    rec.max_nodes = r.max_nodes_per_ray;
    rec.interrupted = r.interrupted;
    rec.rays = r.rays.size();
    rec.invalid = r.invalid_rays;
    rec.hits = r.hit_count;
    if (verify) {
        rec.verify = &r.verify;
        rec.mismatch_rays = &r.mismatch_rays;
    }
}

// Run, functional fidelity: every ray traced, checked against Embree with --verify.
void functional_stage(const WorkloadStage& w, const BvhImage& image, const EmbreeReference* reference, Ran& ran, RunRecord& rec,
                      RunResult& out) {
    FunctionalOptions fo;
    fo.order = w.spec.run.order;
    // The treelets of the configuration, as the timing fidelities' traversal keeps to them.
    const std::unique_ptr<Treelets> treelets = traversal_treelets(w.spec.hw, image, fo.order);
    fo.treelets = treelets.get();
    fo.progress = w.spec.run.progress;
    fo.threads = w.spec.run.threads;
    fo.measure_speed = w.spec.verify;
    fo.stop = w.spec.run.stop;
    // SIGUSR1: the statistics so far, from a copy of the record.
    if (w.spec.write_snapshot)
        fo.snapshot = [&w, &rec, reference](const FunctionalResult& so_far) {
            RunRecord snap = rec;
            record_functional(snap, so_far, reference != nullptr);
            write_snapshot(w.spec, snap, std::to_string(so_far.rays.size()) + " rays traced so far");
        };
    const FunctionalResult r = run_functional(w.scene, image, *w.workload, fo, reference);
    out.rays = traced_from(r);
    ran.verify = r.verify;
    ran.mismatch_rays = r.mismatch_rays;
    rec.has_speed = w.spec.verify;
    rec.speed_rays = out.rays.size();
    rec.ours_s = r.trace_seconds;
    rec.embree_s = r.embree_seconds;
    record_functional(rec, r, false);
}

// A timing result's figures into the record.
void record_timing(RunRecord& rec, const TimingResult& t, const RunSpec& spec) {
    rec.nodes_visited = t.summary.nodes_visited;
    rec.max_nodes = t.summary.max_nodes;
    rec.rays = t.summary.rays;
    rec.invalid = t.summary.invalid;
    rec.hits = t.summary.hits;
    rec.timing = &t;
    rec.hw = &spec.hw;
    rec.sample_rate = spec.run.sample_rate;
    rec.interrupted = t.interrupted;
}

TimingResult sample_of_width(WorkloadStage& w, const BvhImage& image, TimingOptions& to, SampleWidth& planned);

// Run, a timing fidelity (or the merge of a split sample's segments; or with --sample-width, the
// sample it plans, `width` what it planned).
void timing_stage(WorkloadStage& w, const BvhImage& image, Ran& ran, RunRecord& rec, SampleWidth* width) {
    const RunSpec& spec = w.spec;
    TimingOptions to = spec.run;
    if (!spec.run.sample_plan.empty()) {  // hashing the image costs tens of ms on large scenes: only for a plan
        to.plan_identity = prepass_identity(spec, w.scene.name, spec.hw, image, w.ray_file);
        to.sample_plan = plan_file(spec.run.sample_plan, to.plan_identity);
    }
    // A sampled run traces the whole frame functionally first, with fresh instances of the
    // workload (the run's own one accumulates the simulated image).
    if (spec.run.sample_rate < 1.0 || width) to.sample_workload = [&w] { return w.fresh(); };
    // SIGUSR1: the statistics so far, from a copy of the record (the run's own is filled at its end).
    if (spec.write_snapshot)
        to.snapshot = [&spec, &rec](const TimingResult& so_far) {
            RunRecord snap = rec;
            record_timing(snap, so_far, spec);  // interrupted: so_far is partial
            write_snapshot(spec, snap, std::to_string(so_far.summary.rays) + " rays retired and " +
                                           std::to_string(so_far.cycles_simulated) + " cycles simulated so far");
        };
    TimingResult& t = ran.timing;
    const bool merge = spec.run.sample_segments > 1 && spec.run.sample_segment >= spec.run.sample_segments;
    if (merge) {  // the segments ran elsewhere (files), on threads or as child processes: merged into one estimate
        std::vector<SegmentRun> segments;
        double prepass_s = 0;  // the segments on threads: their frame's pre-pass
        const std::vector<IdentityKey> identity = segment_identity(spec, w.scene.name);
        if (!spec.merge_segments.empty()) {
            for (const std::string& f : spec.merge_segments) segments.push_back(read_segment(f));
        } else if (spec.run_segments && spec.run.fidelity == Fidelity::Interval) {
            // Plain C++: the segments on this process's threads, sharing its scene, image and the
            // frame's pre-pass, which the merge takes too (platforms/segment_threads.h).
            std::optional<PrepassResult> prepass;
            try {
                segments = run_segment_threads(spec.hw, image, [&w] { return w.fresh(); }, to, spec.run.threads, identity, prepass,
                                               !spec.run.progress, &prepass_s);
            } catch (const std::invalid_argument& e) {
                throw InputError(e.what());
            }
            to.prepass = std::make_shared<const PrepassResult>(std::move(*prepass));
        } else if (spec.run_segments) {
            segments = spec.run_segments();
        }
        t = merge_segments(spec.hw, image, *w.workload, to, std::move(segments), identity);
        t.prepass_s += prepass_s;  // the segments on threads made the frame's pre-pass before them
    } else if (width) {
        t = sample_of_width(w, image, to, *width);
    } else {
        try {
            t = run_timing(spec.hw, image, *w.workload, to);
        } catch (const std::invalid_argument& e) {
            throw InputError(e.what());
        }
    }
    // The sample design's bias bound, measured on the grids, widens the interval.
    if (t.sampled) t.estimate.design_bias = SamplingBias::built_in().value(spec.rays.empty() ? spec.workload : "");
    if (spec.sample_width > 0 && t.sampled && !t.interrupted) {
        const double h = t.estimate.relative_half_width(double(t.cycles_simulated));
        if (h > spec.sample_width)
            std::cerr << "warning: --sample-width " << percent_text(spec.sample_width) << ": the sample states +-" << percent_text(h)
                      << ", wider than asked (its schedule model's error or its sampling error came out larger than the pilot's)\n";
    }
    if (!merge && spec.run.sample_segments > 1 && !t.interrupted) {
        // One segment: its own cycles; the frame's estimate is the merge's.
        t.cycles = t.cycles_simulated;
        rec.segment = spec.run.sample_segment;
        rec.segments = spec.run.sample_segments;
        ran.identity = segment_identity(spec, w.scene.name);
        rec.segment_identity = &ran.identity;
    }
    record_timing(rec, t, spec);
    rec.sample_rate = to.sample_rate;  // --sample-width: the rate it chose
}

// A timing run's rays against Embree (--verify): classified on `threads` threads, each ray into
// its own slot, then counted in ray order (the same counts and list for any thread count).
void verify_stage(const Scene& scene, const EmbreeReference& reference, const std::vector<TracedRay>& rays, unsigned threads, Ran& ran) {
    std::vector<std::optional<Agreement>> classes(rays.size());
    for_each_index(threads, rays.size(), [&](size_t i) {
        if (rays[i].valid) classes[i] = verify_ray(scene, reference, rays[i].ray, rays[i].hit);
    });
    for (size_t i = 0; i < rays.size(); ++i) {
        if (!rays[i].valid) continue;
        const std::optional<Agreement>& cls = classes[i];
        if (!cls) {
            ++ran.verify.skipped;
            continue;
        }
        ++ran.verify.by_class[size_t(*cls)];
        ++ran.verify.rays;
        if (*cls == Agreement::Mismatch && ran.mismatch_rays.size() < 100) ran.mismatch_rays.push_back(i);
    }
}

uint64_t frame_clusters(uint64_t warps, const HwConfig& hw) {
    const uint64_t cluster = sample_cluster_warps(hw);
    return (warps + cluster - 1) / cluster;
}

// The frame's shader warps: a shader warp is warp_size neighbouring paths (pixels: each thread
// traces its pixel's samples in turn), or rays of a ray file.
uint64_t frame_warps(const WorkloadStage& w) {
    const RunSpec& spec = w.spec;
    const uint64_t paths = w.kind == WorkloadKind::RayFile ? w.ray_file.size() : uint64_t(spec.params.width) * uint64_t(spec.params.height);
    return (paths + spec.hw.warp_size - 1) / spec.hw.warp_size;
}

// --check-error N simulates N + 1 of the frame's clusters twice, in the run's fidelity and in AT,
// each child loading the scene (and one tracing the frame for the plan both use): refused before
// the run where that is more than a fifth of the frame, whose two samples would then simulate two
// fifths of it or more beside their fixed costs, about as much as AT's run where AT is not much
// slower than the fidelity (docs/accuracy.md, "The check against the full runs"); below 4 drawn
// clusters, which pair into fewer than 2 strata pairs for its interval (command_line.cpp); and
// where the frame cannot be sampled.
void check_error_refusal(const WorkloadStage& w, const BvhImage& image) {
    const RunSpec& spec = w.spec;
    if (!spec.check_error) return;
    if (const std::optional<std::string> why = sample_refusal(spec.hw, image))
        throw InputError("--check-error: its check simulates a sample of the frame, and " + *why);
    const uint64_t clusters = frame_clusters(frame_warps(w), spec.hw);
    if (5 * (spec.check_error + 1) > clusters)
        throw InputError("--check-error " + std::to_string(spec.check_error) + ": the check simulates " + std::to_string(spec.check_error + 1) +
                         " clusters (the first wave and N drawn) of this frame's " + std::to_string(clusters) + " (of " +
                         std::to_string(sample_cluster_warps(spec.hw)) + " shader warps each) in this fidelity and in AT; more than a fifth "
                         "of the frame costs about as much as the frame in AT, so run --fidelity at (the reference)" +
                         (clusters >= 25 ? ", or give N at most " + std::to_string(clusters / 5 - 1) : std::string(": the frame is too small for a check")));
}

// A pilot's terms from its statistics' timing.sampling (a child run: AT, LT).
PilotTerms pilot_terms_of(const nlohmann::json& s, double bias) {
    PilotTerms p;
    p.relative_se = s["relative_se"].get<double>();
    p.degrees = s["variance_degrees"].get<double>();
    p.model_error = s["schedule_model_error"].get<double>();
    const double stratified = s["work_estimate_stratified_residence_cycles"].get<double>();
    p.extrapolation_gap = stratified > 0 ? std::fabs(s["work_estimate_residence_cycles"].get<double>() / stratified - 1.0) : 0.0;
    p.first_reads_gap = s["first_reads"]["gap"].get<double>();
    p.design_bias = bias;
    p.strata = s["strata"].get<uint64_t>();
    p.set_frame(s["warps_total"].get<uint64_t>(), s["cluster_warps"].get<uint64_t>(), s["first_wave_clusters"].get<uint64_t>(),
                s["empty_clusters"].get<uint64_t>());
    return p;
}

// --sample-width W (docs/sampling.md, "A sample of a given width"): the frame sampled at the rate
// whose 95 % interval should be within +-W. The design's bias bound is known before anything
// runs: where it alone is W or more, refused at once. Else a pilot samples kMinStrata strata of
// the frame; its interval's parts that no rate narrows (PilotTerms::floor) are taken as the
// frame's at any rate, and its sampling term is carried to more strata (PilotTerms::half_width).
// Refused where the floor reaches W, or where only the whole frame would. The interval fidelity
// (plain C++) runs the pilot in this process, and where the pilot reaches W it is the run; AT and
// LT (SystemC elaborates once per process) run it as a child process that traces the frame for
// the plan this run reads, and this run simulates the rate chosen (the pilot's clusters again
// where it reached W). `to.sample_rate` is set to the rate of the run returned; the workload of
// `w` is the run's (the pilot's where it is the run).
TimingResult sample_of_width(WorkloadStage& w, const BvhImage& image, TimingOptions& to, SampleWidth& planned) {
    const RunSpec& spec = w.spec;
    const double asked = spec.sample_width;
    const std::string workload = spec.rays.empty() ? spec.workload : "";
    const std::string ask = "--sample-width " + percent_text(asked);
    const double bias = SamplingBias::built_in().value(workload);
    if (asked <= bias)
        throw InputError(ask + ": every sampled interval of this workload holds " + SamplingBias::built_in().basis(workload) +
                         ", which no rate narrows: ask for more than " + percent_text(bias) + ", or run the whole frame (no --sample-width)");
    if (const std::optional<std::string> why = sample_refusal(spec.hw, image)) throw InputError(ask + ": " + *why);
    const uint64_t clusters = frame_clusters(frame_warps(w), spec.hw);
    std::optional<double> rate = rate_for_strata(clusters, clusters ? clusters - 1 : 0, kMinStrata);
    // A sample of more than kWidthMaxRate of the frame costs about what the frame costs.
    const std::string beyond = " more than " + percent_text(kWidthMaxRate) + ", beyond which the whole frame costs about as much (docs/sampling.md): "
                               "run it whole (no --sample-width)";
    if (!rate || *rate > kWidthMaxRate)
        throw InputError(ask + ": this frame has " + std::to_string(clusters) + " clusters of " + std::to_string(sample_cluster_warps(spec.hw)) +
                         " shader warps, and a pilot of " + std::to_string(kMinStrata) + " strata beside the first wave would sample " +
                         percent_text(rate.value_or(1.0)) + " of it," + beyond);
    const bool here = spec.run.fidelity == Fidelity::Interval;
    std::optional<TimingResult> pilot;  // here: the last pilot's run, and its workload (its frame's pixels)
    std::unique_ptr<Workload> pilot_workload;
    // A pilot at `r`: its terms, and what the statistics say of it. Here, false where it was stopped
    // (the pilot so far is then the run).
    PilotTerms p;
    const auto measure = [&](double r) {
        planned.pilot_rate = r;
        ++planned.pilots;
        if (spec.run.progress) std::cerr << "planning the sample's width: a pilot sample of " << percent_text(r) << " of the frame\n";
        if (here) {
            const auto t0 = Clock::now();
            TimingOptions po = to;
            po.sample_rate = r;
            po.sample_unchecked = true;  // its strata are read below
            pilot.reset();
            pilot_workload = w.fresh();
            try {
                pilot = run_timing(spec.hw, image, *pilot_workload, po);
            } catch (const std::invalid_argument& e) {
                throw InputError(e.what());
            }
            planned.pilot_s += seconds_since(t0);
            if (pilot->interrupted) return false;
            pilot->estimate.design_bias = bias;
            p = pilot_terms(pilot->estimate, double(pilot->cycles_simulated));
            planned.pilot_half_width = pilot->estimate.relative_half_width(double(pilot->cycles_simulated));
        } else {
            const nlohmann::json j = spec.run_pilot(r);
            p = pilot_terms_of(j, bias);
            planned.pilot_half_width = j["cycles_ci95"].is_array() ? j["cycles_ci95"][1].get<double>() / j["cycles"].get<double>() - 1.0 : 0.0;
            planned.pilot_s += j["pilot_s"].get<double>();
        }
        planned.pilot_strata = p.strata;
        planned.floor = p.floor();
        return true;
    };
    const auto stopped = [&] {  // the pilot so far is the run
        to.sample_rate = planned.pilot_rate;
        w.workload = std::move(pilot_workload);
        return std::move(*pilot);
    };
    if (!measure(*rate)) return stopped();
    // Clusters that read no node are not strata: where the frame has some, the pilot drew fewer
    // than it was asked for, and once more at the rate that draws them.
    if (p.strata < kMinStrata && p.strata < p.candidates)
        if ((rate = rate_for_strata(p.clusters, p.candidates, kMinStrata))) {
            if (*rate > kWidthMaxRate)
                throw InputError(ask + ": this frame has " + std::to_string(p.candidates) + " clusters with work beside the first wave, and a pilot of " +
                                 std::to_string(kMinStrata) + " strata would sample " + percent_text(*rate) + " of it," + beyond);
            if (!measure(*rate)) return stopped();
        }
    if (p.strata >= p.candidates)
        throw InputError(ask + ": the pilot sample simulated every one of this frame's " + std::to_string(p.candidates) +
                         " clusters with work: the frame is too small to sample; run it whole (no --sample-width)");
    if (p.strata < kMinStrata)
        throw InputError(ask + ": this frame has " + std::to_string(p.candidates) + " clusters with work beside the first wave; a sample's interval needs " +
                         std::to_string(kMinStrata) + ": run it whole (no --sample-width)");
    planned.asked = asked;
    const auto said = [&] {
        char terms[256];
        std::snprintf(terms, sizeof terms, "the schedule model's error %s, the extrapolation gap %s, the first reads' gap %s and the design's bias bound %s",
                      percent_text(1.96 * std::sqrt(2.0) * p.model_error).c_str(), percent_text(1.96 * p.extrapolation_gap).c_str(),
                      percent_text(p.first_reads_gap).c_str(), percent_text(bias).c_str());
        return std::string(planned.pilots > 1 ? "its second pilot sample (" : "its pilot sample (") + percent_text(planned.pilot_rate) +
               " of the frame, " + std::to_string(p.strata) + " strata) states +-" + percent_text(planned.pilot_half_width) + ", of which +-" +
               percent_text(planned.floor) + " no larger rate is taken to narrow (" + terms + ")";
    };
    // Where the floor reaches W, the model's term may still fall with the sample's size: where it
    // would reach W if it fell as 1 / sqrt(strata), a second pilot at that size measures it.
    if (planned.floor >= asked) {
        const std::optional<uint64_t> n = strata_for_width(p, asked, true);
        if (!n)
            throw InputError(ask + " is not reachable on this frame: " + said() + ", and even were the model's error to fall as 1 / sqrt(strata), only the whole frame would reach it; ask for more than " +
                             percent_text(planned.floor) + ", or run the whole frame (no --sample-width)");
        if (spec.run.progress)
            std::cerr << said() << "; were the model's error to fall with the sample's size, " << *n << " strata would reach +-" << percent_text(asked) << "\n";
        const double second = rate_for_strata(p.clusters, p.candidates, *n).value_or(1.0);
        if (second > kWidthMaxRate)
            throw InputError(ask + " is not reachable on this frame: " + said() + "; only were the model's error to fall as 1 / sqrt(strata) would " +
                             std::to_string(*n) + " strata reach it, and a second pilot of them would sample " + percent_text(second) + " of the frame," + beyond);
        if (!measure(second)) return stopped();
        if (planned.floor >= asked)
            throw InputError(ask + " is not reachable on this frame: " + said() + "; ask for more than " + percent_text(planned.floor) +
                             ", or run the whole frame (no --sample-width)");
    }
    const std::optional<uint64_t> n = strata_for_width(p, asked);
    if (!n)
        throw InputError(ask + " is not reachable with a sample of this frame: " + said() + ", and its sampling error would need every one of its " +
                         std::to_string(p.candidates) + " clusters with work: run it whole (no --sample-width)");
    planned.predicted = p.half_width(*n);
    const bool pilots = *n == p.strata;  // the pilot reaches W
    to.sample_rate = pilots ? planned.pilot_rate : rate_for_strata(p.clusters, p.candidates, *n).value_or(1.0);
    if (to.sample_rate > kWidthMaxRate)
        throw InputError(ask + " is not reachable on this frame: " + said() + "; " + std::to_string(*n) + " strata should reach it, a sample of " +
                         percent_text(to.sample_rate) + " of the frame," + beyond);
    if (spec.run.progress)
        std::cerr << said()
                  << (pilots ? (here ? "; the pilot is the run" : "; the run simulates the pilot's clusters")
                             : "; sampling " + percent_text(to.sample_rate) + " of the frame (" + std::to_string(*n) + " strata)")
                  << " for a predicted +-" << percent_text(planned.predicted) << "\n";
    if (pilot && pilots) {
        w.workload = std::move(pilot_workload);
        return std::move(*pilot);
    }
    pilot.reset();
    pilot_workload.reset();
    try {
        return run_timing(spec.hw, image, *w.workload, to);
    } catch (const std::invalid_argument& e) {
        throw InputError(e.what());
    }
}

// A timing run's error against AT (docs/accuracy.md); after the run's own time, so that
// --check-error's child runs are not this run's speed.
void error_stage(const RunSpec& spec, const TimingResult& t, double run_s, RunRecord& rec) {
    std::optional<ErrorCheck> check;
    std::string refused;
    if (spec.check_error && spec.run_check && !rec.interrupted) {
        // N drawn clusters and the first wave: a sample at (N + 1) / clusters (at most a fifth of
        // the frame: check_error_refusal).
        const uint64_t clusters = frame_clusters(t.estimate.warps_total, spec.hw);
        try {
            check = spec.run_check(double(spec.check_error + 1) / double(clusters), run_s);
        } catch (const CheckRefused& e) {
            refused = e.what();
            std::cerr << "warning: --check-error refused: " << refused << "\n";
        } catch (...) {
            // The check's child runs got the same signal: the run itself is whole; it is
            // written without its check.
            if (!spec.run.stop.requested()) throw;
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
        rec.error = estimate_error(spec, t, check, ErrorBounds::built_in(), refused);
    }
}

// What the scene needs in memory against what the process holds at its peak.
void memory_record(const Scene& scene, const BvhImage& image, RunRecord& rec) {
    uint64_t scene_bytes = 0;
    for (const Mesh& m : scene.meshes)
        scene_bytes += m.vertices.size() * sizeof(glm::vec3) + m.triangles.size() * sizeof(glm::uvec3) + m.spheres.size() * sizeof(Sphere) +
                       m.material.size() * sizeof(uint32_t);
    struct rusage ru {};
    getrusage(RUSAGE_SELF, &ru);
    const double mb = 1.0 / (1024.0 * 1024.0);
    rec.scene_mb = double(scene_bytes) * mb;
    rec.image_mb = double(image.stats.image_bytes) * mb;
    rec.decoded_mb = double(image.decoded_bytes()) * mb;
    rec.peak_mb = double(ru.ru_maxrss) / 1024.0;
}

// Write the outputs: the statistics and what the caller writes once the run succeeded.
void output_stage(const WorkloadStage& w, const Ran& ran, RunRecord& rec, RunResult& out) {
    // A frame of nothing but invalid rays is all misses and would look like an empty scene (a
    // camera near the float limit does it); a ray file warns per line already.
    if (w.kind != WorkloadKind::RayFile && rec.rays > 0 && rec.invalid == rec.rays)
        std::cerr << "warning: every one of the " << rec.rays
                  << " rays is invalid (an origin or direction out of range): check the camera (eye, look-at) and the scene's "
                     "coordinates; the frame is all misses\n";
    if (w.spec.verify) {
        rec.verify = &ran.verify;
        rec.mismatch_rays = &ran.mismatch_rays;
        out.mismatches = ran.verify.mismatches();
        if (!ran.mismatch_rays.empty()) out.first_mismatch = ran.mismatch_rays.front();
    }
    StatsOut stats(out.stats);
    write_stats(stats, rec);
    seal_segment(out.stats);  // last: it covers every key above
    if (rec.timing && ran.timing.stuck) out.stuck = ran.timing.stuck_report;
    out.interrupted = rec.interrupted;
    out.invariant_failures = ran.timing.invariant_failures;
    if (w.kind != WorkloadKind::RayFile) {
        out.image = w.workload->image();
        out.width = w.spec.params.width;
        out.height = w.spec.params.height;
    }
}

}  // namespace

RunResult run_simulation(const RunSpec& spec, std::ostream* log) {
    const auto start = Clock::now();
    const bool timing = is_timing(spec.run.fidelity);
    RunRecord rec;
    rec.fidelity = spec.run.fidelity;
    rec.order = spec.run.order;
    rec.config = &spec.config;
    rec.command_line = &spec.command_line;
    const Scene scene = load_stage(spec, rec);
    const BvhImage image = build_stage(spec, scene, rec, log);
    WorkloadStage w{spec, scene, spec.rays.empty() ? parse_workload(spec.workload) : WorkloadKind::RayFile, {}, nullptr};
    make_workload_stage(w, image.stats, rec);
    check_error_refusal(w, image);
    std::unique_ptr<EmbreeReference> reference;
    if (spec.verify) reference = std::make_unique<EmbreeReference>(scene);
    RunResult out;
    dump_stage(w, image, out);
    Ran ran;
    const auto t0 = Clock::now();
    SampleWidth width;
    if (timing && spec.sample_width > 0) rec.width = &width;
    if (!timing) {
        functional_stage(w, image, reference.get(), ran, rec, out);
    } else {
        timing_stage(w, image, ran, rec, rec.width ? &width : nullptr);
        out.rays = std::move(ran.timing.rays);
        if (!spec.timeline.empty()) out.files.emplace_back(spec.timeline, std::move(ran.timing.timeline));
        if (reference) verify_stage(scene, *reference, out.rays, spec.run.threads, ran);
    }
    rec.run_s = seconds_since(t0);
    if (timing) error_stage(spec, ran.timing, seconds_since(start), rec);
    memory_record(scene, image, rec);
    output_stage(w, ran, rec, out);
    return out;
}

}  // namespace rtu
