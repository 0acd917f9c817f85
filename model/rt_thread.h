// One thread's entry in an RT unit's warp buffer, kept alike by every fidelity: the ray's
// traversal (stack, closest hit), its pop streak, its prefetcher state and where its node fetches
// were served. The two moments of a node fetch are written here once:
// - begin_fetch, when the warp scheduler sends the fetch: its pop-streak class, and on a pop the
//   prefetcher's look at the stack (TTP's trigger);
// - complete_fetch, when the node has arrived whole: where its bytes came from, the node's tests
//   (a traversal step), and after a push a new pop streak. Plain C++.
#pragma once
#include <algorithm>
#include <cstdint>

#include "bvh_image.h"
#include "pop_streak.h"
#include "prefetcher.h"
#include "rt_unit_stats.h"
#include "trace_source.h"
#include "traversal.h"

namespace rtu {

struct RtThread {
    TraversalThread trav;
    uint64_t key = 0;  // the ray's key for the trace source
    PopStreak streak;
    PrefetchThreadState prefetch;
    uint32_t l1_miss_nodes = 0, dram_nodes = 0;  // node fetches so far not served by L1 / served by DRAM
    bool next_queued = false;  // the current fetch is a pop after which the stack (queue) was not empty

    void start(const WarpRay& r, const ImageHeader& header, const TraversalRule& rule, const Treelets* treelets) {
        key = r.key;
        trav.start(r.ray, header, rule.order, treelets, rule.next_node_register);
        streak = PopStreak{};
        prefetch = PrefetchThreadState{};
        l1_miss_nodes = dram_nodes = 0;
    }

    // The fetch of trav.peek() is sent: returns its pop-streak class (0: not a pop).
    uint8_t begin_fetch(Prefetcher& prefetcher, PrefetchSink& sink) {
        next_queued = false;
        if (!trav.next_is_pop()) return 0;
        next_queued = trav.stack().size() > 1;
        const uint8_t c = streak.pop();
        if (prefetcher.hooks() & Prefetcher::OnPop) prefetcher.on_pop(prefetch, trav.stack(), sink);
        return c;
    }

    // The fetch of trav.peek() counted: a node read under its class, or a header read apart (a
    // header is not a node visit).
    void count_fetch(RtUnitStats& st, uint8_t fetch_class) const {
        if (trav.peek().type == NodeType::Header) {
            ++st.header_fetches;
            return;
        }
        ++st.pop_streak[fetch_class].node_fetches;
        ++st.node_fetches;
    }

    // The fetch's node arrived whole (`l1_miss`: some chunk was not served by L1; `dram`: some
    // chunk came from DRAM): counts it under the fetch's class and runs the node's tests.
    StepInfo complete_fetch(RtUnitStats& st, uint8_t fetch_class, bool l1_miss, bool dram, const BvhImage& image,
                            Prefetcher& prefetcher) {
        if (trav.peek().type == NodeType::Header) {
            st.header_l1_misses += l1_miss;
        } else {
            st.pop_streak[fetch_class].l1_misses += l1_miss;
            st.pop_streak[fetch_class].dram_misses += dram;
            st.l1_misses_with_next_queued += l1_miss && next_queued;
            l1_miss_nodes += l1_miss;
            dram_nodes += dram;
        }
        const StepInfo info = trav.step(image);
        st.intersection_candidates += info.type == NodeType::Procedural;
        if (info.pushed > 0) {
            streak.push();
            if (prefetcher.hooks() & Prefetcher::OnPop) prefetcher.on_push(prefetch, trav.stack().size());
        }
        return info;
    }

    // A finished trace's intersection loop: the most candidates of one of its threads (each with
    // an RtThread `rt`).
    template <class Threads>
    static uint32_t loop_of(const Threads& threads) {
        uint32_t loop = 0;
        for (const auto& t : threads) loop = std::max(loop, t.rt.trav.candidates());
        return loop;
    }

    RetiredRay retired() const { return {key, trav.hit(), trav.nodes_visited(), l1_miss_nodes, dram_nodes, trav.candidates()}; }
};

}  // namespace rtu
