// Prefetch policies: TTP's state machine (paper section 4.1 example), its no-repeat pointer,
// the BFS variant, and usefulness accounting in the cache.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "model/memory_access_queue.h"
#include "model/prefetcher.h"
#include "model/rt_unit_core.h"
#include "model/sector_cache.h"
#include "model/treelet.h"
#include "model/warp_scheduler.h"
#include "test_util.h"
#include "workloads/bvh_builder.h"
#include "workloads/scenes.h"

using namespace rtu;

// Paper: with L, N, O, P on the stack (P on top), popping P prefetches O (state S1); popping O
// then prefetches N and L (state S2).
TEST(Ttp, PaperWorkedExample) {
    const std::array<uint32_t, 3> depth{1, 2, 16};
    TtpDfs ttp;
    ttp.on_push(4);  // stack: L N O P
    std::vector<size_t> out;
    ttp.on_pop(3, depth, out);  // P popped: L N O
    EXPECT_EQ(ttp.state(), 1);
    EXPECT_EQ(out, (std::vector<size_t>{2}));  // O
    out.clear();
    ttp.on_pop(2, depth, out);  // O popped: L N
    EXPECT_EQ(ttp.state(), 2);
    EXPECT_EQ(out, (std::vector<size_t>{1, 0}));  // N, L
    out.clear();
    ttp.on_pop(1, depth, out);  // N popped: L (already prefetched: nothing new)
    EXPECT_EQ(ttp.state(), 3);
    EXPECT_TRUE(out.empty());
    ttp.on_push(3);  // a push resets the state and the pointer
    EXPECT_EQ(ttp.state(), 0);
    ttp.on_pop(2, depth, out);
    EXPECT_EQ(out, (std::vector<size_t>{1}));
}

// Random push/pop sequences against a model stack: every prefetched index is a current entry,
// no entry is prefetched twice between pushes, and a pop in state Sk prefetches at most depth[k].
TEST(Ttp, NeverPrefetchesAnEntryTwiceBetweenPushes) {
    std::mt19937 g(5);
    const std::array<uint32_t, 3> depth{1, 2, 16};
    for (int trial = 0; trial < 200; ++trial) {
        TtpDfs ttp;
        std::vector<int> stack;  // entry ids
        std::set<int> prefetched_since_push;
        int next_id = 0;
        for (int step = 0; step < 200; ++step) {
            if (stack.empty() || g() % 3 == 0) {
                const int n = 1 + int(g() % 5);
                for (int k = 0; k < n; ++k) stack.push_back(next_id++);
                ttp.on_push(stack.size());
                prefetched_since_push.clear();
            } else {
                stack.pop_back();
                std::vector<size_t> out;
                ttp.on_pop(stack.size(), depth, out);
                ASSERT_LE(out.size(), depth[size_t(ttp.state() - 1)]);
                for (size_t i : out) {
                    ASSERT_LT(i, stack.size());
                    EXPECT_TRUE(prefetched_since_push.insert(stack[i]).second) << "entry " << stack[i] << " prefetched twice";
                }
            }
        }
    }
}

TEST(Ttp, BfsPrefetchesUpToNFromTheHeadOnce) {
    TtpBfs bfs;
    std::vector<size_t> out;
    bfs.on_pop(5, 2, out);  // queue after pop has 5 entries: prefetch positions 0, 1
    EXPECT_EQ(out, (std::vector<size_t>{0, 1}));
    out.clear();
    bfs.on_pop(4, 2, out);  // old position 1 is now 0 (already prefetched): only the new position 1
    EXPECT_EQ(out, (std::vector<size_t>{1}));
    out.clear();
    bfs.on_pop(1, 4, out);
    EXPECT_EQ(out, (std::vector<size_t>{}));  // position 0 already prefetched, nothing beyond
}

// The TTP authors' BFS (vulkan_ray_tracing.cc l.551-568, 662-718): the DFS trend's depths from
// the queue's head, a push resetting the state. Hand-worked with depths 1, 2, 16 on a queue of 20
// entries after the first pop: pop 1 (S1) takes position 0; pop 2 (S2) pops that entry and takes
// positions 0 and 1, neither taken yet; pop 3 (S3) takes positions 1..15 (0 was taken at pop 2);
// a push resets the state: pop 4 (S1) and pop 5 (S2) take nothing, the 15 and then 14 entries
// ahead of the head already prefetched covering their depths.
TEST(Ttp, BfsTrendPolicyTakesTheDfsDepthsFromTheHead) {
    const std::array<uint32_t, 3> depth{1, 2, 16};
    TtpBfs bfs;
    std::vector<size_t> out;
    bfs.on_pop_trend(20, depth, out);
    EXPECT_EQ(bfs.state(), 1);
    EXPECT_EQ(out, (std::vector<size_t>{0}));
    out.clear();
    bfs.on_pop_trend(19, depth, out);
    EXPECT_EQ(out, (std::vector<size_t>{0, 1}));
    out.clear();
    bfs.on_pop_trend(18, depth, out);
    EXPECT_EQ(bfs.state(), 3);
    std::vector<size_t> s3;
    for (size_t i = 1; i < 16; ++i) s3.push_back(i);
    EXPECT_EQ(out, s3);
    out.clear();
    bfs.on_push();
    EXPECT_EQ(bfs.state(), 0);
    bfs.on_pop_trend(20, depth, out);
    EXPECT_EQ(bfs.state(), 1);
    EXPECT_TRUE(out.empty());
    bfs.on_pop_trend(19, depth, out);
    EXPECT_TRUE(out.empty());
    // The fixed policy never leaves S0.
    TtpBfs fixed;
    fixed.on_pop(5, 2, out);
    EXPECT_EQ(fixed.state(), 0);
}

// Hand-built sequence: sector A prefetched then read (useful), B prefetched then read while
// still in flight (useful and late), C prefetched and evicted unread (unused).
TEST(PrefetchAccounting, UsefulLateAndUnusedOnAHandBuiltSequence) {
    SectorCache c(CacheConfig{2 * 128, 0, 128, 32, 4, 4, 0});  // two lines, fully associative
    EXPECT_EQ(c.read(0x000, 1, ReqKind::Prefetch), CacheOutcome::LineMiss);  // A
    c.fill(0x000);
    EXPECT_EQ(c.read(0x000, 2, ReqKind::Demand), CacheOutcome::Hit);         // uses A
    EXPECT_EQ(c.read(0x000, 3, ReqKind::Demand), CacheOutcome::Hit);         // second use: not counted again
    EXPECT_EQ(c.read(0x020, 4, ReqKind::Prefetch), CacheOutcome::SectorMiss);  // B
    EXPECT_EQ(c.read(0x020, 5, ReqKind::Demand), CacheOutcome::MshrHit);     // late use of B
    c.fill(0x020);
    EXPECT_EQ(c.read(0x080, 6, ReqKind::Prefetch), CacheOutcome::LineMiss);  // C in the second line
    c.fill(0x080);
    EXPECT_EQ(c.read(0x000, 7, ReqKind::Demand), CacheOutcome::Hit);         // line 0 most recent
    EXPECT_EQ(c.read(0x100, 8, ReqKind::Demand), CacheOutcome::LineMiss);    // evicts C's line unread
    const PrefetchedSectorCounts p = c.counts().prefetched;
    EXPECT_EQ(p.fills, 3u);
    EXPECT_EQ(p.useful, 2u);
    EXPECT_EQ(p.late, 1u);
    EXPECT_EQ(p.unused_evictions, 1u);
    // Accuracy = useful / prefetched = 2 / 3.
    EXPECT_DOUBLE_EQ(double(p.useful) / double(p.fills), 2.0 / 3.0);
    // The authors' count: C's line (last fill a prefetch's, no hit while so marked) was evicted
    // unused: 1 line. Their accuracy (3 - 1) / 3 here equals ours by chance.
    EXPECT_EQ(p.authors_unused_lines, 1u);
}

// The TTP authors' unused-prefetch count and its quirks (gpu-cache.cc): a line whose last fill
// was a demand's is not a prefetched line even if an earlier sector came by prefetch; a hit by a
// prefetch marks the line accessed; and the mark stays with the way, so a later prefetched line
// in the same way that is never read still counts as used.
TEST(PrefetchAccounting, TheAuthorsUnusedLineCount) {
    SectorCache c(CacheConfig{128, 0, 128, 32, 4, 4, 0});  // one line
    EXPECT_EQ(c.read(0x000, 1, ReqKind::Prefetch), CacheOutcome::LineMiss);
    c.fill(0x000);                                                            // line 0: prefetched
    EXPECT_EQ(c.read(0x020, 2, ReqKind::Demand), CacheOutcome::SectorMiss);
    c.fill(0x020);                                                            // last fill a demand's
    EXPECT_EQ(c.read(0x080, 3, ReqKind::Prefetch), CacheOutcome::LineMiss);  // evicts line 0
    c.fill(0x080);
    EXPECT_EQ(c.counts().prefetched.authors_unused_lines, 0u);  // not "prefetched" any more
    EXPECT_EQ(c.counts().prefetched.unused_evictions, 1u);      // ours: sector 0x000 never read
    EXPECT_EQ(c.read(0x080, 4, ReqKind::Prefetch), CacheOutcome::Hit);  // a prefetch hit marks the way
    EXPECT_EQ(c.read(0x100, 5, ReqKind::Prefetch), CacheOutcome::LineMiss);  // evicts line 0x080
    c.fill(0x100);
    EXPECT_EQ(c.counts().prefetched.authors_unused_lines, 0u);  // it had a (prefetch) hit
    EXPECT_EQ(c.read(0x180, 6, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x100, never hit
    c.fill(0x180);
    EXPECT_EQ(c.counts().prefetched.authors_unused_lines, 0u);  // the way's mark stayed
    EXPECT_EQ(c.counts().prefetched.unused_evictions, 3u);      // ours: 0x000, 0x080, 0x100 unread
}

namespace {
// A warp of 32 rays from the camera at the LumiBench bunny.
std::vector<WarpRay> bunny_warp() {
    std::vector<WarpRay> rays;
    for (int i = 0; i < 32; ++i) {
        WarpRay r;
        r.ray.org = {278, 278, 800};
        r.ray.dir = glm::vec3(-0.13f + 0.005f * (i % 8), -0.2f + 0.005f * (i / 8), -1.0f);
        r.key = uint64_t(i);
        rays.push_back(r);
    }
    return rays;
}

// In the RT unit, every prefetch TTP generates is for a node that is in the thread's stack (DFS)
// or queue (BFS) at that moment.
void prefetches_only_current_entries(TraversalOrder order) {
    const Scene s = load_scene("bunny", rtu::test::shared_dir() + "/scenes/bunny");
    const BvhImage img = build_bvh_image(s);
    HwConfig hw = Config::load("mobile").resolve();
    hw.prefetch.kind = PrefetcherKind::Ttp;
    hw.prefetch.bfs_n = 4;
    RtUnitCore core(hw, img, order);
    // A warp of 32 rays from the camera at the bunny; memory answers every request 50 cycles later.
    const std::vector<WarpRay> rays = bunny_warp();
    core.accept_warp(rays, 0);
    uint64_t generated = 0;
    core.on_prefetch_generated = [&](const ChunkRequest& r) {
        ++generated;
        // The prefetched node (64 B aligned; a 128 B instance leaf spans two blocks) must be an
        // entry of the generating thread's stack right now.
        const uint64_t node = r.addr & ~uint64_t(63);
        EXPECT_TRUE(core.stack_contains(r.warp, r.thread, node) || core.stack_contains(r.warp, r.thread, node - 64))
            << "prefetch of " << r.addr << " is not in thread " << r.thread << "'s stack";
    };
    std::multimap<uint64_t, uint64_t> answers;
    uint64_t prefetches = 0;
    for (uint64_t c = 0; c < 200000 && !core.idle(); ++c) {
        for (auto it = answers.begin(); it != answers.end() && it->first <= c; it = answers.erase(it))
            core.on_response(it->second, true, true, c);
        if (core.has_request(c)) {
            const ChunkRequest r = core.front_request(c);
            prefetches += r.prefetch;
            core.pop_request(c);
            answers.insert({c + 50, r.id});
        }
        core.cycle(c);
        core.take_retired();
    }
    EXPECT_TRUE(core.idle());
    EXPECT_GT(prefetches, 10u);
    // Every generated (non-duplicate) prefetch left the unit or was taken out by a demand read of
    // its chunk.
    const PrefetchQueueCounts& q = core.stats().prefetch_queue;
    EXPECT_GT(q.removed_by_demand, 0u);
    EXPECT_EQ(generated, prefetches + q.removed_by_demand);
    EXPECT_EQ(q.generated, generated + q.duplicates_dropped);
    EXPECT_EQ(core.stats().prefetch_queue.sent, prefetches);
}
}  // namespace

// A prefetch's response passes the RT unit's response FIFO like a demand's and takes one of its
// one-per-cycle drains (the TTP authors' rt_unit::fill and its pop, model/response_fifo.h); only
// then is it dropped. Before, it was dropped on arrival, so LT and the interval fidelity, whose
// memory hands over any number of responses per cycle, drained a demand behind a prefetch early:
// -5.6 % cycles against AT on sprng primary rays 128x128 (`mobile`, TTP), 22 % fewer prefetches
// sent at 256x256. Here the bunny's first warp runs with demands answered 30 cycles later and
// every prefetch's response held; then the held prefetches' responses and one demand's reach the
// unit in one cycle, in that order. The demand must drain k + 1 cycles later (k prefetches
// ahead of it), not in the next cycle, and only it counts as a response.
TEST(RtUnitCore, PrefetchResponsesTakeADrainCycleEach) {
    RTU_NEED_SHARED_SCENES();
    const Scene s = load_scene("bunny", rtu::test::shared_dir() + "/scenes/bunny");
    const BvhImage img = build_bvh_image(s);
    HwConfig hw = Config::load("mobile").resolve();
    ASSERT_EQ(hw.response_fifo, 0u);  // unbounded: every response comes in when it arrives
    hw.prefetch.kind = PrefetcherKind::Ttp;
    RtUnitCore core(hw, img, TraversalOrder::DFS);
    const std::vector<WarpRay> rays = bunny_warp();
    core.accept_warp(rays, 0);
    std::multimap<uint64_t, uint64_t> demands;  // cycle -> chunk id
    std::vector<uint64_t> prefetches;           // held
    // The demands due by `now` reach the unit.
    auto answer_due = [&](uint64_t now) {
        for (auto it = demands.begin(); it != demands.end() && it->first <= now; it = demands.erase(it))
            core.on_response(it->second, true, true, now);
    };
    uint64_t c = 0;
    for (; c < 100000 && prefetches.size() < 6; ++c) {
        answer_due(c);
        if (core.has_request(c)) {
            const ChunkRequest r = core.front_request(c);
            core.pop_request(c);
            if (r.prefetch) prefetches.push_back(r.id);
            else demands.insert({c + 30, r.id});
        }
        core.cycle(c);
    }
    ASSERT_EQ(prefetches.size(), 6u) << "TTP sent too few prefetches";
    // Let the FIFO run empty (no response due in the next cycles), then deliver.
    while (core.response_fifo_depth() > 0 || (!demands.empty() && demands.begin()->first <= c + 1)) {
        answer_due(c);
        core.cycle(c++);
    }
    ASSERT_FALSE(demands.empty()) << "no demand left in flight";
    const uint64_t demand = demands.begin()->second;
    demands.erase(demands.begin());
    for (uint64_t id : prefetches) core.on_response(id, true, true, c);
    core.on_response(demand, true, true, c);
    EXPECT_EQ(core.response_fifo_depth(), prefetches.size() + 1);
    EXPECT_EQ(core.stats().prefetch_queue.answered, prefetches.size());
    const uint64_t before = core.stats().responses;
    for (size_t k = 0; k < prefetches.size(); ++k) {
        core.cycle(c++);
        EXPECT_EQ(core.stats().responses, before) << "a demand drained in cycle " << k << " behind " << prefetches.size() << " prefetches";
        EXPECT_EQ(core.response_fifo_depth(), prefetches.size() - k);
    }
    core.cycle(c++);
    EXPECT_EQ(core.stats().responses, before + 1);
    EXPECT_EQ(core.response_fifo_depth(), 0u);
}

TEST(Ttp, RtUnitPrefetchesOnlyCurrentStackEntries) { RTU_NEED_SHARED_SCENES(); prefetches_only_current_entries(TraversalOrder::DFS); }
TEST(Ttp, RtUnitPrefetchesOnlyCurrentQueueEntries) { RTU_NEED_SHARED_SCENES(); prefetches_only_current_entries(TraversalOrder::BFS); }

// Treelets: every node of the image in exactly one treelet, no treelet over the byte budget
// (a single node, with the header it brings, may exceed a budget smaller than itself), each grown
// from its first node.
TEST(Treelets, FormationRespectsTheBudgetAndCoversEveryNodeOnce) {
    RTU_NEED_SHARED_SCENES();
    const Scene s = load_scene("ship", rtu::test::shared_dir() + "/scenes/ship");
    const BvhImage img = build_bvh_image(s);
    // Nodes and the 64 B headers (the TLAS's and each BLAS's).
    ASSERT_TRUE(img.header().has_headers);
    const uint64_t nodes = img.stats.internal_nodes + img.stats.triangle_leaves + img.stats.procedural_leaves + img.stats.instance_leaves + 1 + img.stats.blas_count;
    for (uint32_t budget : {64u, 512u, 4096u, 48u * 1024u}) {
        const Treelets t = form_treelets(img, budget);
        EXPECT_EQ(t.of.size(), nodes) << budget;
        uint64_t listed = 0, bytes = 0;
        for (size_t i = 0; i < t.nodes.size(); ++i) {
            listed += t.nodes[i].size();
            bytes += t.bytes[i];
            ASSERT_FALSE(t.nodes[i].empty());
            const auto node_count = std::count_if(t.nodes[i].begin(), t.nodes[i].end(), [](const StackEntry& e) { return e.type != NodeType::Header; });
            if (node_count > 1) {
                EXPECT_LE(t.bytes[i], budget) << "treelet " << i;
            }
            for (const StackEntry& e : t.nodes[i]) EXPECT_EQ(t.treelet_of(e.addr), i);
        }
        EXPECT_EQ(listed, nodes) << budget;
        EXPECT_EQ(bytes, img.size()) << "every byte, once";
        EXPECT_EQ(t.treelet_of(img.header().root), 0u);
        EXPECT_EQ(t.treelet_of(0), 0u) << "the TLAS header";
        if (budget == 512u) {
            EXPECT_GE(t.nodes.size(), nodes / 8);  // at most 8 nodes of 64 B per 512 B treelet
        }
    }
}

// The contiguous layout (the Treelet paper's): each treelet in a block of budget + stride bytes
// past the image, root first, its nodes back to back, in the order of the roots' addresses; the
// BVH layout moves nothing. Formation is the same either way.
TEST(Treelets, ContiguousLayoutPutsEachTreeletInABlockOfItsOwn) {
    RTU_NEED_SHARED_SCENES();
    const BvhImage img = build_bvh_image(load_scene("ship", rtu::test::shared_dir() + "/scenes/ship"));
    const Treelets bvh = form_treelets(img, 512);
    EXPECT_TRUE(bvh.moved.empty());
    EXPECT_EQ(bvh.placed(img.header().root), img.header().root);
    const Treelets t = form_treelets(img, 512, true, 256);
    ASSERT_EQ(t.nodes.size(), bvh.nodes.size());
    const uint64_t base = (img.size() + 4095) / 4096 * 4096, block = 512 + 256;
    std::vector<uint64_t> roots;
    for (const auto& n : t.nodes) roots.push_back(n[0].addr);
    std::sort(roots.begin(), roots.end());
    std::set<uint64_t> seen;
    for (size_t i = 0; i < t.nodes.size(); ++i) {
        ASSERT_EQ(t.nodes[i].size(), bvh.nodes[i].size());
        for (size_t j = 0; j < t.nodes[i].size(); ++j) EXPECT_EQ(t.nodes[i][j].addr, bvh.nodes[i][j].addr);
        const uint64_t k = uint64_t(std::lower_bound(roots.begin(), roots.end(), t.nodes[i][0].addr) - roots.begin());
        uint64_t at = base + k * block;
        for (const StackEntry& e : t.nodes[i]) {
            EXPECT_EQ(t.placed(e.addr), at);
            EXPECT_TRUE(seen.insert(at).second);
            at += node_bytes(e.type);
        }
        EXPECT_LE(at, base + (k + 1) * block);
    }
}

namespace {
// A hand-made RT unit for the Treelet prefetcher: threads whose next nodes are given.
struct FakeUnit : UnitThreads {
    std::vector<TraversalThread> threads;
    void for_each_live(const std::function<void(const TraversalThread&)>& f) const override {
        for (const TraversalThread& t : threads) f(t);
    }
};
struct Recording : PrefetchSink {
    std::vector<uint64_t> nodes;
    size_t waiting = 0;  // chunks the prefetch queue is said to hold
    void prefetch(const StackEntry& e, uint64_t) override { nodes.push_back(e.addr); }
    void window_drop() override {}
    size_t queued() const override { return waiting; }
};
}  // namespace

// The Treelet prefetcher as the code the paper ran: the RT unit's most popular treelet (by the
// treelet of each live thread's next node; ties: the smaller root address) is prefetched whole,
// unless it was the last one; the popularity heuristic only above its share of the votes.
// Threads are real treelet traversals of the bunny, stepped until their next node is outside the
// root treelet.
TEST(Treelets, PrefetcherPicksTheUnitsMostPopularTreeletOnce) {
    RTU_NEED_SHARED_SCENES();
    const Scene scene = load_scene("bunny", rtu::test::shared_dir() + "/scenes/bunny");
    const BvhImage img = build_bvh_image(scene);
    const Treelets t = form_treelets(img, 512);
    // Rays from the camera, stepped; a copy of a thread is kept each time it heads for a treelet
    // other than the root's and the ones kept so far, until there are two.
    std::vector<TraversalThread> heading;
    std::vector<uint32_t> target;
    for (int i = 0; i < 64 && heading.size() < 2; ++i) {
        Ray r;
        r.org = scene.camera.eye;
        r.dir = glm::normalize(scene.camera.lookat - scene.camera.eye) + glm::vec3(0.06f * float(i % 8 - 4), 0.06f * float(i / 8 - 4), 0);
        scale_direction(r);
        TraversalThread th;
        th.start(r, img.header(), TraversalOrder::Treelet, &t, false);
        while (!th.done() && heading.size() < 2) {
            const uint32_t id = t.treelet_of(th.peek().addr);
            if (id != 0 && std::find(target.begin(), target.end(), id) == target.end()) {
                heading.push_back(th);
                target.push_back(id);
            }
            th.step(img);
        }
    }
    ASSERT_EQ(heading.size(), 2u) << "no two rays heading for different treelets; treelets " << t.nodes.size() << " eye " << scene.camera.eye.x << "," << scene.camera.eye.y << "," << scene.camera.eye.z << " at " << scene.camera.lookat.x << "," << scene.camera.lookat.y << "," << scene.camera.lookat.z;
    auto whole = [&](uint32_t id) {
        std::vector<uint64_t> v;
        for (const StackEntry& e : t.nodes[id]) v.push_back(e.addr);
        return v;
    };
    auto make = [&](TreeletHeuristic h, double threshold, uint32_t queue_limit = 1000000, uint32_t vote_period = 1) {
        PrefetchConfig c;
        c.kind = PrefetcherKind::Treelet;
        c.treelet_heuristic = h;
        c.treelet_threshold = threshold;
        c.treelet_queue_limit = queue_limit;
        c.treelet_vote_period = vote_period;
        return make_prefetcher(c, TraversalOrder::Treelet, RtLatency{}, &t);
    };
    FakeUnit unit;
    unit.threads = {heading[0], heading[1], heading[1]};  // treelet B: 2 votes, A: 1
    auto p = make(TreeletHeuristic::Always, 0.75);
    EXPECT_EQ(p->hooks(), unsigned(Prefetcher::OnCycle));
    Recording out;
    p->on_cycle(unit, out, 0);
    EXPECT_EQ(out.nodes, whole(target[1]));
    out.nodes.clear();
    p->on_cycle(unit, out, 1);
    EXPECT_TRUE(out.nodes.empty());  // the last one prefetched: not again
    // A tie goes to the treelet whose root has the smaller address.
    unit.threads = {heading[0], heading[1]};
    const uint32_t smaller = t.nodes[target[0]][0].addr < t.nodes[target[1]][0].addr ? target[0] : target[1];
    auto q = make(TreeletHeuristic::Always, 0.75);
    q->on_cycle(unit, out, 0);
    EXPECT_EQ(out.nodes, whole(smaller));
    // Popularity: 2 of 3 votes (67 %) is below 75 %: nothing; at 60 % the winner goes.
    unit.threads = {heading[0], heading[1], heading[1]};
    out.nodes.clear();
    make(TreeletHeuristic::Popularity, 0.75)->on_cycle(unit, out, 0);
    EXPECT_TRUE(out.nodes.empty());
    make(TreeletHeuristic::Popularity, 0.6)->on_cycle(unit, out, 0);
    EXPECT_EQ(out.nodes, whole(target[1]));

    // The code's size check (shader.cc l.3577): the treelet's nodes plus the chunks waiting in
    // the queue must be at most treelet_queue_limit, or it is not enqueued (and the vote is taken
    // again later). Its votes come every treelet_vote_period cycles.
    const size_t n = t.nodes[target[1]].size();
    auto gated = [&](uint32_t limit, uint32_t period) { return make(TreeletHeuristic::Always, 0.75, limit, period); };
    out.nodes.clear();
    auto small = gated(uint32_t(n - 1), 1);
    small->on_cycle(unit, out, 0);
    EXPECT_TRUE(out.nodes.empty()) << n << " nodes over a limit of " << n - 1;
    auto fits = gated(uint32_t(n), 1);
    out.waiting = 1;  // nodes and chunks counted together: n + 1 > n
    fits->on_cycle(unit, out, 0);
    EXPECT_TRUE(out.nodes.empty());
    out.waiting = 0;
    fits->on_cycle(unit, out, 1);  // refused before, so voted on again
    EXPECT_EQ(out.nodes, whole(target[1]));
    out.nodes.clear();
    auto slow = gated(1000000, 32);
    unit.threads = {heading[0], heading[0], heading[1]};  // A leads
    slow->on_cycle(unit, out, 5);
    EXPECT_EQ(out.nodes, whole(target[0]));
    out.nodes.clear();
    unit.threads = {heading[1], heading[1], heading[0]};  // B leads, within the same period
    slow->on_cycle(unit, out, 31);
    EXPECT_TRUE(out.nodes.empty());
    slow->on_cycle(unit, out, 32);
    EXPECT_EQ(out.nodes, whole(target[1]));
}

namespace {
// Ray i (of 2,000) of a fan from in front of the bunny, 50 x 40 directions over its middle.
Ray bunny_fan_ray(int i) {
    Ray r;
    r.org = {278, 278, 800};
    r.dir = glm::vec3(-0.3f + 0.6f * float(i % 50) / 49.0f, -0.3f + 0.6f * float(i / 50) / 39.0f, -1.0f);
    return r;
}
// Treelet traversal over `t` finds DFS's closest hit for ray i; a hit is counted in `hits`.
void expect_dfs_hit(const BvhImage& img, const Treelets& t, const Ray& r, int i, int& hits) {
    const TraceResult a = trace_ray(img, r, TraversalOrder::DFS);
    const TraceResult b = trace_ray(img, r, TraversalOrder::Treelet, &t);
    EXPECT_EQ(a.hit.hit, b.hit.hit) << i;
    if (a.hit.hit && b.hit.hit) {
        EXPECT_EQ(a.hit.t, b.hit.t) << i;
        ++hits;
    }
}
}  // namespace

// Treelet traversal finds the same closest hits as DFS, and finishes a treelet before it moves
// on: no ray enters the same treelet twice (bunny has no BLAS instanced twice).
TEST(Treelets, TraversalFindsTheDfsHitsAndFinishesATreeletBeforeLeaving) {
    RTU_NEED_SHARED_SCENES();
    const Scene s = load_scene("bunny", rtu::test::shared_dir() + "/scenes/bunny");
    const BvhImage img = build_bvh_image(s);
    const Treelets t = form_treelets(img, 512);
    int hits = 0, switches = 0;
    for (int i = 0; i < 2000; ++i) {
        const Ray r = bunny_fan_ray(i);
        expect_dfs_hit(img, t, r, i, hits);
        TraversalThread th;
        th.start(r, img.header(), TraversalOrder::Treelet, &t);
        std::set<uint32_t> entered = {th.current_treelet()};
        uint32_t current = th.current_treelet();
        while (!th.done()) {
            const uint32_t next = t.treelet_of(th.peek().addr);
            if (next != current) {
                EXPECT_TRUE(entered.insert(next).second) << "ray " << i << " re-enters treelet " << next;
                current = next;
                ++switches;
            }
            th.step(img);
        }
    }
    EXPECT_GT(hits, 500);
    EXPECT_GT(switches, 1000);
}

// The order of the Treelet code both papers ran (prefetch.treelet_order=root-then-dfs): the root
// treelet first, exactly as treelet-first traversal walks it, then every other node in DFS order,
// so a ray leaves the root treelet once and may go back into other treelets it left (treelet-first
// never does: the test above). Same closest hits as DFS.
TEST(Treelets, RootThenDfsWalksTheRootTreeletThenInDfsOrder) {
    RTU_NEED_SHARED_SCENES();
    const Scene s = load_scene("bunny", rtu::test::shared_dir() + "/scenes/bunny");
    const BvhImage img = build_bvh_image(s);
    const Treelets first = form_treelets(img, 512);
    Treelets root = form_treelets(img, 512);
    root.order = TreeletOrder::RootThenDfs;
    const uint32_t root_id = root.treelet_of(img.header().root);
    // The node addresses a traversal reads, and how many of them lie in the root treelet before
    // it first reads a node outside it.
    const auto reads = [&img](const Ray& r, const Treelets& t, uint32_t root_treelet, size_t& in_root_first) {
        std::vector<uint64_t> nodes;
        in_root_first = 0;
        bool left = false;
        TraversalThread th;
        th.start(r, img.header(), TraversalOrder::Treelet, &t);
        while (!th.done()) {
            nodes.push_back(th.peek().addr);
            left = left || t.treelet_of(th.peek().addr) != root_treelet;
            if (!left) ++in_root_first;
            th.step(img);
        }
        return nodes;
    };
    int hits = 0, reentries = 0, differ = 0;
    for (int i = 0; i < 2000; ++i) {
        const Ray r = bunny_fan_ray(i);
        expect_dfs_hit(img, root, r, i, hits);
        size_t prefix_first = 0, prefix_root = 0;
        const std::vector<uint64_t> f = reads(r, first, root_id, prefix_first), d = reads(r, root, root_id, prefix_root);
        // The root treelet is walked alike, and never entered again once left.
        ASSERT_EQ(prefix_first, prefix_root) << i;
        EXPECT_TRUE(std::equal(d.begin(), d.begin() + long(prefix_root), f.begin())) << i;
        std::set<uint32_t> left;
        uint32_t current = root_id;
        for (size_t k = prefix_root; k < d.size(); ++k) {
            const uint32_t id = root.treelet_of(d[k]);
            EXPECT_NE(id, root_id) << "ray " << i << " reads the root treelet again at read " << k;
            if (id != current) {
                if (left.count(id)) ++reentries;
                left.insert(current);
                current = id;
            }
        }
        differ += d != f;
    }
    EXPECT_GT(hits, 500);
    EXPECT_GT(reentries, 100) << "past the root treelet, the reads should follow DFS, which goes back into treelets";
    EXPECT_GT(differ, 200);
}

namespace {
ChunkRequest chunk(uint64_t id, uint64_t addr, uint32_t warp, bool prefetch = false, bool more = false) {
    ChunkRequest r;
    r.id = id;
    r.addr = addr;
    r.warp = warp;
    r.prefetch = prefetch;
    r.more = more;
    return r;
}
}  // namespace

// A demand chunk that leaves takes a waiting prefetch of the same chunk out of the prefetch
// queue (the TTP authors' RT unit); a bounded queue drops what finds it full; a removed chunk
// never leaves and may be queued again.
TEST(PrefetchQueue, DemandTakesTheSameChunkOutAndABoundDrops) {
    MemoryAccessQueue maq(0, WarpOrder::RoundRobin, 1, 2);
    PrefetchQueue& pq = maq.prefetches();
    pq.push(chunk(1, 0x100, 0, true));
    pq.push(chunk(2, 0x120, 0, true));
    EXPECT_TRUE(pq.full());
    maq.push(chunk(3, 0x120, 0), 1);  // a demand read of the second prefetch's chunk
    uint64_t removed = 0, expired = 0;
    ASSERT_TRUE(maq.has_request(0, expired));
    EXPECT_FALSE(maq.front(0).prefetch);  // demand first
    EXPECT_EQ(maq.pop(0, removed).id, 3u);
    EXPECT_EQ(removed, 1u);
    EXPECT_FALSE(pq.waiting(0x120));
    EXPECT_EQ(pq.size(), 1u);
    EXPECT_FALSE(pq.full());
    pq.push(chunk(4, 0x140, 0, true));
    EXPECT_TRUE(pq.full());
    pq.pop();  // 1 leaves
    pq.push(chunk(5, 0x120, 0, true));  // the removed chunk, queued again
    EXPECT_EQ(pq.size(), 2u);
    std::vector<uint64_t> left;
    while (maq.has_request(1, expired)) left.push_back(maq.pop(1, removed).id);
    EXPECT_EQ(left, (std::vector<uint64_t>{4, 5}));  // 2 was taken out and never left
    EXPECT_EQ(removed, 1u);
}

// Oldest first: the oldest warp's reads leave before a younger warp's, even when the younger
// warp's were queued earlier; the chunks of one read leave together even when an older warp's
// read arrives between them. Round robin keeps queue order.
TEST(MemoryAccessQueue, OldestFirstAndReadsKeptTogether) {
    for (const WarpOrder order : {WarpOrder::RoundRobin, WarpOrder::OldestFirst}) {
        MemoryAccessQueue maq(0, order, 3);
        uint64_t removed = 0, expired = 0;
        // Slot 2 holds the youngest warp (age 9): its read of two chunks is queued first.
        maq.push(chunk(1, 0x000, 2, false, true), 9);
        maq.push(chunk(2, 0x020, 2), 9);
        maq.push(chunk(3, 0x100, 0), 5);  // slot 0, age 5
        std::vector<uint64_t> left;
        ASSERT_TRUE(maq.has_request(0, expired));
        left.push_back(maq.pop(0, removed).id);
        maq.push(chunk(4, 0x200, 1, false, true), 1);  // the oldest warp, two chunks
        maq.push(chunk(5, 0x220, 1), 1);
        while (maq.has_request(1, expired)) left.push_back(maq.pop(1, removed).id);
        if (order == WarpOrder::RoundRobin)
            EXPECT_EQ(left, (std::vector<uint64_t>{1, 2, 3, 4, 5}));
        else  // 3 (age 5) first; then 4 and 5 (age 1); then the youngest's read
            EXPECT_EQ(left, (std::vector<uint64_t>{3, 4, 5, 1, 2}));
    }
    // The rest of a read goes before an older warp's read that arrived meanwhile.
    MemoryAccessQueue maq(0, WarpOrder::OldestFirst, 2);
    uint64_t removed = 0, expired = 0;
    maq.push(chunk(1, 0x000, 1, false, true), 7);
    maq.push(chunk(2, 0x020, 1), 7);
    ASSERT_TRUE(maq.has_request(0, expired));
    EXPECT_EQ(maq.pop(0, removed).id, 1u);
    maq.push(chunk(3, 0x100, 0), 2);
    std::vector<uint64_t> left;
    while (maq.has_request(1, expired)) left.push_back(maq.pop(1, removed).id);
    EXPECT_EQ(left, (std::vector<uint64_t>{2, 3}));
}

TEST(WarpScheduler, RoundRobinAndOldestFirst) {
    const std::vector<uint64_t> age = {7, 3, 9, 5};
    const std::vector<bool> ready = {true, false, true, true};
    auto has_ready = [&](uint32_t s) { return bool(ready[s]); };
    auto age_of = [&](uint32_t s) { return age[s]; };
    WarpScheduler rr(4, WarpOrder::RoundRobin);
    EXPECT_EQ(rr.pick(has_ready, age_of), 0);
    EXPECT_EQ(rr.pick(has_ready, age_of), 2);
    EXPECT_EQ(rr.pick(has_ready, age_of), 3);
    EXPECT_EQ(rr.pick(has_ready, age_of), 0);
    WarpScheduler oldest(4, WarpOrder::OldestFirst);
    EXPECT_EQ(oldest.pick(has_ready, age_of), 3);  // slot 1 (age 3) has no ready thread
    EXPECT_EQ(oldest.pick(has_ready, age_of), 3);
    EXPECT_EQ(oldest.pick([](uint32_t) { return false; }, age_of), -1);
}
