// rtsim's command line: the options (Args), their table and help, and the run's specification
// made from them (the first stage of a run, docs/usage.md), every check that needs no scene first.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "simulation.h"

namespace rtu {

// The cores this process may run on (its CPU affinity mask; at least 1).
unsigned usable_cores();

struct Args {
    std::string scene = "wknd", assets, workload = "pt", rays, hits, traversal = "dfs", fidelity = "functional";
    std::string stats, image, config = "mobile", vcd, trace_warp, prefetcher, timeline;
    std::string dump_bvh, dump_rays, dump_hits;
    std::vector<std::string> sets;
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1;
    std::optional<uint64_t> quantum;  // LT's quantum (given, even as 0, or not)
    double sample = 1.0;
    std::optional<uint64_t> sample_seed;  // which clusters a sampled run simulates (default: --seed)
    bool sample_unchecked = false;
    uint64_t check_error = 0;  // --check-error N
    bool check_error_any_cost = false;  // --check-error-any-cost
    long long sample_segments = 1;  // --sample-segments K (signed: a negative number is an error, not a wrap)
    std::optional<uint64_t> segment;  // --segment I
    std::vector<std::string> merge_segments;  // --merge-segments FILE...
    std::string sample_plan;  // --sample-plan FILE
    std::optional<double> sample_width;  // --sample-width W: the 95 % half-width asked, in percent
    // Threads of the functional work (the functional pass, --verify's checks, the sampling
    // pre-pass); default: the cores this process may run on. Read as signed so that a negative
    // number is an error, not a wrap to 4 billion.
    long long threads = usable_cores();
    std::vector<std::string> stray;  // arguments that are no option's
    std::vector<std::string> command_line;  // argv as given, for the statistics' provenance
    bool verify = false, quiet = false, flatten = false;
};

// Reads the command line into `a`. Returns the exit status when rtsim is done without a run
// (--help, --version, --stats-schema: 0; no arguments or a malformed option: 2, said on stderr), else
// nothing.
std::optional<int> parse_command_line(int argc, char** argv, Args& a);

// The run's specification; throws InputError for what is wrong with the options. `stop`: the
// process's stop flag (SIGINT, SIGTERM), also checked between child runs.
RunSpec spec_of(const Args& a, const std::atomic<int>* stop);

// The frame, workload and configuration options of the run, for a child rtsim.
std::vector<std::string> frame_args(const Args& a);

}  // namespace rtu
