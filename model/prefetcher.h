// The prefetchers of the paper's experiments behind one interface, built once from the
// configuration (make_prefetcher): TTP for DFS and for BFS (paper section 4), Park et al. (section
// 6.7), Treelet (Chou et al., section 6.6) and the perfect upward / downward limit studies
// (section 6.1). Every fidelity's RT unit calls the same hooks at the same moments of a node
// fetch; a prefetcher answers with stack entries through a PrefetchSink, which splits them into
// 32 B chunks for the prefetch queue (model/prefetch_queue.h). Plain C++.
//
// TTP for DFS: a 2-bit state per thread and a prefetch pointer. A push resets the state to S0
// and the pointer to the top of stack T. Each pop advances S0 -> S1 -> S2 -> S3 (saturating);
// the state gives the prefetch depth k (1, 2, 16 by default). The entries from the pointer down
// to T - k are prefetched and the pointer moves below them, so no entry is prefetched twice
// until the next push. Paper example: with L, N, O, P on the stack (P on top), popping P
// prefetches O (S1); popping O then prefetches N and L (S2).
//
// TTP for BFS: the stack is a FIFO queue; each pop prefetches entries from the head that have not
// been prefetched yet: N of them (prefetch.bfs_policy = fixed, the paper's section 4), or as many
// as the DFS state machine's state gives (trend: the TTP authors' code runs the same S1..S3 trend
// for BFS, a push resetting it, and prefetches from the queue's head, vulkan_ray_tracing.cc
// l.551-568 pop_ts_trend, l.662-718 generate_prefetches_BFS, l.1745-1747).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "config.h"
#include "prefetch_config.h"
#include "traversal.h"

namespace rtu {

struct Treelets;

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
    // A push happened (children join the tail; the head entries already prefetched stay so).
    void on_push() { state_ = 0; }
    // A pop from the head happened; `size` is the queue size after it. Appends queue positions
    // (0 = head) to prefetch, at most `n` positions deep.
    void on_pop(size_t size, uint32_t n, std::vector<size_t>& out) {
        if (ahead_ > 0) --ahead_;
        for (; ahead_ < n && ahead_ < size; ++ahead_) out.push_back(ahead_);
    }
    // The same pop under the trend policy: the state advances as DFS's does (S1..S3,
    // saturating) and picks the depth of `depth`.
    void on_pop_trend(size_t size, const std::array<uint32_t, 3>& depth, std::vector<size_t>& out) {
        if (state_ < 3) ++state_;
        on_pop(size, depth[state_ - 1], out);
    }
    int state() const { return state_; }

private:
    size_t ahead_ = 0;  // head entries already prefetched
    int state_ = 0;     // trend policy: 0 after a push, then S1..S3
};

// A prefetcher's state per thread, beside the thread's traversal stack in the warp buffer (TTP:
// the 2-bit state machine and the prefetch pointer, or the BFS head count).
struct PrefetchThreadState {
    TtpDfs dfs;
    TtpBfs bfs;
    std::deque<uint64_t> recent;  // the thread's last prefetched nodes (prefetch.thread_window)
};

// Where a prefetcher's picks go: the RT unit splits each node into chunks and queues them.
class PrefetchSink {
public:
    virtual ~PrefetchSink() = default;
    // `deadline`: the cycle after which an unsent chunk is dropped (~0: none).
    virtual void prefetch(const StackEntry& node, uint64_t deadline) = 0;
    // A pick the thread's window dropped (prefetch.thread_window), for the statistics.
    virtual void window_drop() = 0;
    // Chunks waiting in the RT unit's prefetch queue (the Treelet code's size check reads it).
    virtual size_t queued() const { return 0; }
};

// The RT unit's threads as the Treelet prefetcher reads them: every live thread of every warp
// in the warp buffer.
class UnitThreads {
public:
    virtual ~UnitThreads() = default;
    virtual void for_each_live(const std::function<void(const TraversalThread&)>& f) const = 0;
};

class Prefetcher {
public:
    // The hooks a prefetcher uses (a fidelity that does not call one refuses the prefetcher).
    enum Hook : unsigned { OnPop = 1, OnNodeTest = 2, OnCycle = 4, LimitStudy = 8 };

    explicit Prefetcher(unsigned hooks) : hooks_(hooks) {}
    virtual ~Prefetcher() = default;
    virtual PrefetcherKind kind() const = 0;
    const char* name() const { return prefetcher_name(kind()); }
    // Not virtual: the RT unit asks on every node fetch, and calls only the hooks in use.
    unsigned hooks() const { return hooks_; }
    // A thread's node fetch is scheduled and pops `stack`'s next entry (DFS: the top; BFS: the
    // head); `stack` still holds it.
    virtual void on_pop(PrefetchThreadState&, const std::deque<StackEntry>& stack, PrefetchSink&) {}
    // A thread pushed; `size` is its stack's size after the push.
    virtual void on_push(PrefetchThreadState&, size_t size) {}
    // A thread's node arrived and its tests (`step`) start now and end at cycle `test_end`;
    // `stack` is the thread's stack after the step.
    virtual void on_node_test(const StepInfo& step, const std::deque<StackEntry>& stack, uint64_t test_end, PrefetchSink&) {}
    // A cycle of the RT unit in which some thread's next node changed (a warp came in, or a
    // node's tests ran), before the warp scheduler picks: `threads` are the unit's live threads.
    virtual void on_cycle(const UnitThreads& threads, PrefetchSink&, uint64_t now) {}
    // Limit studies: a node fetch of pop-streak class `fetch_class` is answered as an L1 hit.
    virtual bool answered_as_l1_hit(uint8_t fetch_class) const { return false; }

private:
    unsigned hooks_;
};

// The configured prefetcher for `order`. Throws std::invalid_argument where it cannot work:
// Treelet without treelet traversal (or without `treelets`). `lat`: the RT unit's math latencies
// (Park's prefetch window is the leaf test).
std::unique_ptr<Prefetcher> make_prefetcher(const PrefetchConfig& cfg, TraversalOrder order, const RtLatency& lat,
                                            const Treelets* treelets);
// The same checks of the combination, before there are treelets to build it with.
void check_prefetcher(const PrefetchConfig& cfg, TraversalOrder order);

}  // namespace rtu
