#include "prepass.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "model/node_format.h"
#include "model/on_threads.h"

namespace rtu {
namespace {

// Traces shader warp `wi` functionally: per trace, the most nodes one of its rays visits (a
// trace costs its longest ray, since the warp waits for its last thread); with `rec`, every node
// fetch is appended to it.
struct WarpTracer {
    const FrameWarps& frame;
    const SamplingOptions& opt;
    std::vector<WorkRay> follow;
    std::vector<RayQueue> pending;  // per thread of the warp being traced (reused)
    std::vector<uint32_t> paths;
    std::vector<StackEntry> fetched;

    void trace(PrepassWorkload& shared, size_t wi, std::vector<uint32_t>& trace_nodes, std::vector<WarmFetch>* rec) {
        Workload& workload = shared.get(frame.warps());
        const PrepassWorkload::Hold hold(shared, wi);  // no other thread traces this warp's paths meanwhile
        const uint32_t sm = frame.sm(wi);
        frame.threads(wi, paths, pending);
        for (uint32_t p : paths) workload.restart(p);  // whatever this workload traced of them before
        for (uint32_t k = 0;; ++k) {
            uint32_t longest = 0;
            bool any = false;
            // The threads of the lowest phase trace together, as the workload driver's traces take them.
            uint32_t phase = ~0u;
            for (size_t i = 0; i < paths.size(); ++i)
                if (!pending[i].empty()) phase = std::min(phase, pending[i].front().phase);
            for (size_t i = 0; i < paths.size(); ++i) {
                auto& q = pending[i];
                if (q.empty() || q.front().phase != phase) continue;
                any = true;
                const WorkRay w = q.front();
                q.pop_front();
                TraceResult r;
                fetched.clear();
                if (is_valid_ray(w.ray)) r = opt.trace(w.ray, rec ? &fetched : nullptr);  // invalid rays never reach the RT unit: a miss
                if (rec)
                    for (const StackEntry& e : fetched) rec->push_back({sm, e.addr, node_bytes(e.type), k});
                longest = std::max(longest, r.nodes_visited);
                follow.clear();
                workload.complete(w, r.hit, follow);
                for (const WorkRay& f : follow) {  // a follow-up ray belongs to a path of this warp
                    size_t k = paths[i] == f.path ? i : 0;
                    while (paths[k] != f.path) ++k;
                    pending[k].push_back(f);
                }
            }
            if (!any) break;
            trace_nodes.push_back(longest);
        }
    }
};

// Lowers `a` to `v` if `v` is smaller. A minimum does not depend on the order the threads'
// values arrive in; relaxed, since the table is read only after the threads are joined.
void lower(std::atomic<uint64_t>& a, uint64_t v) {
    uint64_t seen = a.load(std::memory_order_relaxed);
    while (v < seen && !a.compare_exchange_weak(seen, v, std::memory_order_relaxed)) {
    }
}

}  // namespace

// Set up as the driver's workload was; its first rays are in the driver's queues.
Workload& PrepassWorkload::get(uint64_t warps) {
    std::call_once(made_once_, [&] {
        made_ = make_();
        made_->begin_for_restarts();  // WarpTracer::trace restarts every path it traces
        warps_ = warps;
        busy_ = std::make_unique<std::atomic<bool>[]>(warps);  // value-initialised: false
    });
    if (warps != warps_)
        throw std::logic_error("PrepassWorkload: made for " + std::to_string(warps_) + " shader warps, asked for " + std::to_string(warps));
    return *made_;
}

std::atomic<bool>& PrepassWorkload::busy(uint64_t warp) {
    if (warp >= warps_) throw std::logic_error("PrepassWorkload: warp " + std::to_string(warp) + " of " + std::to_string(warps_));
    return busy_[warp];
}

// A spin on the warp's flag: only a warming window that overlaps another segment's waits, for
// one warp's trace.
PrepassWorkload::Hold::Hold(PrepassWorkload& w, uint64_t warp) : busy_(w.busy(warp)) {
    while (busy_.exchange(true, std::memory_order_acquire)) std::this_thread::yield();
}

PrepassWorkload::Hold::~Hold() { busy_.store(false, std::memory_order_release); }

// The warps go to the threads in blocks, each thread taking the next (for_each_index); each warp's
// results land in its own slots, so they do not depend on the number of threads.
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, PrepassWorkload& shared) {
    const auto t0 = std::chrono::steady_clock::now();
    const size_t n_warps = frame.warps();
    const unsigned threads = index_threads(opt.threads, n_warps);
    PrepassResult result;
    result.threads = threads;
    result.trace_nodes.resize(n_warps);
    // First reads: per 64-byte block of the image, the earliest read of the node there, in each
    // of the two orders the GPU may run the frame's traces: in rounds (key: trace, then warp) and
    // warp by warp (key: the warp). One table for all the threads, each read lowering its block's
    // key to its own (an atomic minimum), so the counts do not depend on the number of threads.
    // A table per thread, merged after, cost 16 bytes per block of the image a thread (21 MB on
    // party's 83 MB image) and a serial merge over every block and thread.
    const bool count_first = opt.node_blocks > 0 && n_warps < (uint64_t(1) << 32);
    constexpr uint64_t kUnread = ~uint64_t(0);
    const size_t blocks = count_first ? opt.node_blocks : 0;
    // A block's two keys side by side: a read looks up both, in one line of the host's cache (two
    // tables of one key each cost a cache miss in each on a large image).
    struct alignas(16) FirstRead {
        std::atomic<uint64_t> in_rounds, by_warp;
    };
    const std::unique_ptr<FirstRead[]> first(new FirstRead[blocks]);
    for (size_t b = 0; b < blocks; ++b) first[b].in_rounds.store(kUnread, std::memory_order_relaxed), first[b].by_warp.store(kUnread, std::memory_order_relaxed);
    std::atomic<size_t> done{0};
    // The threads take the warps in blocks, each the next block not yet taken (for_each_index):
    // with fixed shares of the frame (its first half to one thread, ...) a thread waited while the
    // other traced the costlier part of the image (party 512x512 under `paper` on 2 threads: 0.92x
    // the pre-pass's time in blocks of 16, median of 9 interleaved pairs; blocks of 64 the same as
    // 16, 4.19 against 4.17 s, 5 pairs). Each warp writes only
    // its own slots and lowers the first-read keys, whose minimum does not depend on the order, so
    // the results do not depend on which thread traced which warp.
    struct PerThread {
        WarpTracer tracer;
        std::vector<WarmFetch> fetches;
        std::chrono::steady_clock::time_point last;
        bool printed = false;
    };
    std::vector<PerThread> per(threads, PerThread{WarpTracer{frame, opt, {}, {}, {}, {}}, {}, t0, false});
    for_each_index(threads, n_warps, [&](unsigned t, size_t wi) {
        PerThread& p = per[t];
        if (opt.stop.requested()) throw Interrupted{opt.stop.signal()};
        p.fetches.clear();
        p.tracer.trace(shared, wi, result.trace_nodes[wi], count_first ? &p.fetches : nullptr);
        for (const WarmFetch& f : p.fetches) {
            const uint64_t b = f.addr / kBlockBytes;
            if (b >= blocks) continue;
            lower(first[b].in_rounds, (uint64_t(f.trace) << 32) | wi);
            lower(first[b].by_warp, wi);
        }
        const size_t d = ++done;
        if (opt.progress && t == 0 && (d & 63) == 0) {
            const auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - p.last).count() > 2.0) {
                p.last = now;
                const double f = double(d) / double(n_warps), wall = std::chrono::duration<double>(now - t0).count();
                std::cerr << "\r  sampling pre-pass: " << d << " of " << n_warps << " shader warps traced (" << threads
                          << " threads), ETA " << int(wall * (1.0 - f) / std::max(f, 1e-9)) << " s   " << std::flush;
                p.printed = true;
            }
        }
    });
    if (per[0].printed) std::cerr << "\n";
    result.critical_nodes_total = critical_nodes_total(result.trace_nodes);
    if (count_first) {
        result.first_reads_in_rounds.assign(n_warps, 0);
        result.first_reads_by_warp.assign(n_warps, 0);
        for (size_t b = 0; b < blocks; ++b) {
            const uint64_t r = first[b].in_rounds.load(std::memory_order_relaxed), w = first[b].by_warp.load(std::memory_order_relaxed);
            if (r != kUnread) ++result.first_reads_in_rounds[r & 0xffffffffu];
            if (w != kUnread) ++result.first_reads_by_warp[w];
        }
    }
    return result;
}

double first_reads_total(const std::vector<uint32_t>& first_reads) {
    double total = 0;
    for (uint32_t n : first_reads) total += n;
    return total;
}

double critical_nodes_total(const std::vector<std::vector<uint32_t>>& trace_nodes) {
    double total = 0;
    for (const std::vector<uint32_t>& trace : trace_nodes)
        for (uint32_t n : trace) total += n;
    return total;
}

// Only the last `window` fetches before a simulated cluster warm the caches: the warps it feeds
// are traced backwards (warps are independent), recording whole warps until `window` fetches are
// there. Simulated clusters are shared out among the threads; each result lands in its own slot.
std::vector<std::vector<WarmFetch>> warming_fetches(const FrameWarps& frame, const SamplingOptions& opt, const SampleDesign& design,
                                                    PrepassWorkload& shared) {
    const auto& sim = design.simulated();
    std::vector<std::vector<WarmFetch>> warm(sim.size());
    if (opt.warm_window == 0 || sim.empty()) return warm;
    const unsigned threads = unsigned(std::max<size_t>(1, std::min<size_t>(opt.threads, sim.size())));
    on_threads(threads, [&](unsigned t) {
        WarpTracer tracer{frame, opt, {}, {}, {}, {}};
        std::vector<uint32_t> ignored;
        std::vector<std::vector<WarmFetch>> by_warp;  // the recorded warps, last first
        for (size_t i = t; i < sim.size(); i += threads) {
            if (opt.stop.requested()) throw Interrupted{opt.stop.signal()};
            if (design.segments() > 1 && design.segment_of(i) != opt.segment) continue;  // simulated in another run
            const uint64_t from = design.warm_from(i);
            size_t recorded = 0;
            by_warp.clear();
            for (uint64_t w = design.first_warp(i); w-- > from && recorded < opt.warm_window;) {
                by_warp.emplace_back();
                ignored.clear();
                tracer.trace(shared, size_t(w), ignored, &by_warp.back());
                recorded += by_warp.back().size();
            }
            for (auto it = by_warp.rbegin(); it != by_warp.rend(); ++it) warm[i].insert(warm[i].end(), it->begin(), it->end());
            if (warm[i].size() > opt.warm_window) warm[i].erase(warm[i].begin(), warm[i].end() - long(opt.warm_window));
        }
    });
    return warm;
}

}  // namespace rtu
