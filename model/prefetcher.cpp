#include "prefetcher.h"

#include <algorithm>
#include <map>
#include <stdexcept>

#include "node_fetch.h"
#include "treelet.h"

namespace rtu {
namespace {

// Stack entry `k` counted from the next one to be popped (DFS and treelet traversal: the top;
// BFS: the head).
const StackEntry& from_next(const std::deque<StackEntry>& st, TraversalOrder order, size_t k) {
    return order == TraversalOrder::BFS ? st[k] : st[st.size() - 1 - k];
}

class NoPrefetcher : public Prefetcher {
public:
    NoPrefetcher() : Prefetcher(0) {}
    PrefetcherKind kind() const override { return PrefetcherKind::None; }
};

// TTP (paper section 4): on each pop, the state machine picks the entries below the popped one.
class TtpPrefetcher : public Prefetcher {
public:
    TtpPrefetcher(const PrefetchConfig& c, TraversalOrder order) : Prefetcher(OnPop), cfg_(c), bfs_(order == TraversalOrder::BFS) {}
    PrefetcherKind kind() const override { return PrefetcherKind::Ttp; }
    void on_pop(PrefetchThreadState& s, const std::deque<StackEntry>& st, PrefetchSink& sink) override {
        if (st.empty()) return;
        picks_.clear();
        // The stack after the pop is the current one without its top (DFS) or head (BFS).
        if (bfs_) {
            if (cfg_.bfs_policy == BfsPolicy::Trend)
                s.bfs.on_pop_trend(st.size() - 1, cfg_.depth, picks_);
            else
                s.bfs.on_pop(st.size() - 1, cfg_.bfs_n, picks_);
            for (size_t pos : picks_) send(s, st[pos + 1], sink);
        } else {
            s.dfs.on_pop(st.size() - 1, cfg_.depth, picks_);
            for (size_t i : picks_) send(s, st[i], sink);
        }
        if (cfg_.observer) {
            std::vector<uint64_t> picked;
            for (size_t i : picks_) picked.push_back(bfs_ ? st[i + 1].addr : st[i].addr);
            cfg_.observer->on_pop(bfs_ ? st.front().addr : st.back().addr, bfs_ ? s.bfs.state() : s.dfs.state(), picked);
        }
    }
    void on_push(PrefetchThreadState& s, size_t size) override {
        s.dfs.on_push(size);
        s.bfs.on_push();
        if (cfg_.observer) cfg_.observer->on_push(size);
    }

private:
    // With a thread window (the TTP authors' RT unit: a thread's prefetch records are dropped
    // when the same node is among its last 16 prefetches, abstract_hardware_model.cc l.945-951,
    // abstract_hardware_model.h l.1535), a pick of a recent node goes no further.
    void send(PrefetchThreadState& s, const StackEntry& e, PrefetchSink& sink) {
        if (cfg_.thread_window) {
            if (std::find(s.recent.begin(), s.recent.end(), e.addr) != s.recent.end()) {
                sink.window_drop();
                return;
            }
            s.recent.push_back(e.addr);
            if (s.recent.size() > cfg_.thread_window) s.recent.pop_front();
        }
        sink.prefetch(e, ~0ull);
    }
    PrefetchConfig cfg_;
    bool bfs_;
    std::vector<size_t> picks_;
};

// Park et al. (as the TTP paper models them, section 6.7): while a leaf test runs, prefetch as
// many stack entries as can leave during it (one 32 B chunk per cycle of the intersection test
// itself, 8 cycles in the paper's setup), next pop first; what has not left when the test ends
// is dropped.
class ParkPrefetcher : public Prefetcher {
public:
    ParkPrefetcher(TraversalOrder order, const RtLatency& lat) : Prefetcher(OnNodeTest), order_(order), lat_(lat) {}
    PrefetcherKind kind() const override { return PrefetcherKind::Park; }
    void on_node_test(const StepInfo& step, const std::deque<StackEntry>& st, uint64_t test_end, PrefetchSink& sink) override {
        if (step.type != NodeType::Triangle && step.type != NodeType::Procedural) return;
        uint32_t budget = step.type == NodeType::Triangle ? lat_.ray_triangle : lat_.procedural;
        for (size_t k = 0; k < st.size(); ++k) {
            const StackEntry& e = from_next(st, order_, k);
            const uint32_t chunks = chunks_of(e.type);
            if (chunks > budget) break;
            budget -= chunks;
            sink.prefetch(e, test_end);
        }
    }

private:
    TraversalOrder order_;
    RtLatency lat_;
};

// Treelet (Chou et al.), as their published code runs with treelet_prefetch on (shader.cc of
// branch treelet_traversal, l.3419-3640): every treelet_vote_period cycles (its prefetch_delay,
// l.3378), over every live thread of the RT unit, the treelet of the node each will read next
// gets a vote; the most popular treelet (ties: the smaller root address, as the code's map keyed
// by the root) is prefetched whole, unless it is the one prefetched last, and only if its nodes
// plus the chunks already in the prefetch queue are at most treelet_queue_limit (l.3577: a
// treelet too large for that is never enqueued; the code compares nodes with chunks, and so does
// this). Heuristic `always` (the code's 0, which the TTP paper ran) always submits it;
// `popularity` (1) only when its votes are at least treelet_threshold of all.
// The RT unit calls this only in cycles in which some thread's next node changed; between two
// such cycles the votes would not change, so the vote of a period is taken at its first such
// cycle (at most treelet_vote_period - 1 cycles after the code's), and a treelet refused by the
// size check is voted on again at the next one.
class TreeletPrefetcher : public Prefetcher {
public:
    TreeletPrefetcher(const PrefetchConfig& c, const Treelets& t)
        : Prefetcher(OnCycle),
          always_(c.treelet_heuristic == TreeletHeuristic::Always),
          threshold_(c.treelet_threshold),
          queue_limit_(c.treelet_queue_limit),
          period_(c.treelet_vote_period),
          treelets_(t) {}
    PrefetcherKind kind() const override { return PrefetcherKind::Treelet; }
    void on_cycle(const UnitThreads& threads, PrefetchSink& sink, uint64_t now) override {
        if (now / period_ == voted_in_) return;
        voted_in_ = now / period_;
        votes_.clear();
        uint32_t total = 0;
        threads.for_each_live([&](const TraversalThread& t) {
            const uint32_t id = treelets_.treelet_of(t.peek().addr);
            if (id == ~0u) return;
            ++votes_[id];
            ++total;
        });
        uint32_t best = ~0u, count = 0;
        for (const auto& [id, c] : votes_)
            if (c > count || (c == count && treelets_.nodes[id][0].addr < treelets_.nodes[best][0].addr)) best = id, count = c;
        if (best == ~0u || best == last_) return;
        if (!always_ && double(count) < threshold_ * double(total)) return;
        if (treelets_.nodes[best].size() + sink.queued() > queue_limit_) return;
        last_ = best;
        for (const StackEntry& e : treelets_.nodes[best]) sink.prefetch(e, ~0ull);
    }

private:
    bool always_;
    double threshold_;
    uint64_t queue_limit_, period_;
    const Treelets& treelets_;
    std::map<uint32_t, uint32_t> votes_;
    uint32_t last_ = ~0u;            // the treelet prefetched last
    uint64_t voted_in_ = ~0ull;      // the period of the last vote
};

// The limit studies (paper section 6.1): node reads of some pop-streak classes always hit L1.
class PerfectPrefetcher : public Prefetcher {
public:
    explicit PerfectPrefetcher(bool upward) : Prefetcher(LimitStudy), upward_(upward) {}
    PrefetcherKind kind() const override { return upward_ ? PrefetcherKind::PerfectUp : PrefetcherKind::PerfectDown; }
    // Upward: 2nd and later consecutive pops; downward: 1st pops.
    bool answered_as_l1_hit(uint8_t c) const override { return upward_ ? c >= 2 : c == 1; }

private:
    bool upward_;
};

// Every prefetcher once: its name, what it needs, how it is built.
struct Entry {
    PrefetcherKind kind;
    const char* name;
    bool needs_treelet_traversal;
    std::unique_ptr<Prefetcher> (*make)(const PrefetchConfig&, TraversalOrder, const RtLatency&, const Treelets*);
};
const Entry kPrefetchers[] = {
    {PrefetcherKind::None, "none", false, [](const PrefetchConfig&, TraversalOrder, const RtLatency&, const Treelets*) -> std::unique_ptr<Prefetcher> {
         return std::make_unique<NoPrefetcher>();
     }},
    {PrefetcherKind::Ttp, "ttp", false, [](const PrefetchConfig& c, TraversalOrder o, const RtLatency&, const Treelets*) -> std::unique_ptr<Prefetcher> {
         return std::make_unique<TtpPrefetcher>(c, o);
     }},
    {PrefetcherKind::Park, "park", false, [](const PrefetchConfig&, TraversalOrder o, const RtLatency& l, const Treelets*) -> std::unique_ptr<Prefetcher> {
         return std::make_unique<ParkPrefetcher>(o, l);
     }},
    {PrefetcherKind::Treelet, "treelet", true, [](const PrefetchConfig& c, TraversalOrder, const RtLatency&, const Treelets* t) -> std::unique_ptr<Prefetcher> {
         if (!t) throw std::invalid_argument("the Treelet prefetcher needs the BVH's treelets");
         return std::make_unique<TreeletPrefetcher>(c, *t);
     }},
    {PrefetcherKind::PerfectUp, "perfect-up", false, [](const PrefetchConfig&, TraversalOrder, const RtLatency&, const Treelets*) -> std::unique_ptr<Prefetcher> {
         return std::make_unique<PerfectPrefetcher>(true);
     }},
    {PrefetcherKind::PerfectDown, "perfect-down", false, [](const PrefetchConfig&, TraversalOrder, const RtLatency&, const Treelets*) -> std::unique_ptr<Prefetcher> {
         return std::make_unique<PerfectPrefetcher>(false);
     }},
};

const Entry& entry(PrefetcherKind k) {
    for (const Entry& e : kPrefetchers)
        if (e.kind == k) return e;
    throw std::logic_error("unknown prefetcher kind");
}

}  // namespace

PrefetcherKind parse_prefetcher(const std::string& n) {
    std::string names;
    for (const Entry& e : kPrefetchers) {
        if (n == e.name) return e.kind;
        names += std::string(names.empty() ? "" : ", ") + e.name;
    }
    throw std::invalid_argument("--prefetcher '" + n + "': allowed are " + names);
}

const char* prefetcher_name(PrefetcherKind k) { return entry(k).name; }

void check_prefetcher(const PrefetchConfig& cfg, TraversalOrder order) {
    const Entry& e = entry(cfg.kind);
    if (e.needs_treelet_traversal && order != TraversalOrder::Treelet)
        throw std::invalid_argument(std::string("--prefetcher ") + e.name + " needs --traversal treelet (the " + e.name +
                                    " prefetcher requires treelet traversal)");
}

std::unique_ptr<Prefetcher> make_prefetcher(const PrefetchConfig& cfg, TraversalOrder order, const RtLatency& lat,
                                            const Treelets* treelets) {
    check_prefetcher(cfg, order);
    return entry(cfg.kind).make(cfg, order, lat, treelets);
}

}  // namespace rtu
