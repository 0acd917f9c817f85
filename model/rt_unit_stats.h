// The RT unit's counters, the same for every fidelity. Plain C++.
#pragma once
#include <array>
#include <cstdint>

#include "pop_streak.h"

namespace rtu {

enum class ThreadStatus : uint8_t { Idle, WaitSchedule, WaitMemory, InMath, Count };

struct RtUnitStats {
    uint64_t warps = 0, rays = 0, node_fetches = 0, chunk_requests = 0, coalesced = 0, responses = 0;
    std::array<uint64_t, size_t(ThreadStatus::Count)> thread_cycles{};  // summed over thread slots
    // Pop-streak classes 0 (not a pop: first child taken next / root), 1st, 2nd, 3rd, 4th+.
    std::array<uint64_t, PopStreak::kClasses> streak_fetches{}, streak_l1_misses{}, streak_dram_misses{};
    uint64_t max_response_fifo = 0, max_request_queue = 0;
    uint64_t prefetches_generated = 0, prefetch_duplicates = 0, prefetches_sent = 0, prefetch_responses = 0;
    uint64_t prefetches_expired = 0;  // dropped unsent at their deadline
    uint64_t perfect_hits = 0;  // chunk fetches answered as L1 hits by a perfect-up/down limit study
};

}  // namespace rtu
