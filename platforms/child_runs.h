// rtsim run as child processes of itself (SystemC elaborates one platform per process): the
// segments of a split sample, up to --threads at once (--sample-segments K alone), and
// --check-error's two runs of the same clusters in the run's fidelity and in AT. Each child gets
// the parent's frame, workload and configuration options (`frame_args`).
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "error_estimate.h"
#include "model/stop_request.h"
#include "sample_segments.h"

namespace rtu {

// A temporary folder, removed with everything in it when this goes out of scope.
struct TempFolder {
    std::filesystem::path path;
    explicit TempFolder(const char* what);
    ~TempFolder();
    TempFolder(const TempFolder&) = delete;
    TempFolder& operator=(const TempFolder&) = delete;
};

// Runs rtsim itself with `args`, its standard error into the file `err`; throws, with that error
// text, if it does not exit 0 (InputError for its exit status 2).
void run_child(std::vector<std::string> args, const std::string& err, const std::string& what);

// run_child in `fidelity` (`quantum`: LT's, passed on), its statistics and standard error written
// into `dir` as NAME.json and NAME.err; returns the statistics.
nlohmann::json run_child_stats(std::vector<std::string> args, const std::string& fidelity, std::optional<uint64_t> quantum,
                               const std::filesystem::path& dir, const std::string& name, const std::string& what);

// --check-error: the frame sampled at `rate` with `sample_seed` (the same clusters, the same
// functional warming, one pre-pass through a plan in the check's temporary folder), once in
// `fidelity` and once in AT; the sample's cycles, their strata paired, and the times. `quantum`:
// LT's, passed on. `run_s`: the wall time of the run being checked (the whole frame in
// `fidelity`; 0: any cost, --check-error-any-cost). Throws CheckRefused before AT's run where the
// fidelity's took half of that or more: AT's sample would then cost about as much as AT's full
// run (ErrorCheck).
ErrorCheck run_error_check(const std::vector<std::string>& frame_args, const std::string& fidelity, std::optional<uint64_t> quantum,
                           double rate, uint64_t sample_seed, double run_s, bool quiet);

// --sample-width: the pilot sample, the frame sampled at `rate` with `sample_seed` in `fidelity`
// (`quantum`: LT's), writing or reading the run's plan `plan`, without the check on its strata
// (--sample-unchecked: the caller reads them). Returns its statistics' timing.sampling, with the
// frame's estimate added as "cycles" and its wall time as "pilot_s". Throws InputError for what the child refused.
nlohmann::json run_width_pilot(const std::vector<std::string>& frame_args, const std::string& fidelity, std::optional<uint64_t> quantum,
                               double rate, uint64_t sample_seed, const std::string& plan, bool quiet);

// --sample-segments K without --segment: each segment simulated by a child rtsim, up to `threads`
// at once (each child given threads / that many threads), and their statistics read back in
// segment order for the merge (the same files an array of cluster tasks would write, so the
// estimate is the same, bit for bit, for any `threads`). The first segment writes the frame's
// plan (`plan`) after its pre-pass; the others start when that file exists (`plan` empty: when
// the first ends), so the frame is traced once. `segment_args`: the frame's and the sample's
// options. A stop requested ends it (Interrupted); a child that fails ends the others (SIGTERM)
// and its error is thrown.
std::vector<SegmentRun> run_segment_children(const std::vector<std::string>& segment_args, uint32_t segments, unsigned threads,
                                             const std::string& plan, const StopRequest& stop, bool quiet);

// A double as rtsim reads it back exactly.
std::string exact(double v);

}  // namespace rtu
