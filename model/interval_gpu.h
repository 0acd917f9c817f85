// The interval fidelity's GPU (docs/interval.md): the RT units' timing computed one whole trace
// at a time instead of cycle by cycle. Each thread of the trace walks its ray through the BVH
// image (the same execution-driven traversal as AT and LT); every node fetch books the RT unit's
// request port (one 32 B chunk per cycle), reads the L1, and on a miss the L2 slice and the DRAM;
// the response FIFO drains one chunk per cycle; the node's tests take their math latency. The
// thread's next fetch is scheduled when they end, and the trace leaves when its slowest thread is
// done. Threads of a trace that fetch the same node in the same cycle share one fetch (intra-warp
// coalescing). TTP (DFS and BFS) prefetches on pops, as in AT.
//
// Shared resources are booked by timestamp (PortCalendar, DramBookings), so traces may be timed
// in the order they start rather than in global time order; cache tags change in that order and
// each sector remembers the cycle its data arrives (a later read before then waits for it, as an
// MSHR merge would). MSHR counts are kept (a miss waits for a free one, as in LT). Not modelled,
// against AT: the warp scheduler's one-warp-per-cycle choice, MSHR merge limits, the DRAM's
// request queue and FR-FCFS reordering.
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <queue>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "bvh_image.h"
#include "calendar.h"
#include "config.h"
#include "dram.h"
#include "rt_unit_core.h"
#include "sector_cache.h"
#include "traversal.h"

namespace rtu {

class IntervalGpu {
public:
    // Throws std::invalid_argument for what the fidelity does not model: treelet traversal and
    // prefetchers other than none and TTP.
    IntervalGpu(const HwConfig& cfg, const BvhImage& image, TraversalOrder order);

    // Times one trace (at most warp_size rays) of SM `sm` that enters a warp-buffer slot at cycle
    // `start`; appends its rays to `retired` and returns the cycle its last thread finishes.
    // Calls must come in non-decreasing `start` order (see advance()).
    uint64_t trace(uint32_t sm, const std::vector<WarpRay>& rays, uint64_t start, std::vector<RetiredRay>& retired);

    // RT-unit statistics summed over the SMs (thread_cycles: WaitMemory from a fetch's
    // scheduling to its data, InMath, and Idle for finished threads waiting for their trace).
    const RtUnitStats& rt_stats() const { return rt_; }
    const std::vector<SectorCache>& l1() const { return l1_; }
    const std::vector<SectorCache>& l2() const { return l2_; }
    DramStats dram_stats() const { return dram_.total(); }
    uint64_t memory_cycle(uint64_t core_cycle) const;  // the memory-clock cycle at or after a core cycle

private:
    struct Served {
        uint64_t at;  // core cycle the chunk's data is at the RT unit
        bool l1_miss, dram;
    };
    struct Ready {  // a sector's miss left at `sent` and its data arrives at `at`; `dram`: from DRAM
        uint64_t sent, at;
        bool dram;
    };
    struct ReadyMap {
        absl::flat_hash_map<uint64_t, Ready> at;
        size_t prune_above = 0;  // size that triggers the next prune
        // Cycles the cache's MSHRs in use free up (as LT: a miss waits for a free one).
        std::priority_queue<uint64_t, std::vector<uint64_t>, std::greater<uint64_t>> mshr_free;
    };
    // The cycle at or after `c` a miss of cache `tags` gets an MSHR (counting a reservation fail
    // if it had to wait).
    static uint64_t mshr_slot(ReadyMap& m, SectorCache& tags, uint32_t mshrs, uint64_t c, ReqKind kind);
    Served read(uint32_t sm, uint64_t addr, uint64_t cycle, ReqKind kind);
    Ready read_l2(uint64_t addr, uint64_t cycle, ReqKind kind);
    void advance(uint64_t floor);
    uint64_t core_cycle(uint64_t memory_cycle) const;  // the core cycle at or after a memory cycle
    void remember(ReadyMap& m, uint64_t sector, Ready r, size_t lines);
    // A read at `cycle` of a sector the tags hold: its data arrives at the returned cycle, or
    // ~0 when it was there already. A read timestamped before the sector's miss left takes the
    // miss over (it would have been the one to miss, and the later read the one to merge).
    static uint64_t arrival(ReadyMap& m, uint64_t sector, uint64_t cycle, bool* dram);

    HwConfig cfg_;
    const BvhImage& image_;
    TraversalOrder order_;
    uint64_t core_fs_, memory_fs_;  // clock periods in femtoseconds, as the SystemC clocks
    std::vector<PortCalendar> issue_, drain_;  // per SM: request port, response FIFO
    std::vector<PortCalendar> prefetch_;       // per SM: the prefetch queue's one chunk per cycle
    std::vector<PortCalendar> l2_port_;        // per L2 slice: one lookup per cycle
    std::vector<SectorCache> l1_, l2_;
    std::vector<ReadyMap> l1_ready_, l2_ready_;
    std::vector<ReadyMap> prefetch_queue_;     // per SM: prefetch chunks by the cycle they leave
    DramBookings dram_;
    uint64_t floor_ = 0, token_ = 0;
    RtUnitStats rt_;

    // Per trace, reused.
    struct Thread {
        TraversalThread trav;
        uint64_t ready = 0;  // cycle its next fetch is scheduled
        uint8_t streak = 0;
        uint32_t l1_miss_nodes = 0, dram_nodes = 0;
        TtpDfs ttp_dfs;
        TtpBfs ttp_bfs;
    };
    struct Fetch {  // a node fetch of the current trace, for coalescing
        uint64_t done;  // cycle its last chunk drained
        bool l1_miss, dram;
    };
    std::vector<Thread> threads_;
    std::vector<uint32_t> live_, next_live_;
    // The current trace's node fetches by (node address, cycle scheduled).
    absl::flat_hash_map<std::pair<uint64_t, uint64_t>, Fetch> fetches_;
    std::vector<size_t> picks_;
};

}  // namespace rtu
