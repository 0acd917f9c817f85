// rtsim: runs a ray workload over a scene's BVH image on the RT-unit model, at any fidelity.
// It parses its command line into a RunSpec (platforms/command_line.h), runs it
// (platforms/simulation.h) and writes the statistics, hits, frame and summary.
#include <atomic>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <new>
#include <optional>

#include <csignal>
#include <cstring>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <systemc>

#include "child_runs.h"
#include "command_line.h"
#include "output.h"
#include "simulation.h"
#include "workloads/input_error.h"
#include "workloads/verify.h"

using namespace rtu;

namespace {

// SIGINT, SIGTERM and SIGHUP (a dropped SSH session) request a stop (model/stop_request.h): the
// run ends at its next clean point and writes its statistics so far. A second one ends rtsim at
// once, as the signal's default would, after removing the VCD it was writing under its temporary
// name (unlink is async-signal-safe; the name is set before the run starts), so that no cut
// waveform is left behind.
std::atomic<int> stop_signal{0};
char vcd_in_progress[4096] = {0};
extern "C" void on_stop_signal(int sig) {
    if (stop_signal.load(std::memory_order_relaxed) == 0) {
        stop_signal.store(sig, std::memory_order_relaxed);
        return;
    }
    if (vcd_in_progress[0]) ::unlink(vcd_in_progress);
    ::signal(sig, SIG_DFL);
    ::raise(sig);
}

// SIGUSR1 asks for the statistics so far, as gem5's does: the run writes them (the --stats file,
// replaced whole) at its next clean point and goes on; its end replaces them with the final
// statistics, and a run that then fails removes them with its other outputs.
std::atomic<int> snapshot_signal{0};
extern "C" void on_snapshot_signal(int) { snapshot_signal.store(1, std::memory_order_relaxed); }
std::string snapshot_written;  // the --stats file a snapshot is in (empty: none, or the run's own outputs replaced it)
// At rtsim's end, whatever way it ends: a snapshot the run's outputs did not replace is removed.
struct DropSnapshot {
    ~DropSnapshot() {
        if (!snapshot_written.empty()) std::remove(snapshot_written.c_str());
    }
};

void install_stop_handlers() {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    sigaction(SIGHUP, &sa, nullptr);
    struct sigaction su {};
    su.sa_handler = on_snapshot_signal;
    sigemptyset(&su.sa_mask);
    su.sa_flags = SA_RESTART;
    sigaction(SIGUSR1, &su, nullptr);
    // A file-size limit (`ulimit -f`) raises SIGXFSZ, whose default ends the process at the write
    // that crossed it, leaving the output's temporary file behind. Ignored, the write fails with
    // EFBIG instead: an error that names the output, and no output is left (the run's outputs are
    // all or none).
    ::signal(SIGXFSZ, SIG_IGN);
}

const char* signal_name(int sig) {
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

// The shell's convention: 128 + the signal's number (130 for SIGINT, 143 for SIGTERM, 129 for
// SIGHUP).
int interrupted_status(int sig) { return 128 + sig; }

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
    // --sample-width: its pilot writes the frame's plan, and the run reads it (the frame is traced once).
    if (a.sample_width && a.sample_plan.empty()) {
        plan_dir.emplace("--sample-width");
        a.sample_plan = (plan_dir->path / "plan.bin").string();
    }
    RunSpec spec = spec_of(a, &stop_signal);
    spec.run.stop.snapshot = &snapshot_signal;
    spec.write_snapshot = [&a](const std::string& stats, const std::string& what) {
        if (a.stats.empty()) {
            std::cerr << "rtsim: SIGUSR1: " << what << " (no --stats file asked for); the run goes on\n";
        } else if (is_special_file(a.stats)) {
            std::cerr << "rtsim: SIGUSR1: " << what << "; " << a.stats << " is not a regular file, so the statistics so far are not written; the run goes on\n";
        } else {
            try {  // a snapshot that cannot be written does not end the run
                write_file_atomic(a.stats, stats);
                snapshot_written = a.stats;
                std::cerr << "rtsim: SIGUSR1: " << what << "; statistics so far written to " << a.stats << " (\"snapshot\": true); the run goes on\n";
            } catch (const std::exception& e) {
                std::cerr << "rtsim: SIGUSR1: " << what << "; the statistics so far could not be written (" << e.what() << "); the run goes on\n";
            }
        }
    };
    // The VCD, which SystemC writes as the run goes, is written under a temporary name and renamed
    // with the other outputs; a run that fails leaves none of them (OutputFiles).
    OutputFiles outputs;
    std::string vcd;
    if (!spec.run.vcd.empty()) {
        vcd = spec.run.vcd + ".vcd";
        spec.run.vcd = temporary_beside(vcd);
        outputs.adopt(spec.run.vcd + ".vcd", vcd);
        const std::string temporary = spec.run.vcd + ".vcd";
        if (temporary.size() < sizeof vcd_in_progress) std::memcpy(vcd_in_progress, temporary.c_str(), temporary.size() + 1);
    }
    const RunResult r = run_simulation(spec, a.quiet ? nullptr : &std::cout);
    // SystemC does not report a failed write: a full filesystem or the file-size limit cuts a VCD
    // without a word, so both are checked.
    if (!vcd.empty()) check_written_whole(spec.run.vcd + ".vcd", vcd);
    if (r.interrupted) {
        // Only the statistics and the waveforms: the frame, the hits and the dumps are not whole.
        const int sig = stop_signal.load();
        if (!a.stats.empty()) outputs.stage(a.stats, r.stats.dump(2) + "\n");
        outputs.commit();
        snapshot_written.clear();  // the statistics so far replaced it
        std::cerr << "rtsim: interrupted by " << signal_name(sig) << " after " << r.stats["rays"] << " rays"
                  << (r.stats.contains("cycles") ? " and " + r.stats["cycles"].dump() + " simulated cycles" : std::string()) << "; "
                  << (a.stats.empty() ? std::string("no --stats file asked for")
                                      : "statistics so far written to " + a.stats + " (\"interrupted\": true)")
                  << (vcd.empty() ? "" : ", waveforms so far in " + vcd)
                  << "; the frame, hits and dumps are not written\n";
        return interrupted_status(sig);
    }
    if (!r.stuck.empty()) {
        // The waveforms are what shows why the model stopped moving: kept; nothing else.
        outputs.commit();
        std::cerr << "error: " << r.stuck << (vcd.empty() ? "" : " (waveforms in " + vcd + ")") << "\n";
        return 1;
    }
    // Every output only after the whole run succeeded, and all of them or none.
    if (!a.hits.empty()) outputs.stage(a.hits, hits_csv(r.rays));
    for (const auto& [path, bytes] : r.files) outputs.stage(path, bytes);
    if (!a.image.empty()) {
        const std::string png = png_bytes(r.width, r.height, r.image);
        if (png.empty()) throw InputError(a.image + ": PNG encoding failed");
        outputs.stage(a.image, png);
    }
    if (!a.stats.empty()) outputs.stage(a.stats, r.stats.dump(2) + "\n");
    outputs.commit();
    snapshot_written.clear();  // the final statistics replaced it
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
    if (const std::optional<int> done = parse_command_line(argc, argv, a)) return *done;
    install_stop_handlers();
    const DropSnapshot drop_snapshot;
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
