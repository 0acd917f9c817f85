// The statistics every timing fidelity reports (RT unit, pop streaks, L1, L2, prefetch, DRAM,
// energy), from counters summed over the hierarchy's modules.
#pragma once
#include <chrono>

#include <nlohmann/json.hpp>

#include "model/config.h"
#include "model/dram.h"
#include "model/rt_unit_core.h"
#include "model/sector_cache.h"
#include "workloads/workload_driver.h"

namespace rtu {

void add(CacheStats& a, const CacheStats& b);
void add(RtUnitStats& a, const RtUnitStats& b);

struct HierarchyCounts {
    RtUnitStats rt;
    CacheStats l1[kReqKinds], l2[kReqKinds];  // summed over the SMs' L1s / the L2 slices
    DramStats dram;
    uint64_t cycles_simulated;
    double core_period_fs;
    double memory_cycles;  // of the simulated time
};

// Adds rt_unit, pop_streak, l1, l2, prefetch, dram and energy to `j`. `energy_scale`: the frame's
// work over the simulated work (1 unless sampled).
void hierarchy_json(nlohmann::ordered_json& j, const HwConfig& cfg, const HierarchyCounts& h,
                    const WorkloadDriver::RaySummary& sum, double energy_scale);

// Adds `sampling` to `j` for a sampled run: the estimate of the frame's `cycles` with its 95 %
// interval and every ingredient of the estimate (docs/sampling.md).
void sampling_json(nlohmann::ordered_json& j, const WorkloadDriver::Estimate& est, double rate, uint64_t cycles,
                   uint64_t cycles_simulated);

// A timing run's progress on stderr, at most every 2 s: cycle, rays retired, share of pixel warps
// done, rays/s and an estimate of the time left.
class TimingProgress {
public:
    explicit TimingProgress(bool enabled) : enabled_(enabled) {}
    void update(uint64_t cycle, const WorkloadDriver& driver);
    // Ends the progress line, if one was printed.
    void finish();

private:
    bool enabled_, printed_ = false;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_print_ = start_;
};

}  // namespace rtu
