// Sampled simulation's model-level pieces: the schedule model that carries the sample's trace
// durations to the whole frame, and functional cache warming. Checked against hand-worked cases.
#include <gtest/gtest.h>

#include "model/config.h"
#include "model/sector_cache.h"
#include "model/trace_schedule.h"

using namespace rtu;

// One RT unit with one slot, shading 10 cycles between a warp's traces:
//   cycle 0: warp 0 trace 0 starts (ties go to the earlier warp), leaves at 5; warp 0 ready at 15
//   cycle 5: warp 1 (ready since 0) starts, leaves at 8
//   cycle 15: warp 0 trace 1 starts, leaves at 20.
TEST(ScheduleModel, OneSlotHandWorked) {
    EXPECT_DOUBLE_EQ(schedule_cycles({{5, 5}, {3}}, {1, 1, 10}), 20.0);
    // Without shading, warp 0's second trace is ready at 5 together with the slot, but warp 1
    // has waited since 0: it goes first (5..8), then warp 0 (8..13).
    EXPECT_DOUBLE_EQ(schedule_cycles({{5, 5}, {3}}, {1, 1, 0}), 13.0);
}

// Warps go to SMs round robin (0, 2 -> SM 0; 1 -> SM 1); each SM's slots work in parallel and
// the frame ends with the slowest SM.
TEST(ScheduleModel, RoundRobinSmsAndParallelSlots) {
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}}, {2, 2, 0}), 10.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}}, {2, 1, 0}), 10.0);   // SM 0: 4 then 6
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {1}, {7}}, {2, 1, 0}), 11.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({}, {8, 4, 100}), 0.0);
    EXPECT_THROW(schedule_cycles({{1}}, {0, 4, 0}), std::invalid_argument);
}

// Conservation: with one RT unit, one slot and no shading the slot never idles, so the frame
// takes exactly the sum of all durations, in any order of warps.
TEST(ScheduleModel, OneBusySlotTakesTheSumOfAllWork) {
    std::vector<std::vector<double>> t;
    double sum = 0;
    for (int w = 0; w < 50; ++w) {
        t.emplace_back();
        for (int k = 0; k <= w % 7; ++k) {
            t.back().push_back(double((w * 37 + k * 11) % 23 + 1));
            sum += t.back().back();
        }
    }
    EXPECT_DOUBLE_EQ(schedule_cycles(t, {1, 1, 0}), sum);
}

// Warming makes sectors valid without counting anything, evicts by LRU like a read, and leaves
// sectors being fetched (and sets with every way pending) alone.
TEST(SectorCacheWarm, ValidatesWithoutStatisticsAndRespectsPending) {
    SectorCache c(CacheConfig{512, 2, 128, 32, 2, 2, 0});  // 2 sets x 2 ways, 2 MSHRs
    EXPECT_FALSE(c.warm(0x000));
    EXPECT_TRUE(c.warm(0x010));  // same sector
    EXPECT_EQ(c.stats(ReqKind::Demand).accesses + c.stats(ReqKind::Prefetch).accesses, 0u);
    EXPECT_EQ(c.read(0x000, 1, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x020, 2, ReqKind::Demand), CacheOutcome::SectorMiss);  // line 0 there, sector 1 not
    EXPECT_FALSE(c.warm(0x020));  // pending: left to its fetch
    EXPECT_EQ(c.fill(0x020), (SectorCache::Tokens{2}));
    // Set 0 gets 0x100 in its free way; warming 0x200 then evicts line 0, least recently used.
    EXPECT_FALSE(c.warm(0x100));
    EXPECT_FALSE(c.warm(0x200));
    EXPECT_EQ(c.read(0x100, 3, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x200, 4, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x000, 5, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x100 (LRU)
    EXPECT_EQ(c.read(0x300, 6, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x200
    // Set 0 now has two pending lines: warming finds no way and changes nothing.
    EXPECT_FALSE(c.warm(0x100));
    EXPECT_EQ(c.fill(0x000), (SectorCache::Tokens{5}));
    EXPECT_EQ(c.read(0x100, 7, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_EQ(c.stats(ReqKind::Demand).evictions + c.stats(ReqKind::Prefetch).evictions, 3u);  // the reads' (0x100, 0x200, line 0), not the warming's
}
