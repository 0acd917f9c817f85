// The RT unit's per-cycle logic (paper section 2.3, DESIGN.md section 5), independent of how time
// advances: the warp buffer with each thread's traversal state (plain data, never one process
// per thread), the warp scheduler, the memory access queue (intra-warp coalescing of identical
// node addresses, nodes split into 32 B chunks, one chunk leaving per cycle), the response FIFO
// (one response drained per cycle) and the math pipelines with their latencies. Traversal
// decisions are made from the node bytes when they arrive (execution-driven).
// Plain C++ (no SystemC): tlm/rt_unit.h drives it in AT or LT.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <queue>
#include <unordered_map>
#include <vector>

#include <unordered_set>

#include <absl/container/flat_hash_set.h>

#include "bvh_image.h"
#include "config.h"
#include "prefetcher.h"
#include "trace_source.h"
#include "traversal.h"

namespace rtu {

constexpr uint32_t kChunkBytes = 32;

// A 32 B read leaving the RT unit.
struct ChunkRequest {
    uint64_t id;       // unique per RT unit
    uint64_t addr;     // 32 B aligned
    uint32_t warp;     // warp-buffer slot
    uint32_t thread;   // first thread waiting on the node (others coalesced onto it)
    uint8_t streak;    // pop-streak class of the node fetch: 0 not a pop, 1, 2, 3, 4 = 4th or later
    bool prefetch = false;
    uint64_t deadline = ~0ull;  // prefetch not sent by this cycle is dropped (Park: end of the leaf test)
};

// Cycles of a node's tests in the RT unit's math pipelines (at least 1).
uint32_t rt_math_latency(const RtLatency& lat, const StepInfo& s);

enum class ThreadStatus : uint8_t { Idle, WaitSchedule, WaitMemory, InMath, Count };

struct RtUnitStats {
    uint64_t warps = 0, rays = 0, node_fetches = 0, chunk_requests = 0, coalesced = 0, responses = 0;
    std::array<uint64_t, size_t(ThreadStatus::Count)> thread_cycles{};  // summed over thread slots
    // Pop-streak classes 0 (not a pop: first child taken next / root), 1st, 2nd, 3rd, 4th+.
    std::array<uint64_t, 5> streak_fetches{}, streak_l1_misses{}, streak_dram_misses{};
    uint64_t max_response_fifo = 0, max_request_queue = 0;
    uint64_t prefetches_generated = 0, prefetch_duplicates = 0, prefetches_sent = 0, prefetch_responses = 0;
    uint64_t prefetches_expired = 0;  // dropped unsent at their deadline
    uint64_t perfect_hits = 0;  // chunk fetches answered as L1 hits by a perfect-up/down limit study
};

// A thread's node has arrived whole: counts where its bytes came from (under the fetch's
// pop-streak class), runs the node's tests, and after a push restarts the thread's pop streak and
// TTP pointer. Shared by the RT unit (AT, LT) and the interval fidelity (model/interval_gpu.h),
// whose threads have these fields.
template <class Thread>
StepInfo complete_fetch(Thread& t, RtUnitStats& st, uint8_t fetch_class, bool l1_miss, bool dram, const BvhImage& image) {
    st.streak_l1_misses[fetch_class] += l1_miss;
    st.streak_dram_misses[fetch_class] += dram;
    t.l1_miss_nodes += l1_miss;
    t.dram_nodes += dram;
    const StepInfo info = t.trav.step(image);
    if (info.pushed > 0) {
        t.streak = 0;
        t.ttp_dfs.on_push(t.trav.stack().size());
    }
    return info;
}

class RtUnitCore {
public:
    // `treelets` is needed for treelet traversal and the Treelet prefetcher (else may be null).
    RtUnitCore(const HwConfig& cfg, const BvhImage& image, TraversalOrder order, const Treelets* treelets = nullptr);

    bool has_free_slot() const;
    // Takes a warp (at most warp_size rays) into a free slot at cycle `now`.
    void accept_warp(const std::vector<WarpRay>& rays, uint64_t now);

    // One cycle at `now`: drain one response, finish math that ends by now, and let the warp
    // scheduler move one warp's ready threads into the memory access queue.
    void cycle(uint64_t now);

    // The request to send this cycle: demand first; a prefetch when no demand is waiting, or
    // first when none was sent in the last prefetch.priority_after cycles. The choice sticks
    // until pop_request() (a request held by backpressure stays the one to send).
    // Drops prefetches past their deadline first (unless one is already selected).
    bool has_request(uint64_t now);
    const ChunkRequest& front_request(uint64_t now);
    void pop_request(uint64_t now);

    // A response for chunk `id` entered the response FIFO; `l1_miss`/`dram` describe where it
    // was served.
    void on_response(uint64_t id, bool l1_miss, bool dram, uint64_t now);

    // Rays of warps that finished since the last call.
    std::vector<RetiredRay> take_retired();
    size_t warps_resident() const;

    // The cycle of the next work with no further input: now + 1 while the request queue, the
    // response FIFO or a ready thread has work; else the earliest math completion; else ~0.
    uint64_t next_event(uint64_t now) const;
    bool idle() const;

    // Closes the thread-status accounting at `now` (call before reading stats).
    void account(uint64_t now);
    const RtUnitStats& stats() const { return stats_; }
    uint32_t warp_buffer_occupancy() const;
    uint32_t active_threads() const;
    size_t response_fifo_depth() const { return fifo_.size(); }
    size_t request_queue_depth() const { return maq_.size(); }
    // Stack depth of thread t of slot w (for waveforms); -1 if empty slot.
    int stack_depth(uint32_t w, uint32_t t) const;
    // Whether thread t of slot w has the node at `addr` in its stack (tests).
    bool stack_contains(uint32_t w, uint32_t t, uint64_t addr) const;
    // Called for every prefetch chunk a policy generates, at the moment it generates it (tests).
    std::function<void(const ChunkRequest&)> on_prefetch_generated;

private:
    struct Thread {
        TraversalThread trav;
        ThreadStatus status = ThreadStatus::Idle;
        uint64_t key = 0;
        uint64_t since = 0;        // status entered at
        uint32_t chunks_left = 0;
        uint8_t streak = 0;        // consecutive pops so far
        uint8_t fetch_class = 0;   // class of the node being fetched
        uint32_t l1_miss_nodes = 0, dram_nodes = 0;  // node fetches so far that missed L1 / went to DRAM
        bool fetch_l1_miss = false, fetch_dram = false;
        NodeType fetch_type = NodeType::Empty;
        TtpDfs ttp_dfs;
        TtpBfs ttp_bfs;
    };
    struct Warp {
        bool used = false;
        std::unordered_set<uint32_t> treelets_prefetched;
        std::vector<Thread> threads;
        uint32_t live = 0;  // threads not Idle
        uint32_t ready = 0; // threads in WaitSchedule
    };
    struct Pending {  // chunk in flight: which threads wait for it
        uint64_t id = 0;  // 0: slot free
        uint32_t warp = 0;
        std::vector<uint16_t> threads;  // capacity is kept when the slot is reused
    };
    struct MathDone {
        uint64_t at;
        uint32_t warp, thread;
        bool operator>(const MathDone& o) const { return at > o.at; }
    };

    void set_status(Thread& t, ThreadStatus s, uint64_t now);
    void after_step(uint32_t w, uint32_t t, uint64_t now);
    uint32_t math_latency(const StepInfo& s) const;
    void prefetch_entry(const StackEntry& e, uint32_t warp, uint32_t thread, uint64_t deadline = ~0ull);
    void prefetch_on_pop(Thread& t, uint32_t warp, uint32_t thread);
    void prefetch_popular_treelet(Warp& w, uint32_t warp);

    HwConfig cfg_;
    const BvhImage& image_;
    TraversalOrder order_;
    const Treelets* treelets_;
    std::vector<Warp> warps_;
    uint32_t rr_ = 0;
    std::deque<ChunkRequest> maq_, pfq_;        // demand / prefetch chunks waiting to leave
    bool selected_ = false, selected_prefetch_ = false;
    uint64_t last_prefetch_sent_ = 0;
    absl::flat_hash_set<uint64_t> prefetch_ids_;  // prefetch chunks in flight
    std::deque<std::pair<uint64_t, uint64_t>> perfect_;  // (cycle, chunk id) answered without memory
    std::deque<std::pair<uint64_t, std::pair<bool, bool>>> fifo_;  // chunk id, (l1 miss, dram)
    // Chunks in flight, in a ring indexed by id & (size - 1). Ids are sequential, so a slot is
    // usually free again long before its index comes round; when it is not (a response held back
    // for longer than the ring's size in requests, as LT with a large quantum can), the ring
    // doubles until every chunk in flight has a slot of its own.
    Pending& claim_slot(uint64_t id);
    Pending& slot_of(uint64_t id) { return inflight_[id & (inflight_.size() - 1)]; }
    std::vector<Pending> inflight_ = std::vector<Pending>(1 << 13);
    size_t inflight_count_ = 0;
    std::priority_queue<MathDone, std::vector<MathDone>, std::greater<MathDone>> math_;
    std::vector<RetiredRay> retired_;
    uint64_t next_id_ = 1;
    RtUnitStats stats_;
};

}  // namespace rtu
