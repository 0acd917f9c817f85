#include "command_line.h"

#include <sched.h>

#include <filesystem>
#include <iostream>
#include <tuple>

#include <boost/program_options.hpp>

#include "build_info.h"
#include "child_runs.h"
#include "fidelity_run.h"
#include "model/prefetcher.h"
#include "output.h"
#include "sampling/plan.h"
#include "workloads/input_error.h"

namespace po = boost::program_options;

namespace rtu {

unsigned usable_cores() {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
    return std::max(1u, std::thread::hardware_concurrency());
}
namespace {

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

// A split sample's segments, for child runs: the frame's options and the sample's.
std::vector<std::string> segment_args(const Args& a) {
    std::vector<std::string> base = frame_args(a);
    base.insert(base.end(), {"--fidelity", a.fidelity, "--sample", exact(a.sample), "--sample-seed", std::to_string(a.sample_seed.value_or(a.seed)),
                             "--sample-segments", std::to_string(a.sample_segments)});
    if (a.sample_unchecked) base.push_back("--sample-unchecked");
    if (a.quantum) base.insert(base.end(), {"--quantum", std::to_string(*a.quantum)});
    if (!a.sample_plan.empty()) base.insert(base.end(), {"--sample-plan", a.sample_plan});  // the first segment writes it, the rest read it
    return base;
}

// --vcd FILE names the waveforms FILE, or FILE.vcd if it does not end so; SystemC takes the name
// without the extension.
std::string vcd_base(const std::string& vcd) {
    return vcd.size() > 4 && vcd.compare(vcd.size() - 4, 4, ".vcd") == 0 ? vcd.substr(0, vcd.size() - 4) : vcd;
}

// Two outputs on one file: the one written last would replace the other (the hits lost under
// the statistics, say). Compared as the files they are (symlinks and ".." resolved as far as the
// path exists); the VCD as the file it becomes (FILE.vcd).
void check_distinct_outputs(const Args& a) {
    namespace fs = std::filesystem;
    const std::string vcd = a.vcd.empty() ? std::string() : vcd_base(a.vcd) + ".vcd";
    const std::string plan = a.sample_plan.empty() || fs::is_directory(a.sample_plan) ? std::string() : a.sample_plan;
    std::vector<std::pair<fs::path, std::string>> seen;
    for (const auto& [option, path] : {std::pair<const char*, std::string>{"--stats", a.stats}, {"--image", a.image}, {"--hits", a.hits},
                                       {"--vcd", vcd}, {"--timeline", a.timeline}, {"--dump-bvh", a.dump_bvh}, {"--dump-rays", a.dump_rays},
                                       {"--dump-hits", a.dump_hits}, {"--sample-plan", plan}}) {
        if (path.empty()) continue;
        if (is_special_file(path)) continue;  // /dev/null twice is fine
        std::error_code ec;
        fs::path file = fs::weakly_canonical(fs::absolute(path), ec);
        if (ec) file = fs::absolute(path).lexically_normal();
        for (const auto& [other, other_option] : seen)
            if (other == file)
                throw InputError(std::string(option) + " " + path + ": also named by " + other_option + "; give each output its own file");
        seen.emplace_back(file, option);
    }
}

}  // namespace

// The frame, workload and configuration options of the run, for a child rtsim.
std::vector<std::string> frame_args(const Args& a) {
    std::vector<std::string> base = {"--scene", a.scene, "--workload", a.workload, "--width", std::to_string(a.width), "--height",
                                     std::to_string(a.height), "--spp", std::to_string(a.spp), "--bounces", std::to_string(a.bounces),
                                     "--seed", std::to_string(a.seed), "--traversal", a.traversal, "--config", a.config,
                                     "--threads", std::to_string(a.threads), "--quiet"};
    if (!a.assets.empty()) base.insert(base.end(), {"--assets", a.assets});
    if (!a.rays.empty()) base.insert(base.end(), {"--rays", a.rays});
    for (const std::string& set : a.sets) base.insert(base.end(), {"--set", set});
    if (!a.prefetcher.empty()) base.insert(base.end(), {"--prefetcher", a.prefetcher});
    if (a.flatten) base.push_back("--flatten");
    return base;
}

// The run's specification from the command line; every check that needs no scene comes first.
RunSpec spec_of(const Args& a, const std::atomic<int>* stop) {
    RunSpec spec;
    try {
        spec.run.fidelity = parse_fidelity(a.fidelity, "--fidelity");
    } catch (const std::invalid_argument& e) {
        throw InputError(e.what());
    }
    const bool timing = is_timing(spec.run.fidelity), interval = spec.run.fidelity == Fidelity::Interval;
    if (a.traversal == "dfs") spec.run.order = TraversalOrder::DFS;
    else if (a.traversal == "bfs") spec.run.order = TraversalOrder::BFS;
    else if (a.traversal == "treelet") spec.run.order = TraversalOrder::Treelet;
    else throw InputError("--traversal '" + a.traversal + "': allowed are dfs, bfs, treelet");
    if (a.rays.empty()) parse_workload(a.workload);  // throws InputError
    if (!a.rays.empty() && !a.image.empty()) throw InputError("--image needs a scene workload, not --rays");
    if (!a.stray.empty()) throw InputError("unexpected argument '" + a.stray.front() + "' (every option starts with --; see rtsim --help)");
    if (!timing && (!a.vcd.empty() || !a.timeline.empty() || !a.trace_warp.empty() || !a.sets.empty() || a.quantum || !a.prefetcher.empty() ||
                    a.sample != 1.0))
        throw InputError("--vcd, --timeline, --trace-warp, --set, --quantum, --prefetcher and --sample need --fidelity at, lt or interval");
    if (interval && (!a.vcd.empty() || !a.timeline.empty() || !a.trace_warp.empty() || a.quantum))
        throw InputError("--vcd, --timeline, --trace-warp and --quantum need --fidelity at or lt (the interval fidelity has no "
                         "SystemC signals, cycle-by-cycle RT unit or quantum)");
    if (a.quantum && spec.run.fidelity != Fidelity::LT) throw InputError("--quantum is the loosely timed model's: it needs --fidelity lt");
    if (a.quantum && *a.quantum == 0) throw InputError("--quantum 0: the LT quantum must be at least 1 core cycle");
    if (!a.trace_warp.empty() && a.vcd.empty() && a.timeline.empty())
        throw InputError("--trace-warp picks the warp-buffer slot traced: it needs --vcd FILE or --timeline FILE");
    if (a.sample_width) {
        if (!timing) throw InputError("--sample-width needs --fidelity at, lt or interval");
        if (!(*a.sample_width > 0 && *a.sample_width < 100))
            throw InputError("--sample-width " + exact(*a.sample_width) + ": the 95 % half-width asked is a percentage of the frame's cycles, above 0 and below 100");
        if (a.sample != 1.0 || a.sample_unchecked || a.sample_segments > 1 || a.check_error)
            throw InputError("--sample-width chooses the sample's rate itself: not with --sample, --sample-unchecked, --sample-segments or --check-error");
    }
    const bool sampled = a.sample != 1.0 || a.sample_width;
    if (a.sample_seed && !sampled && !a.check_error) throw InputError("--sample-seed needs --sample RATE below 1 (or --sample-width W, or --check-error N)");
    if (a.sample_unchecked && a.sample == 1.0) throw InputError("--sample-unchecked needs --sample RATE below 1");
    if (!a.sample_plan.empty() && !sampled) throw InputError("--sample-plan keeps a sampled run's pre-pass: it needs --sample RATE below 1 (or --sample-width W)");
    if (a.check_error && spec.run.fidelity != Fidelity::LT && spec.run.fidelity != Fidelity::Interval)
        throw InputError("--check-error compares a fast fidelity with AT: it needs --fidelity lt or interval (AT is the reference)");
    if (a.check_error_any_cost && !a.check_error) throw InputError("--check-error-any-cost needs --check-error N");
    if (a.check_error && a.check_error < 4)
        throw InputError("--check-error " + std::to_string(a.check_error) +
                         ": the check pairs its drawn clusters' strata two by two for its interval; it needs N of at least 4 (2 pairs)");
    if (a.sample_segments < 1 || a.sample_segments > 4096)
        throw InputError("--sample-segments " + std::to_string(a.sample_segments) + ": a sample splits into 1 to 4096 segments");
    if (a.sample_segments > 1 && a.sample == 1.0)
        throw InputError("--sample-segments splits a sample: it needs --sample RATE below 1 (a whole frame is one continuous run)");
    if ((a.segment || !a.merge_segments.empty()) && a.sample_segments == 1)
        throw InputError("--segment and --merge-segments need --sample-segments K (2 or more)");
    if (a.segment && *a.segment >= uint64_t(a.sample_segments))
        throw InputError("--segment " + std::to_string(*a.segment) + ": the segments are numbered 0.." + std::to_string(a.sample_segments - 1));
    if (a.segment && !a.merge_segments.empty()) throw InputError("--segment simulates one segment, --merge-segments merges them: give one of the two");
    if (a.sample_segments > 1 && (!a.hits.empty() || !a.image.empty() || !a.vcd.empty() || !a.timeline.empty() || a.check_error || a.verify))
        throw InputError("--hits, --image, --vcd, --timeline, --check-error and --verify need one continuous run: not with --sample-segments "
                         "(each segment simulates some of the rays)");
    if (!a.merge_segments.empty() && a.merge_segments.size() != size_t(a.sample_segments))
        throw InputError("--merge-segments: " + std::to_string(a.merge_segments.size()) + " files for --sample-segments " +
                         std::to_string(a.sample_segments) + ": give each segment's statistics once");
    if (a.threads < 1 || a.threads > 4096)
        throw InputError("--threads " + std::to_string(a.threads) + ": allowed are 1 to 4096 threads");
    // Outputs are checked before anything runs: a bad path should not wait for the simulation.
    for (const auto& [option, path] : {std::pair<const char*, std::string>{"--stats", a.stats}, {"--image", a.image},
                                       {"--hits", a.hits}, {"--vcd", a.vcd}, {"--timeline", a.timeline}, {"--dump-bvh", a.dump_bvh},
                                       {"--dump-rays", a.dump_rays}, {"--dump-hits", a.dump_hits}})
        if (!path.empty()) check_writable_folder(option, path);
    // A plan's file, or given a folder a file in it (plan_file; the frame's name is not known yet).
    if (!a.sample_plan.empty()) check_writable_folder("--sample-plan", plan_file(a.sample_plan, ""));
    check_distinct_outputs(a);
    if (!(a.sample > 0.0 && a.sample <= 1.0))
        throw InputError("--sample " + std::to_string(a.sample) + ": the share of the frame to simulate must be in (0, 1]");
    // Configuration first, whatever the fidelity: a bad key should not wait for a scene to load,
    // and a functional run's statistics record the configuration too.
    {
        try {
            spec.config = Config::load(a.config);
            for (const auto& s : a.sets) spec.config.set(s);
            if (a.quantum) spec.config.set("sim.quantum=" + std::to_string(*a.quantum));
            if (!a.prefetcher.empty()) spec.config.set("prefetch.kind=" + a.prefetcher);
            spec.hw = spec.config.resolve();
            check_prefetcher(spec.hw.prefetch, spec.run.order);
        } catch (const ConfigError& e) {
            throw InputError(e.what());
        } catch (const std::invalid_argument& e) {
            throw InputError(e.what());
        }
    }
    spec.scene = a.scene;
    spec.assets = a.assets;
    spec.flatten = a.flatten;
    spec.workload = a.workload;
    spec.rays = a.rays;
    spec.params = WorkloadParams{a.width, a.height, a.spp, a.bounces, a.seed};
    TimingOptions& run = spec.run;
    run.sample_rate = a.sample;
    run.sample_seed = a.sample_seed.value_or(a.seed);
    run.sample_unchecked = a.sample_unchecked;
    run.sample_segments = uint32_t(a.sample_segments);
    if (a.segment) run.sample_segment = uint32_t(*a.segment);
    run.sample_plan = a.sample_plan;
    run.threads = unsigned(a.threads);
    run.vcd = vcd_base(a.vcd);
    if (!a.trace_warp.empty()) std::tie(run.trace_sm, run.trace_warp) = parse_trace_warp(a.trace_warp, spec.hw);
    run.timeline = !a.timeline.empty();
    if (run.timeline && run.trace_sm >= 0) run.timeline_sm = uint32_t(run.trace_sm), run.timeline_slot = uint32_t(run.trace_warp);
    // With --trace-warp the VCD's per-thread signals follow the slot too; the timeline alone
    // does not add them.
    if (a.vcd.empty()) run.trace_sm = run.trace_warp = -1;
    spec.timeline = a.timeline;
    run.keep_rays = !a.hits.empty() || a.verify;  // else memory for the rays in flight only
    run.progress = !a.quiet;
    run.stop.flag = stop;
    spec.merge_segments = a.merge_segments;
    spec.verify = a.verify;
    spec.dump_bvh = a.dump_bvh;
    spec.dump_rays = a.dump_rays;
    spec.dump_hits = a.dump_hits;
    spec.check_error = a.check_error;
    spec.command_line = a.command_line;
    // Child runs of rtsim itself: the segments of a split sample, up to --threads at once, and the
    // check's two runs.
    if (a.sample_segments > 1 && !a.segment && a.merge_segments.empty())
        spec.run_segments = [&a, stop = run.stop] {
            // The plan's file, when its name is known before the run (not a folder's plan-HASH.bin).
            const bool folder = a.sample_plan.empty() || a.sample_plan.back() == '/' || std::filesystem::is_directory(a.sample_plan);
            return run_segment_children(segment_args(a), uint32_t(a.sample_segments), unsigned(a.threads), folder ? std::string() : a.sample_plan,
                                        stop, a.quiet);
        };
    spec.sample_width = a.sample_width.value_or(0) / 100.0;
    if (a.sample_width)
        spec.run_pilot = [&a](double rate) {
            return run_width_pilot(frame_args(a), a.fidelity, a.quantum, rate, a.sample_seed.value_or(a.seed), a.sample_plan, a.quiet);
        };
    if (a.check_error)
        spec.run_check = [&a](double rate, double run_s) {
            return run_error_check(frame_args(a), a.fidelity, a.quantum, rate, a.sample_seed.value_or(a.seed),
                                   a.check_error_any_cost ? 0.0 : run_s, a.quiet);
        };
    return spec;
}

std::optional<int> parse_command_line(int argc, char** argv, Args& a) {
    // Every option is in the usage lines (a test checks it against the option table).
    const std::string usage =
        "rtsim: ray-tracing unit model\n"
        "usage: rtsim --scene NAME|PATH [--assets DIR] [--workload primary|pt|ao|sh] [--rays FILE] [--hits FILE]\n"
        "             [--width W --height H --spp N --bounces B --seed S] [--traversal dfs|bfs|treelet] [--flatten]\n"
        "             [--fidelity functional|at|lt|interval] [--config NAME|FILE] [--set KEY=VALUE]... [--quantum CYCLES]\n"
        "             [--prefetcher none|ttp|park|treelet|perfect-up|perfect-down]\n"
        "             [--sample RATE [--sample-seed S] [--sample-unchecked]\n"
        "              [--sample-plan FILE] [--sample-segments K [--segment I | --merge-segments FILE...]]] [--check-error N [--sample-seed S] [--check-error-any-cost]]\n"
        "             [--sample-width W [--sample-seed S] [--sample-plan FILE]]\n"
        "             [--threads N]\n"
        "             [--stats FILE.json] [--image FILE.png] [--vcd FILE] [--timeline FILE.json] [--trace-warp SM:WARP] [--verify] [--quiet]\n"
        "             [--dump-bvh FILE] [--dump-rays FILE] [--dump-hits FILE]\n"
        "       rtsim --stats-schema | --help | --version\n"
        "exit status: 0 ok, 1 a check failed (--verify mismatches), 2 bad input, 3 internal error,\n"
        "             130 / 143 stopped by SIGINT / SIGTERM (statistics so far written, \"interrupted\": true)\n";
    if (argc <= 1) {
        std::cerr << usage << "example: rtsim --scene wknd --fidelity at --prefetcher ttp --stats out.json\n"
                  << "rtsim --help describes every option\n";
        return 2;
    }
    po::options_description desc(usage + "options");
    desc.add_options()
        ("help,h", "this help")
        ("version", "print rtsim's version and the git commit it was built from, and exit")
        ("stats-schema", "print every key --stats can write (key, unit, description; tab-separated) and exit")
        ("scene", po::value(&a.scene)->default_value(a.scene), "wknd, cornell, ship, bunny, ref, bath, sprng, party, a mesh file or a folder")
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
        ("config", po::value(&a.config)->default_value(a.config), "hardware preset (mobile: the paper's Table 2; paper: the TTP authors' MOBILE setup; desktop: their RTX 2060-like setup) or JSON file")
        ("set", po::value(&a.sets)->composing(), "override one configuration key, e.g. --set l1.size_kb=64 (repeatable)")
        ("quantum", po::value<uint64_t>()->notifier([&a](uint64_t v) { a.quantum = v; }), "LT quantum in core cycles (same as --set sim.quantum=N)")
        ("prefetcher", po::value(&a.prefetcher), "none, ttp, park, treelet, perfect-up, perfect-down (same as --set prefetch.kind=...; interval: none, ttp)")
        ("sample", po::value(&a.sample), "simulate this share (0..1] of the frame's warps, stratified, and extrapolate (at, lt, interval)")
        ("sample-seed", po::value<uint64_t>()->notifier([&a](uint64_t v) { a.sample_seed = v; }),
         "which clusters --sample and --check-error draw (default: --seed, which also seeds the rays)")
        ("sample-width", po::value<double>()->notifier([&a](double v) { a.sample_width = v; }),
         "at, lt, interval: sample the frame at the smallest rate whose 95 % interval should be within +-W % of its cycles, "
         "planned from a pilot sample of 10 strata (in AT and LT a child run; a second pilot where the first's model term "
         "might fall with more strata); refused where the sample design's bias bound alone is W or more, where the pilot's "
         "parts that no larger rate is taken to narrow reach W, or where a pilot or the run would sample more than half "
         "the frame (docs/sampling.md, \"A sample of a given width\")")
        ("sample-unchecked", po::bool_switch(&a.sample_unchecked),
         "run a sample too small for a 95 % interval (fewer than 10 strata) and report no interval")
        ("sample-segments", po::value(&a.sample_segments), "simulate the sample as K independent segments and merge them "
         "(docs/sampling.md, \"Segments\"); alone: each segment in a child process, up to --threads at once")
        ("segment", po::value<uint64_t>()->notifier([&a](uint64_t v) { a.segment = v; }),
         "with --sample-segments K: simulate only segment I (0..K-1) and write it for --merge-segments (a cluster's array task)")
        ("sample-plan", po::value(&a.sample_plan), "keep the sampling pre-pass in this file (or, given a folder, in a file of the "
         "frame's own in it): read if it exists (of the same frame, traversal and warp size; any fidelity, preset or sample), "
         "else written; segments and their merge, and the runs of a sweep over configurations, then trace the frame once")
        ("merge-segments", po::value(&a.merge_segments)->multitoken(),
         "with --sample-segments K and the same frame options: merge the K segments' --stats files into the frame's estimate")
        ("threads", po::value(&a.threads)->default_value(a.threads),
         "threads of the functional pass, --verify's checks against Embree and --sample's pre-pass, and --sample-segments' "
         "child runs at once (default: the cores this process may use; the timing fidelities simulate on one; results do not "
         "depend on it)")
        ("check-error", po::value<uint64_t>()->notifier([&a](uint64_t v) {
             if (v == 0) throw po::validation_error(po::validation_error::invalid_option_value, "check-error", "0");
             a.check_error = v;
         }),
         "lt, interval: simulate N randomly drawn clusters (and the first wave) of the frame in this fidelity and in AT, "
         "and report their RT-unit residence's difference, paired by stratum, with its 95 % interval, in the error estimate "
         "(N at least 4; the N + 1 clusters at most a fifth of the frame's; refused after the run where its sample took half "
         "the run's time or more)")
        ("check-error-any-cost", po::bool_switch(&a.check_error_any_cost),
         "run --check-error's check even where its sample took half the run's time or more (it may then cost more than "
         "AT's full run)")
        ("vcd", po::value(&a.vcd), "write waveforms to this VCD file (at, lt)")
        ("trace-warp", po::value(&a.trace_warp), "with --vcd: trace each thread's stack depth of warp-buffer slot WARP of SM; with --timeline: the slot it records (default 0:0)")
        ("timeline", po::value(&a.timeline), "write one warp-buffer slot's threads as Chrome trace events, JSON for Perfetto or chrome://tracing (at, lt)")
        ("stats", po::value(&a.stats), "write statistics JSON")
        ("image", po::value(&a.image), "write the rendered frame as PNG")
        ("verify", po::bool_switch(&a.verify), "compare every ray with Embree (robust mode); exit 1 on mismatches")
        ("dump-bvh", po::value(&a.dump_bvh), "write the BVH image's bytes (an SoC peripheral's input; docs/peripheral.md)")
        ("dump-rays", po::value(&a.dump_rays), "write the workload's first rays (or the ray file's) as 48-byte ray records (rtunit/rtu_regs.h)")
        ("dump-hits", po::value(&a.dump_hits), "write the golden 48-byte hit records of the --dump-rays rays")
        ("flatten", po::bool_switch(&a.flatten), "scenes whose meshes are all placed as they are: one single-level BVH instead of TLAS + BLAS")
        ("quiet,q", po::bool_switch(&a.quiet), "no progress or summary");
    a.command_line.assign(argv, argv + argc);
    try {
        po::variables_map vm;
        const po::parsed_options parsed = po::command_line_parser(argc, argv).options(desc).run();
        po::store(parsed, vm);
        a.stray = po::collect_unrecognized(parsed.options, po::include_positional);
        if (vm.count("help")) {
            std::cout << desc << "\n";
            return 0;
        }
        if (vm.count("version")) {
            std::cout << "rtsim " << rtunit_version() << " (commit " << rtunit_commit() << ")\n";
            return 0;
        }
        if (vm.count("stats-schema")) {
            std::cout << "key\tunit\tdescription\n";
            for (const StatKey& k : stats_schema()) std::cout << k.key << "\t" << k.unit << "\t" << k.what << "\n";
            return 0;
        }
        po::notify(vm);
    } catch (const po::error& e) {
        std::cerr << "rtsim: " << e.what() << " (see rtsim --help)\n";
        return 2;
    }
    return std::nullopt;
}

}  // namespace rtu
