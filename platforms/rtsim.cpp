// rtsim: runs a ray workload over a scene's BVH image on the RT-unit model.
// This is the functional fidelity (issue #2); the timing fidelities plug into the same program.
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>
#include <sstream>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include <sys/resource.h>

#include <systemc>

#include "functional_run.h"
#include "gpu_platform.h"
#include "interval_run.h"
#include "model/traversal.h"
#include "model/treelet.h"
#include "output.h"
#include "workloads/bvh_builder.h"
#include "workloads/embree_reference.h"
#include "workloads/input_error.h"
#include "workloads/rays.h"
#include "workloads/scenes.h"

namespace po = boost::program_options;
using namespace rtu;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Args {
    std::string scene = "wknd", assets, workload = "pt", rays, hits, traversal = "dfs", fidelity = "functional";
    std::string stats, image, config = "mobile", vcd, trace_warp, prefetcher;
    std::vector<std::string> sets;
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1, quantum = 0;
    double sample = 1.0;
    std::optional<uint64_t> sample_seed;  // which clusters a sampled run simulates (default: --seed)
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());  // sampling pre-pass
    bool verify = false, quiet = false, flatten = false;
};

// Hits in (path, seq) order: for ray files the line order, for generated workloads each pixel
// sample's rays in the order its path made them. Functional and timing runs write the same file.
std::string hits_csv(const std::vector<TracedRay>& rays) {
    std::string out = "ray,hit,t,geom,prim\n";
    char line[96];
    for (size_t i = 0; i < rays.size(); ++i) {
        const Hit& h = rays[i].hit;
        if (h.hit)
            std::snprintf(line, sizeof line, "%zu,1,%.9g,%u,%u\n", i, double(h.t), h.geom, h.prim);
        else
            std::snprintf(line, sizeof line, "%zu,0,-1,-1,-1\n", i);
        out += line;
    }
    return out;
}

std::vector<TracedRay> traced_from(const FunctionalResult& r) {
    std::vector<TracedRay> v(r.rays.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = TracedRay{r.path[i], r.seq[i], r.rays[i], r.hits[i], 0, is_valid_ray(r.rays[i])};
    std::stable_sort(v.begin(), v.end(), [](const TracedRay& a, const TracedRay& b) { return a.path != b.path ? a.path < b.path : a.seq < b.seq; });
    return v;
}

std::pair<int, int> parse_trace_warp(const std::string& s, const HwConfig& hw) {
    const auto colon = s.find(':');
    try {
        if (colon == std::string::npos) throw std::invalid_argument("no colon");
        const int sm = std::stoi(s.substr(0, colon)), warp = std::stoi(s.substr(colon + 1));
        if (sm < 0 || sm >= int(hw.sms) || warp < 0 || warp >= int(hw.warp_buffer)) throw std::out_of_range("range");
        return {sm, warp};
    } catch (const std::exception&) {
        throw InputError("--trace-warp '" + s + "': expected SM:WARP with SM in 0.." + std::to_string(hw.sms - 1) +
                         " and WARP (warp-buffer slot) in 0.." + std::to_string(hw.warp_buffer - 1));
    }
}

int run(const Args& a) {
    const bool interval = a.fidelity == "interval";
    const bool timing = a.fidelity == "at" || a.fidelity == "lt" || interval;
    if (!timing && a.fidelity != "functional")
        throw InputError("--fidelity '" + a.fidelity + "': allowed are functional, at, lt, interval");
    TraversalOrder order;
    if (a.traversal == "dfs") order = TraversalOrder::DFS;
    else if (a.traversal == "bfs") order = TraversalOrder::BFS;
    else if (a.traversal == "treelet") order = TraversalOrder::Treelet;
    else throw InputError("--traversal '" + a.traversal + "': allowed are dfs, bfs, treelet");
    const WorkloadKind kind = a.rays.empty() ? parse_workload(a.workload) : WorkloadKind::RayFile;
    if (!a.rays.empty() && !a.image.empty()) throw InputError("--image needs a scene workload, not --rays");
    if (!timing && (!a.vcd.empty() || !a.trace_warp.empty() || !a.sets.empty() || a.quantum || !a.prefetcher.empty() || a.sample != 1.0))
        throw InputError("--vcd, --trace-warp, --set, --quantum, --prefetcher and --sample need --fidelity at, lt or interval");
    if (interval && (!a.vcd.empty() || !a.trace_warp.empty() || a.quantum))
        throw InputError("--vcd, --trace-warp and --quantum need --fidelity at or lt (the interval fidelity has no "
                         "SystemC signals or quantum)");
    if (a.sample_seed && a.sample == 1.0) throw InputError("--sample-seed needs --sample RATE below 1");
    if (a.threads == 0) throw InputError("--threads 0: the sampling pre-pass needs at least 1 thread");
    if (!(a.sample > 0.0 && a.sample <= 1.0))
        throw InputError("--sample " + std::to_string(a.sample) + ": the share of the frame to simulate must be in (0, 1]");

    // Configuration first: a bad key should not wait for a scene to load.
    Config config;
    HwConfig hw{};
    if (timing) {
        try {
            config = Config::load(a.config);
            for (const auto& s : a.sets) config.set(s);
            if (a.quantum) config.set("sim.quantum=" + std::to_string(a.quantum));
            if (!a.prefetcher.empty()) config.set("prefetch.kind=" + a.prefetcher);
            hw = config.resolve();
            if (hw.prefetch.kind == PrefetcherKind::Treelet && order != TraversalOrder::Treelet)
                throw ConfigError("--prefetcher treelet needs --traversal treelet (the Treelet prefetcher requires treelet traversal)");
        } catch (const ConfigError& e) {
            throw InputError(e.what());
        }
    }

    auto t0 = Clock::now();
    Scene scene = load_scene(a.scene, a.assets);
    scene.flatten = a.flatten;
    const double load_s = seconds_since(t0);
    t0 = Clock::now();
    const BvhImage image = build_bvh_image(scene);
    const double build_s = seconds_since(t0);
    const BvhStats& bs = image.stats;
    if (!a.quiet)
        std::cout << "scene " << scene.name << ": " << scene.meshes.size() << " meshes, " << scene.primitive_count()
                  << " primitives, " << scene.instances.size() << " instances (" << (scene.two_level() ? "two-level" : "single-level")
                  << " BVH), loaded in " << load_s << " s\n"
                  << "BVH image: " << bs.image_bytes << " bytes, " << bs.internal_nodes << " internal nodes, "
                  << bs.triangle_leaves << " triangle + " << bs.procedural_leaves << " procedural + " << bs.instance_leaves
                  << " instance leaves, depth " << bs.depth << ", built in " << build_s << " s\n";

    std::vector<RayFileEntry> ray_entries;
    std::unique_ptr<Workload> workload;
    WorkloadParams params{a.width, a.height, a.spp, a.bounces, a.seed};
    if (kind == WorkloadKind::RayFile) {
        ray_entries = read_ray_file(a.rays);
        size_t warned = 0;
        for (const RayFileEntry& e : ray_entries)
            if (!e.valid && warned++ < 5) std::cerr << "warning: " << a.rays << ":" << e.line << ": " << e.problem << " (reported as a miss)\n";
        if (warned > 5) std::cerr << "warning: " << warned << " invalid rays in all\n";
        workload = make_ray_file_workload(ray_entries);
    } else {
        workload = make_scene_workload(kind, scene, params);
    }

    std::unique_ptr<EmbreeReference> reference;
    if (a.verify) reference = std::make_unique<EmbreeReference>(scene);
    nlohmann::ordered_json j;
    j["scene"] = scene.name;
    j["workload"] = kind == WorkloadKind::RayFile ? "rays" : a.workload;
    j["fidelity"] = a.fidelity;
    j["traversal"] = a.traversal;
    if (kind != WorkloadKind::RayFile) j["params"] = {{"width", a.width}, {"height", a.height}, {"spp", a.spp}, {"bounces", a.bounces}, {"seed", a.seed}};

    std::vector<TracedRay> rays;
    VerifyCounts verify;
    std::vector<uint64_t> mismatch_rays;
    double speed_ours = 0, speed_embree = 0;
    TimingResult timing_result;
    t0 = Clock::now();
    if (!timing) {
        FunctionalOptions fo;
        fo.order = order;
        std::unique_ptr<Treelets> treelets;
        if (order == TraversalOrder::Treelet) {
            treelets = std::make_unique<Treelets>(form_treelets(image, PrefetchConfig{}.treelet_budget));
            fo.treelets = treelets.get();
        }
        fo.progress = !a.quiet;
        fo.measure_speed = a.verify;
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
        to.fidelity = a.fidelity == "at" ? Fidelity::AT : Fidelity::LT;
        to.order = order;
        to.progress = !a.quiet;
        to.vcd = a.vcd;
        to.sample_rate = a.sample;
        to.sample_seed = a.sample_seed.value_or(a.seed);
        // A sampled run traces the whole frame functionally first, with fresh instances of the
        // workload (the run's own one accumulates the simulated image).
        if (a.sample < 1.0) {
            to.sample_workload = [&] {
                return kind == WorkloadKind::RayFile ? make_ray_file_workload(ray_entries) : make_scene_workload(kind, scene, params);
            };
            to.sample_threads = a.threads;
        }
        if (to.vcd.size() > 4 && to.vcd.compare(to.vcd.size() - 4, 4, ".vcd") == 0) to.vcd.resize(to.vcd.size() - 4);
        if (!a.trace_warp.empty()) std::tie(to.trace_sm, to.trace_warp) = parse_trace_warp(a.trace_warp, hw);
        to.keep_rays = !a.hits.empty() || a.verify;  // else memory for the rays in flight only
        if (interval) {
            try {
                timing_result = run_interval(hw, image, *workload, to);
            } catch (const std::invalid_argument& e) {
                throw InputError(e.what());
            }
        } else {
            GpuPlatform platform(hw, image, *workload, to);
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
        j["config"] = config.to_json();
    }
    if (a.verify) {
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
    }
    if (timing && timing_result.stuck) {
        std::cerr << "error: " << timing_result.stuck_report << "\n";
        return 1;
    }

    // Write every output only after the whole run succeeded.
    if (!a.hits.empty()) write_file_atomic(a.hits, hits_csv(rays));
    if (!a.image.empty()) write_png_atomic(a.image, a.width, a.height, workload->image());
    if (!a.stats.empty()) write_file_atomic(a.stats, j.dump(2) + "\n");

    if (!a.quiet) {
        std::cout << "rays " << n_rays << " (" << invalid << " invalid), hits " << hits << ", nodes/ray "
                  << j["nodes_per_ray"].get<double>() << " (max " << j["max_nodes_per_ray"] << "), " << a.traversal << ", "
                  << a.fidelity << ", " << run_s << " s\n";
        if (timing) {
            const auto& t = timing_result.stats;
            if (t.contains("sampling"))
                std::cout << "sampled " << t["sampling"]["warps_simulated"] << " of " << t["sampling"]["warps_total"]
                          << " warps: " << timing_result.cycles_simulated << " cycles simulated, frame estimate "
                          << timing_result.cycles << " (95 % interval " << uint64_t(t["sampling"]["cycles_ci95"][0].get<double>())
                          << ".." << uint64_t(t["sampling"]["cycles_ci95"][1].get<double>()) << ")\n";
            std::cout << "cycles " << timing_result.cycles << ", L1 miss rate " << t["l1"]["demand"]["miss_rate"].get<double>()
                      << ", L2 miss rate " << t["l2"]["demand"]["miss_rate"].get<double>() << ", DRAM reads "
                      << t["dram"]["reads"] << " (bandwidth " << t["dram"]["bandwidth_utilisation"].get<double>() * 100
                      << " %), " << uint64_t(j["simulation_rate"]["rays_per_s"].get<double>()) << " rays/s simulated\n";
        }
        if (a.verify) {
            std::cout << "verify against Embree (robust): " << verify.rays << " rays, " << verify.mismatches() << " mismatches";
            for (size_t c = 1; c + 1 < size_t(Agreement::Count); ++c)
                if (verify.by_class[c]) std::cout << ", " << agreement_name(Agreement(c)) << " " << verify.by_class[c];
            if (verify.skipped) std::cout << ", skipped " << verify.skipped;
            std::cout << "\n";
            if (!timing)
                std::cout << "speed: ours " << uint64_t(j["speed"]["ours_rays_per_s"].get<double>()) << " rays/s, Embree "
                          << uint64_t(j["speed"]["embree_rays_per_s"].get<double>()) << " rays/s (Embree is "
                          << j["speed"]["embree_over_ours"].get<double>() << "x faster)\n";
        }
    }
    for (const std::string& f : timing_result.invariant_failures) std::cerr << "error: invariant violated: " << f << "\n";
    if (!timing_result.invariant_failures.empty()) return 1;
    if (a.verify && verify.mismatches() > 0) {
        std::cerr << "error: " << verify.mismatches() << " rays disagree with Embree outside the documented classes (first: ray "
                  << mismatch_rays.front() << ")\n";
        return 1;
    }
    return 0;
}

}  // namespace

int sc_main(int argc, char** argv) {
    sc_core::sc_set_time_resolution(1, sc_core::SC_FS);
    Args a;
    po::options_description desc(
        "rtsim: ray-tracing unit model\n"
        "usage: rtsim --scene NAME|PATH [--assets DIR] [--workload primary|pt|ao|sh] [--rays FILE] [--hits FILE]\n"
        "             [--width W --height H --spp N --bounces B --seed S] [--traversal dfs|bfs|treelet]\n"
        "             [--fidelity functional|at|lt|interval] [--config NAME|FILE] [--set KEY=VALUE]... [--quantum CYCLES]\n"
        "             [--prefetcher none|ttp|park|treelet|perfect-up|perfect-down] [--sample RATE [--sample-seed S]]\n"
        "             [--stats FILE.json] [--image FILE.png] [--vcd FILE] [--trace-warp SM:WARP] [--verify] [--quiet]\n"
        "exit status: 0 ok, 1 a check failed (--verify mismatches), 2 bad input, 3 internal error\noptions");
    desc.add_options()
        ("help,h", "this help")
        ("scene", po::value(&a.scene)->default_value(a.scene), "wknd, cornell, ship, bunny, ref, bath, sprng, a mesh file or a folder")
        ("assets", po::value(&a.assets), "asset folder of a LumiBench scene (e.g. ../shared/scenes/bunny)")
        ("workload", po::value(&a.workload)->default_value(a.workload), "primary, pt (path tracing), ao (ambient occlusion), sh (shadow)")
        ("rays", po::value(&a.rays), "ray file (replaces --workload)")
        ("hits", po::value(&a.hits), "write hits CSV: ray,hit,t,geom,prim")
        ("width", po::value(&a.width)->default_value(a.width), "image width")
        ("height", po::value(&a.height)->default_value(a.height), "image height")
        ("spp", po::value(&a.spp)->default_value(a.spp), "samples per pixel")
        ("bounces", po::value(&a.bounces)->default_value(a.bounces), "path tracing: at most this many rays per path")
        ("seed", po::value(&a.seed)->default_value(a.seed), "random seed")
        ("traversal", po::value(&a.traversal)->default_value(a.traversal), "dfs, bfs or treelet")
        ("fidelity", po::value(&a.fidelity)->default_value(a.fidelity), "functional, at (reference timing), lt (loosely timed) or interval (fastest timing, one event per node fetch)")
        ("config", po::value(&a.config)->default_value(a.config), "hardware preset (mobile, desktop) or JSON file")
        ("set", po::value(&a.sets)->composing(), "override one configuration key, e.g. --set l1.size_kb=64 (repeatable)")
        ("quantum", po::value(&a.quantum), "LT quantum in core cycles (same as --set sim.quantum=N)")
        ("prefetcher", po::value(&a.prefetcher), "none, ttp, park, treelet, perfect-up, perfect-down (same as --set prefetch.kind=...; interval: none, ttp)")
        ("sample", po::value(&a.sample), "simulate this share (0..1] of the frame's warps, stratified, and extrapolate (at, lt, interval)")
        ("sample-seed", po::value<uint64_t>()->notifier([&a](uint64_t v) { a.sample_seed = v; }),
         "which clusters --sample draws (default: --seed, which also seeds the rays)")
        ("threads", po::value(&a.threads)->default_value(a.threads),
         "threads for --sample's functional pre-pass (the simulation itself runs on one; results do not depend on it)")
        ("vcd", po::value(&a.vcd), "write waveforms to this VCD file (at, lt)")
        ("trace-warp", po::value(&a.trace_warp), "with --vcd: trace each thread's stack depth of warp-buffer slot WARP of SM")
        ("stats", po::value(&a.stats), "write statistics JSON")
        ("image", po::value(&a.image), "write the rendered frame as PNG")
        ("verify", po::bool_switch(&a.verify), "compare every ray with Embree (robust mode); exit 1 on mismatches")
        ("flatten", po::bool_switch(&a.flatten), "scenes whose meshes are all placed as they are: one single-level BVH instead of TLAS + BLAS")
        ("quiet,q", po::bool_switch(&a.quiet), "no progress or summary");
    try {
        po::variables_map vm;
        po::store(po::command_line_parser(argc, argv).options(desc).run(), vm);
        if (vm.count("help")) {
            std::cout << desc << "\n";
            return 0;
        }
        po::notify(vm);
    } catch (const po::error& e) {
        std::cerr << "rtsim: " << e.what() << " (see rtsim --help)\n";
        return 2;
    }
    try {
        return run(a);
    } catch (const InputError& e) {
        std::cerr << "rtsim: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "rtsim: internal error: " << e.what() << "\n";
        return 3;
    }
}

// Our own main: silence SystemC's banner (stdout carries the run summary), then SystemC's
// elaboration calls sc_main.
int main(int argc, char** argv) {
    setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0);
    return sc_core::sc_elab_and_sim(argc, argv);
}
