// One run of the model, whatever its fidelity: the scene loaded, its BVH image built, the
// workload made, the run done (functional, AT, LT or interval), checked against Embree when asked,
// and its statistics gathered. rtsim parses its command line into a RunSpec, calls run_simulation
// and writes what comes back; other programs can do the same.
#pragma once
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "error_estimate.h"
#include "sample_segments.h"
#include "model/bvh_image.h"
#include "model/config.h"
#include "model/fidelity.h"
#include "model/stats.h"
#include "model/stop_request.h"
#include "model/traversal.h"
#include "timing_run.h"
#include "workloads/rays.h"
#include "workloads/workload_driver.h"

namespace rtu {

struct RunSpec {
    RunSpec() { run.fidelity = Fidelity::Functional; }
    std::string scene = "wknd", assets;
    bool flatten = false;
    std::string workload = "pt";  // primary, pt, ao or sh
    std::string rays;             // a ray file, in place of the workload
    WorkloadParams params;
    // Timing fidelities: the configuration (resolved into `hw`; written into the statistics).
    Config config;
    HwConfig hw{};
    // The run's fidelity (functional too) and its options: traversal order, progress, waveforms,
    // the sample (rate, seed, segments, plan, the pre-pass's threads), whether to keep every ray
    // (--hits, --verify) and the stop request. The functional fidelity reads the order, the
    // progress and the stop; run_simulation fills in the sample's workload maker and the plan's
    // identity.
    TimingOptions run;
    // --sample-segments K (docs/sampling.md, "Segments"): run.sample_segment < K simulates that
    // one and writes its "segment" section; else the K segments' statistics are merged, from
    // `merge_segments` (files) or from `run_segments` (rtsim runs each segment as a child process
    // and returns their statistics, read back; platforms/child_runs.h).
    std::vector<std::string> merge_segments;
    std::function<std::vector<SegmentRun>()> run_segments;
    bool verify = false;       // every ray against Embree (robust mode)
    std::vector<std::string> command_line;  // the program's arguments, for the statistics' provenance
    // On a snapshot request (RunSpec::run.stop, SIGUSR1): the statistics so far as JSON text and a
    // sentence on what was simulated; the caller writes them. Empty: snapshots are not taken.
    std::function<void(const std::string& stats, const std::string& what)> write_snapshot;
    // The SoC peripheral's inputs (docs/peripheral.md): the BVH image's bytes, the workload's
    // first rays as 48-byte ray records, and their golden 48-byte hit records (RunResult::files).
    std::string dump_bvh, dump_rays, dump_hits;
    std::string timeline;  // --timeline: the file TimingResult::timeline goes to (RunResult::files)
    // --check-error N (LT, interval): N clusters drawn besides the first wave simulated in the
    // run's fidelity and in AT; run_check simulates the sample of the frame at `rate` in both
    // (rtsim runs child processes) and returns what they measured; `run_s`, the run's own wall
    // time so far, decides whether the check would cost less than AT's full run (CheckRefused).
    uint64_t check_error = 0;
    std::function<ErrorCheck(double rate, double run_s)> run_check;
    // --sample-width W (docs/sampling.md, "A sample of a given width"): the 95 % half-width asked,
    // relative (0: not asked); the run samples the frame at the rate planned from a pilot sample,
    // which run_pilot simulates at `rate` (rtsim: a child process with the run's fidelity, seed and
    // plan) and whose statistics' timing.sampling it returns.
    double sample_width = 0;
    std::function<nlohmann::json(double rate)> run_pilot;
    // A stop requested through run.stop (rtsim: SIGINT, SIGTERM) ends the run at its next clean
    // point with what it simulated so far (RunResult::interrupted); before the simulation
    // starts, Interrupted is thrown instead (model/stop_request.h).
};

struct RunResult {
    nlohmann::ordered_json stats;  // everything rtsim writes with --stats
    std::vector<TracedRay> rays;   // in (path, seq) order, with RunSpec::keep_rays or verify
    std::vector<glm::vec3> image;  // a scene workload's frame (linear RGB), else empty
    int width = 0, height = 0;
    // A timing run that stopped without finishing (the watchdog, or no events left): its outputs
    // must not be written.
    std::string stuck;
    std::vector<std::string> invariant_failures;
    std::vector<std::pair<std::string, std::string>> files;  // path and bytes, written once the run succeeded
    uint64_t mismatches = 0;       // --verify: rays outside the documented classes
    uint64_t first_mismatch = 0;
    // Stopped by RunSpec::stop: `stats` hold what was simulated so far ("interrupted": true);
    // the frame, hits and dumps are not whole and must not be written.
    bool interrupted = false;
};

// `log` (may be null) receives the scene and BVH lines as the run reaches them. Throws
// InputError for bad input and std::exception for internal errors.
RunResult run_simulation(const RunSpec& spec, std::ostream* log);

// What must be equal in every segment of one split sampled run (--sample-segments): the frame,
// the sample, the fidelity and the configuration. `scene`: the loaded scene's name.
std::vector<IdentityKey> segment_identity(const RunSpec& spec, const std::string& scene);

// What a sample plan (--sample-plan) must match: what the functional pre-pass depends on, and
// nothing else. The BVH (the scene's name, flattened or not, and a hash of the image's bytes),
// the rays (the workload and the frame; a ray file's rays hashed, `ray_file`), the traversal (its
// order, the next-node register, the treelets it keeps to) and how paths form shader warps
// (rt.warp_size). Not the fidelity, the sample, the SMs, the memory system, the latencies or the
// prefetcher: one plan serves every run of a sweep over them on one frame.
std::string prepass_identity(const RunSpec& spec, const std::string& scene, const HwConfig& hw, const BvhImage& image,
                             const std::vector<RayFileEntry>& ray_file);

// Every key a run's statistics can have (RunResult::stats, rtsim --stats): dotted path, list
// items as "[]", unit and description; from the code that writes them (model/stats.h).
std::vector<StatKey> stats_schema();

}  // namespace rtu
