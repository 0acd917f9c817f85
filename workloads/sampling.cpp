#include "sampling.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <iostream>
#include <thread>

#include <boost/math/distributions/students_t.hpp>

#include "model/node_format.h"

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

// Stratified cluster sample. The unit is a cluster of `cluster` consecutive warps (as many as the
// GPU holds at once), so that the warps in flight together are neighbours sharing BVH nodes in
// the caches, as in the full frame. The clusters are split into n equal strata in frame order
// and one cluster per stratum is simulated.
SampleDesign::SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed)
    : warps_(warps), cluster_(std::max<uint64_t>(1, cluster)), clusters_((warps + cluster_ - 1) / cluster_) {
    const uint64_t n = std::max<uint64_t>(1, std::min<uint64_t>(clusters_, uint64_t(std::llround(double(clusters_) * rate))));
    picks_.resize(n);
    for (uint64_t h = 0; h < n; ++h) {
        Rng rng(seed, h, 0x5A3B1E);
        picks_[h] = lo(h) + rng.next() % (hi(h) - lo(h));
    }
}

uint64_t SampleDesign::end_warp(uint64_t h) const { return std::min(warps_, (picks_[h] + 1) * cluster_); }

std::vector<uint32_t> SampleDesign::feeds() const {
    std::vector<uint32_t> feeds(warps_, ~0u);
    for (uint64_t h = 0; h < strata(); ++h)
        for (uint64_t w = h ? end_warp(h - 1) : 0; w < std::min(warps_, first_warp(h)); ++w) feeds[w] = uint32_t(h);
    return feeds;
}

// The functional pre-pass: a trace costs its longest ray, since the warp waits for its last
// thread. Contiguous ranges of warps go to the threads, each with its own workload instance; the
// results are put together in frame order, so they do not depend on the number of threads.
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, const std::vector<uint32_t>& feeds, size_t strata) {
    const auto t0 = std::chrono::steady_clock::now();
    // Only the last `window` fetches before a simulated cluster warm the caches. Each thread
    // traces its range of warps backwards (warps are independent) and records the fetches of
    // whole warps until it has `window` of them for that stratum; the rest are traced unrecorded.
    const size_t window = opt.warm_window;
    const size_t n_warps = frame.warps();
    const unsigned threads = unsigned(std::max<size_t>(1, std::min<size_t>(opt.threads, (n_warps + 63) / 64)));
    PrepassResult result;
    result.threads = threads;
    result.trace_nodes.resize(n_warps);
    std::vector<std::vector<WarmFetch>> warp_fetches(n_warps);
    std::vector<std::vector<size_t>> recorded(threads, std::vector<size_t>(strata, 0));
    std::atomic<size_t> done{0};
    auto work = [&](unsigned t) {
        const std::unique_ptr<Workload> fresh = opt.make_workload();
        std::vector<WorkRay> follow;
        {
            std::vector<WorkRay> ignored;
            fresh->begin(ignored);  // the workload's own set-up; the first rays are in the driver's queues
        }
        std::vector<RayQueue> pending;  // per thread of the warp being traced (reused)
        std::vector<uint32_t> paths;
        std::vector<StackEntry> fetched;
        auto last = t0;
        bool printed = false;
        const size_t lo = n_warps * t / threads, hi = n_warps * (t + 1) / threads;
        for (size_t wi = hi; wi-- > lo;) {
            const uint32_t sm = frame.sm(wi);
            frame.threads(wi, paths, pending);
            std::vector<uint32_t>& trace_nodes = result.trace_nodes[wi];
            const uint32_t h = feeds[wi];
            std::vector<WarmFetch>* rec = h != ~0u && recorded[t][h] < window ? &warp_fetches[wi] : nullptr;
            for (;;) {
                uint32_t longest = 0;
                bool any = false;
                for (size_t i = 0; i < paths.size(); ++i) {
                    auto& q = pending[i];
                    if (q.empty()) continue;
                    any = true;
                    const WorkRay w = q.front();
                    q.pop_front();
                    TraceResult r;
                    fetched.clear();
                    if (is_valid_ray(w.ray)) r = opt.trace(w.ray, rec ? &fetched : nullptr);  // invalid rays never reach the RT unit: a miss
                    for (const StackEntry& e : fetched) rec->push_back({sm, e.addr, node_bytes(e.type)});
                    longest = std::max(longest, r.nodes_visited);
                    follow.clear();
                    fresh->complete(w, r.hit, follow);
                    for (const WorkRay& f : follow) {  // a follow-up ray belongs to a path of this warp
                        size_t k = paths[i] == f.path ? i : 0;
                        while (paths[k] != f.path) ++k;
                        pending[k].push_back(f);
                    }
                }
                if (!any) break;
                trace_nodes.push_back(longest);
            }
            if (rec) recorded[t][h] += rec->size();
            const size_t d = ++done;
            if (opt.progress && t == 0 && (d & 63) == 0) {
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
    for (const std::vector<uint32_t>& trace : result.trace_nodes)
        for (uint32_t n : trace) result.critical_nodes_total += n;
    // Each stratum's recorded fetches in frame order; the last `window` kept.
    result.warm.assign(strata, {});
    for (size_t wi = 0; wi < n_warps; ++wi)
        if (!warp_fetches[wi].empty()) {
            std::vector<WarmFetch>& w = result.warm[feeds[wi]];
            w.insert(w.end(), warp_fetches[wi].begin(), warp_fetches[wi].end());
            std::vector<WarmFetch>().swap(warp_fetches[wi]);
        }
    for (std::vector<WarmFetch>& w : result.warm)
        if (w.size() > window) w.erase(w.begin(), w.end() - long(window));
    return result;
}

void SampleEstimator::set_prepass(PrepassResult&& p) {
    frame_traces_ = std::move(p.trace_nodes);
    critical_nodes_total_ = p.critical_nodes_total;
    prepass_threads_ = p.threads;
}

void SampleEstimator::on_trace_done(WarpRecord& w, double residence) {
    if (w.traces_done < w.trace_nodes.size()) {  // pre-pass: fit residence against the critical path
        const double x = w.trace_nodes[w.traces_done];
        if (x > 0) {
            fit_n_ += 1;
            fit_x_ += x;
            fit_y_ += residence;
            fit_xx_ += x * x;
            fit_xy_ += x * residence;
        }
    }
    ++w.traces_done;
    w.work += residence;
    work_done_ += residence;
}

void SampleEstimator::on_warp_finished(uint64_t unfinished, uint64_t now) {
    if (unfinished < capacity_ && saturated_until_ == 0 && unfinished + 1 >= capacity_) {
        saturated_until_ = now;  // the tail begins: fewer unfinished warps than the GPU holds
        work_saturated_ = work_done_;
    }
}

SampleEstimate SampleEstimator::estimate(const std::vector<WarpRecord>& warps, uint64_t warps_total, bool sampled) const {
    SampleEstimate e;
    e.warps_total = warps_total;
    e.warps_simulated = warps.size();
    // Per stratum (one cluster each, weighted by the stratum's size): work and critical-path nodes.
    std::vector<double> work, nodes;
    double weighted_nodes = 0;
    for (const WarpRecord& w : warps) {
        e.work_simulated += w.work;
        e.work_estimate_stratified += w.weight * w.work;
        weighted_nodes += w.weight * w.critical_nodes;
        if (work.size() <= w.stratum) work.resize(w.stratum + 1, 0.0), nodes.resize(w.stratum + 1, 0.0);
        work[w.stratum] += w.weight * w.work;
        nodes[w.stratum] += w.weight * w.critical_nodes;
    }
    const bool ratio = sampled && weighted_nodes > 0;  // the pre-pass ran and the sample visited nodes
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
        auto duration = [&](uint32_t n) { return n == 0 ? 0.0 : std::max(0.0, e.fit_a + e.fit_b * double(n)); };
        auto durations = [&](const std::vector<uint32_t>& n) {
            std::vector<double> d(n.size());
            for (size_t k = 0; k < n.size(); ++k) d[k] = duration(n[k]);
            return d;
        };
        std::vector<std::vector<double>> frame, sample;
        e.work_estimate = 0;
        for (const auto& t : frame_traces_) {
            frame.push_back(durations(t));
            for (double d : frame.back()) e.work_estimate += d;
        }
        for (const WarpRecord& w : warps) sample.push_back(durations(w.trace_nodes));
        e.model_frame = schedule_cycles(frame, shape_);
        e.model_sample = schedule_cycles(sample, shape_);
    }
    // The work's variance: of the strata's weighted work, or for the ratio estimate of their
    // residuals from the ratio line.
    std::vector<double> residual(work.size());
    for (size_t h = 0; h < work.size(); ++h) residual[h] = work[h] - r * nodes[h];
    double v = collapsed_pairs_variance(residual);
    if (ratio) v *= (critical_nodes_total_ / weighted_nodes) * (critical_nodes_total_ / weighted_nodes);
    e.relative_se = sampled && e.work_estimate > 0 ? std::sqrt(v) / e.work_estimate : 0.0;
    e.variance_pairs = uint32_t(work.size() / 2);
    // Shares of node fetches: ratio estimates over the strata, residual variance by collapsed pairs.
    const double t = t95(e.variance_pairs);
    auto share = [&](double WarpRecord::*part) {
        std::vector<double> num(work.size(), 0.0), den(work.size(), 0.0);
        for (const WarpRecord& w : warps) {
            num[w.stratum] += w.weight * (w.*part);
            den[w.stratum] += w.weight * w.nodes;
        }
        double sn = 0, sd = 0;
        for (size_t h = 0; h < num.size(); ++h) sn += num[h], sd += den[h];
        SampleEstimate::Share s;
        if (sd <= 0) return s;
        s.estimate = sn / sd;
        std::vector<double> res(num.size());
        for (size_t h = 0; h < num.size(); ++h) res[h] = num[h] - s.estimate * den[h];
        const double half = sampled ? t * std::sqrt(collapsed_pairs_variance(res)) / sd : 0.0;
        s.lo = std::max(0.0, s.estimate - half);
        s.hi = std::min(1.0, s.estimate + half);
        return s;
    };
    e.l1_miss_nodes = share(&WarpRecord::l1_miss_nodes);
    e.dram_nodes = share(&WarpRecord::dram_nodes);
    e.saturated_until = saturated_until_;
    e.work_saturated = work_saturated_;
    return e;
}

double SampleEstimate::relative_half_width(double cycles_simulated) const {
    const double t = t95(variance_pairs);
    const double model = 1.96 * std::sqrt(2.0) * model_misfit(cycles_simulated);
    return std::hypot(t * relative_se, model);
}

}  // namespace rtu
