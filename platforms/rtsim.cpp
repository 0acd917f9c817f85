// rtsim: runs a ray workload over a scene's BVH image on the RT-unit model.
// This is the functional fidelity (issue #2); the timing fidelities plug into the same program.
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "functional_run.h"
#include "model/traversal.h"
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
    std::string stats, image;
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1;
    bool verify = false, quiet = false;
};

std::string hits_csv(const FunctionalResult& r) {
    std::string out = "ray,hit,t,geom,prim\n";
    char line[96];
    for (size_t i = 0; i < r.hits.size(); ++i) {
        const Hit& h = r.hits[i];
        if (h.hit)
            std::snprintf(line, sizeof line, "%zu,1,%.9g,%u,%u\n", i, double(h.t), h.geom, h.prim);
        else
            std::snprintf(line, sizeof line, "%zu,0,-1,-1,-1\n", i);
        out += line;
    }
    return out;
}

int run(const Args& a) {
    if (a.fidelity != "functional") {
        if (a.fidelity == "at" || a.fidelity == "lt")
            throw InputError("--fidelity " + a.fidelity + ": the timing model is not built yet; use --fidelity functional");
        throw InputError("--fidelity '" + a.fidelity + "': allowed are functional (at and lt follow)");
    }
    TraversalOrder order;
    if (a.traversal == "dfs") order = TraversalOrder::DFS;
    else if (a.traversal == "bfs") order = TraversalOrder::BFS;
    else throw InputError("--traversal '" + a.traversal + "': allowed are dfs, bfs");
    const WorkloadKind kind = a.rays.empty() ? parse_workload(a.workload) : WorkloadKind::RayFile;
    if (!a.rays.empty() && !a.image.empty()) throw InputError("--image needs a scene workload, not --rays");

    auto t0 = Clock::now();
    const Scene scene = load_scene(a.scene, a.assets);
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
    FunctionalOptions fo;
    fo.order = order;
    fo.progress = !a.quiet;
    fo.measure_speed = a.verify;
    t0 = Clock::now();
    const FunctionalResult r = run_functional(scene, image, *workload, fo, reference.get());
    const double run_s = seconds_since(t0);
    const uint64_t valid_rays = r.rays.size() - r.invalid_rays;

    nlohmann::ordered_json j;
    j["scene"] = scene.name;
    j["workload"] = kind == WorkloadKind::RayFile ? "rays" : a.workload;
    j["fidelity"] = a.fidelity;
    j["traversal"] = a.traversal;
    if (kind != WorkloadKind::RayFile) j["params"] = {{"width", a.width}, {"height", a.height}, {"spp", a.spp}, {"bounces", a.bounces}, {"seed", a.seed}};
    j["rays"] = r.rays.size();
    j["invalid_rays"] = r.invalid_rays;
    j["hits"] = r.hit_count;
    j["nodes_visited"] = r.nodes_visited;
    j["nodes_per_ray"] = valid_rays ? double(r.nodes_visited) / double(valid_rays) : 0.0;
    j["max_nodes_per_ray"] = r.max_nodes_per_ray;
    j["bvh"] = {{"two_level", scene.two_level()}, {"image_bytes", bs.image_bytes}, {"internal_nodes", bs.internal_nodes},
                {"triangle_leaves", bs.triangle_leaves}, {"procedural_leaves", bs.procedural_leaves},
                {"instance_leaves", bs.instance_leaves}, {"blas", bs.blas_count}, {"depth", bs.depth}, {"tlas_depth", bs.tlas_depth}};
    j["time_s"] = {{"load", load_s}, {"build", build_s}, {"run", run_s}};
    if (a.verify) {
        nlohmann::ordered_json classes;
        for (size_t c = 0; c < size_t(Agreement::Count); ++c) classes[agreement_name(Agreement(c))] = r.verify.by_class[c];
        j["verify"] = {{"rays", r.verify.rays}, {"skipped", r.verify.skipped}, {"mismatches", r.verify.mismatches()},
                       {"classes", classes}, {"mismatch_rays", r.mismatch_rays}};
        j["speed"] = {{"rays", r.rays.size()},
                      {"ours_s", r.trace_seconds},
                      {"embree_s", r.embree_seconds},
                      {"ours_rays_per_s", r.trace_seconds > 0 ? double(r.rays.size()) / r.trace_seconds : 0.0},
                      {"embree_rays_per_s", r.embree_seconds > 0 ? double(r.rays.size()) / r.embree_seconds : 0.0},
                      {"embree_over_ours", r.trace_seconds > 0 && r.embree_seconds > 0 ? r.trace_seconds / r.embree_seconds : 0.0}};
    }

    // Write every output only after the whole run succeeded.
    if (!a.hits.empty()) write_file_atomic(a.hits, hits_csv(r));
    if (!a.image.empty()) write_png_atomic(a.image, a.width, a.height, workload->image());
    if (!a.stats.empty()) write_file_atomic(a.stats, j.dump(2) + "\n");

    if (!a.quiet) {
        std::cout << "rays " << r.rays.size() << " (" << r.invalid_rays << " invalid), hits " << r.hit_count << ", nodes/ray "
                  << j["nodes_per_ray"].get<double>() << " (max " << r.max_nodes_per_ray << "), " << a.traversal << ", " << run_s << " s\n";
        if (a.verify) {
            std::cout << "verify against Embree (robust): " << r.verify.rays << " rays, " << r.verify.mismatches() << " mismatches";
            for (size_t c = 1; c + 1 < size_t(Agreement::Count); ++c)
                if (r.verify.by_class[c]) std::cout << ", " << agreement_name(Agreement(c)) << " " << r.verify.by_class[c];
            if (r.verify.skipped) std::cout << ", skipped " << r.verify.skipped;
            std::cout << "\nspeed: ours " << uint64_t(j["speed"]["ours_rays_per_s"].get<double>()) << " rays/s, Embree "
                      << uint64_t(j["speed"]["embree_rays_per_s"].get<double>()) << " rays/s (Embree is "
                      << j["speed"]["embree_over_ours"].get<double>() << "x faster)\n";
        }
    }
    if (a.verify && r.verify.mismatches() > 0) {
        std::cerr << "error: " << r.verify.mismatches() << " rays disagree with Embree outside the documented classes (first: ray "
                  << r.mismatch_rays.front() << ")\n";
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Args a;
    po::options_description desc(
        "rtsim: ray-tracing unit model\n"
        "usage: rtsim --scene NAME|PATH [--assets DIR] [--workload primary|pt|ao|sh] [--rays FILE] [--hits FILE]\n"
        "             [--width W --height H --spp N --bounces B --seed S] [--traversal dfs|bfs]\n"
        "             [--fidelity functional] [--stats FILE.json] [--image FILE.png] [--verify]\n"
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
        ("traversal", po::value(&a.traversal)->default_value(a.traversal), "dfs or bfs")
        ("fidelity", po::value(&a.fidelity)->default_value(a.fidelity), "functional")
        ("stats", po::value(&a.stats), "write statistics JSON")
        ("image", po::value(&a.image), "write the rendered frame as PNG")
        ("verify", po::bool_switch(&a.verify), "compare every ray with Embree (robust mode); exit 1 on mismatches")
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
