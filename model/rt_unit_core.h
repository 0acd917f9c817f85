// The RT unit's per-cycle logic (paper section 2.3; docs/paper-preset.md) for the AT and LT
// fidelities, independent of how time advances: the warp buffer of threads (model/rt_thread.h;
// plain data, never one process per thread), the warp scheduler (model/warp_scheduler.h), the
// memory access queue with the prefetch queue beside it (model/memory_access_queue.h), the
// response FIFO (model/response_fifo.h) and the math pipelines with their latencies. The
// prefetcher (model/prefetcher.h) watches through its hooks. Traversal decisions are made from
// the node bytes when they arrive (execution-driven).
// Each cycle: drain one response, finish the math that ends, and schedule one warp's reads; the
// caller sends the request the memory access queue offers (tlm/rt_unit.h, AT or LT).
// Plain C++ (no SystemC).
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <queue>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <absl/container/flat_hash_set.h>

#include "bvh_image.h"
#include "config.h"
#include "memory_access_queue.h"
#include "node_fetch.h"
#include "prefetcher.h"
#include "response_fifo.h"
#include "rt_thread.h"
#include "rt_unit_stats.h"
#include "trace_source.h"
#include "traversal.h"
#include "warp_scheduler.h"

namespace rtu {

// Cycles of a node's tests in the RT unit's math pipelines (at least 1). With
// `leaf_descriptor_read` the descriptor's latency belongs to the first of a leaf's two reads
// (model/node_fetch.h), and an instance leaf, read whole, costs its transform alone (the
// authors' INSTANCE_LEAF latency).
uint32_t rt_math_latency(const RtLatency& lat, const StepInfo& s, bool leaf_descriptor_read = false);

class RtUnitCore {
public:
    // `treelets` is needed for treelet traversal and the Treelet prefetcher (else may be null).
    RtUnitCore(const HwConfig& cfg, const BvhImage& image, TraversalOrder order, const Treelets* treelets = nullptr);

    bool has_free_slot() const;
    // Takes a warp (at most warp_size rays) into a free slot at cycle `now`.
    void accept_warp(const std::vector<WarpRay>& rays, uint64_t now);

    // One cycle at `now`: limit-study answers due, one response drained from the response FIFO,
    // the math that ends by now finished, and one warp's ready threads scheduled.
    void cycle(uint64_t now);

    // The memory access queue's request for this cycle (see MemoryAccessQueue): has_request drops
    // expired prefetches first; pop_request means it left.
    bool has_request(uint64_t now);
    const ChunkRequest& front_request(uint64_t now);
    void pop_request(uint64_t now);

    // A response for chunk `id` reached the RT unit; `l1_miss`/`dram` describe where it was
    // served. It enters the response FIFO, which must have room (takes_response), a prefetch's
    // as well: it takes its drain cycle and is then dropped (model/response_fifo.h).
    void on_response(uint64_t id, bool l1_miss, bool dram, uint64_t now);
    // Whether a response can come in now: while the response FIFO (rt.response_fifo entries) has
    // room; otherwise memory holds it back.
    bool takes_response() const { return !fifo_.full(); }

    // Rays of warps that finished since the last call.
    std::vector<RetiredRay> take_retired();
    size_t warps_resident() const;

    // The cycle of the next work with no further input: now + 1 while the response FIFO or a
    // ready thread has work; else the earliest math completion or limit-study answer; else ~0.
    uint64_t next_event(uint64_t now) const;
    bool idle() const;

    // Closes the thread-status accounting at `now` (call before reading stats).
    void account(uint64_t now);
    const RtUnitStats& stats() const { return stats_; }
    // The SM's shader code read a sector after a trace (workload.shader_reads; the RT unit's
    // module issues them, this counts them with the unit's statistics).
    void count_shader_read() { ++stats_.shader_reads; }
    const Prefetcher& prefetcher() const { return *prefetcher_; }
    uint32_t warp_buffer_occupancy() const;
    uint32_t active_threads() const;
    size_t response_fifo_depth() const { return fifo_.size(); }
    size_t memory_access_queue_depth() const { return maq_.depth(); }
    // Stack depth of thread t of slot w (for waveforms); -1 if empty slot.
    int stack_depth(uint32_t w, uint32_t t) const;
    // For the waveforms (reading them changes nothing): the warp-buffer slot the warp scheduler
    // picked in cycle `now` (-1: none), the slots holding a warp with ready threads, the chunks
    // waiting in the prefetch queue, and the TTP state machine of thread t of slot w (0 after a
    // push, 1..3 for S1..S3; BFS under the fixed policy: 0; -1 if empty slot).
    int picked_slot(uint64_t now) const { return picked_at_ == now ? picked_ : -1; }
    uint32_t ready_warps() const;
    size_t prefetch_queue_depth() const { return maq_.prefetches().size(); }
    int ttp_state(uint32_t w, uint32_t t) const;
    // For the timeline (reading it changes nothing): thread t of slot w's status (Idle for an
    // empty slot), the node it reads or last read, where its read was served (valid once the read
    // is whole), and the slot's warp (its order of entering the warp buffer, 0: empty).
    struct ThreadView {
        ThreadStatus status = ThreadStatus::Idle;
        uint64_t node = 0;
        bool l1_miss = false, dram = false;
        uint64_t warp = 0;
    };
    ThreadView thread_view(uint32_t w, uint32_t t) const;
    // Whether thread t of slot w has the node at `addr` in its stack (tests).
    bool stack_contains(uint32_t w, uint32_t t, uint64_t addr) const;
    // Called for every prefetch chunk a policy generates, at the moment it generates it (tests).
    std::function<void(const ChunkRequest&)> on_prefetch_generated;

private:
    struct Thread {
        RtThread rt;
        ThreadStatus status = ThreadStatus::Idle;
        uint64_t since = 0;        // status entered at
        uint32_t chunks_left = 0;
        uint8_t fetch_class = 0;   // pop-streak class of the node being fetched
        bool fetch_l1_miss = false, fetch_dram = false;
        bool descriptor_read = false;  // a two-step leaf read: its descriptor is on the way (or being decoded)
        bool leaf_read = false;        // a two-step leaf read: the descriptor is decoded, the leaf comes next
    };
    struct Warp {
        bool used = false;
        std::vector<Thread> threads;
        uint32_t live = 0;  // threads not Idle
        uint32_t ready = 0; // threads in WaitSchedule
        uint64_t age = 0;   // order of entering the warp buffer (oldest-first scheduling)
        // rt.merge_in_flight: the warp's demand chunks queued or in flight (placed address -> request
        // id), from their scheduling until their response drains.
        absl::flat_hash_map<uint64_t, uint64_t> chunks_pending;
    };
    struct Pending {  // chunk in flight: which threads wait for it
        uint64_t id = 0;  // 0: slot free
        uint32_t warp = 0;
        uint64_t addr = 0;  // the chunk's placed address
        std::vector<uint16_t> threads;  // capacity is kept when the slot is reused
    };
    struct MathDone {
        uint64_t at;
        uint32_t warp, thread;
        bool operator>(const MathDone& o) const { return at > o.at; }
    };
    // The prefetcher's picks become chunks in the prefetch queue, on behalf of one thread.
    struct Sink : PrefetchSink {
        explicit Sink(RtUnitCore& c) : core(c) {}
        void prefetch(const StackEntry& node, uint64_t deadline) override;
        size_t queued() const override;
        void window_drop() override { ++core.stats_.prefetch_queue.window_dropped; }
        RtUnitCore& core;
        uint32_t warp = 0, thread = 0;
    };
    class UnitView;

    // The steps of a cycle.
    void answer_limit_study_fetches(uint64_t now);
    void drain_response(uint64_t now);
    void finish_math(uint64_t now);
    void schedule_warp(uint64_t now);

    void set_status(Thread& t, ThreadStatus s, uint64_t now);
    uint32_t math_latency(const StepInfo& s) const;
    // Where a node sits in simulated memory (treelet layout, model/treelet.h).
    uint64_t placed(uint64_t node) const;

    HwConfig cfg_;
    const BvhImage& image_;
    TraversalOrder order_;
    const Treelets* treelets_;
    std::unique_ptr<Prefetcher> prefetcher_;
    Sink sink_{*this};
    std::vector<Warp> warps_;
    WarpScheduler scheduler_;
    int picked_ = -1;             // the slot last picked, in cycle picked_at_ (waveforms)
    uint64_t picked_at_ = ~0ull;
    MemoryAccessQueue maq_;
    ResponseFifo fifo_;
    absl::flat_hash_set<uint64_t> prefetch_ids_;  // prefetch chunks in flight
    std::deque<std::pair<uint64_t, uint64_t>> limit_study_;  // (cycle, chunk id) answered without memory
    // Chunks in flight, in a ring indexed by id & (size - 1). Ids are sequential, so a slot is
    // usually free again long before its index comes round; when it is not (a response held back
    // for longer than the ring's size in requests, as LT with a large quantum can), the ring
    // doubles until every chunk in flight has a slot of its own.
    Pending& claim_slot(uint64_t id);
    Pending& slot_of(uint64_t id) { return inflight_[id & (inflight_.size() - 1)]; }
    std::vector<Pending> inflight_ = std::vector<Pending>(1 << 13);
    size_t inflight_count_ = 0;
    std::priority_queue<MathDone, std::vector<MathDone>, std::greater<MathDone>> math_;
    // The warp being scheduled: its distinct node reads and the threads of each (a warp has at
    // most 32 threads: rt.warp_size).
    FetchCoalescer<uint64_t> coalescer_;
    std::array<uint32_t, 32> group_chunks_{};
    std::array<std::array<uint16_t, 32>, 32> group_members_{};
    std::array<uint8_t, 32> group_size_{};
    std::vector<RetiredRay> retired_;
    uint64_t next_id_ = 1;
    uint64_t warps_accepted_ = 0;  // warps taken into the warp buffer so far (their age)
    bool next_nodes_changed_ = false;  // a thread's next node changed since the prefetcher last looked (OnCycle)
    RtUnitStats stats_;
};

}  // namespace rtu
