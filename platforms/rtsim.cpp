// rtsim: runs a ray workload over a scene's BVH image on the RT-unit model, at any fidelity.
// It parses its command line into a RunSpec, runs it (platforms/simulation.h) and writes the
// statistics, hits, frame and summary.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cinttypes>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <sstream>
#include <iostream>
#include <optional>
#include <thread>

#include <csignal>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include <systemc>

#include "output.h"
#include "model/prefetcher.h"
#include "sampling/plan.h"
#include "simulation.h"
#include "workloads/input_error.h"
#include "workloads/verify.h"

namespace po = boost::program_options;
using namespace rtu;

namespace {

// SIGINT and SIGTERM request a stop (model/stop_request.h): the run ends at its next clean point
// and writes its statistics so far. The handler is reset by its first signal, so a second one
// ends rtsim at once.
std::atomic<int> stop_signal{0};
extern "C" void on_stop_signal(int sig) { stop_signal.store(sig, std::memory_order_relaxed); }

void install_stop_handlers() {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND | SA_RESTART;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

const char* signal_name(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal"; }

// The shell's convention: 128 + the signal's number (130 for SIGINT, 143 for SIGTERM).
int interrupted_status(int sig) { return 128 + sig; }

struct Args {
    std::string scene = "wknd", assets, workload = "pt", rays, hits, traversal = "dfs", fidelity = "functional";
    std::string stats, image, config = "mobile", vcd, trace_warp, prefetcher;
    std::string dump_bvh, dump_rays, dump_hits;
    std::vector<std::string> sets;
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1;
    std::optional<uint64_t> quantum;  // LT's quantum (given, even as 0, or not)
    double sample = 1.0;
    std::optional<uint64_t> sample_seed;  // which clusters a sampled run simulates (default: --seed)
    bool sample_unchecked = false;
    uint64_t check_error = 0;  // --check-error N
    long long sample_segments = 1;  // --sample-segments K (signed: a negative number is an error, not a wrap)
    std::optional<uint64_t> segment;  // --segment I
    std::vector<std::string> merge_segments;  // --merge-segments FILE...
    std::string sample_plan;  // --sample-plan FILE
    // The sampling pre-pass's threads; read as signed so that a negative number is an error,
    // not a wrap to 4 billion.
    long long threads = std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::string> stray;  // arguments that are no option's
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

// A temporary folder, removed with everything in it when this goes out of scope.
struct TempFolder {
    std::filesystem::path path;
    explicit TempFolder(const char* what) {
        namespace fs = std::filesystem;
        std::string tmpl = (fs::temp_directory_path() / "rtsim-XXXXXX").string();
        if (!mkdtemp(tmpl.data())) throw std::runtime_error(std::string(what) + ": cannot make a temporary folder in " + fs::temp_directory_path().string());
        path = tmpl;
    }
    ~TempFolder() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

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

std::string exact(double v) {
    char r[32];
    std::snprintf(r, sizeof r, "%.17g", v);
    return r;
}

// Runs rtsim itself (SystemC elaborates one platform per process) with `args`, its standard error
// into `err`; throws, with that error text, if it does not exit 0.
void run_child(std::vector<std::string> args, const std::string& err, const std::string& what) {
    args.insert(args.begin(), "rtsim");
    std::vector<char*> argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, "/proc/self/exe", &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw std::runtime_error(what + ": cannot start rtsim: " + std::string(std::strerror(rc)));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::ifstream in(err);
        std::stringstream msg;
        msg << in.rdbuf();
        const std::string text = what + " failed (" + (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : std::string("a signal")) +
                                 "): " + msg.str();
        if (WIFEXITED(status) && WEXITSTATUS(status) == 2) throw InputError(text);
        throw std::runtime_error(text);
    }
}

// --check-error: rtsim itself, run twice as a child process on the same frame and options,
// sampled at `rate` with the run's sample seed (the same clusters, the same functional warming)
// or whole at rate 1: once in the run's fidelity, once in AT. Their simulated cycles are the check.
ErrorCheck run_error_check(const Args& a, double rate) {
    const TempFolder dir("--check-error");
    std::vector<std::string> base = frame_args(a);
    if (rate < 1.0) base.insert(base.end(), {"--sample", exact(rate), "--sample-seed", std::to_string(a.sample_seed.value_or(a.seed)), "--sample-unchecked"});
    struct Child {
        uint64_t cycles;
        double seconds;
        uint64_t warps, warps_total, clusters;  // sampled: simulated warps, the frame's, simulated clusters
    };
    auto child = [&](const std::string& fidelity) {
        std::vector<std::string> args = base;
        const std::string stats = (dir.path / (fidelity + ".json")).string(), err = (dir.path / (fidelity + ".err")).string();
        args.insert(args.end(), {"--fidelity", fidelity, "--stats", stats});
        if (fidelity == "lt" && a.quantum) args.insert(args.end(), {"--quantum", std::to_string(*a.quantum)});
        try {
            run_child(args, err, "--check-error: the " + fidelity + " run of the check");
        } catch (const InputError& e) {
            throw std::runtime_error(e.what());  // the run itself was accepted: not the user's input
        }
        const nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
        const bool sampled = j["timing"].contains("sampling");
        Child c;
        c.cycles = sampled ? j["timing"]["sampling"]["cycles_simulated"].get<uint64_t>() : j["cycles"].get<uint64_t>();
        c.seconds = j["time_s"]["run"].get<double>();
        c.warps = sampled ? j["timing"]["sampling"]["warps_simulated"].get<uint64_t>() : 1;
        c.warps_total = sampled ? j["timing"]["sampling"]["warps_total"].get<uint64_t>() : 1;
        c.clusters = sampled ? j["timing"]["sampling"]["strata"].get<uint64_t>() + j["timing"]["sampling"]["first_wave_clusters"].get<uint64_t>() : 0;
        return c;
    };
    if (!a.quiet) std::cerr << "checking the error: the same " << (rate < 1.0 ? "sample" : "frame") << " in " << a.fidelity << " and in AT\n";
    const Child f = child(a.fidelity), at = child("at");
    ErrorCheck c;
    c.share = double(f.warps) / double(std::max<uint64_t>(1, f.warps_total));
    c.clusters = f.clusters;  // 0 for the whole frame: the caller knows its clusters
    c.fidelity_cycles = f.cycles;
    c.at_cycles = at.cycles;
    c.fidelity_s = f.seconds;
    c.at_s = at.seconds;
    return c;
}

// --sample-segments K without --segment: each segment simulated by a child rtsim, one after
// another, and their statistics read back for the merge (the same files an array of cluster
// tasks would write, so the estimate is the same, bit for bit).
std::vector<SegmentRun> run_segment_children(const Args& a) {
    const TempFolder dir("--sample-segments");
    std::vector<std::string> base = frame_args(a);
    base.insert(base.end(), {"--fidelity", a.fidelity, "--sample", exact(a.sample), "--sample-seed", std::to_string(a.sample_seed.value_or(a.seed)),
                             "--sample-segments", std::to_string(a.sample_segments)});
    if (a.sample_unchecked) base.push_back("--sample-unchecked");
    if (a.quantum) base.insert(base.end(), {"--quantum", std::to_string(*a.quantum)});
    if (!a.sample_plan.empty()) base.insert(base.end(), {"--sample-plan", a.sample_plan});  // the first segment writes it, the rest read it
    std::vector<SegmentRun> runs;
    for (long long i = 0; i < a.sample_segments; ++i) {
        if (stop_signal.load()) throw Interrupted{stop_signal.load()};
        if (!a.quiet) std::cerr << "segment " << i + 1 << " of " << a.sample_segments << "\n";
        std::vector<std::string> args = base;
        const std::string stats = (dir.path / ("segment" + std::to_string(i) + ".json")).string();
        args.insert(args.end(), {"--segment", std::to_string(i), "--stats", stats});
        try {
            run_child(args, (dir.path / ("segment" + std::to_string(i) + ".err")).string(), "segment " + std::to_string(i));
        } catch (...) {
            if (stop_signal.load()) throw Interrupted{stop_signal.load()};  // the child got the signal too
            throw;
        }
        runs.push_back(read_segment(stats));
    }
    return runs;
}

// The run's specification from the command line; every check that needs no scene comes first.
RunSpec spec_of(const Args& a) {
    RunSpec spec;
    try {
        spec.fidelity = parse_fidelity(a.fidelity);
    } catch (const std::invalid_argument& e) {
        throw InputError(e.what());
    }
    const bool timing = is_timing(spec.fidelity), interval = spec.fidelity == Fidelity::Interval;
    if (a.traversal == "dfs") spec.order = TraversalOrder::DFS;
    else if (a.traversal == "bfs") spec.order = TraversalOrder::BFS;
    else if (a.traversal == "treelet") spec.order = TraversalOrder::Treelet;
    else throw InputError("--traversal '" + a.traversal + "': allowed are dfs, bfs, treelet");
    if (a.rays.empty()) parse_workload(a.workload);  // throws InputError
    if (!a.rays.empty() && !a.image.empty()) throw InputError("--image needs a scene workload, not --rays");
    if (!a.stray.empty()) throw InputError("unexpected argument '" + a.stray.front() + "' (every option starts with --; see rtsim --help)");
    if (!timing && (!a.vcd.empty() || !a.trace_warp.empty() || !a.sets.empty() || a.quantum || !a.prefetcher.empty() || a.sample != 1.0))
        throw InputError("--vcd, --trace-warp, --set, --quantum, --prefetcher and --sample need --fidelity at, lt or interval");
    if (interval && (!a.vcd.empty() || !a.trace_warp.empty() || a.quantum))
        throw InputError("--vcd, --trace-warp and --quantum need --fidelity at or lt (the interval fidelity has no "
                         "SystemC signals or quantum)");
    if (a.quantum && spec.fidelity != Fidelity::LT) throw InputError("--quantum is the loosely timed model's: it needs --fidelity lt");
    if (a.quantum && *a.quantum == 0) throw InputError("--quantum 0: the LT quantum must be at least 1 core cycle");
    if (!a.trace_warp.empty() && a.vcd.empty()) throw InputError("--trace-warp traces into the waveforms: it needs --vcd FILE");
    if (a.sample_seed && a.sample == 1.0) throw InputError("--sample-seed needs --sample RATE below 1");
    if (a.sample_unchecked && a.sample == 1.0) throw InputError("--sample-unchecked needs --sample RATE below 1");
    if (!a.sample_plan.empty() && a.sample == 1.0) throw InputError("--sample-plan keeps a sampled run's pre-pass: it needs --sample RATE below 1");
    if (a.check_error && spec.fidelity != Fidelity::LT && spec.fidelity != Fidelity::Interval)
        throw InputError("--check-error compares a fast fidelity with AT: it needs --fidelity lt or interval (AT is the reference)");
    if (a.sample_segments < 1 || a.sample_segments > 4096)
        throw InputError("--sample-segments " + std::to_string(a.sample_segments) + ": a sample splits into 1 to 4096 segments");
    if (a.sample_segments > 1 && a.sample == 1.0)
        throw InputError("--sample-segments splits a sample: it needs --sample RATE below 1 (a whole frame is one continuous run)");
    if ((a.segment || !a.merge_segments.empty()) && a.sample_segments == 1)
        throw InputError("--segment and --merge-segments need --sample-segments K (2 or more)");
    if (a.segment && *a.segment >= uint64_t(a.sample_segments))
        throw InputError("--segment " + std::to_string(*a.segment) + ": the segments are numbered 0.." + std::to_string(a.sample_segments - 1));
    if (a.segment && !a.merge_segments.empty()) throw InputError("--segment simulates one segment, --merge-segments merges them: give one of the two");
    if (a.sample_segments > 1 && (!a.hits.empty() || !a.image.empty() || !a.vcd.empty() || a.check_error || a.verify))
        throw InputError("--hits, --image, --vcd, --check-error and --verify need one continuous run: not with --sample-segments "
                         "(each segment simulates some of the rays)");
    if (!a.merge_segments.empty() && a.merge_segments.size() != size_t(a.sample_segments))
        throw InputError("--merge-segments: " + std::to_string(a.merge_segments.size()) + " files for --sample-segments " +
                         std::to_string(a.sample_segments) + ": give each segment's statistics once");
    if (a.threads < 1 || a.threads > 4096)
        throw InputError("--threads " + std::to_string(a.threads) + ": the sampling pre-pass takes 1 to 4096 threads");
    // Outputs are checked before anything runs: a bad path should not wait for the simulation.
    for (const auto& [option, path] : {std::pair<const char*, std::string>{"--stats", a.stats}, {"--image", a.image},
                                       {"--hits", a.hits}, {"--vcd", a.vcd}, {"--dump-bvh", a.dump_bvh},
                                       {"--dump-rays", a.dump_rays}, {"--dump-hits", a.dump_hits}})
        if (!path.empty()) check_writable_folder(option, path);
    // A plan's file, or given a folder a file in it (plan_file; the frame's name is not known yet).
    if (!a.sample_plan.empty()) check_writable_folder("--sample-plan", plan_file(a.sample_plan, ""));
    if (!(a.sample > 0.0 && a.sample <= 1.0))
        throw InputError("--sample " + std::to_string(a.sample) + ": the share of the frame to simulate must be in (0, 1]");
    // Configuration first: a bad key should not wait for a scene to load.
    if (timing) {
        try {
            spec.config = Config::load(a.config);
            for (const auto& s : a.sets) spec.config.set(s);
            if (a.quantum) spec.config.set("sim.quantum=" + std::to_string(*a.quantum));
            if (!a.prefetcher.empty()) spec.config.set("prefetch.kind=" + a.prefetcher);
            spec.hw = spec.config.resolve();
            check_prefetcher(spec.hw.prefetch, spec.order);
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
    spec.sample_rate = a.sample;
    spec.sample_seed = a.sample_seed.value_or(a.seed);
    spec.sample_unchecked = a.sample_unchecked;
    spec.sample_segments = uint32_t(a.sample_segments);
    if (a.segment) spec.segment = uint32_t(*a.segment);
    spec.merge_segments = a.merge_segments;
    spec.sample_plan = a.sample_plan;
    if (a.sample_segments > 1 && !a.segment && a.merge_segments.empty()) spec.run_segments = [&a] { return run_segment_children(a); };
    spec.threads = unsigned(a.threads);
    spec.vcd = a.vcd;
    if (spec.vcd.size() > 4 && spec.vcd.compare(spec.vcd.size() - 4, 4, ".vcd") == 0) spec.vcd.resize(spec.vcd.size() - 4);
    if (!a.trace_warp.empty()) std::tie(spec.trace_sm, spec.trace_warp) = parse_trace_warp(a.trace_warp, spec.hw);
    spec.verify = a.verify;
    spec.keep_rays = !a.hits.empty();
    spec.dump_bvh = a.dump_bvh;
    spec.dump_rays = a.dump_rays;
    spec.dump_hits = a.dump_hits;
    spec.progress = !a.quiet;
    spec.check_error = a.check_error;
    spec.stop.flag = &stop_signal;
    if (a.check_error) spec.run_check = [&a](double rate) { return run_error_check(a, rate); };
    return spec;
}

void print_summary(const Args& a, const RunResult& r) {
    const nlohmann::ordered_json& j = r.stats;
    std::cout << "rays " << j["rays"] << " (" << j["invalid_rays"] << " invalid), hits " << j["hits"] << ", nodes/ray "
              << j["nodes_per_ray"].get<double>() << " (max " << j["max_nodes_per_ray"] << "), " << a.traversal << ", "
              << a.fidelity << ", " << j["time_s"]["run"].get<double>() << " s\n";
    if (j.contains("timing")) {
        const auto& t = j["timing"];
        if (t.contains("sampling")) {
            const auto& sm = t["sampling"];
            std::cout << "sampled " << sm["warps_simulated"] << " of " << sm["warps_total"] << " warps ("
                      << double(std::llround(1000 * sm["rate_simulated"].get<double>())) / 10 << " % of the frame; "
                      << double(std::llround(1000 * sm["rate"].get<double>())) / 10 << " % asked): " << sm["cycles_simulated"]
                      << " cycles simulated, frame estimate " << j["cycles"];
            if (sm["cycles_ci95"].is_array())
                std::cout << " (95 % interval " << std::llround(sm["cycles_ci95"][0].get<double>()) << ".."
                          << std::llround(sm["cycles_ci95"][1].get<double>()) << ")\n";
            else
                std::cout << " (no interval: too few strata or clusters per segment, --sample-unchecked)\n";
        }
        std::cout << error_line(j["error_estimate"]) << "\n";
        std::cout << "cycles " << j["cycles"] << ", L1 miss rate " << t["l1"]["demand"]["miss_rate"].get<double>()
                  << ", L2 miss rate " << t["l2"]["demand"]["miss_rate"].get<double>() << ", DRAM reads "
                  << t["dram"]["reads"] << " (bandwidth " << t["dram"]["bandwidth_utilisation"].get<double>() * 100
                  << " %), " << uint64_t(j["simulation_rate"]["rays_per_s"].get<double>()) << " rays/s simulated\n";
    }
    if (j.contains("verify")) {
        const auto& v = j["verify"];
        std::cout << "verify against Embree (robust): " << v["rays"] << " rays, " << v["mismatches"] << " mismatches";
        for (size_t c = 1; c + 1 < size_t(Agreement::Count); ++c) {
            const uint64_t n = v["classes"][agreement_name(Agreement(c))].get<uint64_t>();
            if (n) std::cout << ", " << agreement_name(Agreement(c)) << " " << n;
        }
        if (v["skipped"].get<uint64_t>()) std::cout << ", skipped " << v["skipped"];
        std::cout << "\n";
        if (j.contains("speed"))
            std::cout << "speed: ours " << uint64_t(j["speed"]["ours_rays_per_s"].get<double>()) << " rays/s, Embree "
                      << uint64_t(j["speed"]["embree_rays_per_s"].get<double>()) << " rays/s (Embree is "
                      << j["speed"]["embree_over_ours"].get<double>() << "x faster)\n";
    }
}

int run(const Args& given) {
    // --sample-segments alone: its child runs share one pre-pass through a plan file (the first
    // writes it) unless --sample-plan names one.
    Args a = given;
    std::optional<TempFolder> plan_dir;
    if (a.sample_segments > 1 && !a.segment && a.merge_segments.empty() && a.sample_plan.empty() && a.sample < 1.0) {
        plan_dir.emplace("--sample-segments");
        a.sample_plan = (plan_dir->path / "plan.bin").string();
    }
    const RunSpec spec = spec_of(a);
    const RunResult r = run_simulation(spec, a.quiet ? nullptr : &std::cout);
    if (r.interrupted) {
        // Only the statistics: the frame, the hits and the dumps are not whole.
        const int sig = stop_signal.load();
        if (!a.stats.empty()) write_file_atomic(a.stats, r.stats.dump(2) + "\n");
        std::cerr << "rtsim: interrupted by " << signal_name(sig) << " after " << r.stats["rays"] << " rays"
                  << (r.stats.contains("cycles") ? " and " + r.stats["cycles"].dump() + " simulated cycles" : std::string()) << "; "
                  << (a.stats.empty() ? std::string("no --stats file asked for")
                                      : "statistics so far written to " + a.stats + " (\"interrupted\": true)")
                  << (a.vcd.empty() ? "" : ", waveforms so far in " + spec.vcd + ".vcd")
                  << "; the frame, hits and dumps are not written\n";
        return interrupted_status(sig);
    }
    if (!r.stuck.empty()) {
        std::cerr << "error: " << r.stuck << "\n";
        return 1;
    }
    // Write every output only after the whole run succeeded.
    if (!a.hits.empty()) write_file_atomic(a.hits, hits_csv(r.rays));
    for (const auto& [path, bytes] : r.files) write_file_atomic(path, bytes);
    if (!a.image.empty()) write_png_atomic(a.image, r.width, r.height, r.image);
    if (!a.stats.empty()) write_file_atomic(a.stats, r.stats.dump(2) + "\n");
    if (!a.quiet) print_summary(a, r);
    for (const std::string& f : r.invariant_failures) std::cerr << "error: invariant violated: " << f << "\n";
    if (!r.invariant_failures.empty()) return 1;
    if (a.verify && r.mismatches > 0) {
        std::cerr << "error: " << r.mismatches << " rays disagree with Embree outside the documented classes (first: ray "
                  << r.first_mismatch << ")\n";
        return 1;
    }
    return 0;
}

}  // namespace

int sc_main(int argc, char** argv) {
    // Process-wide SystemC settings are rtsim's, not the model's (tlm/rt_complex.h): the clocks'
    // periods are whole femtoseconds, and SystemC's informational reports ("simulation stopped
    // by user", "timescale unit set") would clutter the run's own output (warnings and errors
    // still show).
    sc_core::sc_set_time_resolution(1, sc_core::SC_FS);
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
    Args a;
    // Every option is in the usage lines (a test checks it against the option table).
    const std::string usage =
        "rtsim: ray-tracing unit model\n"
        "usage: rtsim --scene NAME|PATH [--assets DIR] [--workload primary|pt|ao|sh] [--rays FILE] [--hits FILE]\n"
        "             [--width W --height H --spp N --bounces B --seed S] [--traversal dfs|bfs|treelet] [--flatten]\n"
        "             [--fidelity functional|at|lt|interval] [--config NAME|FILE] [--set KEY=VALUE]... [--quantum CYCLES]\n"
        "             [--prefetcher none|ttp|park|treelet|perfect-up|perfect-down]\n"
        "             [--sample RATE [--sample-seed S] [--sample-unchecked] [--threads N]\n"
        "              [--sample-plan FILE] [--sample-segments K [--segment I | --merge-segments FILE...]]] [--check-error N]\n"
        "             [--stats FILE.json] [--image FILE.png] [--vcd FILE] [--trace-warp SM:WARP] [--verify] [--quiet]\n"
        "             [--dump-bvh FILE] [--dump-rays FILE] [--dump-hits FILE]\n"
        "       rtsim --stats-schema | --help\n"
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
         "which clusters --sample draws (default: --seed, which also seeds the rays)")
        ("sample-unchecked", po::bool_switch(&a.sample_unchecked),
         "run a sample too small for a 95 % interval (fewer than 10 strata) and report no interval")
        ("sample-segments", po::value(&a.sample_segments), "simulate the sample as K independent segments and merge them "
         "(docs/sampling.md, \"Segments\"); alone: each segment in a child process, one after another")
        ("segment", po::value<uint64_t>()->notifier([&a](uint64_t v) { a.segment = v; }),
         "with --sample-segments K: simulate only segment I (0..K-1) and write it for --merge-segments (a cluster's array task)")
        ("sample-plan", po::value(&a.sample_plan), "keep the sampling pre-pass in this file (or, given a folder, in a file of the "
         "frame's own in it): read if it exists (of the same frame, traversal and warp size; any fidelity, preset or sample), "
         "else written; segments and their merge, and the runs of a sweep over configurations, then trace the frame once")
        ("merge-segments", po::value(&a.merge_segments)->multitoken(),
         "with --sample-segments K and the same frame options: merge the K segments' --stats files into the frame's estimate")
        ("threads", po::value(&a.threads)->default_value(a.threads),
         "threads for --sample's functional pre-pass (the simulation itself runs on one; results do not depend on it)")
        ("check-error", po::value<uint64_t>()->notifier([&a](uint64_t v) {
             if (v == 0) throw po::validation_error(po::validation_error::invalid_option_value, "check-error", "0");
             a.check_error = v;
         }),
         "lt, interval: simulate N randomly drawn clusters (and the first wave) of the frame in this fidelity and in AT, "
         "and report the measured difference beside the error estimate")
        ("vcd", po::value(&a.vcd), "write waveforms to this VCD file (at, lt)")
        ("trace-warp", po::value(&a.trace_warp), "with --vcd: trace each thread's stack depth of warp-buffer slot WARP of SM")
        ("stats", po::value(&a.stats), "write statistics JSON")
        ("image", po::value(&a.image), "write the rendered frame as PNG")
        ("verify", po::bool_switch(&a.verify), "compare every ray with Embree (robust mode); exit 1 on mismatches")
        ("dump-bvh", po::value(&a.dump_bvh), "write the BVH image's bytes (an SoC peripheral's input; docs/peripheral.md)")
        ("dump-rays", po::value(&a.dump_rays), "write the workload's first rays (or the ray file's) as 48-byte ray records (rtunit/rtu_regs.h)")
        ("dump-hits", po::value(&a.dump_hits), "write the golden 48-byte hit records of the --dump-rays rays")
        ("flatten", po::bool_switch(&a.flatten), "scenes whose meshes are all placed as they are: one single-level BVH instead of TLAS + BLAS")
        ("quiet,q", po::bool_switch(&a.quiet), "no progress or summary");
    try {
        po::variables_map vm;
        const po::parsed_options parsed = po::command_line_parser(argc, argv).options(desc).run();
        po::store(parsed, vm);
        a.stray = po::collect_unrecognized(parsed.options, po::include_positional);
        if (vm.count("help")) {
            std::cout << desc << "\n";
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
    install_stop_handlers();
    // A stop that ends the run before anything was simulated (or makes a child process fail)
    // leaves nothing to write: said as such, whatever the error it caused.
    const auto interrupted = [&a] {
        const int sig = stop_signal.load();
        std::cerr << (a.quiet ? "" : "\n") << "rtsim: interrupted by " << signal_name(sig) << " before the simulation started; nothing written\n";
        return interrupted_status(sig);
    };
    try {
        return run(a);
    } catch (const Interrupted&) {
        return interrupted();
    } catch (const InputError& e) {
        if (stop_signal.load()) return interrupted();
        std::cerr << "rtsim: " << e.what() << "\n";
        return 2;
    } catch (const std::bad_alloc&) {
        // The input asked for more than this machine holds; nothing was written (outputs are
        // written whole at the end).
        std::cerr << "rtsim: out of memory for a frame of " << a.width << "x" << a.height << " at " << a.spp
                  << " spp; try a smaller frame, fewer samples per pixel, or --sample\n";
        return 2;
    } catch (const std::exception& e) {
        if (stop_signal.load()) return interrupted();
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
