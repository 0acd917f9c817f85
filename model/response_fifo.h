// The RT unit's response FIFO (paper section 2.3): chunks answered by memory wait here and drain
// into the math units one per cycle. `capacity` entries (rt.response_fifo; 0 = unbounded, as in
// Vulkan-sim). A prefetch's response takes its place and its drain cycle like a demand's and is
// then dropped (its data went into the caches): in the TTP authors' simulator every returned
// ray-tracing read, prefetches included (they are marked raytrace, shader.cc l.3408), enters
// the RT unit's response FIFO (rt_unit::fill, l.3735), which pops one per cycle (l.2986-2990).
// Plain C++.
#pragma once
#include <cstdint>
#include <deque>

namespace rtu {

struct ChunkResponse {
    uint64_t id;   // the chunk request's id
    bool l1_miss;  // not served by L1
    bool dram;     // served by DRAM
    bool prefetch = false;  // a prefetch's: takes a drain cycle, wakes no thread
};

class ResponseFifo {
public:
    explicit ResponseFifo(uint32_t capacity) : capacity_(capacity) {}
    bool full() const { return capacity_ && q_.size() >= capacity_; }
    bool empty() const { return q_.empty(); }
    size_t size() const { return q_.size(); }
    uint32_t capacity() const { return capacity_; }
    void push(const ChunkResponse& r) { q_.push_back(r); }
    ChunkResponse pop() {
        const ChunkResponse r = q_.front();
        q_.pop_front();
        return r;
    }

private:
    uint32_t capacity_;
    std::deque<ChunkResponse> q_;
};

}  // namespace rtu
