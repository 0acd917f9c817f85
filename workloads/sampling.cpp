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
// Each pair is a stratum of weight[a] + weight[b] clusters of which 2 were drawn: the finite
// population correction 1 - 2 / (weight[a] + weight[b]) makes a pair of single-cluster strata
// (simulated whole) contribute nothing.
double collapsed_pairs_variance(const std::vector<double>& d, const std::vector<double>& weight) {
    double v = 0;
    for (size_t i = 0; i + 1 < d.size(); i += 2)
        v += (d[i] - d[i + 1]) * (d[i] - d[i + 1]) * std::max(0.0, 1.0 - 2.0 / std::max(2.0, weight[i] + weight[i + 1]));
    return v;
}

// Student's t for a two-sided 95 % interval; one pair (or none) leaves one degree of freedom at the least.
double t95(uint32_t pairs) {
    return boost::math::quantile(boost::math::complement(boost::math::students_t(std::max<uint32_t>(1, pairs)), 0.025));
}

}  // namespace

// The first wave: the warps that start together on the frame's cold caches, a startup the full
// frame pays once; simulated always (weight 1), it is paid once in the sample too, where a drawn
// cluster would start on warmed caches. It is the first cluster that reads a BVH node: where the
// frame begins with empty clusters (sky above a scene), they leave the RT units at once and the
// first cluster with work starts on the cold caches. (As cluster 0 whatever its work, an empty
// first wave left that cold start to the draw: cornell's primary rays at 256x256, whose first
// cluster with work holds half the frame's first reads of BVH nodes and 6.5 % of its work, came
// out 16-17 % low on the draws that missed it and 15 % high on one that took it; the clusters
// that first read the other nodes still hold ~10 % of its work, docs/sampling.md, "The first
// wave".) Empty clusters: no node read, no RT work, nothing to simulate. The other clusters,
// sorted by their critical-path node reads, fall into equal strata (neighbouring strata alike,
// as the collapsed pairs of the variance want), and one cluster per stratum is drawn.
SampleDesign::SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed, const std::vector<double>& work)
    : warps_(warps), cluster_(std::max<uint64_t>(1, cluster)), clusters_((warps + cluster_ - 1) / cluster_) {
    certain_ = std::min<uint64_t>(clusters_, 1);
    uint64_t first = 0;  // the first wave's cluster (without the pre-pass's work: cluster 0)
    while (!work.empty() && first + 1 < clusters_ && work[first] <= 0) ++first;
    std::vector<uint64_t> order;
    for (uint64_t c = 0; c < clusters_; ++c)
        if (c != first && (work.empty() || work[c] > 0)) order.push_back(c);
    empty_ = clusters_ - certain_ - order.size();
    candidates_ = order.size();
    if (!work.empty())
        std::stable_sort(order.begin(), order.end(), [&](uint64_t a, uint64_t b) { return work[a] < work[b]; });
    // round(clusters x rate) clusters simulated, the first wave among them.
    const uint64_t total = std::min<uint64_t>(clusters_, uint64_t(std::llround(double(clusters_) * rate)));
    strata_ = std::min<uint64_t>(candidates_, total > certain_ ? total - certain_ : 0);
    if (certain_) sim_.push_back({first, SampledCluster::kCertain, 1.0});
    for (uint64_t h = 0; h < strata_; ++h) {
        const uint64_t lo = h * candidates_ / strata_, hi = (h + 1) * candidates_ / strata_;
        Rng rng(seed, h, 0x5A3B1E);
        sim_.push_back({order[lo + rng.next() % (hi - lo)], uint32_t(h), double(hi - lo)});
    }
    std::sort(sim_.begin(), sim_.end(), [](const SampledCluster& a, const SampledCluster& b) { return a.cluster < b.cluster; });
}

std::optional<double> rate_for_strata(uint64_t clusters, uint64_t candidates, uint64_t strata) {
    if (clusters == 0 || candidates < strata) return std::nullopt;
    // round(clusters x rate) >= 1 + strata: clusters x rate >= strata + 0.5 (llround rounds halves up).
    return std::min(1.0, std::ceil(1000.0 * (double(strata) + 0.5) / double(clusters)) / 1000.0);
}

std::vector<uint32_t> SampleDesign::feeds() const {
    std::vector<uint32_t> feeds(warps_, ~0u);
    for (size_t i = 0; i < sim_.size(); ++i)
        for (uint64_t w = i ? end_warp(i - 1) : 0; w < first_warp(i); ++w) feeds[w] = uint32_t(i);
    return feeds;
}

void SampleDesign::split(uint32_t k) {
    if (k < 1 || k > sim_.size())
        throw std::invalid_argument(std::to_string(k) + " segments of " + std::to_string(sim_.size()) + " simulated clusters");
    segments_ = k;
}

namespace {

// Runs body(thread, workload) on `threads` threads, each with its own workload, and rethrows the
// first exception any of them threw.
void on_threads(unsigned threads, PrepassWorkloads& workloads, const std::function<void(unsigned, Workload&)>& body) {
    auto run = [&](unsigned t) { body(t, workloads.of_thread(t)); };
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> failed(threads);
    for (unsigned t = 1; t < threads; ++t)
        pool.emplace_back([&, t] {
            try {
                run(t);
            } catch (...) {
                failed[t] = std::current_exception();
            }
        });
    try {
        run(0);
    } catch (...) {
        failed[0] = std::current_exception();
    }
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : failed)
        if (e) std::rethrow_exception(e);
}

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

    void trace(Workload& workload, size_t wi, std::vector<uint32_t>& trace_nodes, std::vector<WarmFetch>* rec) {
        const uint32_t sm = frame.sm(wi);
        frame.threads(wi, paths, pending);
        for (uint32_t k = 0;; ++k) {
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

}  // namespace

PrepassWorkloads::PrepassWorkloads(const SamplingOptions& opt) : opt_(opt), made_(std::max(1u, opt.threads)) {}

// Set up as the driver's workload was; its first rays are in the driver's queues.
Workload& PrepassWorkloads::of_thread(unsigned t) {
    if (!made_.at(t)) {
        made_[t] = opt_.make_workload();
        std::vector<WorkRay> ignored;
        made_[t]->begin(ignored);
    }
    return *made_[t];
}

// Contiguous ranges of warps go to the threads; the results are put together in frame order, so
// they do not depend on the number of threads.
PrepassResult run_prepass(const FrameWarps& frame, const SamplingOptions& opt, PrepassWorkloads& workloads) {
    const auto t0 = std::chrono::steady_clock::now();
    const size_t n_warps = frame.warps();
    const unsigned threads = unsigned(std::max<size_t>(1, std::min<size_t>(opt.threads, (n_warps + 63) / 64)));
    PrepassResult result;
    result.threads = threads;
    result.trace_nodes.resize(n_warps);
    // First reads: per thread and per 64-byte block of the image, the earliest read of the node
    // there, in each of the two orders the GPU may run the frame's traces: in rounds (key: trace,
    // then warp) and warp by warp (key: the warp). The threads' tables are merged by their
    // minimum, so the counts do not depend on the number of threads.
    const bool count_first = opt.node_blocks > 0 && n_warps < (uint64_t(1) << 32);
    constexpr uint64_t kUnread = ~uint64_t(0);
    std::vector<std::vector<uint64_t>> in_rounds(count_first ? threads : 0), by_warp(count_first ? threads : 0);
    std::atomic<size_t> done{0};
    on_threads(threads, workloads, [&](unsigned t, Workload& workload) {
        WarpTracer tracer{frame, opt, {}, {}, {}, {}};
        std::vector<WarmFetch> fetches;
        if (count_first) in_rounds[t].assign(opt.node_blocks, kUnread), by_warp[t].assign(opt.node_blocks, kUnread);
        auto last = t0;
        bool printed = false;
        for (size_t wi = n_warps * t / threads, hi = n_warps * (t + 1) / threads; wi < hi; ++wi) {
            if (opt.stop.requested()) throw Interrupted{opt.stop.signal()};
            fetches.clear();
            tracer.trace(workload, wi, result.trace_nodes[wi], count_first ? &fetches : nullptr);
            for (const WarmFetch& f : fetches) {
                const uint64_t b = f.addr / kBlockBytes;
                if (b >= opt.node_blocks) continue;
                in_rounds[t][b] = std::min(in_rounds[t][b], (uint64_t(f.trace) << 32) | wi);
                by_warp[t][b] = std::min<uint64_t>(by_warp[t][b], wi);
            }
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
    });
    result.critical_nodes_total = critical_nodes_total(result.trace_nodes);
    if (count_first) {
        result.first_reads_in_rounds.assign(n_warps, 0);
        result.first_reads_by_warp.assign(n_warps, 0);
        for (uint64_t b = 0; b < opt.node_blocks; ++b) {
            uint64_t r = kUnread, w = kUnread;
            for (unsigned t = 0; t < threads; ++t) r = std::min(r, in_rounds[t][b]), w = std::min(w, by_warp[t][b]);
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
                                                    PrepassWorkloads& workloads) {
    const auto& sim = design.simulated();
    std::vector<std::vector<WarmFetch>> warm(sim.size());
    if (opt.warm_window == 0 || sim.empty()) return warm;
    const unsigned threads = unsigned(std::max<size_t>(1, std::min<size_t>(opt.threads, sim.size())));
    on_threads(threads, workloads, [&](unsigned t, Workload& workload) {
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
                tracer.trace(workload, size_t(w), ignored, &by_warp.back());
                recorded += by_warp.back().size();
            }
            for (auto it = by_warp.rbegin(); it != by_warp.rend(); ++it) warm[i].insert(warm[i].end(), it->begin(), it->end());
            if (warm[i].size() > opt.warm_window) warm[i].erase(warm[i].begin(), warm[i].end() - long(opt.warm_window));
        }
    });
    return warm;
}

void SampleEstimator::set_prepass(PrepassResult&& p) {
    frame_traces_ = std::move(p.trace_nodes);
    critical_nodes_total_ = p.critical_nodes_total;
    first_reads_total_ = first_reads_total(p.first_reads(shape_.resident == 0));
    prepass_threads_ = p.threads;
}

void SampleEstimator::on_trace_done(WarpRecord& w, double residence) {
    // Pre-pass: fit residence against the critical path, on the drawn clusters (the first wave
    // starts on cold caches, unlike the rest of the frame).
    if (w.stratum != SampledCluster::kCertain && w.traces_done < w.trace_nodes.size()) {
        const double x = w.trace_nodes[w.traces_done];
        if (x > 0) fit_.add(x, residence);
    }
    ++w.traces_done;
    w.residences.push_back(residence);
    w.work += residence;
    work_done_ += residence;
}

void SampleEstimator::on_warp_finished(uint64_t unfinished, uint64_t now) {
    if (unfinished < capacity_ && saturated_until_ == 0 && unfinished + 1 >= capacity_) {
        saturated_until_ = now;  // the tail begins: fewer unfinished warps than the GPU holds
        work_saturated_ = work_done_;
    }
}

SampleEstimate SampleEstimator::estimate(const std::vector<WarpRecord>& warps, uint64_t warps_total, bool sampled,
                                         const std::vector<size_t>& segment_ends) const {
    SampleEstimate e;
    e.warps_total = warps_total;
    e.warps_simulated = warps.size();
    e.critical_nodes_total = critical_nodes_total_;
    e.prepass_threads = prepass_threads_;
    // Per drawn stratum (one cluster each, weighted by the stratum's size): work, critical-path
    // nodes and the weight. The first wave is known exactly, the empty clusters do no RT work.
    std::vector<double> work, nodes, weight, firsts;
    double certain_work = 0, certain_nodes = 0, drawn_work = 0, drawn_nodes = 0, certain_first = 0, drawn_first = 0;
    for (const WarpRecord& w : warps) {
        e.work_simulated += w.work;
        if (w.stratum == SampledCluster::kCertain) {
            certain_work += w.work;
            certain_nodes += w.critical_nodes;
            certain_first += w.first_reads;
            continue;
        }
        drawn_first += w.weight * w.first_reads;
        if (work.size() <= w.stratum)
            work.resize(w.stratum + 1, 0.0), nodes.resize(w.stratum + 1, 0.0), weight.resize(w.stratum + 1, 0.0), firsts.resize(w.stratum + 1, 0.0);
        work[w.stratum] += w.weight * w.work;
        firsts[w.stratum] += w.weight * w.first_reads;
        nodes[w.stratum] += w.weight * w.critical_nodes;
        weight[w.stratum] = w.weight;
        drawn_work += w.weight * w.work;
        drawn_nodes += w.weight * w.critical_nodes;
    }
    // The stratified estimate of the frame's work: without the pre-pass the drawn clusters'
    // weighted work; with it the ratio estimate, work per critical-path node of the drawn
    // clusters times the frame's critical-path nodes outside the first wave.
    const bool ratio = sampled && drawn_nodes > 0 && critical_nodes_total_ > 0;
    const double r = ratio ? drawn_work / drawn_nodes : 0.0;  // work per critical-path node
    const double rest_nodes = std::max(0.0, critical_nodes_total_ - certain_nodes);
    e.work_estimate_stratified = certain_work + (ratio ? r * rest_nodes : drawn_work);
    e.work_estimate = e.work_estimate_stratified;
    // Segments: the same traces as on_trace_done fits, taken in frame order.
    FitSums fit = fit_;
    if (!segment_ends.empty()) {
        fit = FitSums{};
        for (const WarpRecord& w : warps)
            if (w.stratum != SampledCluster::kCertain)
                for (size_t k = 0; k < std::min(w.residences.size(), w.trace_nodes.size()); ++k)
                    if (w.trace_nodes[k] > 0) fit.add(w.trace_nodes[k], w.residences[k]);
    }
    const double det = fit.n * fit.xx - fit.x * fit.x;
    if (ratio && fit.n >= 2 && det > 0) {
        e.schedule = true;
        e.fit_traces = uint64_t(fit.n);
        e.fit_b = (fit.n * fit.xy - fit.x * fit.y) / det;
        e.fit_a = (fit.y - e.fit_b * fit.x) / fit.n;
        // The schedule model is fed with the fitted durations, but for the first wave's traces,
        // which ran on the frame's cold caches, with their own residences. A trace whose rays all
        // miss the root box never occupies a slot.
        auto duration = [&](uint32_t n) { return n == 0 ? 0.0 : std::max(0.0, e.fit_a + e.fit_b * double(n)); };
        std::vector<const WarpRecord*> certain(frame_traces_.size(), nullptr);
        for (const WarpRecord& w : warps)
            if (w.stratum == SampledCluster::kCertain && w.frame_warp < certain.size()) certain[w.frame_warp] = &w;
        auto durations = [&](size_t fw) {
            const std::vector<uint32_t>& n = frame_traces_[fw];
            std::vector<double> d(n.size());
            for (size_t k = 0; k < n.size(); ++k)
                d[k] = certain[fw] && k < certain[fw]->residences.size() ? certain[fw]->residences[k] : duration(n[k]);
            return d;
        };
        std::vector<std::vector<double>> frame, sample;
        e.work_estimate = 0;
        for (size_t fw = 0; fw < frame_traces_.size(); ++fw) {
            frame.push_back(durations(fw));
            for (double d : frame.back()) e.work_estimate += d;
        }
        for (const WarpRecord& w : warps) sample.push_back(durations(w.frame_warp));
        e.model_frame = schedule_cycles(frame, shape_);
        // First reads (SampleEstimate::first_reads_gap). The work estimate takes the frame's
        // first reads as the drawn clusters hold them per critical-path node; the pre-pass knows
        // how many there are. Their price beyond what the fit gives their critical paths: the
        // drawn strata's slope of work off the ratio line on first reads off theirs, where the
        // drawn clusters hold first reads (never below 0: party's and sprng's come out negative,
        // as noise); where they hold none (a small BVH whose first reads a few clusters hold:
        // cornell's primary rays), the first wave's traces, the only simulated ones that hold
        // any, beyond the fit per first read. That price also takes the first wave's other cold
        // misses (each SM's L1), so it errs high rather than low, far high on large scenes, whose
        // draws always hold first reads: sprng, the bunny and the bunny mesh 2,300-6,200
        // slot-cycles a first read against drawn slopes of 0-120 (docs/sampling.md "First reads").
        if (first_reads_total_ > 0 && sampled && drawn_nodes > 0) {
            e.first_reads_rest = std::max(0.0, first_reads_total_ - certain_first);
            const double rf = drawn_first / drawn_nodes;  // first reads per critical-path node, drawn
            e.first_reads_estimate = rf * rest_nodes;
            double sxy = 0, sxx = 0;
            for (size_t h = 0; h < work.size(); ++h) {
                const double x = firsts[h] - rf * nodes[h], y = work[h] - r * nodes[h];
                sxy += x * y, sxx += x * x;
            }
            if (sxx > 0) {
                e.first_read_cost = std::max(0.0, sxy / sxx);
            } else {
                double excess = 0;
                for (const WarpRecord& w : warps)
                    if (w.stratum == SampledCluster::kCertain)
                        for (size_t k = 0; k < std::min(w.residences.size(), w.trace_nodes.size()); ++k)
                            excess += w.residences[k] - duration(w.trace_nodes[k]);
                e.first_read_cost = certain_first > 0 ? std::max(0.0, excess) / certain_first : 0.0;
                e.first_read_cost_of_first_wave = true;
            }
        }
        // The sample's model: with segments, each ran alone from its own start, so its ramp and
        // tail are in the simulated cycles (their sum) and in the model of the sample too. Per SM,
        // the cycle its last trace left, simulated and modelled, summed over the segments in the
        // same way (records without it, read from older segment files, give no per-SM misfit).
        const std::vector<size_t> ends = segment_ends.empty() ? std::vector<size_t>{sample.size()} : segment_ends;
        std::vector<double> model_ends(shape_.sms, 0.0), sim_ends(shape_.sms, 0.0);
        bool timed = true;
        size_t begin = 0;
        for (size_t end : ends) {
            const std::vector<double> m = schedule_sm_ends({sample.begin() + long(begin), sample.begin() + long(end)}, shape_);
            e.model_sample += *std::max_element(m.begin(), m.end());
            std::vector<double> sim(shape_.sms, 0.0);
            for (size_t i = begin; i < end; ++i) {
                const WarpRecord& w = warps[i];
                if (w.residences.empty()) continue;
                if (w.sm >= shape_.sms || w.last_done < 0) timed = false;
                else sim[w.sm] = std::max(sim[w.sm], w.last_done);
            }
            for (uint32_t s = 0; s < shape_.sms; ++s) model_ends[s] += m[s], sim_ends[s] += sim[s];
            begin = end;
        }
        for (uint32_t s = 0; timed && s < shape_.sms; ++s)
            if (model_ends[s] > 0 && sim_ends[s] > 0) e.misfit_per_sm.push_back(sim_ends[s] / model_ends[s] - 1.0);
    }
    // The stratified work's variance: of the strata's weighted work, or for the ratio estimate of
    // their residuals from the ratio line, scaled to the frame's nodes outside the first wave.
    std::vector<double> residual(work.size());
    for (size_t h = 0; h < work.size(); ++h) residual[h] = work[h] - r * nodes[h];
    double v = collapsed_pairs_variance(residual, weight);
    if (ratio) v *= (rest_nodes / drawn_nodes) * (rest_nodes / drawn_nodes);
    e.relative_se = sampled && e.work_estimate > 0 ? std::sqrt(v) / e.work_estimate : 0.0;
    e.variance_pairs = uint32_t(work.size() / 2);
    // Shares of node fetches: ratio estimates over the strata, residual variance by collapsed pairs.
    const double t = t95(e.variance_pairs);
    auto share = [&](double WarpRecord::*part) {
        std::vector<double> num(work.size(), 0.0), den(work.size(), 0.0);
        double sn = 0, sd = 0;
        for (const WarpRecord& w : warps) {
            sn += w.weight * (w.*part);
            sd += w.weight * w.nodes;
            if (w.stratum == SampledCluster::kCertain) continue;
            num[w.stratum] += w.weight * (w.*part);
            den[w.stratum] += w.weight * w.nodes;
        }
        SampleEstimate::Share s;
        if (sd <= 0) return s;
        s.estimate = sn / sd;
        std::vector<double> res(num.size());
        for (size_t h = 0; h < num.size(); ++h) res[h] = num[h] - s.estimate * den[h];
        const double half = sampled ? t * std::sqrt(collapsed_pairs_variance(res, weight)) / sd : 0.0;
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
    const double model = 1.96 * std::sqrt(2.0) * model_error(cycles_simulated);
    const double gap = 1.96 * extrapolation_gap(), first = first_reads_gap();
    return std::sqrt(t * relative_se * t * relative_se + model * model + gap * gap + first * first + design_bias * design_bias);
}

}  // namespace rtu
