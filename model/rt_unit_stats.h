// The RT unit's counters (statistics group "rt_unit", per SM), the same for every fidelity.
// Plain C++.
#pragma once
#include <cstdint>

#include "pop_streak.h"
#include "stats.h"

namespace rtu {

enum class ThreadStatus : uint8_t { Idle, WaitSchedule, WaitMemory, InMath, Count };

// Thread slots' cycles by status (paper Figure 1), summed over the warp buffer's thread slots
// while their warp is resident.
struct ThreadCycles {
    uint64_t waiting_to_be_scheduled = 0, waiting_on_memory = 0, in_math = 0, done_waiting_for_warp = 0;
    uint64_t& operator[](ThreadStatus s) { return this->*kByStatus[size_t(s)]; }
    uint64_t total() const { return waiting_to_be_scheduled + waiting_on_memory + in_math + done_waiting_for_warp; }
    static constexpr uint64_t ThreadCycles::*kByStatus[] = {&ThreadCycles::done_waiting_for_warp, &ThreadCycles::waiting_to_be_scheduled,
                                                          &ThreadCycles::waiting_on_memory, &ThreadCycles::in_math};
    static constexpr Counter<ThreadCycles> kCounters[] = {
        {"waiting_to_be_scheduled", &ThreadCycles::waiting_to_be_scheduled, "thread-cycles", "ready for its next node read, waiting for the warp scheduler"},
        {"waiting_on_memory", &ThreadCycles::waiting_on_memory, "thread-cycles", "node read sent, waiting for all of its chunks"},
        {"in_math", &ThreadCycles::in_math, "thread-cycles", "in the math pipelines (the node's tests)"},
        {"done_waiting_for_warp", &ThreadCycles::done_waiting_for_warp, "thread-cycles", "traversal done, waiting for the warp's other threads"},
    };
};

// The prefetch queue (model/prefetch_queue.h): what the prefetcher picked and what became of it.
struct PrefetchQueueCounts {
    uint64_t window_dropped = 0, generated = 0, duplicates_dropped = 0, full_dropped = 0, removed_by_demand = 0, sent = 0, expired_unsent = 0, answered = 0;
    static constexpr Counter<PrefetchQueueCounts> kCounters[] = {
        {"window_dropped", &PrefetchQueueCounts::window_dropped, "nodes", "TTP picks of a node among the thread's last prefetch.thread_window prefetches: dropped before the queue"},
        {"generated", &PrefetchQueueCounts::generated, "chunks", "32 B prefetch chunks the prefetcher picked"},
        {"duplicates_dropped", &PrefetchQueueCounts::duplicates_dropped, "chunks", "picked while the same chunk waited in the queue: dropped"},
        {"full_dropped", &PrefetchQueueCounts::full_dropped, "chunks", "picked while the queue was full (prefetch.queue): dropped"},
        {"removed_by_demand", &PrefetchQueueCounts::removed_by_demand, "chunks", "taken out of the queue unsent because a demand read of the same chunk left"},
        {"sent", &PrefetchQueueCounts::sent, "requests", "prefetch requests sent to the L1"},
        {"expired_unsent", &PrefetchQueueCounts::expired_unsent, "chunks", "dropped unsent at their deadline (Park: the end of the leaf test)"},
        {"answered", &PrefetchQueueCounts::answered, "responses", "prefetch responses (the RT unit drops them: the data is in the caches)"},
    };
};

// Node reads by pop-streak class (model/pop_streak.h; paper Figure 'pop_miss_rates').
struct PopStreakCounts {
    uint64_t node_fetches = 0, l1_misses = 0, dram_misses = 0;
    static constexpr Counter<PopStreakCounts> kCounters[] = {
        {"node_fetches", &PopStreakCounts::node_fetches, "node reads", "node reads of this class"},
        {"l1_misses", &PopStreakCounts::l1_misses, "node reads", "of them, not served by L1 (some chunk missed)"},
        {"dram_misses", &PopStreakCounts::dram_misses, "node reads", "of them, served by DRAM (some chunk missed L1 and L2)"},
    };
};

struct PopStreakStats {
    PopStreakCounts not_a_pop, pop_1, pop_2, pop_3, pop_4_or_more;
    PopStreakCounts& operator[](int c) { return this->*kByClass[c]; }
    const PopStreakCounts& operator[](int c) const { return this->*kByClass[c]; }
    static constexpr PopStreakCounts PopStreakStats::*kByClass[PopStreak::kClasses] = {
        &PopStreakStats::not_a_pop, &PopStreakStats::pop_1, &PopStreakStats::pop_2, &PopStreakStats::pop_3, &PopStreakStats::pop_4_or_more};
    static constexpr bool kParts = true;
    template <class F>
    static void parts(F&& f) {
        f("not_a_pop", &PopStreakStats::not_a_pop, "node reads that are not a pop: the root (or the next-node register)");
        f("pop_1", &PopStreakStats::pop_1, "first pops after a push (downward traversal)");
        f("pop_2", &PopStreakStats::pop_2, "second consecutive pops (upward or same-level traversal)");
        f("pop_3", &PopStreakStats::pop_3, "third consecutive pops");
        f("pop_4_or_more", &PopStreakStats::pop_4_or_more, "fourth and later consecutive pops");
    }
};

struct RtUnitStats {
    uint64_t warps = 0, rays = 0, node_fetches = 0, chunk_requests = 0, coalesced_fetches = 0, merged_in_flight = 0, responses = 0;
    uint64_t limit_study_hits = 0, max_response_fifo = 0, max_memory_access_queue = 0;
    uint64_t l1_misses_with_next_queued = 0;
    uint64_t header_fetches = 0, header_l1_misses = 0;
    uint64_t shader_reads = 0;
    uint64_t intersection_candidates = 0, intersection_loop_iterations = 0;
    ThreadCycles thread_cycles;
    PrefetchQueueCounts prefetch_queue;
    PopStreakStats pop_streak;

    static constexpr Counter<RtUnitStats> kCounters[] = {
        {"warps", &RtUnitStats::warps, "traces", "traces (a shader warp's trace_ray) taken into the warp buffer"},
        {"rays", &RtUnitStats::rays, "rays", "rays taken into the warp buffer"},
        {"node_fetches", &RtUnitStats::node_fetches, "node reads", "node reads of all threads (coalesced ones included)"},
        {"header_fetches", &RtUnitStats::header_fetches, "header reads",
         "64 B BVH header reads: the TLAS's at each ray's start and a BLAS's after each instance leaf (not node reads, not pops)"},
        {"header_l1_misses", &RtUnitStats::header_l1_misses, "header reads", "of them, not served by L1"},
        {"chunk_requests", &RtUnitStats::chunk_requests, "requests", "32 B demand requests of node reads (sent to L1, or answered by a limit study)"},
        {"coalesced_fetches", &RtUnitStats::coalesced_fetches, "node reads", "node reads that shared another thread's read of the same node in one scheduling (intra-warp coalescing)"},
        {"merged_in_flight", &RtUnitStats::merged_in_flight, "chunks", "32 B chunks of node reads not requested because the warp had the same chunk queued or in flight (rt.merge_in_flight)"},
        {"responses", &RtUnitStats::responses, "responses", "demand responses drained from the response FIFO"},
        {"shader_reads", &RtUnitStats::shader_reads, "sectors", "32 B sectors the SM's shader code read after this unit's traces (workload.shader_reads), through the L1's shader port"},
        {"intersection_candidates", &RtUnitStats::intersection_candidates, "leaves",
         "procedural leaves the rays reached: each an intersection shader call after the trace (RetiredRay::candidates)"},
        {"intersection_loop_iterations", &RtUnitStats::intersection_loop_iterations, "iterations",
         "the traces' intersection loops: per trace, the candidates of its ray with the most (workload.intersection_latency cycles each)"},
        {"limit_study_hits", &RtUnitStats::limit_study_hits, "requests", "32 B demand requests answered as L1 hits by a perfect-up/down limit study"},
        {"l1_misses_with_next_queued", &RtUnitStats::l1_misses_with_next_queued, "node reads",
         "pops whose node read missed L1 while the thread's stack (BFS: queue) still held a node after the pop: with BFS an accurate prefetch could follow (paper Figure 'bfs_trend')"},
        {"max_response_fifo", &RtUnitStats::max_response_fifo, "entries", "most responses (prefetches' included) waiting in the response FIFO at once", Merge::Max},
        {"max_memory_access_queue", &RtUnitStats::max_memory_access_queue, "requests", "most demand requests waiting in the memory access queue at once", Merge::Max},
    };
    static constexpr bool kParts = true;
    template <class F>
    static void parts(F&& f) {
        f("thread_cycles", &RtUnitStats::thread_cycles, "thread slots' cycles by status");
        f("prefetch_queue", &RtUnitStats::prefetch_queue, "the prefetch queue's chunks");
        f("pop_streak", &RtUnitStats::pop_streak, "node reads by pop-streak class");
    }
};

}  // namespace rtu
