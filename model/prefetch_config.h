// The prefetcher's configuration keys (prefetch.* in platforms/configs/*.json). The prefetchers
// themselves are in model/prefetcher.h. Plain C++.
#pragma once
#include <array>
#include <memory>
#include <vector>
#include <cstdint>
#include <string>

namespace rtu {

enum class PrefetcherKind : uint8_t { None, Ttp, Park, Treelet, PerfectUp, PerfectDown };
// When the Treelet prefetcher submits the RT unit's most popular treelet (model/prefetcher.cpp).
enum class TreeletHeuristic : uint8_t { Always, Popularity };
// Where treelet traversal goes when its current treelet is finished (model/traversal.h): into the
// treelet of the newest deferred node, every treelet finished before the next (Treelets: Chou et
// al.'s design), or, as the Treelet code both papers ran does, nowhere: only the root treelet is
// kept to, and every node after it is read in DFS order (RootThenDfs; docs/paper-preset.md).
enum class TreeletOrder : uint8_t { Treelets, RootThenDfs };
// How many queue entries TTP prefetches per pop under BFS (model/prefetcher.h TtpBfs).
enum class BfsPolicy : uint8_t { Fixed, Trend };
PrefetcherKind parse_prefetcher(const std::string& name);  // throws std::invalid_argument
const char* prefetcher_name(PrefetcherKind k);

// What TTP saw and did, in order (tests and traces; observing changes nothing): each pop with the
// popped node, the state after it (1..3 for S1..S3; BFS: 0) and the nodes it prefetched, and
// each push with the stack's size after it.
struct PrefetchObserver {
    virtual ~PrefetchObserver() = default;
    virtual void on_pop(uint64_t popped, int state, const std::vector<uint64_t>& prefetched) = 0;
    virtual void on_push(size_t stack_size) = 0;
};

struct PrefetchConfig {
    PrefetcherKind kind = PrefetcherKind::None;
    std::array<uint32_t, 3> depth{1, 2, 16};  // TTP DFS depths of S1, S2, S3
    uint32_t bfs_n = 1;                       // TTP BFS, fixed policy: entries prefetched per pop
    BfsPolicy bfs_policy = BfsPolicy::Fixed;  // TTP BFS: fixed (bfs_n a pop) or trend (the depths above)
    uint32_t priority_after = 0;              // 0: prefetch only in cycles without a demand request;
                                              // X: a prefetch goes first if none was sent in the last X cycles
    uint32_t queue = 0;                       // prefetch queue entries per RT unit (0: unbounded)
    uint32_t thread_window = 0;               // TTP: a node among a thread's last this many prefetches is not prefetched again (0: off)
    std::shared_ptr<PrefetchObserver> observer;  // not a configuration key: set by tests
    uint32_t treelet_budget = 512;            // Treelet: bytes per treelet
    double treelet_threshold = 0.75;          // Treelet (popularity): share of the RT unit's threads that must head for a treelet
    TreeletHeuristic treelet_heuristic = TreeletHeuristic::Always;
    bool treelet_contiguous = false;          // Treelet: each treelet laid out in a block of its own (model/treelet.h)
    uint32_t treelet_stride = 256;            // Treelet, contiguous layout: bytes between blocks beyond the budget
    uint32_t treelet_queue_limit = 1000000;   // Treelet: a treelet is enqueued only if its nodes + the queue's chunks fit
    uint32_t treelet_vote_period = 1;         // Treelet: cycles between two votes
    TreeletOrder treelet_order = TreeletOrder::Treelets;  // treelet traversal: see TreeletOrder
};

}  // namespace rtu
