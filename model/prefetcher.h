// Prefetch policies that watch a thread's traversal stack (paper section 4). Plain C++.
//
// TTP for DFS: a 2-bit state per thread and a prefetch pointer. A push resets the state to S0
// and the pointer to the top of stack T. Each pop advances S0 -> S1 -> S2 -> S3 (saturating);
// the state gives the prefetch depth k (1, 2, 16 by default). The entries from the pointer down
// to T - k are prefetched and the pointer moves below them, so no entry is prefetched twice
// until the next push. Paper example: with L, N, O, P on the stack (P on top), popping P
// prefetches O (S1); popping O then prefetches N and L (S2).
//
// TTP for BFS: the stack is a FIFO queue; each pop prefetches up to N entries from the head
// that have not been prefetched yet.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rtu {

enum class PrefetcherKind : uint8_t { None, Ttp, Park, Treelet, PerfectUp, PerfectDown };
PrefetcherKind parse_prefetcher(const std::string& name);  // throws std::invalid_argument
const char* prefetcher_name(PrefetcherKind k);

struct PrefetchConfig {
    PrefetcherKind kind = PrefetcherKind::None;
    std::array<uint32_t, 3> depth{1, 2, 16};  // TTP DFS depths of S1, S2, S3
    uint32_t bfs_n = 1;                       // TTP BFS: entries prefetched per pop
    uint32_t priority_after = 0;              // 0: prefetch only in cycles without a demand request;
                                              // X: a prefetch goes first if none was sent in the last X cycles
    uint32_t treelet_budget = 512;            // Treelet: bytes per treelet
    double treelet_threshold = 0.75;          // Treelet: share of a warp's threads that must head for a treelet
};

class TtpDfs {
public:
    // A push happened; `size` is the stack size after it.
    void on_push(size_t size) {
        state_ = 0;
        pointer_ = long(size) - 1;
    }
    // A pop happened; `size` is the stack size after it. Appends the stack indices (0 = bottom)
    // to prefetch, nearest the top first.
    void on_pop(size_t size, const std::array<uint32_t, 3>& depth, std::vector<size_t>& out) {
        if (state_ < 3) ++state_;
        const long top = long(size) - 1;
        if (pointer_ > top) pointer_ = top;
        const long limit = top - long(depth[state_ - 1]) + 1;  // lowest index to prefetch
        for (; pointer_ >= 0 && pointer_ >= limit; --pointer_) out.push_back(size_t(pointer_));
    }
    int state() const { return state_; }
    long pointer() const { return pointer_; }

private:
    int state_ = 0;
    long pointer_ = -1;
};

class TtpBfs {
public:
    // A pop from the head happened; `size` is the queue size after it. Appends queue positions
    // (0 = head) to prefetch.
    void on_pop(size_t size, uint32_t n, std::vector<size_t>& out) {
        if (ahead_ > 0) --ahead_;
        for (; ahead_ < n && ahead_ < size; ++ahead_) out.push_back(ahead_);
    }

private:
    size_t ahead_ = 0;  // head entries already prefetched
};

}  // namespace rtu
