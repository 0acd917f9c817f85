#include "run_record.h"

#include <set>

#include "build_info.h"
#include "sample_segments.h"
#include "timing_stats.h"

namespace rtu {

const char* traversal_name(TraversalOrder o) {
    switch (o) {
        case TraversalOrder::DFS: return "dfs";
        case TraversalOrder::BFS: return "bfs";
        case TraversalOrder::Treelet: return "treelet";
    }
    return "?";
}

namespace {

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
    c.value("fidelity_cycles", e.check->fidelity_cycles, "cycles", "the sample's cycles in this run's fidelity (its makespan: not what the check states)");
    c.value("at_cycles", e.check->at_cycles, "cycles", "the sample's cycles in AT");
    c.value("difference", e.check->difference(), "ratio",
            "the frame's RT-unit residence in this fidelity / in AT - 1: a ratio estimate over the strata, paired by stratum");
    c.value("difference_half_width", e.check->residence.half_width, "ratio", "its 95 % half-width (Student's t over collapsed stratum pairs)");
    c.value("variance_pairs", e.check->residence.pairs, "pairs", "collapsed stratum pairs behind the half-width");
    c.value("fidelity_s", e.check->fidelity_s, "s", "the fidelity's simulation time");
    c.value("at_s", e.check->at_s, "s", "AT's simulation time");
    c.value("wall_s", e.check->wall_s, "s", "the whole check: both child runs from start to end (scene, BVH and one pre-pass, shared through a plan)");
}

}  // namespace

void write_stats(StatsOut& out, const RunRecord& r) {
    {
        StatsOut p = out.child("provenance", "what made this file, to reproduce it from the file alone (with config)");
        p.value("version", std::string(rtunit_version()), "", "rtsim's version");
        p.value("commit", std::string(rtunit_commit()), "", "the git commit rtsim was built from (-dirty: with changes to it; unknown: not built from a git checkout)");
        p.json()["command_line"] = r.command_line ? nlohmann::ordered_json(*r.command_line) : nlohmann::ordered_json::array();
        p.note("command_line", "", "the program and its arguments, as given");
    }
    out.value("scene", r.scene, "", "the scene's name");
    out.value("workload", r.workload, "", "primary, pt, ao, sh, or rays (a ray file)");
    out.value("fidelity", fidelity_name(r.fidelity), "", "functional, at, lt or interval");
    out.value("traversal", traversal_name(r.order), "", "dfs, bfs or treelet");
    out.value("interrupted", r.interrupted, "",
              "stopped by SIGINT, SIGTERM or SIGHUP before the end, or a snapshot: every figure is of what was simulated so far, and "
              "cycles are the cycles simulated, not the frame's (docs/robustness.md)");
    out.value("snapshot", r.snapshot, "",
              "written on SIGUSR1 while the run went on (its end replaces this file with the final statistics); the threads' cycles "
              "count up to each thread's last change of status");
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
        StatsOut b = out.child("bvh", "the BVH image (model/node_format.h)");
        b.value("two_level", r.two_level, "", "a TLAS over instanced BLASes (false: one single-level BVH)");
        b.value("image_bytes", r.bvh.image_bytes, "bytes", "the BVH image in simulated memory");
        b.value("internal_nodes", r.bvh.internal_nodes, "nodes", "64 B internal nodes");
        b.value("triangle_leaves", r.bvh.triangle_leaves, "nodes", "64 B triangle leaves");
        b.value("procedural_leaves", r.bvh.procedural_leaves, "nodes", "64 B procedural (sphere) leaves");
        b.value("instance_leaves", r.bvh.instance_leaves, "nodes", "128 B instance leaves");
        b.value("blas", r.bvh.blas_count, "BVHs", "bottom-level BVHs");
        b.value("depth", r.bvh.depth, "nodes", "nodes on the longest root-to-leaf path, leaves included (the paper's Table 2)");
        b.value("tlas_depth", r.bvh.tlas_depth, "nodes", "internal levels of the TLAS (0: single-level)");
        b.value("repeats_left_out", r.bvh.repeats_left_out, "faces",
                "faces left out of the BVH as copies of another face beyond its first 8 (workloads/bvh_builder.cpp)");
    }
    {
        StatsOut t = out.child("time_s", "wall-clock time of this run's phases");
        t.value("load", r.load_s, "s", "loading the scene");
        t.value("build", r.build_s, "s", "building the BVH image with Embree");
        t.value("run", r.run_s, "s", "tracing or simulating (the sampling pre-pass included)");
        if (r.timing && r.timing->sampled)
            t.value("prepass", r.timing->prepass_s, "s",
                    "sampled runs, part of run: before the first simulated warp, the frame's functional pre-pass (or reading its plan) "
                    "and tracing the warming fetches; a merge of segments: its own, and the frame's pre-pass its segments' threads made "
                    "before them (each segment's warming is in the segments' time)");
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
        if (t.sampled && !t.interrupted && !r.segment_identity) write_sampling(tm, t.estimate, r.sample_rate, t.cycles, t.cycles_simulated, r.width);
        write_hierarchy(tm, *r.hw, t.counts, t.summary, t.estimate.scale());
        if (r.fidelity != Fidelity::Interval)
            tm.value("payloads_allocated", t.payloads_allocated, "payloads", "TLM payloads the pool made (AT, LT)");
        if (r.segment_identity) write_segment(out, t, r.segment, r.segments, *r.segment_identity);
        StatsOut rate = out.child("simulation_rate", "the simulator's speed");
        rate.value("rays_per_s", r.run_s > 0 ? double(r.rays) / r.run_s : 0.0, "rays / s", "rays over time_s.run");
        rate.value("cycles_per_s", r.run_s > 0 ? double(t.cycles) / r.run_s : 0.0, "cycles / s", "cycles over time_s.run");
    }
    if (r.config) {
        out.json()["config"] = r.config->to_json();
        out.note("config", "", "the effective configuration (platforms/configs/*.json keys; a functional run reads none of them)");
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

}  // namespace rtu
