#include "interval_gpu.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "node_format.h"

namespace rtu {

IntervalGpu::IntervalGpu(const HwConfig& cfg, const BvhImage& image, TraversalOrder order)
    : cfg_(cfg),
      image_(image),
      order_(order),
      core_fs_(uint64_t(std::llround(1e9 / cfg.core_mhz))),
      memory_fs_(uint64_t(std::llround(1e9 / cfg.memory_mhz))),
      issue_(cfg.sms),
      drain_(cfg.sms),
      prefetch_queue_(cfg.sms, SmPrefetchQueue{PrefetchQueue(cfg.prefetch.queue), false}),
      map_(cfg.address_map()),
      dram_(cfg.dram, map_),
      rt_(cfg.sms),
      sched_cycle_(cfg.sms, ~0ull),
      sched_trace_(cfg.sms, ~0u),
      rr_next_(cfg.sms, 0),
      slot_busy_(cfg.sms, std::vector<uint8_t>(cfg.warp_buffer, 0)) {
    if (order == TraversalOrder::Treelet)
        throw std::invalid_argument("the interval fidelity models DFS and BFS traversal, not treelet traversal (use --fidelity at or lt)");
    if (cfg.response_fifo != 0)
        throw std::invalid_argument("the interval fidelity models an unbounded response FIFO (rt.response_fifo 0), not " +
                                    std::to_string(cfg.response_fifo) + " entries (use --fidelity at or lt)");
    prefetcher_ = make_prefetcher(cfg.prefetch, order, cfg.lat, nullptr);
    // A fetch event is where a pop happens: the prefetchers that act on other moments (a node's
    // test, a warp's scheduling, the limit studies) are AT's and LT's.
    if (prefetcher_->hooks() & ~unsigned(Prefetcher::OnPop))
        throw std::invalid_argument(std::string("the interval fidelity models the prefetchers none and ttp, not '") +
                                    prefetcher_->name() + "' (use --fidelity at or lt)");
    if (prefetcher_->hooks() && cfg.prefetch.priority_after != 0)
        throw std::invalid_argument("the interval fidelity sends prefetches only in cycles without a demand "
                                    "(prefetch.priority_after 0), not after " + std::to_string(cfg.prefetch.priority_after) +
                                    " cycles (use --fidelity at or lt)");
    // The L1 takes what the RT unit's request port sends, one chunk per cycle; an L2 slice books
    // its own lookups.
    for (uint32_t s = 0; s < cfg.sms; ++s) l1_.emplace_back(cfg.l1, cfg.l1_hit_latency, false);
    for (uint32_t s = 0; s < cfg.l2_slices; ++s) l2_.emplace_back(cfg.l2, cfg.l2.latency, true);
}

uint64_t IntervalGpu::memory_cycle(uint64_t c) const { return (c * core_fs_ + memory_fs_ - 1) / memory_fs_; }
uint64_t IntervalGpu::core_cycle(uint64_t m) const { return (m * memory_fs_ + core_fs_ - 1) / core_fs_; }

void IntervalGpu::advance(uint64_t floor) {
    if (floor <= floor_) return;
    floor_ = floor;
    // The ports' rings are recycled, and the caches forget sectors that arrived, every 1,024
    // cycles: bookings come at or after the floor anyway, since fetches run in time order, and a
    // sector remembered past its arrival answers as it would forgotten.
    if (floor < ports_floor_ + 1024) return;
    ports_floor_ = floor;
    for (CacheBookings& c : l1_) c.advance(floor);
    for (CacheBookings& c : l2_) c.advance(floor);
    for (PortCalendar& p : issue_) p.advance(floor);
    for (PortCalendar& p : drain_) p.advance(floor);
}

uint32_t IntervalGpu::slice_of(uint64_t addr) const { return map_.slice(addr); }

void IntervalGpu::warm(uint32_t sm, uint64_t addr) {
    if (!l1_[sm].tags().warm(addr)) l2_[slice_of(addr)].tags().warm(addr);
}

IntervalGpu::Served IntervalGpu::read_l2(uint64_t addr, uint64_t cycle, ReqKind kind) {
    CacheBookings& l2 = l2_[slice_of(addr)];
    const CacheBookings::Lookup l = l2.lookup(addr, cycle, kind);
    if (l.outcome != CacheBookings::Lookup::Miss) return {l.ready, false, l.dram};
    // A miss: DRAM after the lookup's latency and the front-end latency queue.
    const uint64_t done = core_cycle(dram_.access(l2.tags().sector_of(addr), cfg_.l2.sector, memory_cycle(l.ready + cfg_.dram.frontend_latency),
                                                  memory_cycle(floor_)));
    l2.fill(addr, l, done, true, kind);
    return {done, false, true};
}

IntervalGpu::Served IntervalGpu::read(uint32_t sm, uint64_t addr, uint64_t cycle, ReqKind kind) {
    CacheBookings& l1 = l1_[sm];
    const CacheBookings::Lookup l = l1.lookup(addr, cycle, kind);
    switch (l.outcome) {
        case CacheBookings::Lookup::Hit: return {l.ready, false, false};
        case CacheBookings::Lookup::InFlight: return {l.ready, true, l.dram};
        case CacheBookings::Lookup::Retry:
            // A reservation fail holds the RT unit's request port until the sector arrives (END_REQ
            // withheld, as in AT); the retry then hits.
            // (The shader reads have a port of their own.)
            if (kind != ReqKind::Shader) issue_[sm].hold(cycle + 1, l.retry_at);
            return {l.ready, false, false};
        case CacheBookings::Lookup::Miss:
            // Every MSHR busy: the port waits with the miss for the first to free.
            if (l.retry_at && kind != ReqKind::Shader) issue_[sm].hold(cycle + 1, l.retry_at);
            break;
    }
    const uint64_t xbar = cfg_.xbar_latency;
    const Served r = read_l2(l1.tags().sector_of(addr), l.ready + xbar, kind);
    const uint64_t done = r.at + xbar;
    l1.fill(addr, l, done, r.dram, kind);
    return {done, true, r.dram};
}

// Traces and the pools' records are reused: a free list each, so that a frame allocates only its peak in flight.
template <class T>
static uint32_t take(std::vector<T>& pool, std::vector<uint32_t>& free) {
    if (free.empty()) {
        pool.emplace_back();
        return uint32_t(pool.size() - 1);
    }
    const uint32_t id = free.back();
    free.pop_back();
    return id;
}

void IntervalGpu::start_trace(uint32_t sm, const std::vector<WarpRay>& rays, uint64_t start, std::vector<Finished>& finished) {
    const uint32_t id = take(traces_, free_traces_);
    Trace& tr = traces_[id];
    tr.sm = sm;
    tr.start = tr.end = start;
    tr.age = next_age_++;
    // The first free warp-buffer slot, as the RT unit's accept_warp takes it.
    std::vector<uint8_t>& busy = slot_busy_[sm];
    const auto free_slot = std::find(busy.begin(), busy.end(), uint8_t(0));
    if (free_slot == busy.end()) throw std::logic_error("interval: a trace started with every warp-buffer slot of its SM busy");
    *free_slot = 1;
    tr.slot = uint32_t(free_slot - busy.begin());
    tr.live = 0;
    tr.threads.resize(rays.size());
    for (uint32_t i = 0; i < rays.size(); ++i) {
        Thread& t = tr.threads[i];
        t.rt.start(rays[i], image_.header(), {order_, cfg_.next_node_register}, nullptr);
        t.ready = start;
        t.descriptor_done = false;
        if (!t.rt.trav.done()) {
            ++tr.live;
            events_.push({start, next_seq_++, id, i});
        }
    }
    ++rt_[sm].warps;
    rt_[sm].rays += rays.size();
    if (tr.live == 0) finish(id, finished);  // every ray missed the root box
}

void IntervalGpu::set_shader_reads(const ShaderReads& reads) {
    shader_.clear();
    shader_free_.clear();
    if (reads.per_ray <= 0) return;
    shader_.resize(cfg_.sms);
    shader_free_.assign(cfg_.sms, 0);
    for (uint32_t s = 0; s < cfg_.sms; ++s) shader_[s].start(s, reads);
}

void IntervalGpu::finish(uint32_t id, std::vector<Finished>& finished) {
    Trace& tr = traces_[id];
    if (!shader_.empty()) {
        // The shader code's reads leave one a cycle from the trace's end, each as an event of its
        // cycle, so that they book the L1, L2 and DRAM in time order with the RT units' reads.
        // Booked all at once here, they would take the L2's and DRAM's slots ahead of reads of
        // earlier cycles that are scheduled later (docs/accuracy.md measures what that did).
        // The port has an event queued exactly while it owes reads (send_shader_read).
        ShaderLoads& loads = shader_[tr.sm];
        const bool port_idle = loads.owed() == 0;
        loads.owe(tr.threads.size());
        if (port_idle && loads.owed()) events_.push({std::max(tr.end, shader_free_[tr.sm]), next_seq_++, tr.sm, kShader});
    }
    rt_[tr.sm].intersection_loop_iterations += RtThread::loop_of(tr.threads);
    Finished f{tr.sm, tr.end, {}};
    for (const Thread& t : tr.threads) {
        rt_[tr.sm].thread_cycles[ThreadStatus::Idle] += tr.end - (t.rt.trav.nodes_visited() ? t.ready : tr.start);
        f.rays.push_back(t.rt.retired());
    }
    finished.push_back(std::move(f));
    // Its chunks have all drained: every one is a fetch's of this trace, and its threads are done.
    for (const Trace::Chunk& c : tr.chunks) free_chunk_wait(c.wait);
    tr.chunks.clear();
    slot_busy_[tr.sm][tr.slot] = 0;
    free_traces_.push_back(id);
}

// Fetches run in time order and book their chunks from the cycle after they are scheduled, so
// when cycle `cycle` comes every demand for it has booked: a free request port then means no
// demand waits, and the oldest prefetch chunk leaves.
void IntervalGpu::Sink::prefetch(const StackEntry& node, uint64_t) {
    PrefetchQueue& q = gpu.prefetch_queue_[sm].chunks;
    for (uint32_t c = 0; c < chunks_of(node.type); ++c) {
        const uint64_t chunk = chunk_address(node.addr, c);
        ++gpu.rt_[sm].prefetch_queue.generated;
        if (q.waiting(chunk)) {
            ++gpu.rt_[sm].prefetch_queue.duplicates_dropped;  // still waiting in the queue: dropped, as in AT
            continue;
        }
        if (q.full()) {
            ++gpu.rt_[sm].prefetch_queue.full_dropped;
            continue;
        }
        ChunkRequest r;
        r.addr = chunk;
        r.prefetch = true;
        q.push(r);
    }
}

void IntervalGpu::send_prefetch(uint32_t sm, uint64_t cycle) {
    SmPrefetchQueue& q = prefetch_queue_[sm];
    if (q.chunks.empty()) {  // demands took every waiting chunk out
        q.scheduled = false;
        return;
    }
    PortCalendar& issue = issue_[sm];
    const uint64_t sent = issue.first_free(cycle);
    if (sent == cycle) {
        issue.book(cycle);
        const uint64_t chunk = q.chunks.front().addr;
        q.chunks.pop();
        const Served s = read(sm, chunk, cycle, ReqKind::Prefetch);
        // Its response takes a cycle of the response FIFO's drain, as a demand's does
        // (model/response_fifo.h).
        queue_drain(sm, std::max(s.at, cycle + 1), kNone);
        ++rt_[sm].prefetch_queue.sent;
        ++rt_[sm].prefetch_queue.answered;
    }
    if (q.chunks.empty()) {
        q.scheduled = false;
        return;
    }
    events_.push({sent == cycle ? cycle + 1 : sent, next_seq_++, sm, kPrefetch});
}

void IntervalGpu::send_shader_read(uint32_t sm, uint64_t cycle) {
    ShaderLoads& loads = shader_[sm];
    read(sm, loads.next(), cycle, ReqKind::Shader);
    loads.issued();
    ++rt_[sm].shader_reads;
    shader_free_[sm] = cycle + 1;
    if (loads.owed()) events_.push({cycle + 1, next_seq_++, sm, kShader});
}

// The response FIFO (AT's model/response_fifo.h) drains one chunk a cycle in the order the chunks
// reach it. A fetch knows when its chunks arrive as soon as it runs, but a chunk of a later fetch
// may arrive before one of an earlier fetch (an L1 hit before an earlier miss), so a chunk's drain
// cycle is booked only when no chunk that reaches the FIFO before it can still be sent: a fetch
// scheduled in cycle c sends its chunks from c + 1, which reach the FIFO from c + 2, so before
// the fetches of cycle c run, every chunk that may drain by c + 1 is known, and is booked in
// arrival order (drain_until). Booked at once when the fetch ran, two threads' reads of a
// two-chunk node one cycle apart drained back to back instead of interleaved, which split
// fetches AT coalesces (docs/interval.md).
void IntervalGpu::queue_drain(uint32_t sm, uint64_t at, uint32_t wait) { drains_.push({at, next_drain_seq_++, sm, wait}); }

uint32_t IntervalGpu::new_fetch(uint64_t ready) {
    const uint32_t id = take(fetch_waits_, free_fetch_waits_);
    FetchWait& f = fetch_waits_[id];
    f.done = ready;
    f.pending = 0;
    f.first = f.last = kNone;
    f.l1_miss = f.dram = false;
    f.in_cycle = true;
    return id;
}

uint32_t IntervalGpu::new_chunk_wait(uint32_t fetch) {
    const uint32_t id = take(chunk_waits_, free_chunk_waits_);
    chunk_waits_[id] = {~0ull, fetch, kNone};
    return id;
}

void IntervalGpu::free_chunk_wait(uint32_t c) { free_chunk_waits_.push_back(c); }

void IntervalGpu::join(uint32_t chunk, uint32_t fetch) {
    const uint32_t j = take(joins_, free_joins_);
    joins_[j] = {fetch, chunk_waits_[chunk].joins};
    chunk_waits_[chunk].joins = j;
}

void IntervalGpu::drain_until(uint64_t upto, std::vector<Finished>& finished) {
    while (!drains_.empty() && drains_.top().at <= upto) drain_next(finished);
}

// The responses that the next cycles' stops would drain before anything else happens: one whose
// cycle before it comes no later than the next fetch and before the next trace starts (`slot`,
// or a slot a trace finished here frees) is drained now, in the same order, and the caller runs
// one stop fewer for it (rtsim's loop: a slot's trace starts before the fetches of its cycle).
void IntervalGpu::drain_ahead(uint64_t slot, std::vector<Finished>& finished) {
    for (size_t seen = 0; !drains_.empty();) {
        for (; seen < finished.size(); ++seen) slot = std::min(slot, finished[seen].end + 1);
        const uint64_t at = drains_.top().at;
        if (at > slot || (!events_.empty() && at > events_.top().at + 1)) return;
        drain_next(finished);
    }
}

void IntervalGpu::drain_next(std::vector<Finished>& finished) {
    const Drain d = drains_.top();
    drains_.pop();
    // In (at, seq) order: each takes the first free drain cycle from `at`, as a FIFO.
    const uint64_t drained = drain_[d.sm].book(d.at);
    if (d.wait == kNone) return;  // a prefetch's: no thread waits for it
    ChunkWait& c = chunk_waits_[d.wait];
    c.drained = drained;
    const uint32_t sender = c.fetch;
    uint32_t j = c.joins;
    c.joins = kNone;
    // Without rt.merge_in_flight no later read joins it; with it, the trace's list holds it
    // until it is dropped there (run_event) or the trace ends (finish).
    if (!cfg_.merge_in_flight) free_chunk_wait(d.wait);
    // Its sender, then the fetches that joined it (none is freed before all are told).
    const auto answer = [&](uint32_t id) {
        FetchWait& f = fetch_waits_[id];
        f.done = std::max(f.done, drained);
        if (--f.pending == 0) fetched(id, finished);
    };
    answer(sender);
    while (j != kNone) {
        const Join n = joins_[j];
        free_joins_.push_back(j);
        answer(n.fetch);
        j = n.next;
    }
}

void IntervalGpu::fetched(uint32_t id, std::vector<Finished>& finished) {
    const FetchWait f = fetch_waits_[id];
    if (!f.in_cycle) free_fetch_waits_.push_back(id);
    Trace& tr = traces_[f.trace];
    for (uint32_t th = f.first; th != kNone;) {
        const uint32_t next = tr.threads[th].next_waiting;  // read before the thread moves on
        thread_fetched(f.trace, th, f.done, finished);
        if (th == f.last) break;
        th = next;
    }
}

// A thread's fetch has drained at `done`: its tests (or the descriptor's decode) take `after`
// cycles, then it fetches its next node, or is done.
void IntervalGpu::thread_fetched(uint32_t trace, uint32_t thread, uint64_t done, std::vector<Finished>& finished) {
    Trace& tr = traces_[trace];
    Thread& t = tr.threads[thread];
    rt_[tr.sm].thread_cycles[ThreadStatus::WaitMemory] += done - t.ready;
    t.ready = done + t.after;
    if (t.descriptor_done || !t.rt.trav.done()) {
        events_.push({t.ready, next_seq_++, trace, thread});
        return;
    }
    tr.end = std::max(tr.end, t.ready);
    if (--tr.live == 0) finish(trace, finished);
}

// The next scheduled fetch, or the cycle before the earliest queued chunk may drain.
uint64_t IntervalGpu::next_event() const {
    const uint64_t fetch = events_.empty() ? ~0ull : events_.top().at;
    const uint64_t drain = drains_.empty() ? ~0ull : drains_.top().at - 1;
    return std::min(fetch, drain);
}

// The events of one cycle run together, in the warp scheduler's order (model/warp_scheduler.h):
// the prefetch queues first (they only try the request port in this cycle, which no demand of
// this cycle books), then the threads' fetches, per SM by rt.warp_scheduler: round robin, the
// slots from the one after the last picked; oldest first, by their trace's entry (the TTP
// authors' scheduler, the first non-stalled warp in uid order, shader.cc l.3254-3267), then the
// shader ports. No event of a cycle schedules another in the same cycle, but for a shader port's
// first read at a trace's end, which runs after the cycle's batch, as the shader ports run last.
void IntervalGpu::run_next(std::vector<Finished>& finished, uint64_t slot) {
    run_cycle(finished);
    drain_ahead(slot, finished);
}

void IntervalGpu::run_cycle(std::vector<Finished>& finished) {
    const uint64_t at = next_event();
    if (at != coalesce_at_) {
        for (uint32_t id : coalesced_) {
            FetchWait& f = fetch_waits_[id];
            f.in_cycle = false;
            if (f.pending == 0) free_fetch_waits_.push_back(id);  // drained, or joined drained chunks only
        }
        coalescer_.clear();
        coalesced_.clear();
        coalesce_at_ = at;
    }
    // The responses that may drain by the cycle after: none of this cycle's fetches comes before them.
    drain_until(at + 1, finished);
    if (events_.empty() || events_.top().at != at) return;
    batch_.clear();
    while (!events_.empty() && events_.top().at == at) {
        batch_.push_back(events_.top());
        events_.pop();
    }
    const uint32_t slots = cfg_.warp_buffer;
    const bool oldest = cfg_.warp_order == WarpOrder::OldestFirst;
    if (batch_.size() == 1) return run_event(batch_[0], finished);
    // The warp scheduler's order, taken for every event before any runs, then the order the
    // wheel gave them: a total order, so sorting the keys gives the sequence a stable sort of the
    // events by the scheduler's order gave, without computing each key once per comparison or
    // the stable sort's buffer allocated per cycle (4 % of party's run: docs/performance.md).
    batch_order_.clear();
    for (uint32_t i = 0; i < uint32_t(batch_.size()); ++i) {
        const Event& e = batch_[i];
        if (e.thread == kPrefetch) {
            batch_order_.push_back({0, 0, i});
        } else if (e.thread == kShader) {
            batch_order_.push_back({~0ull, e.trace, i});  // after the RT units' reads, as AT's shader port
        } else {
            const Trace& tr = traces_[e.trace];
            batch_order_.push_back({1 + (oldest ? 0 : (tr.slot + slots - rr_next_[tr.sm]) % slots), tr.age, i});
        }
    }
    std::sort(batch_order_.begin(), batch_order_.end());
    for (const BatchOrder& o : batch_order_) run_event(batch_[o.index], finished);
}

void IntervalGpu::run_event(const Event& ev, std::vector<Finished>& finished) {
    advance(ev.at);  // every later fetch is scheduled at or after this one
    if (ev.thread == kPrefetch) return send_prefetch(ev.trace, ev.at);
    if (ev.thread == kShader) return send_shader_read(ev.trace, ev.at);
    Trace& tr = traces_[ev.trace];
    Thread& t = tr.threads[ev.thread];
    const uint32_t sm = tr.sm;
    // The warp scheduler picks one warp per cycle and sends all its ready threads' reads: a
    // thread of another trace than the one picked in this cycle waits for the next (and the
    // threads that become ready meanwhile coalesce with it). Without this the interval fidelity
    // coalesced 28 % fewer fetches than AT on party 64x64 primary rays (`paper` with TTP, oldest
    // first) and ran 35 % slow; with it, within 1 % of AT's coalescing (docs/interval.md).
    if (sched_cycle_[sm] == ev.at && sched_trace_[sm] != ev.trace) {
        ++rt_[sm].thread_cycles[ThreadStatus::WaitSchedule];
        ++t.ready;
        events_.push({ev.at + 1, next_seq_++, ev.trace, ev.thread});
        return;
    }
    if (sched_cycle_[sm] != ev.at) rr_next_[sm] = (tr.slot + 1) % cfg_.warp_buffer;
    sched_cycle_[sm] = ev.at;
    sched_trace_[sm] = ev.trace;
    PortCalendar& issue = issue_[sm];
    const StackEntry e = t.rt.trav.peek();
    // The read this event makes: a whole node, a leaf's descriptor (the first of a two-step leaf
    // read, model/node_fetch.h), or the leaf after its descriptor.
    const bool leaf_after_descriptor = t.descriptor_done;
    if (!leaf_after_descriptor) {
        // On a pop, TTP's picks join the SM's prefetch queue, which sends one chunk in each cycle
        // the request port has no demand for (send_prefetch).
        sink_.sm = sm;
        t.fetch_class = t.rt.begin_fetch(*prefetcher_, sink_);
        SmPrefetchQueue& pq = prefetch_queue_[sm];
        if (!pq.chunks.empty() && !pq.scheduled) {
            pq.scheduled = true;
            events_.push({t.ready + 1, next_seq_++, sm, kPrefetch});
        }
        t.rt.count_fetch(rt_[sm], t.fetch_class);
        t.fetch_l1_miss = t.fetch_dram = false;
    }
    const bool descriptor = !leaf_after_descriptor && read_in_two_steps(e.type, cfg_.leaf_descriptor_read);
    const uint32_t chunks = descriptor ? kDescriptorChunks : chunks_of(e.type);
    // Threads of one trace that make the same read scheduled in the same cycle share one fetch.
    const auto [g, fresh] = coalescer_.add({ev.trace, e.addr | (descriptor ? 2ull : 0ull)});
    uint32_t id;
    if (!fresh) {
        ++rt_[sm].coalesced_fetches;
        id = coalesced_[g];
    } else {
        id = new_fetch(t.ready);
        coalesced_.push_back(id);
        FetchWait& f = fetch_waits_[id];
        uint32_t sent_chunks = 0;
        if (cfg_.merge_in_flight)
            tr.chunks.erase(std::remove_if(tr.chunks.begin(), tr.chunks.end(),
                                           [&](const Trace::Chunk& k) {
                                               const uint64_t drained = chunk_waits_[k.wait].drained;
                                               if (drained > ev.at) return false;  // (~0: not drained yet)
                                               free_chunk_wait(k.wait);
                                               return true;
                                           }),
                            tr.chunks.end());
        for (uint32_t c = 0; c < chunks; ++c) {
            const uint64_t addr = chunk_address(e.addr, c);
            if (cfg_.merge_in_flight) {
                // The warp has this chunk queued or in flight: its response serves this read too
                // (as RtUnitCore::schedule_warp).
                const auto it = std::find_if(tr.chunks.begin(), tr.chunks.end(), [&](const Trace::Chunk& k) { return k.addr == addr; });
                if (it != tr.chunks.end()) {
                    const uint64_t drained = chunk_waits_[it->wait].drained;
                    if (drained != ~0ull) {
                        f.done = std::max(f.done, drained);
                    } else {
                        join(it->wait, id);
                        ++f.pending;
                    }
                    f.l1_miss |= it->l1_miss;
                    f.dram |= it->dram;
                    ++rt_[sm].merged_in_flight;
                    continue;
                }
            }
            const uint64_t sent = issue.book(t.ready + 1);
            // The demand takes a waiting prefetch of its chunk out of the prefetch queue, as in AT.
            rt_[sm].prefetch_queue.removed_by_demand += prefetch_queue_[sm].chunks.remove(addr);
            const Served s = read(sm, addr, sent, ReqKind::Demand);
            // Drained from the response FIFO one per cycle, at the earliest in the cycle after
            // the request left (an L1 hit's answer comes in that same cycle).
            const uint32_t w = new_chunk_wait(id);
            queue_drain(sm, std::max(s.at, sent + 1), w);
            ++f.pending;
            f.l1_miss |= s.l1_miss;
            f.dram |= s.dram;
            if (cfg_.merge_in_flight) {  // none was in flight (above)
                // Written field by field in place: an entry built on the stack and copied in is
                // read back as one word just after its narrow stores, which the host's store buffer
                // cannot forward (perf: a fifth of this function's samples on that load).
                Trace::Chunk& k = tr.chunks.emplace_back();
                k.addr = addr;
                k.wait = w;
                k.l1_miss = s.l1_miss;
                k.dram = s.dram;
            }
            ++sent_chunks;
        }
        rt_[sm].chunk_requests += sent_chunks;
        rt_[sm].responses += sent_chunks;
    }
    FetchWait& f = fetch_waits_[id];
    t.fetch_l1_miss |= f.l1_miss;
    t.fetch_dram |= f.dram;
    if (descriptor) {
        // Decode the descriptor, then read the leaf.
        const uint32_t decode = std::max<uint32_t>(1, cfg_.lat.leaf_descriptor);
        rt_[sm].thread_cycles[ThreadStatus::InMath] += decode;
        t.after = decode;
        t.descriptor_done = true;
    } else {
        // The node's tests run when its data has drained; what they find does not depend on when.
        t.descriptor_done = false;
        const StepInfo info = t.rt.complete_fetch(rt_[sm], t.fetch_class, t.fetch_l1_miss, t.fetch_dram, image_, *prefetcher_);
        const uint32_t math = rt_math_latency(cfg_.lat, info, cfg_.leaf_descriptor_read);
        rt_[sm].thread_cycles[ThreadStatus::InMath] += math;
        t.after = math;
    }
    if (f.pending == 0) return thread_fetched(ev.trace, ev.thread, f.done, finished);  // it joined drained chunks only
    // Waits, after the threads that joined the fetch before it.
    if (f.first == kNone) {
        f.trace = ev.trace;
        f.first = ev.thread;
    } else {
        tr.threads[f.last].next_waiting = ev.thread;
    }
    f.last = ev.thread;
}

}  // namespace rtu
