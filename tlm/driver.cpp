#include "driver.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <stdexcept>
#include <thread>

#include <boost/math/distributions/students_t.hpp>

#include "model/trace_schedule.h"

namespace rtu {
namespace {

// Variance of a stratified total with one sample per stratum, by collapsing neighbouring strata
// in pairs: the sum over pairs of (d_a - d_b)^2, d being each stratum's weighted value or its
// residual from a ratio line (Cochran, Sampling Techniques, 5A.12 and 6.12).
double collapsed_pairs_variance(const std::vector<double>& d) {
    double v = 0;
    for (size_t i = 0; i + 1 < d.size(); i += 2) v += (d[i] - d[i + 1]) * (d[i] - d[i + 1]);
    return v;
}

// Student's t for a two-sided 95 % interval; one pair (or none) leaves one degree of freedom at the least.
double t95(uint32_t pairs) {
    return boost::math::quantile(boost::math::complement(boost::math::students_t(std::max<uint32_t>(1, pairs)), 0.025));
}

}  // namespace

WorkloadDriver::WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency,
                               const SamplingOptions& sampling)
    : workload_(workload), shade_(shade_latency), ready_(sms), capacity_(sampling.capacity),
      slots_(std::max<uint32_t>(1, sampling.capacity / std::max<uint32_t>(1, sms))) {
    const double sample_rate = sampling.rate;
    const uint64_t seed = sampling.seed, cluster = sampling.cluster;
    std::vector<WorkRay> first;
    workload_.begin(first);
    // Paths in order; each run of warp_size paths (neighbouring pixels) is one shader warp.
    uint32_t max_path = 0;
    for (const WorkRay& w : first) max_path = std::max(max_path, w.path);
    path_warp_.assign(first.empty() ? 0 : max_path + 1, ~0u);
    for (const WorkRay& w : first) {
        if (path_warp_[w.path] == ~0u) {
            if (warps_.empty() || warps_.back().threads.size() == warp_size) {
                ShaderWarp sw;
                sw.sm = uint32_t(warps_.size() % sms);
                warps_.push_back(std::move(sw));
            }
            warps_.back().threads.push_back(Thread{w.path, 0, {}});
            path_warp_[w.path] = uint32_t(warps_.size() - 1);
        }
        ShaderWarp& sw = warps_[path_warp_[w.path]];
        auto it = std::find_if(sw.threads.begin(), sw.threads.end(), [&](const Thread& t) { return t.path == w.path; });
        it->pending.push_back(w);
    }
    warps_total_ = warps_.size();
    if (sample_rate < 1.0 && !warps_.empty()) {
        // Stratified cluster sample. The unit is a cluster of `cluster` consecutive warps (as
        // many as the GPU holds at once), so that the warps in flight together are neighbours
        // sharing BVH nodes in the caches, as in the full frame. The clusters are split into n
        // equal strata in frame order and one cluster per stratum is simulated.
        sampled_ = true;
        const uint64_t n_warps = warps_.size();
        const uint64_t cl = std::max<uint64_t>(1, cluster);
        const uint64_t n_all = (n_warps + cl - 1) / cl;
        const uint64_t n = std::max<uint64_t>(1, std::min<uint64_t>(n_all, uint64_t(std::llround(double(n_all) * sample_rate))));
        std::vector<uint64_t> picks(n);
        for (uint64_t h = 0; h < n; ++h) {
            const uint64_t lo = h * n_all / n, hi = (h + 1) * n_all / n;
            Rng rng(seed, h, 0x5A3B1E);
            picks[h] = lo + rng.next() % (hi - lo);
        }
        // The pre-pass also records, for each simulated cluster, the last node fetches of the
        // clusters skipped before it, to warm the caches with when it starts.
        if (sampling.make_workload && sampling.trace) {
            std::vector<uint32_t> feeds(n_warps, ~0u);  // warp -> the stratum whose warming it feeds
            for (uint64_t h = 0; h < n; ++h)
                for (uint64_t w = (h ? picks[h - 1] + 1 : 0) * cl; w < std::min(n_warps, picks[h] * cl); ++w) feeds[w] = uint32_t(h);
            prepass(sampling.make_workload, sampling.trace, feeds, n, sampling.warm_window, sampling.progress, sampling.threads);
        }
        std::vector<ShaderWarp> kept;
        for (uint64_t h = 0; h < n; ++h) {
            const uint64_t lo = h * n_all / n, hi = (h + 1) * n_all / n;
            const uint64_t pick = picks[h];
            for (uint64_t w = pick * cl; w < std::min(n_warps, (pick + 1) * cl); ++w) {
                ShaderWarp sw = std::move(warps_[w]);
                sw.weight = double(hi - lo);
                sw.stratum = uint32_t(h);
                sw.sm = uint32_t(kept.size() % sms);
                kept.push_back(std::move(sw));
            }
        }
        warps_ = std::move(kept);
        for (uint32_t i = 0; i < warps_.size(); ++i)
            for (const Thread& t : warps_[i].threads) path_warp_[t.path] = i;
    }
    for (uint32_t i = 0; i < warps_.size(); ++i) enqueue(i, 0);
    live_warps_ = warps_.size();
}

// The functional pre-pass: every path of the frame traced as the timing run will trace it (the
// same rays, because a workload's random numbers depend only on path and depth), warp by warp
// and trace by trace; a trace costs its longest ray, since the warp waits for its last thread.
// Contiguous ranges of warps go to `threads` threads, each with its own workload instance; the
// results are put together in frame order, so they do not depend on the number of threads.
void WorkloadDriver::prepass(const std::function<std::unique_ptr<Workload>()>& make_workload, const TraceFn& trace,
                             const std::vector<uint32_t>& feeds, size_t strata, size_t window, bool progress,
                             unsigned threads) {
    const auto t0 = std::chrono::steady_clock::now();
    // Only the last `window` fetches before a simulated cluster warm the caches. Each thread
    // traces its range of warps backwards (warps are independent) and records the fetches of
    // whole warps until it has `window` of them for that stratum; the rest are traced unrecorded.
    const size_t n_warps = warps_.size();
    threads = unsigned(std::max<size_t>(1, std::min<size_t>(threads, (n_warps + 63) / 64)));
    prepass_threads_ = threads;
    std::vector<std::vector<WarmFetch>> warp_fetches(n_warps);
    std::vector<std::vector<size_t>> recorded(threads, std::vector<size_t>(strata, 0));
    std::atomic<size_t> done{0};
    auto work = [&](unsigned t) {
        const std::unique_ptr<Workload> fresh = make_workload();
        std::vector<WorkRay> follow;
        {
            std::vector<WorkRay> ignored;
            fresh->begin(ignored);  // the workload's own set-up; the first rays are in the driver's queues
        }
        std::vector<RayQueue> pending;  // per thread of the warp being traced (reused)
        std::vector<StackEntry> fetched;
        auto last = t0;
        bool printed = false;
        const size_t lo = n_warps * t / threads, hi = n_warps * (t + 1) / threads;
        for (size_t wi = hi; wi-- > lo;) {
            ShaderWarp& sw = warps_[wi];
            const uint32_t h = feeds[wi];
            std::vector<WarmFetch>* rec = h != ~0u && recorded[t][h] < window ? &warp_fetches[wi] : nullptr;
            pending.resize(std::max(pending.size(), sw.threads.size()));
            for (size_t i = 0; i < sw.threads.size(); ++i) pending[i] = sw.threads[i].pending;  // its first rays
            for (;;) {
                uint32_t longest = 0;
                bool any = false;
                for (size_t i = 0; i < sw.threads.size(); ++i) {
                    auto& q = pending[i];
                    if (q.empty()) continue;
                    any = true;
                    const WorkRay w = q.front();
                    q.pop_front();
                    TraceResult r;
                    fetched.clear();
                    if (is_valid_ray(w.ray)) r = trace(w.ray, rec ? &fetched : nullptr);  // invalid rays never reach the RT unit: a miss
                    for (const StackEntry& e : fetched) rec->push_back({sw.sm, e.addr, node_bytes(e.type)});
                    longest = std::max(longest, r.nodes_visited);
                    follow.clear();
                    fresh->complete(w, r.hit, follow);
                    for (const WorkRay& f : follow) {  // a follow-up ray belongs to a path of this warp
                        size_t k = sw.threads[i].path == f.path ? i : 0;
                        while (sw.threads[k].path != f.path) ++k;
                        pending[k].push_back(f);
                    }
                }
                if (!any) break;
                sw.trace_nodes.push_back(longest);
                sw.critical_nodes += longest;
            }
            if (rec) recorded[t][h] += rec->size();
            const size_t d = ++done;
            if (progress && t == 0 && (d & 63) == 0) {
                const auto now = std::chrono::steady_clock::now();
                if (std::chrono::duration<double>(now - last).count() > 2.0) {
                    last = now;
                    const double f = double(d) / double(n_warps), wall = std::chrono::duration<double>(now - t0).count();
                    std::cerr << "\r  sampling pre-pass: " << d << " of " << n_warps << " shader warps traced (" << threads
                              << " threads), ETA " << int(wall * (1.0 - f) / std::max(f, 1e-9)) << " s   " << std::flush;
                    printed = true;
                }
            }
        }
        if (printed) std::cerr << "\n";
    };
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> failed(threads);
    for (unsigned t = 1; t < threads; ++t)
        pool.emplace_back([&, t] {
            try {
                work(t);
            } catch (...) {
                failed[t] = std::current_exception();
            }
        });
    try {
        work(0);
    } catch (...) {
        failed[0] = std::current_exception();
    }
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : failed)
        if (e) std::rethrow_exception(e);
    for (const ShaderWarp& sw : warps_) {
        critical_nodes_total_ += sw.critical_nodes;
        frame_traces_.push_back(sw.trace_nodes);
    }
    // Each stratum's recorded fetches in frame order; the last `window` kept.
    warm_.assign(strata, {});
    for (size_t wi = 0; wi < n_warps; ++wi)
        if (!warp_fetches[wi].empty()) {
            warm_[feeds[wi]].insert(warm_[feeds[wi]].end(), warp_fetches[wi].begin(), warp_fetches[wi].end());
            std::vector<WarmFetch>().swap(warp_fetches[wi]);
        }
    for (std::vector<WarmFetch>& w : warm_)
        if (w.size() > window) w.erase(w.begin(), w.end() - long(window));
}

WorkloadDriver::Estimate WorkloadDriver::estimate() const {
    Estimate e;
    e.warps_total = warps_total_;
    e.warps_simulated = warps_.size();
    // Per stratum (one cluster each, weighted by the stratum's size): work and critical-path nodes.
    std::vector<double> work, nodes;
    double weighted_nodes = 0;
    for (const ShaderWarp& w : warps_) {
        e.work_simulated += w.work;
        e.work_estimate_stratified += w.weight * w.work;
        weighted_nodes += w.weight * w.critical_nodes;
        if (work.size() <= w.stratum) work.resize(w.stratum + 1, 0.0), nodes.resize(w.stratum + 1, 0.0);
        work[w.stratum] += w.weight * w.work;
        nodes[w.stratum] += w.weight * w.critical_nodes;
    }
    const bool ratio = sampled_ && weighted_nodes > 0;  // the pre-pass ran and the sample visited nodes
    e.critical_nodes_total = critical_nodes_total_;
    e.prepass_threads = prepass_threads_;
    const double r = ratio ? e.work_estimate_stratified / weighted_nodes : 0.0;  // work per critical-path node
    e.work_estimate = e.work_estimate_stratified;
    const double det = fit_n_ * fit_xx_ - fit_x_ * fit_x_;
    if (ratio && fit_n_ >= 2 && det > 0) {
        e.schedule = true;
        e.fit_traces = uint64_t(fit_n_);
        e.fit_b = (fit_n_ * fit_xy_ - fit_x_ * fit_y_) / det;
        e.fit_a = (fit_y_ - e.fit_b * fit_x_) / fit_n_;
        // A trace whose rays all miss the root box never occupies a slot.
        auto duration = [&](uint32_t nodes) { return nodes == 0 ? 0.0 : std::max(0.0, e.fit_a + e.fit_b * double(nodes)); };
        auto durations = [&](const std::vector<uint32_t>& nodes) {
            std::vector<double> d(nodes.size());
            for (size_t k = 0; k < nodes.size(); ++k) d[k] = duration(nodes[k]);
            return d;
        };
        std::vector<std::vector<double>> frame, sample;
        e.work_estimate = 0;
        for (const auto& t : frame_traces_) {
            frame.push_back(durations(t));
            for (double d : frame.back()) e.work_estimate += d;
        }
        for (const ShaderWarp& w : warps_) sample.push_back(durations(w.trace_nodes));
        const ScheduleShape shape{uint32_t(ready_.size()), slots_, shade_};
        e.model_frame = schedule_cycles(frame, shape);
        e.model_sample = schedule_cycles(sample, shape);
    }
    // The work's variance: of the strata's weighted work, or for the ratio estimate of their
    // residuals from the ratio line.
    std::vector<double> residual(work.size());
    for (size_t h = 0; h < work.size(); ++h) residual[h] = work[h] - r * nodes[h];
    double v = collapsed_pairs_variance(residual);
    if (ratio) v *= (critical_nodes_total_ / weighted_nodes) * (critical_nodes_total_ / weighted_nodes);
    e.relative_se = sampled_ && e.work_estimate > 0 ? std::sqrt(v) / e.work_estimate : 0.0;
    e.variance_pairs = uint32_t(work.size() / 2);
    // Shares of node fetches: ratio estimates over the strata, residual variance by collapsed pairs.
    const double t = t95(e.variance_pairs);
    auto share = [&](double ShaderWarp::*part) {
        std::vector<double> num(work.size(), 0.0), den(work.size(), 0.0);
        for (const ShaderWarp& w : warps_) {
            num[w.stratum] += w.weight * (w.*part);
            den[w.stratum] += w.weight * w.nodes;
        }
        double sn = 0, sd = 0;
        for (size_t h = 0; h < num.size(); ++h) sn += num[h], sd += den[h];
        Estimate::Share s;
        if (sd <= 0) return s;
        s.estimate = sn / sd;
        std::vector<double> res(num.size());
        for (size_t h = 0; h < num.size(); ++h) res[h] = num[h] - s.estimate * den[h];
        const double half = sampled_ ? t * std::sqrt(collapsed_pairs_variance(res)) / sd : 0.0;
        s.lo = std::max(0.0, s.estimate - half);
        s.hi = std::min(1.0, s.estimate + half);
        return s;
    };
    e.l1_miss_nodes = share(&ShaderWarp::l1_miss_nodes);
    e.dram_nodes = share(&ShaderWarp::dram_nodes);
    e.saturated_until = saturated_until_;
    e.work_saturated = work_saturated_;
    return e;
}

double WorkloadDriver::Estimate::relative_half_width(double cycles_simulated) const {
    const double t = t95(variance_pairs);
    const double model = 1.96 * std::sqrt(2.0) * model_misfit(cycles_simulated);
    return std::hypot(t * relative_se, model);
}

void WorkloadDriver::enqueue(uint32_t warp, uint64_t ready_at) { ready_[warps_[warp].sm].insert({ready_at, warp}); }

uint64_t WorkloadDriver::earliest_ready(uint32_t sm) const { return ready_[sm].empty() ? ~0ull : ready_[sm].begin()->first; }

std::optional<std::vector<WarpRay>> WorkloadDriver::next_trace(uint32_t sm, uint64_t now) {
    auto& q = ready_[sm];
    while (!q.empty() && q.begin()->first <= now) {
        const uint32_t wi = q.begin()->second;
        q.erase(q.begin());
        ShaderWarp& sw = warps_[wi];
        if (sw.stratum < warm_.size() && !warm_[sw.stratum].empty()) {  // the first trace of a simulated cluster
            if (on_warm) on_warm(warm_[sw.stratum]);
            std::vector<WarmFetch>().swap(warm_[sw.stratum]);
        }
        std::vector<WarpRay> rays;
        std::vector<RetiredRay> invalid;
        for (Thread& t : sw.threads) {
            if (t.pending.empty()) continue;
            const WorkRay w = t.pending.front();
            t.pending.pop_front();
            Record rec;
            rec.r.path = w.path;
            rec.r.seq = t.next_seq++;
            rec.r.ray = w.ray;
            rec.work = w;
            rec.warp = wi;
            rec.r.valid = is_valid_ray(w.ray);
            Ray scaled = w.ray;
            rec.scale = rec.r.valid ? scale_direction(scaled) : 0;
            uint64_t key = records_.size();
            if (!keep_rays_ && !free_records_.empty()) {  // the slot of a retired ray
                key = free_records_.back();
                free_records_.pop_back();
                records_[key] = rec;
            } else {
                records_.push_back(rec);
            }
            ++issued_;
            if (!rec.r.valid) {
                // Invalid rays never reach the RT unit: a miss (counted when it retires).
                invalid.push_back({key, Hit{}, 0});
                continue;
            }
            rays.push_back({scaled, rec.scale, key});
        }
        sw.in_flight = uint32_t(rays.size() + invalid.size());
        sw.issued_at = now;
        if (!invalid.empty()) retire(sm, invalid, now);
        if (!rays.empty()) return rays;
    }
    return std::nullopt;
}

void WorkloadDriver::retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now) {
    std::vector<WorkRay> follow;
    for (const RetiredRay& rr : rays) {
        Record& rec = records_.at(rr.key);
        rec.r.hit = rr.hit;
        if (rec.r.hit.hit) rec.r.hit.t = std::ldexp(rec.r.hit.t, -rec.scale);
        rec.r.nodes_visited = rr.nodes_visited;
        summary_.rays += 1;
        summary_.invalid += !rec.r.valid;
        summary_.hits += rec.r.hit.hit;
        summary_.nodes_visited += rr.nodes_visited;
        summary_.l1_miss_nodes += rr.l1_miss_nodes;
        summary_.dram_nodes += rr.dram_nodes;
        summary_.max_nodes = std::max(summary_.max_nodes, rr.nodes_visited);
        ShaderWarp& sw = warps_[rec.warp];
        sw.nodes += rr.nodes_visited;
        sw.l1_miss_nodes += rr.l1_miss_nodes;
        sw.dram_nodes += rr.dram_nodes;
        last_progress_ = now;
        follow.clear();
        workload_.complete(rec.work, rec.r.hit, follow);
        for (const WorkRay& f : follow) {
            auto it = std::find_if(sw.threads.begin(), sw.threads.end(), [&](const Thread& t) { return t.path == f.path; });
            it->pending.push_back(f);
        }
        if (--sw.in_flight == 0) {
            // The trace left the RT unit: its residence there is the warp's work (cycles of a
            // warp-buffer slot), which is what the GPU's throughput is made of.
            const double residence = double(now - sw.issued_at);
            if (sw.traces_done < sw.trace_nodes.size()) {  // pre-pass: fit residence against the critical path
                const double x = sw.trace_nodes[sw.traces_done];
                if (x > 0) {
                    fit_n_ += 1;
                    fit_x_ += x;
                    fit_y_ += residence;
                    fit_xx_ += x * x;
                    fit_xy_ += x * residence;
                }
            }
            ++sw.traces_done;
            sw.work += residence;
            work_done_ += residence;
            const bool more = std::any_of(sw.threads.begin(), sw.threads.end(), [](const Thread& t) { return !t.pending.empty(); });
            if (more) {
                enqueue(rec.warp, now + shade_);
            } else if (--live_warps_ < capacity_ && saturated_until_ == 0 && live_warps_ + 1 >= capacity_) {
                saturated_until_ = now;  // the tail begins: fewer unfinished warps than the GPU holds
                work_saturated_ = work_done_;
            }
        }
        if (!keep_rays_) free_records_.push_back(rr.key);  // reused by a later ray (next_trace)
    }
    (void)sm;
}

std::vector<TracedRay> WorkloadDriver::results() const {
    std::vector<TracedRay> out;
    if (!keep_rays_) return out;
    out.reserve(records_.size());
    for (const Record& r : records_) out.push_back(r.r);
    std::sort(out.begin(), out.end(), [](const TracedRay& a, const TracedRay& b) {
        return a.path != b.path ? a.path < b.path : a.seq < b.seq;
    });
    return out;
}

std::string WorkloadDriver::oldest_in_flight() const {
    const ShaderWarp* oldest = nullptr;
    size_t idx = 0;
    for (size_t i = 0; i < warps_.size(); ++i)
        if (warps_[i].in_flight && (!oldest || warps_[i].issued_at < oldest->issued_at)) oldest = &warps_[i], idx = i;
    if (!oldest) return "no trace in flight";
    return "SM " + std::to_string(oldest->sm) + " shader warp " + std::to_string(idx) + " (trace issued at cycle " +
           std::to_string(oldest->issued_at) + ", " + std::to_string(oldest->in_flight) + " rays outstanding)";
}

}  // namespace rtu
