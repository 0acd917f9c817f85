// What feeds an RT unit: traces (one ray per thread of a shader warp) come from a trace source
// when the unit has a free warp-buffer slot, and their rays go back to it when the trace leaves
// the unit. The workload driver (workloads/workload_driver.h) is the trace source of rtsim; an
// SoC peripheral would be another. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "ray.h"

namespace rtu {

// One ray handed to the RT unit: the direction is already rescaled (scale_direction), `key`
// identifies it to the trace source.
struct WarpRay {
    Ray ray;
    int scale = 0;
    uint64_t key = 0;
};

struct RetiredRay {
    uint64_t key;
    Hit hit;  // t in the rescaled units (the trace source undoes the scaling)
    uint32_t nodes_visited;
    uint32_t l1_miss_nodes = 0, dram_nodes = 0;  // of its node fetches: not served by L1 / served by DRAM
    // Procedural leaves it reached: the candidates its shader code tests after the trace, one
    // intersection shader call each (the TTP authors' simulator records one intersection-table
    // entry per procedural leaf, vulkan_ray_tracing.cc l.2198-2199, and never culls by them).
    uint32_t candidates = 0;
};

class TraceSource {
public:
    virtual ~TraceSource() = default;
    // The next trace for SM `sm` that is ready by cycle `now`, or nothing.
    virtual std::optional<std::vector<WarpRay>> next_trace(uint32_t sm, uint64_t now) = 0;
    // The earliest cycle a trace for SM `sm` becomes ready (~0: none waiting).
    virtual uint64_t earliest_ready(uint32_t sm) const = 0;
    // The rays of one trace of SM `sm` left the RT unit at cycle `now`.
    virtual void retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now) = 0;
};

}  // namespace rtu
