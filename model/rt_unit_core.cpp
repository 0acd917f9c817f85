#include "rt_unit_core.h"

#include <algorithm>
#include <stdexcept>

#include <absl/container/inlined_vector.h>

#include "treelet.h"

namespace rtu {

// The unit's live threads as the prefetcher reads them.
class RtUnitCore::UnitView : public UnitThreads {
public:
    explicit UnitView(const std::vector<Warp>& warps) : warps_(warps) {}
    void for_each_live(const std::function<void(const TraversalThread&)>& f) const override {
        for (const Warp& w : warps_)
            if (w.used)
                for (const Thread& t : w.threads)
                    if (t.status != ThreadStatus::Idle && !t.rt.trav.done()) f(t.rt.trav);
    }

private:
    const std::vector<Warp>& warps_;
};

RtUnitCore::RtUnitCore(const HwConfig& cfg, const BvhImage& image, TraversalOrder order, const Treelets* treelets)
    : cfg_(cfg), image_(image), order_(order), treelets_(treelets),
      prefetcher_(make_prefetcher(cfg.prefetch, order, cfg.lat, treelets)), warps_(cfg.warp_buffer),
      scheduler_(cfg.warp_buffer, cfg.warp_order), maq_(cfg.prefetch.priority_after, cfg.warp_order, cfg.warp_buffer, cfg.prefetch.queue),
      fifo_(cfg.response_fifo) {
    if (order == TraversalOrder::Treelet && !treelets) throw std::logic_error("treelet traversal needs treelets");
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
    return int(warps_[w].threads[t].rt.trav.stack().size());
}

uint32_t RtUnitCore::ready_warps() const {
    uint32_t n = 0;
    for (const Warp& w : warps_) n += w.used && w.ready > 0;
    return n;
}

RtUnitCore::ThreadView RtUnitCore::thread_view(uint32_t w, uint32_t t) const {
    ThreadView v;
    if (w >= warps_.size() || !warps_[w].used || t >= warps_[w].threads.size()) return v;
    const Thread& th = warps_[w].threads[t];
    v.status = th.status;
    v.node = th.rt.trav.done() ? 0 : th.rt.trav.peek().addr;
    v.l1_miss = th.fetch_l1_miss;
    v.dram = th.fetch_dram;
    v.warp = warps_[w].age;
    return v;
}

int RtUnitCore::ttp_state(uint32_t w, uint32_t t) const {
    if (w >= warps_.size() || !warps_[w].used || t >= warps_[w].threads.size()) return -1;
    const PrefetchThreadState& p = warps_[w].threads[t].rt.prefetch;
    return order_ == TraversalOrder::BFS ? p.bfs.state() : p.dfs.state();
}

bool RtUnitCore::stack_contains(uint32_t w, uint32_t t, uint64_t addr) const {
    if (w >= warps_.size() || !warps_[w].used || t >= warps_[w].threads.size()) return false;
    for (const StackEntry& e : warps_[w].threads[t].rt.trav.stack())
        if (e.addr == addr) return true;
    return false;
}

void RtUnitCore::set_status(Thread& t, ThreadStatus s, uint64_t now) {
    stats_.thread_cycles[t.status] += now - t.since;
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
    next_nodes_changed_ = true;
    w.threads.assign(rays.size(), Thread{});
    w.live = w.ready = 0;
    w.age = ++warps_accepted_;
    for (size_t i = 0; i < rays.size(); ++i) {
        Thread& t = w.threads[i];
        t.since = now;
        t.rt.start(rays[i], image_.header(), {order_, cfg_.next_node_register}, treelets_);
        if (!t.rt.trav.done()) {
            t.status = ThreadStatus::WaitSchedule;
            ++w.live;
            ++w.ready;
        }
    }
    ++stats_.warps;
    stats_.rays += rays.size();
    if (w.live == 0) {  // every ray missed the root box
        for (const Thread& t : w.threads) retired_.push_back(t.rt.retired());
        w.used = false;
    }
}

uint32_t rt_math_latency(const RtLatency& lat, const StepInfo& s, bool leaf_descriptor_read) {
    const uint32_t descriptor = leaf_descriptor_read ? 0 : lat.leaf_descriptor;  // else paid by the first read
    uint32_t l = 0;
    switch (s.type) {
        case NodeType::Internal: l = lat.ray_box; break;
        case NodeType::Triangle: l = descriptor + lat.ray_triangle + (s.hit ? lat.triangle_hit : 0); break;
        case NodeType::Procedural: l = descriptor + lat.procedural; break;
        case NodeType::Instance: l = descriptor + lat.transform; break;
        case NodeType::Header: l = lat.structure; break;
        case NodeType::Empty: break;
    }
    return std::max<uint32_t>(l, 1);
}

uint64_t RtUnitCore::placed(uint64_t node) const { return treelets_ ? treelets_->placed(node) : node; }

uint32_t RtUnitCore::math_latency(const StepInfo& s) const { return rt_math_latency(cfg_.lat, s, cfg_.leaf_descriptor_read); }

bool RtUnitCore::has_request(uint64_t now) { return maq_.has_request(now, stats_.prefetch_queue.expired_unsent); }

const ChunkRequest& RtUnitCore::front_request(uint64_t now) {
    if (!has_request(now)) throw std::logic_error("front_request without a request");
    return maq_.front(now);
}

void RtUnitCore::pop_request(uint64_t now) {
    const ChunkRequest r = maq_.pop(now, stats_.prefetch_queue.removed_by_demand);
    if (!r.prefetch) return;
    prefetch_ids_.insert(r.id);
    ++stats_.prefetch_queue.sent;
}

size_t RtUnitCore::Sink::queued() const { return core.maq_.prefetches().size(); }

void RtUnitCore::Sink::prefetch(const StackEntry& e, uint64_t deadline) {
    PrefetchQueue& q = core.maq_.prefetches();
    for (uint32_t c = 0; c < chunks_of(e.type); ++c) {
        const uint64_t addr = chunk_address(core.placed(e.addr), c);
        const uint64_t image_addr = chunk_address(e.addr, c);
        ++core.stats_.prefetch_queue.generated;
        if (q.waiting(addr)) {
            ++core.stats_.prefetch_queue.duplicates_dropped;
            continue;
        }
        if (q.full()) {
            ++core.stats_.prefetch_queue.full_dropped;
            continue;
        }
        ChunkRequest r;
        r.id = core.next_id_++;
        r.addr = addr;
        r.image_addr = image_addr;
        r.warp = warp;
        r.thread = thread;
        r.prefetch = true;
        r.deadline = deadline;
        if (core.on_prefetch_generated) core.on_prefetch_generated(r);
        q.push(r);
    }
}

void RtUnitCore::on_response(uint64_t id, bool l1_miss, bool dram, uint64_t now) {
    if (fifo_.full()) throw std::logic_error("response into a full response FIFO");
    // A prefetch filled the caches; its response still passes the FIFO (model/response_fifo.h).
    const bool prefetch = prefetch_ids_.erase(id) > 0;
    if (prefetch) ++stats_.prefetch_queue.answered;
    fifo_.push({id, l1_miss, dram, prefetch});
    stats_.max_response_fifo = std::max<uint64_t>(stats_.max_response_fifo, fifo_.size());
    (void)now;
}

void RtUnitCore::cycle(uint64_t now) {
    answer_limit_study_fetches(now);
    drain_response(now);
    finish_math(now);
    if ((prefetcher_->hooks() & Prefetcher::OnCycle) && next_nodes_changed_) {
        next_nodes_changed_ = false;
        sink_.warp = sink_.thread = 0;
        prefetcher_->on_cycle(UnitView(warps_), sink_, now);
    }
    schedule_warp(now);
}

// Limit studies: fetches answered as L1 hits reach the response FIFO on their cycle (or when it
// has room).
void RtUnitCore::answer_limit_study_fetches(uint64_t now) {
    while (!limit_study_.empty() && limit_study_.front().first <= now && !fifo_.full()) {
        fifo_.push({limit_study_.front().second, false, false});
        limit_study_.pop_front();
    }
}

// Response FIFO: one response per cycle. A prefetch's is dropped; a thread whose node is now
// whole runs the node's tests.
void RtUnitCore::drain_response(uint64_t now) {
    if (fifo_.empty()) return;
    const ChunkResponse resp = fifo_.pop();
    if (resp.prefetch) return;
    ++stats_.responses;
    Pending& p = slot_of(resp.id);
    if (p.id != resp.id) throw std::logic_error("response for an unknown or answered request");
    p.id = 0;  // free again; `p` stays valid below (nothing is issued while responses drain)
    --inflight_count_;
    Warp& w = warps_[p.warp];
    if (cfg_.merge_in_flight) {
        const auto it = w.chunks_pending.find(p.addr);
        if (it != w.chunks_pending.end() && it->second == resp.id) w.chunks_pending.erase(it);
    }
    for (uint16_t ti : p.threads) {
        Thread& t = w.threads[ti];
        t.fetch_l1_miss |= resp.l1_miss;
        t.fetch_dram |= resp.dram;
        if (--t.chunks_left > 0) continue;
        if (t.descriptor_read) {
            // The leaf's descriptor is here: decoding it takes its latency, then the leaf is read.
            set_status(t, ThreadStatus::InMath, now);
            math_.push({now + std::max<uint32_t>(1, cfg_.lat.leaf_descriptor), p.warp, ti});
            continue;
        }
        const StepInfo info = t.rt.complete_fetch(stats_, t.fetch_class, t.fetch_l1_miss, t.fetch_dram, image_, *prefetcher_);
        next_nodes_changed_ = true;
        const uint64_t end = now + math_latency(info);
        sink_.warp = p.warp;
        sink_.thread = ti;
        if (prefetcher_->hooks() & Prefetcher::OnNodeTest) prefetcher_->on_node_test(info, t.rt.trav.stack(), end, sink_);
        set_status(t, ThreadStatus::InMath, now);
        math_.push({end, p.warp, ti});
    }
}

// Math pipelines: threads whose tests end by now are ready for their next node, or done; a warp
// whose threads are all done leaves the warp buffer.
void RtUnitCore::finish_math(uint64_t now) {
    while (!math_.empty() && math_.top().at <= now) {
        const MathDone m = math_.top();
        math_.pop();
        Warp& w = warps_[m.warp];
        Thread& t = w.threads[m.thread];
        if (t.rt.trav.done()) {
            set_status(t, ThreadStatus::Idle, now);
            if (--w.live == 0) {
                stats_.intersection_loop_iterations += RtThread::loop_of(w.threads);
                for (Thread& x : w.threads) {
                    set_status(x, ThreadStatus::Idle, now);
                    retired_.push_back(x.rt.retired());
                }
                w.used = false;
                w.threads.clear();
            }
        } else {
            if (t.descriptor_read) {
                t.descriptor_read = false;
                t.leaf_read = true;
            }
            set_status(t, ThreadStatus::WaitSchedule, now);
            ++w.ready;
        }
    }
}

// Warp scheduler: one warp's ready threads go to the memory access queue, their node reads
// coalesced and split into chunks.
void RtUnitCore::schedule_warp(uint64_t now) {
    const int picked = scheduler_.pick([&](uint32_t s) { return warps_[s].used && warps_[s].ready > 0; }, [&](uint32_t s) { return warps_[s].age; });
    if (picked < 0) return;
    picked_ = picked;
    picked_at_ = now;
    const uint32_t wi = uint32_t(picked);
    Warp& w = warps_[wi];
    coalescer_.clear();
    for (uint16_t ti = 0; ti < w.threads.size(); ++ti) {
        Thread& t = w.threads[ti];
        if (t.status != ThreadStatus::WaitSchedule) continue;
        const StackEntry e = t.rt.trav.peek();
        if (t.leaf_read) {
            // The second read of a two-step leaf: no pop, the same node read.
            t.leaf_read = false;
            t.chunks_left = chunks_of(e.type);
        } else {
            sink_.warp = wi;
            sink_.thread = ti;
            t.fetch_class = t.rt.begin_fetch(*prefetcher_, sink_);
            t.rt.count_fetch(stats_, t.fetch_class);
            t.fetch_l1_miss = t.fetch_dram = false;
            t.descriptor_read = read_in_two_steps(e.type, cfg_.leaf_descriptor_read);
            t.chunks_left = t.descriptor_read ? kDescriptorChunks : chunks_of(e.type);
        }
        const bool limit_study = (prefetcher_->hooks() & Prefetcher::LimitStudy) && prefetcher_->answered_as_l1_hit(t.fetch_class);
        set_status(t, ThreadStatus::WaitMemory, now);
        // Coalesce identical reads (a limit-study hit does not merge with a real fetch, nor a
        // descriptor read with a whole leaf's). Node addresses are 64 B aligned: the low bits are free.
        const auto [g, fresh] = coalescer_.add(e.addr | (limit_study ? 1ull : 0ull) | (t.descriptor_read ? 2ull : 0ull));
        if (fresh) {
            group_chunks_[g] = t.chunks_left;
            group_size_[g] = 0;
        } else {
            ++stats_.coalesced_fetches;
        }
        group_members_[g][group_size_[g]++] = ti;
    }
    w.ready = 0;
    for (uint32_t g = 0; g < coalescer_.groups(); ++g) {
        const uint16_t* members = group_members_[g].data();
        const bool limit_study = coalescer_.key(g) & 1ull;
        const uint64_t node = coalescer_.key(g) & ~3ull;
        // rt.merge_in_flight (the TTP authors' RT unit): a chunk the warp already has queued or in
        // flight is not requested again; these threads join its waiting list and take its response
        // (abstract_hardware_model.cc l.1051-1062 keeps one queued request per address and size
        // for the warp, until its first chunk leaves, l.1113; l.1148-1186 give a returning chunk
        // to every thread of the warp whose next record starts at its address). A descriptor read and its leaf's first chunk share
        // an address, as there. Limit-study answers never merge with real fetches.
        const bool merge = cfg_.merge_in_flight && !limit_study;
        const uint64_t at = placed(node);
        // Per chunk, the request it joins (0: none, it is sent); `more` ends at the last one sent.
        absl::InlinedVector<uint64_t, 4> joins(group_chunks_[g], 0);
        uint32_t last_sent = ~0u;
        for (uint32_t c = 0; c < group_chunks_[g]; ++c) {
            if (merge) {
                const auto it = w.chunks_pending.find(chunk_address(at, c));
                if (it != w.chunks_pending.end()) joins[c] = it->second;
            }
            if (!joins[c]) last_sent = c;
        }
        for (uint32_t c = 0; c < group_chunks_[g]; ++c) {
            const uint64_t addr = chunk_address(at, c);
            if (joins[c]) {
                std::vector<uint16_t>& waiting = slot_of(joins[c]).threads;
                waiting.insert(waiting.end(), members, members + group_size_[g]);
                ++stats_.merged_in_flight;
                continue;
            }
            ChunkRequest r;
            r.id = next_id_++;
            r.addr = addr;
            r.image_addr = chunk_address(node, c);
            r.warp = wi;
            r.thread = members[0];
            r.streak = w.threads[members[0]].fetch_class;
            r.more = c < last_sent;
            Pending& slot = claim_slot(r.id);
            slot.id = r.id;
            slot.warp = wi;
            slot.addr = addr;
            slot.threads.assign(members, members + group_size_[g]);
            if (merge) w.chunks_pending.emplace(addr, r.id);
            ++inflight_count_;
            ++stats_.chunk_requests;
            if (limit_study) {
                limit_study_.push_back({now + std::max<uint64_t>(1, cfg_.l1_hit_latency) + c, r.id});
                ++stats_.limit_study_hits;
            } else {
                maq_.push(r, w.age);
            }
        }
    }
    stats_.max_memory_access_queue = std::max<uint64_t>(stats_.max_memory_access_queue, maq_.depth());
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
    return maq_.empty() && fifo_.empty() && math_.empty() && inflight_count_ == 0 &&
           limit_study_.empty() && warps_resident() == 0;
}

uint64_t RtUnitCore::next_event(uint64_t now) const {
    if (!fifo_.empty()) return now + 1;
    uint64_t next = ~0ull;
    if (!limit_study_.empty()) next = std::max(now + 1, limit_study_.front().first);
    for (const Warp& w : warps_)
        if (w.used && w.ready) return now + 1;
    if (!math_.empty()) next = std::min(next, std::max(now + 1, math_.top().at));
    return next;
}

}  // namespace rtu
