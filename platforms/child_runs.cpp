#include "child_runs.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "workloads/input_error.h"

extern char** environ;

namespace rtu {

TempFolder::TempFolder(const char* what) {
    namespace fs = std::filesystem;
    std::string tmpl = (fs::temp_directory_path() / "rtsim-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error(std::string(what) + ": cannot make a temporary folder in " + fs::temp_directory_path().string());
    path = tmpl;
}

TempFolder::~TempFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
}

std::string exact(double v) {
    char r[32];
    std::snprintf(r, sizeof r, "%.17g", v);
    return r;
}

namespace {

// rtsim started with `args` (its output to /dev/null, its standard error into the file `err`).
pid_t spawn_child(std::vector<std::string> args, const std::string& err, const std::string& what) {
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
    return pid;
}

// The exit status of child `pid` (blocking).
int reap(pid_t pid) {
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

// Throws, with the child's error text (the file `err`), if `status` is not exit 0; InputError for
// exit status 2.
void check_child(int status, const std::string& err, const std::string& what) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
    std::ifstream in(err);
    std::stringstream msg;
    msg << in.rdbuf();
    const std::string text = what + " failed (" + (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : std::string("a signal")) +
                             "): " + msg.str();
    if (WIFEXITED(status) && WEXITSTATUS(status) == 2) throw InputError(text);
    throw std::runtime_error(text);
}

}  // namespace

void run_child(std::vector<std::string> args, const std::string& err, const std::string& what) {
    check_child(reap(spawn_child(std::move(args), err, what)), err, what);
}

nlohmann::json run_child_stats(std::vector<std::string> args, const std::string& fidelity, std::optional<uint64_t> quantum,
                               const std::filesystem::path& dir, const std::string& name, const std::string& what) {
    const std::string stats = (dir / (name + ".json")).string(), err = (dir / (name + ".err")).string();
    args.insert(args.end(), {"--fidelity", fidelity, "--stats", stats});
    if (fidelity == "lt" && quantum) args.insert(args.end(), {"--quantum", std::to_string(*quantum)});
    run_child(std::move(args), err, what);
    return nlohmann::json::parse(std::ifstream(stats));
}

nlohmann::json run_width_pilot(const std::vector<std::string>& frame_args, const std::string& fidelity, std::optional<uint64_t> quantum,
                               double rate, uint64_t sample_seed, const std::string& plan, bool quiet) {
    const auto start = std::chrono::steady_clock::now();
    const TempFolder dir("--sample-width");
    std::vector<std::string> args = frame_args;
    args.insert(args.end(), {"--sample", exact(rate), "--sample-seed", std::to_string(sample_seed), "--sample-unchecked", "--sample-plan", plan});
    if (!quiet) std::cerr << "planning the sample's width: a pilot sample of " << exact(100.0 * rate) << " % of the frame\n";
    const nlohmann::json j = run_child_stats(args, fidelity, quantum, dir.path, "pilot", "--sample-width: the pilot sample");
    nlohmann::json s = j["timing"]["sampling"];
    s["cycles"] = j["cycles"];
    s["pilot_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return s;
}

ErrorCheck run_error_check(const std::vector<std::string>& frame_args, const std::string& fidelity, std::optional<uint64_t> quantum,
                           double rate, uint64_t sample_seed, double run_s, bool quiet) {
    const auto start = std::chrono::steady_clock::now();
    const TempFolder dir("--check-error");
    // The fidelity's child traces the frame for the sample's plan and writes it; AT's reads it
    // (a plan holds no timing: docs/sampling.md, "Sample plan"), so the frame is traced once.
    std::vector<std::string> base = frame_args;
    base.insert(base.end(), {"--sample", exact(rate), "--sample-seed", std::to_string(sample_seed), "--sample-unchecked", "--sample-plan",
                             (dir.path / "plan.bin").string()});
    struct Child {
        uint64_t cycles;
        double seconds;
        uint64_t warps, warps_total, clusters;  // simulated warps, the frame's, simulated clusters
        StrataWork strata;
        double wall;  // the child's wall time, start to end
    };
    auto child = [&](const std::string& fid) {
        const auto child_start = std::chrono::steady_clock::now();
        nlohmann::json j;
        try {
            j = run_child_stats(base, fid, quantum, dir.path, fid, "--check-error: the " + fid + " run of the check");
        } catch (const InputError& e) {
            throw std::runtime_error(e.what());  // the run itself was accepted: not the user's input
        }
        const nlohmann::json& s = j["timing"]["sampling"];
        Child c;
        c.cycles = s["cycles_simulated"].get<uint64_t>();
        c.seconds = j["time_s"]["run"].get<double>();
        c.warps = s["warps_simulated"].get<uint64_t>();
        c.warps_total = s["warps_total"].get<uint64_t>();
        c.clusters = s["strata"].get<uint64_t>() + s["first_wave_clusters"].get<uint64_t>();
        c.strata.first_wave = s["strata_work"]["first_wave_residence_cycles"].get<double>();
        c.strata.work = s["strata_work"]["residence_cycles"].get<std::vector<double>>();
        c.strata.weight = s["strata_work"]["weights"].get<std::vector<double>>();
        c.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - child_start).count();
        return c;
    };
    if (!quiet) std::cerr << "checking the error: the same sample in " << fidelity << " and in AT\n";
    const Child f = child(fidelity);
    // The sample took a share q of the full run's time T in this fidelity. If AT's sample takes the
    // same share of AT's full run T_at (less where AT's fixed costs weigh less in its longer run),
    // the check costs q (T + T_at), below T_at exactly when q < T_at / (T + T_at), which is at
    // least 1/2 wherever AT's run is not the faster. (On the check's grids AT took 0.8-6.9 times
    // the fidelity's time: LT can be slower than AT on small frames, and there a check that passes
    // can cost about AT's run, docs/accuracy.md.) Where the sample costs half the run or more
    // (small frames, whose load, pre-pass and warming outweigh their simulation: primary rays at
    // 256x256), AT's full run is the cheaper answer.
    const double q = run_s > 0 ? f.wall / run_s : 0.0;
    if (q >= 0.5) {
        char why[320];
        std::snprintf(why, sizeof why,
                      "its sample took %.2f s in %s, %.0f %% of this run's %.2f s: AT's sample would cost about as much as AT's full "
                      "run, so run --fidelity at for the reference",
                      f.wall, fidelity.c_str(), 100.0 * q, run_s);
        throw CheckRefused(why);
    }
    const Child at = child("at");
    ErrorCheck c;
    c.share = double(f.warps) / double(std::max<uint64_t>(1, f.warps_total));
    c.clusters = f.clusters;
    c.fidelity_cycles = f.cycles;
    c.at_cycles = at.cycles;
    c.residence = paired_work_difference(f.strata, at.strata);
    if (c.residence.pairs == 0)
        throw std::runtime_error("--check-error: the check's sample drew " + std::to_string(f.strata.work.size()) +
                                 " strata with work, too few to pair for an interval");
    c.fidelity_s = f.seconds;
    c.at_s = at.seconds;
    c.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return c;
}

std::vector<SegmentRun> run_segment_children(const std::vector<std::string>& segment_args, uint32_t segments, unsigned threads,
                                             const std::string& plan, const StopRequest& stop, bool quiet) {
    const TempFolder dir("--sample-segments");
    // Up to `threads` children at once, the threads shared among them (a child's results do not
    // depend on its threads); the first, alone until its pre-pass is done, takes them all.
    const uint32_t parallel = std::max(1u, std::min<uint32_t>(segments, threads));
    auto with_threads = [&](unsigned n) {
        std::vector<std::string> args = segment_args;
        const auto t = std::find(args.begin(), args.end(), std::string("--threads"));
        if (t != args.end() && t + 1 != args.end()) *(t + 1) = std::to_string(std::max(1u, n));
        return args;
    };
    const std::vector<std::string> first = with_threads(threads), rest = with_threads(threads / parallel);
    auto stats_of = [&](uint32_t i) { return (dir.path / ("segment" + std::to_string(i) + ".json")).string(); };
    auto err_of = [&](uint32_t i) { return (dir.path / ("segment" + std::to_string(i) + ".err")).string(); };
    auto what_of = [](uint32_t i) { return "segment " + std::to_string(i); };
    struct Running {
        uint32_t index;
        pid_t pid;
        std::optional<int> status;  // reaped already
    };
    std::deque<Running> running;  // in the order started
    auto start = [&](uint32_t i) {
        if (!quiet) std::cerr << "segment " << i + 1 << " of " << segments << (parallel > 1 ? " started" : "") << "\n";
        std::vector<std::string> args = i == 0 ? first : rest;
        args.insert(args.end(), {"--segment", std::to_string(i), "--stats", stats_of(i)});
        running.push_back({i, spawn_child(args, err_of(i), what_of(i)), std::nullopt});
    };
    // A failure or a stop ends the others: they are told to stop (SIGTERM) and reaped first.
    auto end_all = [&] {
        for (const Running& r : running)
            if (!r.status) kill(r.pid, SIGTERM);
        for (const Running& r : running)
            if (!r.status) reap(r.pid);
        running.clear();
    };
    uint32_t next = 0;
    try {
        start(next++);
        // The first segment writes the frame's plan right after its pre-pass: the others start
        // when the plan is there (`plan`; empty: when the first ends), so the frame is traced once.
        if (parallel > 1 && segments > 1) {
            if (plan.empty()) running.front().status = reap(running.front().pid);
            while (!running.front().status && !std::filesystem::exists(plan) && !stop.requested()) {
                int status = 0;
                if (waitpid(running.front().pid, &status, WNOHANG) == running.front().pid) running.front().status = status;
                else usleep(20000);
            }
        }
        while (!running.empty()) {
            if (!running.front().status)
                while (next < segments && running.size() < parallel && !stop.requested()) start(next++);
            const Running r = running.front();
            const int status = r.status ? *r.status : reap(r.pid);
            running.pop_front();
            if (stop.requested()) throw Interrupted{stop.signal()};  // the children got the signal too
            check_child(status, err_of(r.index), what_of(r.index));
            if (running.empty() && next < segments) start(next++);
        }
    } catch (...) {
        end_all();
        throw;
    }
    std::vector<SegmentRun> runs;
    for (uint32_t i = 0; i < segments; ++i) runs.push_back(read_segment(stats_of(i)));
    return runs;
}

}  // namespace rtu
