// The RT unit's prefetch queue (paper section 4.3): 32 B prefetch chunks waiting to leave in a
// cycle the memory access queue has no demand request to send. A chunk already waiting is
// dropped when it is generated again; a chunk with a deadline (Park: the end of its leaf test)
// is dropped unsent once the deadline has passed. Used by every fidelity. Plain C++.
#pragma once
#include <cstdint>
#include <deque>

#include <absl/container/flat_hash_set.h>

#include "node_fetch.h"

namespace rtu {

class PrefetchQueue {
public:
    // Whether a chunk of `addr` is waiting.
    bool waiting(uint64_t addr) const { return waiting_.contains(addr); }
    // Queues `r` (its address must not be waiting).
    void push(const ChunkRequest& r) {
        q_.push_back(r);
        waiting_.insert(r.addr);
    }
    bool empty() const { return q_.empty(); }
    size_t size() const { return q_.size(); }
    const ChunkRequest& front() const { return q_.front(); }
    void pop() {
        waiting_.erase(q_.front().addr);
        q_.pop_front();
    }
    // Drops the chunks at the front whose deadline is before `now`; returns how many.
    uint64_t expire(uint64_t now) {
        uint64_t n = 0;
        for (; !q_.empty() && q_.front().deadline < now; ++n) pop();
        return n;
    }

private:
    std::deque<ChunkRequest> q_;
    absl::flat_hash_set<uint64_t> waiting_;
};

}  // namespace rtu
