#include "rt_unit_core.h"

#include <map>

#include "treelet.h"

#include <algorithm>
#include <stdexcept>

namespace rtu {

RtUnitCore::RtUnitCore(const HwConfig& cfg, const BvhImage& image, TraversalOrder order, const Treelets* treelets)
    : cfg_(cfg), image_(image), order_(order), treelets_(treelets), warps_(cfg.warp_buffer) {
    if ((order == TraversalOrder::Treelet || cfg.prefetch.kind == PrefetcherKind::Treelet) && !treelets)
        throw std::logic_error("treelet traversal / prefetching needs treelets");
}

// Treelet prefetcher: when at least `treelet_threshold` of the warp's live threads head for the
// same next treelet, the whole treelet is prefetched (once per warp).
void RtUnitCore::prefetch_popular_treelet(Warp& w, uint32_t warp) {
    std::map<uint32_t, uint32_t> votes;
    for (const Thread& t : w.threads)
        if (t.status != ThreadStatus::Idle) {
            const uint32_t n = t.trav.next_treelet();
            if (n != ~0u) ++votes[n];
        }
    uint32_t best = ~0u, count = 0;
    for (const auto& [id, c] : votes)
        if (c > count) best = id, count = c;
    if (best == ~0u || double(count) < cfg_.prefetch.treelet_threshold * double(w.live)) return;
    if (!w.treelets_prefetched.insert(best).second) return;
    for (const StackEntry& e : treelets_->nodes[best]) prefetch_entry(e, warp, 0);
}

bool RtUnitCore::has_free_slot() const {
    for (const Warp& w : warps_)
        if (!w.used) return true;
    return false;
}

size_t RtUnitCore::warps_resident() const {
    size_t n = 0;
    for (const Warp& w : warps_) n += w.used;
    return n;
}

uint32_t RtUnitCore::warp_buffer_occupancy() const { return uint32_t(warps_resident()); }

uint32_t RtUnitCore::active_threads() const {
    uint32_t n = 0;
    for (const Warp& w : warps_)
        if (w.used) n += w.live;
    return n;
}

int RtUnitCore::stack_depth(uint32_t w, uint32_t t) const {
    if (w >= warps_.size() || !warps_[w].used || t >= warps_[w].threads.size()) return -1;
    return int(warps_[w].threads[t].trav.stack().size());
}

bool RtUnitCore::stack_contains(uint32_t w, uint32_t t, uint64_t addr) const {
    if (w >= warps_.size() || !warps_[w].used || t >= warps_[w].threads.size()) return false;
    for (const StackEntry& e : warps_[w].threads[t].trav.stack())
        if (e.addr == addr) return true;
    return false;
}

void RtUnitCore::set_status(Thread& t, ThreadStatus s, uint64_t now) {
    stats_.thread_cycles[size_t(t.status)] += now - t.since;
    t.status = s;
    t.since = now;
}

void RtUnitCore::account(uint64_t now) {
    for (Warp& w : warps_)
        if (w.used)
            for (Thread& t : w.threads) set_status(t, t.status, now);
}

void RtUnitCore::accept_warp(const std::vector<WarpRay>& rays, uint64_t now) {
    if (rays.empty() || rays.size() > cfg_.warp_size) throw std::logic_error("warp of " + std::to_string(rays.size()) + " rays");
    auto it = std::find_if(warps_.begin(), warps_.end(), [](const Warp& w) { return !w.used; });
    if (it == warps_.end()) throw std::logic_error("no free warp-buffer slot");
    Warp& w = *it;
    w.used = true;
    w.treelets_prefetched.clear();
    w.threads.assign(rays.size(), Thread{});
    w.live = w.ready = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        Thread& t = w.threads[i];
        t.key = rays[i].key;
        t.since = now;
        t.trav.start(rays[i].ray, image_.header(), order_, treelets_);
        if (!t.trav.done()) {
            t.status = ThreadStatus::WaitSchedule;
            ++w.live;
            ++w.ready;
        }
    }
    ++stats_.warps;
    stats_.rays += rays.size();
    if (w.live == 0) {  // every ray missed the root box
        for (const Thread& t : w.threads) retired_.push_back({t.key, t.trav.hit(), t.trav.nodes_visited(), 0, 0});
        w.used = false;
    }
}

uint32_t rt_math_latency(const RtLatency& lat, const StepInfo& s) {
    uint32_t l = 0;
    switch (s.type) {
        case NodeType::Internal: l = lat.header + lat.ray_box; break;
        case NodeType::Triangle: l = lat.leaf_descriptor + lat.ray_triangle + (s.hit ? lat.triangle_hit : 0); break;
        case NodeType::Procedural: l = lat.leaf_descriptor + lat.procedural; break;
        case NodeType::Instance: l = lat.leaf_descriptor + lat.transform; break;
        case NodeType::Empty: break;
    }
    return std::max<uint32_t>(l, 1);
}

uint32_t RtUnitCore::math_latency(const StepInfo& s) const { return rt_math_latency(cfg_.lat, s); }

bool RtUnitCore::has_request(uint64_t now) {
    if (!selected_) {
        while (!pfq_.empty() && pfq_.front().deadline < now) {
            pfq_.pop_front();
            ++stats_.prefetches_expired;
        }
    }
    return !maq_.empty() || !pfq_.empty();
}

const ChunkRequest& RtUnitCore::front_request(uint64_t now) {
    if (!has_request(now)) throw std::logic_error("front_request without a request");
    if (!selected_) {
        const uint32_t x = cfg_.prefetch.priority_after;
        const bool starving = x > 0 && now >= last_prefetch_sent_ + x;
        selected_prefetch_ = !pfq_.empty() && (maq_.empty() || starving);
        selected_ = true;
    }
    return selected_prefetch_ ? pfq_.front() : maq_.front();
}

void RtUnitCore::pop_request(uint64_t now) {
    if (!selected_) front_request(now);
    if (selected_prefetch_) {
        prefetch_ids_.insert(pfq_.front().id);
        pfq_.pop_front();
        last_prefetch_sent_ = now;
        ++stats_.prefetches_sent;
    } else {
        maq_.pop_front();
    }
    selected_ = false;
}

void RtUnitCore::prefetch_entry(const StackEntry& e, uint32_t warp, uint32_t thread, uint64_t deadline) {
    for (uint32_t c = 0; c < node_bytes(e.type) / kChunkBytes; ++c) {
        const uint64_t addr = e.addr + uint64_t(c) * kChunkBytes;
        ++stats_.prefetches_generated;
        if (std::any_of(pfq_.begin(), pfq_.end(), [&](const ChunkRequest& r) { return r.addr == addr; })) {
            ++stats_.prefetch_duplicates;
            continue;
        }
        ChunkRequest r;
        r.id = next_id_++;
        r.addr = addr;
        r.warp = warp;
        r.thread = thread;
        r.streak = 0;
        r.prefetch = true;
        r.deadline = deadline;
        if (on_prefetch_generated) on_prefetch_generated(r);
        pfq_.push_back(r);
    }
}

// TTP: the thread is about to pop; its stack after the pop is the current one without its top
// (DFS) or head (BFS).
void RtUnitCore::prefetch_on_pop(Thread& t, uint32_t warp, uint32_t thread) {
    const auto& st = t.trav.stack();
    if (st.empty()) return;
    std::vector<size_t> picks;
    if (order_ == TraversalOrder::DFS) {
        t.ttp_dfs.on_pop(st.size() - 1, cfg_.prefetch.depth, picks);
        for (size_t i : picks) prefetch_entry(st[i], warp, thread);
    } else {
        t.ttp_bfs.on_pop(st.size() - 1, cfg_.prefetch.bfs_n, picks);
        for (size_t pos : picks) prefetch_entry(st[pos + 1], warp, thread);
    }
}

void RtUnitCore::on_response(uint64_t id, bool l1_miss, bool dram, uint64_t now) {
    if (prefetch_ids_.erase(id)) {  // a prefetch filled the caches; the RT unit drops the data
        ++stats_.prefetch_responses;
        return;
    }
    fifo_.push_back({id, {l1_miss, dram}});
    stats_.max_response_fifo = std::max<uint64_t>(stats_.max_response_fifo, fifo_.size());
    (void)now;
}

void RtUnitCore::cycle(uint64_t now) {
    // Limit studies: fetches answered as L1 hits reach the response FIFO on their cycle.
    while (!perfect_.empty() && perfect_.front().first <= now) {
        fifo_.push_back({perfect_.front().second, {false, false}});
        perfect_.pop_front();
    }
    // Response FIFO: one response per cycle.
    if (!fifo_.empty()) {
        const auto [id, flags] = fifo_.front();
        fifo_.pop_front();
        ++stats_.responses;
        Pending& p = slot_of(id);
        if (p.id != id) throw std::logic_error("response for an unknown or answered request");
        p.id = 0;  // free again; `p` stays valid below (nothing is issued while responses drain)
        --inflight_count_;
        Warp& w = warps_[p.warp];
        for (uint16_t ti : p.threads) {
            Thread& t = w.threads[ti];
            t.fetch_l1_miss |= flags.first;
            t.fetch_dram |= flags.second;
            if (--t.chunks_left > 0) continue;
            // The whole node is here: decode it and run its tests.
            const StepInfo info = complete_fetch(t, stats_, t.fetch_class, t.fetch_l1_miss, t.fetch_dram, image_);
            // Park et al. (as the TTP paper models them): while a leaf test runs, prefetch as many
            // stack entries as can leave during it (one 32 B chunk per cycle), next pop first;
            // what has not left when the test ends is dropped.
            if (cfg_.prefetch.kind == PrefetcherKind::Park && (info.type == NodeType::Triangle || info.type == NodeType::Procedural)) {
                const auto& st = t.trav.stack();
                // Chunk slots during the intersection test itself (8 cycles in the paper's setup).
                uint32_t budget = info.type == NodeType::Triangle ? cfg_.lat.ray_triangle : cfg_.lat.procedural;
                const uint64_t test_end = now + math_latency(info);
                for (size_t k = 0; k < st.size(); ++k) {
                    const StackEntry& e = order_ == TraversalOrder::DFS ? st[st.size() - 1 - k] : st[k];
                    const uint32_t chunks = node_bytes(e.type) / kChunkBytes;
                    if (chunks > budget) break;
                    budget -= chunks;
                    prefetch_entry(e, p.warp, ti, test_end);
                }
            }
            set_status(t, ThreadStatus::InMath, now);
            math_.push({now + math_latency(info), p.warp, ti});
        }
    }
    // Math pipelines: threads whose tests end by now.
    while (!math_.empty() && math_.top().at <= now) {
        const MathDone m = math_.top();
        math_.pop();
        Warp& w = warps_[m.warp];
        Thread& t = w.threads[m.thread];
        if (t.trav.done()) {
            set_status(t, ThreadStatus::Idle, now);
            if (--w.live == 0) {
                for (Thread& x : w.threads) {
                    set_status(x, ThreadStatus::Idle, now);
                    retired_.push_back({x.key, x.trav.hit(), x.trav.nodes_visited(), x.l1_miss_nodes, x.dram_nodes});
                }
                w.used = false;
                w.threads.clear();
            }
        } else {
            set_status(t, ThreadStatus::WaitSchedule, now);
            ++w.ready;
        }
    }
    // Warp scheduler: one warp's ready threads go to the memory access queue, coalesced.
    for (uint32_t k = 0; k < warps_.size(); ++k) {
        const uint32_t wi = (rr_ + k) % uint32_t(warps_.size());
        Warp& w = warps_[wi];
        if (!w.used || w.ready == 0) continue;
        rr_ = wi + 1;
        // Unique node addresses of this warp's ready threads (at most one per thread), on the stack.
        uint32_t n_nodes = 0;
        std::array<uint64_t, 64> keys;
        std::array<NodeType, 64> types;
        std::array<uint8_t, 64> counts;
        std::array<std::array<uint16_t, 64>, 64> members;
        for (uint16_t ti = 0; ti < w.threads.size(); ++ti) {
            Thread& t = w.threads[ti];
            if (t.status != ThreadStatus::WaitSchedule) continue;
            const StackEntry& e = t.trav.peek();
            if (t.trav.next_is_pop()) {
                t.streak = uint8_t(std::min(t.streak + 1, 4));
                t.fetch_class = t.streak;
                if (cfg_.prefetch.kind == PrefetcherKind::Ttp) prefetch_on_pop(t, wi, ti);
            } else {
                t.fetch_class = 0;
            }
            const bool perfect = (cfg_.prefetch.kind == PrefetcherKind::PerfectUp && t.fetch_class >= 2) ||
                                 (cfg_.prefetch.kind == PrefetcherKind::PerfectDown && t.fetch_class == 1);
            ++stats_.streak_fetches[t.fetch_class];
            t.fetch_l1_miss = t.fetch_dram = false;
            t.fetch_type = e.type;
            t.chunks_left = node_bytes(e.type) / kChunkBytes;
            set_status(t, ThreadStatus::WaitMemory, now);
            ++stats_.node_fetches;
            // Coalesce identical addresses (a limit-study hit does not merge with a real fetch).
            const uint64_t key = e.addr | (perfect ? 1ull : 0ull);  // node addresses are 64 B aligned
            uint32_t k = 0;
            while (k < n_nodes && keys[k] != key) ++k;
            if (k == n_nodes) {
                keys[k] = key;
                types[k] = e.type;
                counts[k] = 0;
                ++n_nodes;
            } else {
                ++stats_.coalesced;
            }
            members[k][counts[k]++] = ti;
        }
        w.ready = 0;
        if (cfg_.prefetch.kind == PrefetcherKind::Treelet) prefetch_popular_treelet(w, wi);
        for (uint32_t n = 0; n < n_nodes; ++n) {
            const uint32_t chunks = node_bytes(types[n]) / kChunkBytes;
            const bool perfect = keys[n] & 1ull;
            const uint64_t base = keys[n] & ~1ull;
            for (uint32_t c = 0; c < chunks; ++c) {
                ChunkRequest r;
                r.id = next_id_++;
                r.addr = base + uint64_t(c) * kChunkBytes;
                r.warp = wi;
                r.thread = members[n][0];
                r.streak = w.threads[members[n][0]].fetch_class;
                Pending& slot = claim_slot(r.id);
                slot.id = r.id;
                slot.warp = wi;
                slot.threads.assign(members[n].begin(), members[n].begin() + counts[n]);
                ++inflight_count_;
                ++stats_.chunk_requests;
                if (perfect) {
                    perfect_.push_back({now + std::max<uint64_t>(1, cfg_.l1_hit_latency) + c, r.id});
                    ++stats_.perfect_hits;
                } else {
                    maq_.push_back(r);
                }
            }
        }
        stats_.max_request_queue = std::max<uint64_t>(stats_.max_request_queue, maq_.size());
        break;
    }
}

RtUnitCore::Pending& RtUnitCore::claim_slot(uint64_t id) {
    if (slot_of(id).id == 0) return slot_of(id);
    for (size_t size = inflight_.size() * 2;; size *= 2) {
        std::vector<Pending> grown(size);
        bool clash = false;
        for (Pending& p : inflight_) {
            if (p.id == 0) continue;
            Pending& q = grown[p.id & (size - 1)];
            if (q.id != 0) {
                clash = true;
                break;
            }
            q = std::move(p);
        }
        if (clash || grown[id & (size - 1)].id != 0) {
            // Put back what moved and try twice the size.
            for (Pending& q : grown)
                if (q.id != 0) inflight_[q.id & (inflight_.size() - 1)] = std::move(q);
            continue;
        }
        inflight_ = std::move(grown);
        return slot_of(id);
    }
}

std::vector<RetiredRay> RtUnitCore::take_retired() {
    std::vector<RetiredRay> r;
    r.swap(retired_);
    return r;
}

bool RtUnitCore::idle() const {
    return maq_.empty() && pfq_.empty() && fifo_.empty() && math_.empty() && inflight_count_ == 0 && perfect_.empty() &&
           warps_resident() == 0;
}

uint64_t RtUnitCore::next_event(uint64_t now) const {
    if (!fifo_.empty()) return now + 1;
    uint64_t next = ~0ull;
    if (!perfect_.empty()) next = std::max(now + 1, perfect_.front().first);
    for (const Warp& w : warps_)
        if (w.used && w.ready) return now + 1;
    if (!math_.empty()) next = std::min(next, std::max(now + 1, math_.top().at));
    return next;
}

}  // namespace rtu
