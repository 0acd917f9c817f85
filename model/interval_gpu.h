// The interval fidelity's GPU (docs/interval.md): the RT units' timing with one event per node
// fetch instead of cycle stepping. Each thread walks its ray through the BVH image (the same
// execution-driven traversal as AT and LT). Its node fetch, taken at the cycle it is scheduled,
// books the RT unit's request port (one 32 B chunk per cycle), reads the L1, and on a miss the
// L2 slice and the DRAM; the response FIFO drains one chunk per cycle; the node's tests take
// their math latency, and the thread's next fetch is scheduled when they end. All of that is
// worked out at once, so the time between two fetches of a thread costs nothing to simulate.
// A trace leaves its warp-buffer slot when its slowest thread is done. Threads of a trace that
// fetch the same node in the same cycle share one fetch (intra-warp coalescing). The threads,
// their pop streaks, the prefetcher's hooks and the prefetch queue are the RT unit's own
// (model/rt_thread.h, model/prefetcher.h, model/prefetch_queue.h): TTP (DFS and BFS) prefetches on
// pops, as in AT.
//
// Fetches run in the order they are scheduled, across all traces. Shared resources are booked
// by timestamp (PortCalendar, DramBookings), since a fetch books cycles after its own; each
// sector remembers the cycle its data arrives (a later read before then waits for it, as an
// MSHR merge would), and MSHR counts are kept (a miss waits for a free one, as in LT). An L1 read
// past the MSHR's merge limit is a reservation fail: it retries when the sector arrives, and the
// RT unit's request port is held until then (END_REQ withheld, as in AT). The response FIFO
// drains one chunk per cycle in the order the chunks arrive, as AT's: a chunk's drain cycle is
// booked once every chunk that can arrive before it is known (the cycle before it arrives; a
// fetch books its chunks from the cycle after its own), and the thread's next fetch is scheduled
// when its last chunk has drained. The warp scheduler picks
// one trace per SM and cycle, by rt.warp_scheduler (round robin over the warp-buffer slots, or
// oldest first); threads of the others wait a cycle. Not modelled, against AT: the L2's merge
// limit, the DRAM's request queue and FR-FCFS reordering.
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <queue>
#include <vector>

#include "bvh_image.h"
#include "cache_bookings.h"
#include "calendar.h"
#include "config.h"
#include "dram.h"
#include "event_wheel.h"
#include "node_fetch.h"
#include "prefetch_queue.h"
#include "prefetcher.h"
#include "rt_thread.h"
#include "rt_unit_core.h"
#include "sector_cache.h"
#include "shader_loads.h"
#include "traversal.h"

namespace rtu {

class IntervalGpu {
public:
    // Throws std::invalid_argument for what the fidelity does not model: treelet traversal and
    // prefetchers with hooks other than on_pop (Park, Treelet, the limit studies).
    IntervalGpu(const HwConfig& cfg, const BvhImage& image, TraversalOrder order);

    // A trace (at most warp_size rays) of SM `sm` enters a warp-buffer slot at cycle `start`;
    // its threads' first fetches are scheduled then. Not before next_event() (time order).
    struct Finished {
        uint32_t sm;
        uint64_t end;  // the cycle its last thread's last test ends
        std::vector<RetiredRay> rays;
    };
    void start_trace(uint32_t sm, const std::vector<WarpRay>& rays, uint64_t start, std::vector<Finished>& finished);
    // Functional warming before a sampled cluster (docs/sampling.md), as the AT and LT platforms
    // do it: the sector holding `addr` into SM `sm`'s L1, and into its L2 slice when the L1 did
    // not hold it (tags and LRU only, no statistics).
    void warm(uint32_t sm, uint64_t addr);
    // The shader code's loads after each trace (workload.shader_reads), as the AT and LT RT
    // units issue them (tlm/rt_unit.h): per_ray sectors per ray of a finished trace, of data no
    // cache holds, through the SM's L1 from the trace's end, one per cycle per SM.
    void set_shader_reads(const ShaderReads& reads);
    // The cycle of the next thing to run: the earliest scheduled node fetch, or the cycle before
    // a queued response may drain (~0: none).
    uint64_t next_event() const;
    // Runs that fetch: its chunks, the node's tests, and the thread's next fetch. A trace whose
    // last thread is done is appended to `finished`. `slot`: the cycle the next trace may start
    // (start_trace), ~0 if none is due.
    void run_next(std::vector<Finished>& finished, uint64_t slot = ~0ull);

    // RT-unit statistics per SM (thread_cycles: WaitMemory from a fetch's scheduling to its
    // data, InMath, and Idle for finished threads waiting for their trace).
    const std::vector<RtUnitStats>& rt_stats() const { return rt_; }
    const std::vector<CacheBookings>& l1() const { return l1_; }
    const std::vector<CacheBookings>& l2() const { return l2_; }
    const std::vector<DramStats>& dram_stats() const { return dram_.stats(); }  // per channel
    uint64_t memory_cycle(uint64_t core_cycle) const;  // the memory-clock cycle at or after a core cycle
    uint64_t core_period_fs() const { return core_fs_; }

private:
    struct Served {
        uint64_t at;  // core cycle the chunk's data is at the RT unit
        bool l1_miss, dram;
    };
    Served read(uint32_t sm, uint64_t addr, uint64_t cycle, ReqKind kind);
    Served read_l2(uint64_t addr, uint64_t cycle, ReqKind kind);  // l1_miss unused
    uint32_t slice_of(uint64_t addr) const;  // the L2 slice of an address, as the crossbar's
    void advance(uint64_t floor);
    uint64_t core_cycle(uint64_t memory_cycle) const;  // the core cycle at or after a memory cycle

    HwConfig cfg_;
    const BvhImage& image_;
    TraversalOrder order_;
    uint64_t core_fs_, memory_fs_;  // clock periods in femtoseconds, as the SystemC clocks
    std::vector<PortCalendar> issue_, drain_;  // per SM: request port, response FIFO
    std::vector<CacheBookings> l1_, l2_;       // per SM / per L2 slice
    // Per SM, the prefetch queue and whether its issue event is scheduled.
    struct SmPrefetchQueue {
        PrefetchQueue chunks;
        bool scheduled = false;
    };
    std::vector<SmPrefetchQueue> prefetch_queue_;
    std::unique_ptr<Prefetcher> prefetcher_;
    // The prefetcher's picks go into an SM's prefetch queue as chunks.
    struct Sink : PrefetchSink {
        explicit Sink(IntervalGpu& g) : gpu(g) {}
        void prefetch(const StackEntry& node, uint64_t deadline) override;
        void window_drop() override { ++gpu.rt_[sm].prefetch_queue.window_dropped; }
        IntervalGpu& gpu;
        uint32_t sm = 0;
    };
    Sink sink_{*this};
    AddressMap map_;  // L2 slices and DRAM (model/address_map.h)
    DramBookings dram_;
    uint64_t floor_ = 0, ports_floor_ = 0;
    std::vector<RtUnitStats> rt_;  // per SM

    struct Thread {
        RtThread rt;
        uint64_t ready = 0;  // cycle its next fetch is scheduled; while it waits for a fetch, the cycle it was
        uint32_t after = 0;  // while it waits for a fetch: the cycles from the fetch's last drain to its next
        uint32_t next_waiting = 0;  // while it waits for a fetch: the next thread of the trace waiting for it
        uint8_t fetch_class = 0;           // pop-streak class of the node being read
        bool fetch_l1_miss = false, fetch_dram = false;
        bool descriptor_done = false;      // a two-step leaf read: the descriptor is read, the leaf is next
    };
    struct Trace {  // in a warp-buffer slot; reused
        uint32_t sm = 0, live = 0;  // live: threads not done
        uint64_t start = 0, end = 0;
        uint64_t age = 0;   // order of entry into a warp buffer (the warp scheduler's oldest first)
        uint32_t slot = 0;  // its warp-buffer slot (the scheduler's round robin)
        std::vector<Thread> threads;
        // rt.merge_in_flight: the trace's demand chunks in flight, by address: where each was
        // served and its response (`wait`, in chunk_waits_; a read scheduled before it drains joins
        // it). Fetches run in time order, so a chunk once drained is never joined again: each fetch
        // drops those first, which keeps the list as short as the trace's reads in flight (a map
        // of every chunk the trace read cost 15 % of party's run in host cache misses).
        struct Chunk {
            uint64_t addr;
            uint32_t wait;
            bool l1_miss, dram;
        };
        std::vector<Chunk> chunks;
    };
    // A thread's next node fetch, scheduled at `at`; or, with thread == kPrefetch, SM `trace`'s
    // prefetch queue trying to send its oldest chunk in cycle `at`; or, with thread == kShader,
    // SM `trace`'s shader port sending its next read in cycle `at`.
    static constexpr uint32_t kPrefetch = ~0u, kShader = ~0u - 1;
    struct Event {
        uint64_t at, seq;  // seq: scheduling order, for ties
        uint32_t trace, thread;
    };
    // A node fetch: the threads that share it (coalesced in its cycle, all of one trace) wait until
    // the last of its chunks' responses, its own and those it joined (rt.merge_in_flight), has
    // drained. Its threads in the order they joined it: first, then each Thread::next_waiting.
    static constexpr uint32_t kNone = ~0u;
    struct FetchWait {
        uint64_t done = 0;      // the latest drain cycle known so far
        uint32_t pending = 0;   // chunk responses not drained yet
        uint32_t trace = 0, first = kNone, last = kNone;
        bool l1_miss = false, dram = false;
        bool in_cycle = false;  // still in coalesced_ (its cycle's fetches); freed after both
    };
    // A demand chunk's response: the cycle it drained (~0: not yet), the fetch that sent it, and
    // the later fetches that joined it (a list in joins_).
    struct ChunkWait {
        uint64_t drained = ~0ull;
        uint32_t fetch = 0, joins = kNone;
    };
    struct Join {
        uint32_t fetch, next;
    };
    // A chunk's response queued for the response FIFO's drain: it may drain from cycle `at` (its
    // data is at the RT unit, at the earliest the cycle after it left), in the order of (at, the
    // order the chunks were sent in: seq). wait: its ChunkWait, or kNone for a prefetch's.
    struct Drain {
        uint64_t at, seq;
        uint32_t sm, wait;
    };
    void queue_drain(uint32_t sm, uint64_t at, uint32_t wait);
    void drain_until(uint64_t upto, std::vector<Finished>& finished);  // drains every response that may drain by `upto`
    void drain_ahead(uint64_t slot, std::vector<Finished>& finished);
    void drain_next(std::vector<Finished>& finished);  // the first response queued
    void run_cycle(std::vector<Finished>& finished);  // run_next less drain_ahead
    void fetched(uint32_t fetch, std::vector<Finished>& finished);     // a fetch's last chunk drained
    void thread_fetched(uint32_t trace, uint32_t thread, uint64_t done, std::vector<Finished>& finished);
    uint32_t new_fetch(uint64_t ready);
    uint32_t new_chunk_wait(uint32_t fetch);
    void free_chunk_wait(uint32_t c);
    void join(uint32_t chunk, uint32_t fetch);  // `fetch` waits for `chunk` too (rt.merge_in_flight)
    void finish(uint32_t trace, std::vector<Finished>& finished);
    void run_event(const Event& ev, std::vector<Finished>& finished);
    void send_prefetch(uint32_t sm, uint64_t cycle);
    void send_shader_read(uint32_t sm, uint64_t cycle);

    std::vector<Trace> traces_;
    std::vector<uint32_t> free_traces_;
    EventWheel<Event> events_;
    uint64_t next_seq_ = 0;
    // Fetches scheduled at coalesce_at_, by (trace, node address): their FetchWait.
    FetchCoalescer<std::pair<uint32_t, uint64_t>> coalescer_;
    std::vector<uint32_t> coalesced_;
    uint64_t coalesce_at_ = ~0ull;
    std::vector<FetchWait> fetch_waits_;
    std::vector<uint32_t> free_fetch_waits_;
    std::vector<ChunkWait> chunk_waits_;
    std::vector<uint32_t> free_chunk_waits_;
    std::vector<Join> joins_;
    std::vector<uint32_t> free_joins_;
    EventWheel<Drain> drains_;
    uint64_t next_drain_seq_ = 0;
    std::vector<uint64_t> sched_cycle_;   // per SM: the last cycle its warp scheduler picked a trace
    std::vector<uint32_t> sched_trace_;   // per SM: that trace
    std::vector<uint32_t> rr_next_;       // per SM, round robin: the slot the scheduler looks at first
    std::vector<std::vector<uint8_t>> slot_busy_;  // per SM and warp-buffer slot: holds a trace
    uint64_t next_age_ = 0;
    std::vector<Event> batch_;            // the events of one cycle, in the order the wheel gave them
    struct BatchOrder {                   // an event of batch_ and its place in the cycle (run_next)
        uint64_t scheduler, age;
        uint32_t index;
        bool operator<(const BatchOrder& o) const {
            return scheduler != o.scheduler ? scheduler < o.scheduler : age != o.age ? age < o.age : index < o.index;
        }
    };
    std::vector<BatchOrder> batch_order_;  // the order they run in
    // The shader reads (set_shader_reads): per SM, what is owed and the cycle its shader port is
    // free; empty: none.
    std::vector<ShaderLoads> shader_;
    std::vector<uint64_t> shader_free_;
};

}  // namespace rtu
