// The RT unit's memory access queue (paper section 2.3): the warp scheduler's coalesced node reads,
// as 32 B chunks, wait here; one request leaves the unit per cycle. Beside it the prefetch queue
// (model/prefetch_queue.h), and the arbitration between the two (paper section 6.2): a prefetch
// leaves only in a cycle without a demand request, or, with prefetch.priority_after = X > 0,
// first when no prefetch was sent in the last X cycles. The choice sticks until the request has
// left (a request held back by the L1 stays the one to send). A demand chunk that leaves takes a
// waiting prefetch of the same chunk out of the prefetch queue.
// Which demand leaves first follows the warp scheduler's policy (rt.warp_scheduler): round
// robin, in the order the scheduler queued them; oldest first, the oldest warp's, so that a warp
// that entered the warp buffer earlier goes ahead of younger ones (the TTP authors' RT unit picks
// a warp and sends one of its reads each cycle). Either way the chunks of one read leave one
// after another (the authors' mem_access_q: the rest of a read goes before anything else).
// Plain C++.
#pragma once
#include <cstdint>
#include <deque>
#include <vector>

#include "config.h"
#include "prefetch_queue.h"

namespace rtu {

class MemoryAccessQueue {
public:
    MemoryAccessQueue(uint32_t priority_after, WarpOrder order = WarpOrder::RoundRobin, uint32_t slots = 1, uint32_t prefetch_bound = 0)
        : priority_after_(priority_after), order_(order), prefetch_(prefetch_bound), per_slot_(slots), age_(slots, 0) {}
    // Queues a demand chunk of warp slot `demand.warp`, whose warp entered the buffer at `age`.
    // `more`: another chunk of the same read follows.
    void push(const ChunkRequest& demand, uint64_t age) {
        ++depth_;
        if (order_ == WarpOrder::RoundRobin) {
            fifo_.push_back(demand);
            return;
        }
        per_slot_[demand.warp].push_back(demand);
        age_[demand.warp] = age;
    }
    PrefetchQueue& prefetches() { return prefetch_; }
    const PrefetchQueue& prefetches() const { return prefetch_; }
    size_t depth() const { return depth_; }  // demand requests waiting
    bool empty() const { return depth_ == 0 && prefetch_.empty(); }

    // Whether a request waits at `now`, after dropping prefetches past their deadline (unless one
    // is chosen already); `expired` counts the drops.
    bool has_request(uint64_t now, uint64_t& expired) {
        if (!selected_) expired += prefetch_.expire(now);
        return depth_ > 0 || !prefetch_.empty();
    }
    // The request to send at `now` (there must be one).
    const ChunkRequest& front(uint64_t now) {
        select(now);
        return prefetch_chosen_ ? prefetch_.front() : demand_front();
    }
    // The chosen request left at `now`; returns it. `removed` counts the prefetches of the same
    // chunk a demand took out of the prefetch queue.
    ChunkRequest pop(uint64_t now, uint64_t& removed) {
        select(now);
        ChunkRequest r;
        if (prefetch_chosen_) {
            r = prefetch_.front();
            prefetch_.pop();
            last_prefetch_sent_ = now;
        } else {
            r = demand_front();
            if (order_ == WarpOrder::RoundRobin) {
                fifo_.pop_front();
            } else {
                per_slot_[slot_].pop_front();
                continuing_ = r.more;  // the rest of this read goes next
            }
            --depth_;
            removed += prefetch_.remove(r.addr);
        }
        selected_ = false;
        return r;
    }

private:
    void select(uint64_t now) {
        if (selected_) return;
        const bool starving = priority_after_ > 0 && now >= last_prefetch_sent_ + priority_after_;
        prefetch_chosen_ = !prefetch_.empty() && (depth_ == 0 || starving);
        if (!prefetch_chosen_ && order_ == WarpOrder::OldestFirst && !continuing_) {
            int best = -1;
            for (uint32_t s = 0; s < per_slot_.size(); ++s)
                if (!per_slot_[s].empty() && (best < 0 || age_[s] < age_[uint32_t(best)])) best = int(s);
            slot_ = uint32_t(best);
        }
        selected_ = true;
    }
    const ChunkRequest& demand_front() const { return order_ == WarpOrder::RoundRobin ? fifo_.front() : per_slot_[slot_].front(); }

    uint32_t priority_after_;
    WarpOrder order_;
    PrefetchQueue prefetch_;
    std::deque<ChunkRequest> fifo_;                     // round robin: every demand in queue order
    std::vector<std::deque<ChunkRequest>> per_slot_;   // oldest first: each warp slot's demands
    std::vector<uint64_t> age_;                          // oldest first: when each slot's warp entered
    size_t depth_ = 0;
    uint32_t slot_ = 0;       // oldest first: the slot whose demand is chosen
    bool continuing_ = false; // oldest first: the last demand sent has more chunks of its read
    bool selected_ = false, prefetch_chosen_ = false;
    uint64_t last_prefetch_sent_ = 0;
};

}  // namespace rtu
