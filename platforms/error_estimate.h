// Every timing run's error against the AT reference (docs/accuracy.md), in one place: what kind
// of figure it is (AT itself, a sampling interval, a bound validated on the error grid, a
// measurement of this run's own frame) and what it rests on.
// - AT is the reference: error 0 (its error against hardware is the model's, not a fidelity's).
// - LT at its default quantum and the interval fidelity carry the worst |cycles error| that
//   scripts/bench_error_grid.py measured against AT on its grid of scenes, frames, presets and
//   workloads (platforms/configs/error_bounds.json, compiled in) wherever the run lies inside
//   that grid's regime; outside it there is no bound, and --check-error N measures one.
// - A sampled run adds its 95 % interval's relative half-width (docs/sampling.md).
// Plain C++ (no SystemC).
#pragma once
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sampling/estimator.h"

namespace rtu {

struct RunSpec;
struct TimingResult;

// --check-error N: the same clusters of the frame (a sample of N drawn strata and the first wave)
// simulated in the run's fidelity and in AT (child runs of rtsim; SystemC elaborates once per
// process). The error it states is the frame's RT-unit residence in the fidelity against AT, a
// ratio estimate paired by stratum, with its 95 % interval (paired_work_difference,
// sampling/estimator.h): the sample's own cycles are its makespan, which one SM's tail sets, and
// their ratio lay up to 14.1 % from the full runs' where the paired residence lay within 1.8 %
// (ship's path tracing at 256x256 under `paper`; docs/accuracy.md, "The check against the full
// runs").
struct ErrorCheck {
    uint64_t clusters = 0;  // clusters simulated, the first wave included
    double share = 0;       // of the frame's shader warps
    uint64_t fidelity_cycles = 0, at_cycles = 0;  // the sample's simulated cycles in each
    PairedDifference residence;                   // the fidelity against AT, paired by stratum
    double fidelity_s = 0, at_s = 0;  // wall-clock time of each child's simulation
    double wall_s = 0;                // of the whole check, both children from start to end
    double difference() const { return residence.difference; }
    // The largest |error| within the check's 95 % interval: what the error estimate takes.
    double bound() const { return std::abs(residence.difference) + residence.half_width; }
};

// --check-error refused after the run (child_runs.h): the run stands without a check.
struct CheckRefused : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct ErrorEstimate {
    std::optional<double> value;  // relative (0.02: the cycles within +-2 %); none: no estimate
    std::string kind;             // reference, interval, validated bound, measured, the sums of
                                  // interval and one of the latter two, or none
    std::string basis;            // what the value rests on
    std::optional<ErrorCheck> check;
};

// The validated bounds compiled into the program (the grid's regime and, per fidelity and
// workload, the mean and worst |error| against AT).
struct ErrorBounds {
    struct Bound {
        uint64_t runs = 0;
        double worst = 0;
        // Frame sizes added to the grid later (scripts/bench_error_grid.py, EXTEND), as
        // "512x512 added later: 5 scenes (mesh, ...), rtsim COMMIT": their own scenes and commit.
        std::vector<std::string> added;
        // Taken from the grid's frame sizes nearest the run's (false: over the whole grid).
        bool nearest = false;
    };
    std::string measured_on;
    // The commit a fidelity's bounds were measured on: its own where its whole grid was run again
    // after a change to it alone (scripts/bench_error_grid.py, REPLACE), else the file's.
    std::string measured_on_for(const std::string& fidelity) const;
    std::vector<std::string> scenes, configs;  // configs as NAME or NAME+PREFETCHER
    std::vector<int> primary_sizes, pt_sizes;  // square frames
    int spp = 2;
    nlohmann::json bounds;  // fidelity -> workload -> {runs, mean, worst, by_size: {side: {...}}}
    // The grid's frame sides for `workload`.
    const std::vector<int>& sizes(const std::string& workload) const { return workload == "primary" ? primary_sizes : pt_sizes; }
    // The side of the square frame with as many pixel samples at the grid's spp as `spec`'s frame.
    double side(const RunSpec& spec) const;
    // Over the whole grid; with `side`, the worst of the grid's frame sizes on either side of it
    // (one size on the grid's own). `scene` (rtsim's --scene): a size added later without a scene
    // of the grid does not bound that scene, which the whole grid's bound does then.
    std::optional<Bound> bound(const std::string& fidelity, const std::string& workload) const;
    std::optional<Bound> bound(const std::string& fidelity, const std::string& workload, double side,
                               const std::string& scene = "") const;
    static ErrorBounds parse(const std::string& json);
    static const ErrorBounds& built_in();
};

// Why the run lies outside the bounds' regime, or nothing when it lies inside.
std::optional<std::string> outside_regime(const RunSpec& spec, const ErrorBounds& bounds);

// The run's error estimate; `t` is its timing result (a timing fidelity's run).
// `check_refused`: why --check-error did not run its check (CheckRefused), or empty.
ErrorEstimate estimate_error(const RunSpec& spec, const TimingResult& t, const std::optional<ErrorCheck>& check,
                             const ErrorBounds& bounds = ErrorBounds::built_in(), const std::string& check_refused = "");

// One line for the run's summary: "error estimate: +-1.9 % (validated bound: ...)".
std::string error_line(const nlohmann::ordered_json& error_estimate_stats);

}  // namespace rtu
