// The sample design's bias bound compiled into the program (scripts/sampling_bias.py over the
// sampling grids; platforms/configs/sampling_bias.json): per workload kind, the largest bias
// beyond the draws' noise that a cell of the grids showed. It widens every sampled interval
// (SampleEstimate::design_bias). Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <string>

namespace rtu {

// A fraction as a percentage for messages: 0.0352 -> "3.5 %", 0.25 -> "25 %" (two significant
// digits below 10 %, three above).
std::string percent_text(double fraction);

struct SamplingBias {
    struct Kind {
        double value = 0;   // relative
        std::string cell;   // where it was measured
        uint64_t cells = 0, runs = 0;
    };
    std::string measured_on;
    Kind primary, other;  // primary rays; every other workload (measured on path tracing)
    // The bound for `workload` (primary, pt, ao, sh; a ray file: empty), and what it rests on.
    // ao, sh and ray files were not measured: the larger of the two kinds.
    double value(const std::string& workload) const { return of(workload).value; }
    std::string basis(const std::string& workload) const;
    static SamplingBias parse(const std::string& json);
    static const SamplingBias& built_in();

private:
    const Kind& of(const std::string& workload) const;  // the kind whose bound `workload` takes
};

}  // namespace rtu
