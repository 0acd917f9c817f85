// The RT unit's prefetch queue (paper section 4.3): 32 B prefetch chunks waiting to leave in a
// cycle the memory access queue has no demand request to send. A chunk already waiting is
// dropped when it is generated again; a chunk with a deadline (Park: the end of its leaf test)
// is dropped unsent once the deadline has passed; a demand read of a waiting chunk takes it out
// (remove, as the TTP authors' RT unit does when it sends a demand chunk: shader.cc l.3474-3479
// and l.3527-3532); with a bound (prefetch.queue) a chunk that finds the queue full is dropped.
// Used by every fidelity. Plain C++.
#pragma once
#include <cstdint>
#include <deque>

#include <absl/container/flat_hash_map.h>

#include "node_fetch.h"

namespace rtu {

class PrefetchQueue {
public:
    // `bound`: at most this many chunks wait (0: no bound).
    explicit PrefetchQueue(uint32_t bound = 0) : bound_(bound) {}
    // Whether a chunk of `addr` is waiting.
    bool waiting(uint64_t addr) const { return waiting_.contains(addr); }
    bool full() const { return bound_ && waiting_.size() >= bound_; }
    // Queues `r` (its address must not be waiting, and the queue not full).
    void push(const ChunkRequest& r) {
        q_.push_back({r, ++seq_});
        waiting_[r.addr] = seq_;
    }
    // Takes the waiting chunk of `addr` out, if any; returns whether there was one.
    bool remove(uint64_t addr) { return waiting_.erase(addr) > 0; }
    bool empty() const { return waiting_.empty(); }
    size_t size() const { return waiting_.size(); }
    const ChunkRequest& front() {
        prune();
        return q_.front().r;
    }
    void pop() {
        prune();
        waiting_.erase(q_.front().r.addr);
        q_.pop_front();
    }
    // Drops the chunks at the front whose deadline is before `now`; returns how many.
    uint64_t expire(uint64_t now) {
        uint64_t n = 0;
        for (; !empty() && front().deadline < now; ++n) pop();
        return n;
    }

private:
    struct Entry {
        ChunkRequest r;
        uint64_t seq;  // the entry is current while waiting_[r.addr] == seq
    };
    // Removed chunks stay in the deque until they reach the front.
    void prune() {
        while (!q_.empty()) {
            auto it = waiting_.find(q_.front().r.addr);
            if (it != waiting_.end() && it->second == q_.front().seq) return;
            q_.pop_front();
        }
    }
    uint32_t bound_;
    uint64_t seq_ = 0;
    std::deque<Entry> q_;
    absl::flat_hash_map<uint64_t, uint64_t> waiting_;  // address -> seq of its current entry
};

}  // namespace rtu
