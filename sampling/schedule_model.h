// The schedule model of sampled simulation (docs/sampling.md): how long a frame takes when each
// trace of a shader warp occupies one warp-buffer slot of its SM's RT unit for a known number of
// cycles. Shader warps are bound to SMs round robin in the order given; a warp's next trace is
// ready `shade` cycles after its previous one left the RT unit; an RT unit takes ready traces in
// order of readiness (ties: the earlier warp) into its earliest free slot. With `resident` > 0 an
// SM holds that many warps at once: the first sms x resident warps go round robin, and each later
// warp (in order) starts on the SM where a warp finished its last trace, when it finished. Memory contention is
// not modelled here: it is in the trace durations, which come from the detailed simulation.
// The first warps' first traces are ready at `first` (ShaderTiming::first), a later warp's
// `lead` cycles after it takes its place.
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <vector>

namespace rtu {

struct ScheduleShape {
    uint32_t sms = 1, slots = 1;  // RT units, warp-buffer slots per RT unit
    uint64_t shade = 0;           // cycles between a warp's traces
    uint32_t resident = 0;        // shader warps an SM holds at once (0: all of them from the start)
    uint64_t first = 0;           // the cycle the frame's first warps' first traces are ready
    uint64_t lead = 0;            // cycles a later warp (with `resident`) takes before its first trace
    // With `resident` only: shader code (`shade`, `lead`, and the `lead` in `first`) takes 1 +
    // contention x n times as long, n the other warps of the SM in shader code when it begins
    // (ShaderTiming::contended).
    double contention = 0;
};

// `traces[w]`: the durations, in cycles, of shader warp w's traces in order. Returns the cycle
// the last trace leaves its RT unit (0 for no traces).
double schedule_cycles(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape);
// The same run: per RT unit, the cycle its last trace leaves (0 for an RT unit without traces).
std::vector<double> schedule_sm_ends(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape);

}  // namespace rtu
