// The RT unit's memory access queue (paper section 2.3): the warp scheduler's coalesced node reads,
// as 32 B chunks, wait here; one request leaves the unit per cycle. Beside it the prefetch queue
// (model/prefetch_queue.h), and the arbitration between the two (paper section 6.2): a prefetch
// leaves only in a cycle without a demand request, or, with prefetch.priority_after = X > 0,
// first when no prefetch was sent in the last X cycles. The choice sticks until the request has
// left (a request held back by the L1 stays the one to send). Plain C++.
#pragma once
#include <cstdint>
#include <deque>

#include "prefetch_queue.h"

namespace rtu {

class MemoryAccessQueue {
public:
    explicit MemoryAccessQueue(uint32_t priority_after) : priority_after_(priority_after) {}
    void push(const ChunkRequest& demand) { demand_.push_back(demand); }
    PrefetchQueue& prefetches() { return prefetch_; }
    size_t depth() const { return demand_.size(); }  // demand requests waiting
    bool empty() const { return demand_.empty() && prefetch_.empty(); }

    // Whether a request waits at `now`, after dropping prefetches past their deadline (unless one
    // is chosen already); `expired` counts the drops.
    bool has_request(uint64_t now, uint64_t& expired) {
        if (!selected_) expired += prefetch_.expire(now);
        return !demand_.empty() || !prefetch_.empty();
    }
    // The request to send at `now` (there must be one).
    const ChunkRequest& front(uint64_t now) {
        select(now);
        return prefetch_chosen_ ? prefetch_.front() : demand_.front();
    }
    // The chosen request left at `now`; returns it.
    ChunkRequest pop(uint64_t now) {
        select(now);
        ChunkRequest r;
        if (prefetch_chosen_) {
            r = prefetch_.front();
            prefetch_.pop();
            last_prefetch_sent_ = now;
        } else {
            r = demand_.front();
            demand_.pop_front();
        }
        selected_ = false;
        return r;
    }

private:
    void select(uint64_t now) {
        if (selected_) return;
        const bool starving = priority_after_ > 0 && now >= last_prefetch_sent_ + priority_after_;
        prefetch_chosen_ = !prefetch_.empty() && (demand_.empty() || starving);
        selected_ = true;
    }

    uint32_t priority_after_;
    std::deque<ChunkRequest> demand_;
    PrefetchQueue prefetch_;
    bool selected_ = false, prefetch_chosen_ = false;
    uint64_t last_prefetch_sent_ = 0;
};

}  // namespace rtu
