// The statistics every timing fidelity reports (RT unit, pop streaks, L1, L2, prefetch, DRAM,
// energy, sampling), written from the counter groups (model/stats.h) with per-instance values
// beside the totals, and derived figures with their units.
#pragma once
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "model/config.h"
#include "model/dram.h"
#include "model/rt_unit_stats.h"
#include "model/sector_cache.h"
#include "model/stats.h"
#include "sampling/estimator.h"
#include "sampling/width.h"
#include "workloads/workload_driver.h"

namespace rtu {

// Counters of a timing run, per instance.
struct HierarchyCounts {
    std::vector<RtUnitStats> rt;  // per SM
    std::vector<CacheCounts> l1;  // per SM
    std::vector<CacheCounts> l2;  // per L2 slice
    std::vector<DramStats> dram;  // per DRAM channel
    uint64_t cycles_simulated = 0;
    double core_period_fs = 0;
    double memory_cycles = 0;  // of the simulated time
};

// Checks that must hold of any finished run's counters (cache lookups add up, every request was
// answered, node reads agree with the rays' traversal); returns what does not.
std::vector<std::string> counter_invariants(const HierarchyCounts& h, const WorkloadDriver::RaySummary& sum);

// rt_unit, l1, l2, prefetch, dram and energy. `energy_scale`: the frame's work over the
// simulated work (1 unless sampled).
void write_hierarchy(StatsOut& out, const HwConfig& cfg, const HierarchyCounts& h, const WorkloadDriver::RaySummary& sum,
                     double energy_scale);

// A sampled run's estimate of the frame's `cycles` with its 95 % interval and every ingredient of
// the estimate (docs/sampling.md).
// `width`: what --sample-width planned (null: not asked).
void write_sampling(StatsOut& out, const SampleEstimate& est, double rate, uint64_t cycles, uint64_t cycles_simulated,
                    const SampleWidth* width = nullptr);

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
