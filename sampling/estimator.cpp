#include "estimator.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/students_t.hpp>

namespace rtu {
namespace {

// Variance of a stratified total with one sample per stratum, by collapsing neighbouring strata
// in pairs: the sum over pairs of (d_a - d_b)^2, d being each stratum's weighted value or its
// residual from a ratio line (Cochran, Sampling Techniques, 5A.12 and 6.12).
// Each pair is a stratum of weight[a] + weight[b] clusters of which 2 were drawn: the finite
// population correction 1 - 2 / (weight[a] + weight[b]) makes a pair of single-cluster strata
// (simulated whole) contribute nothing.
// One pair's term, strata i and i + 1.
double pair_variance(const std::vector<double>& d, const std::vector<double>& weight, size_t i) {
    return (d[i] - d[i + 1]) * (d[i] - d[i + 1]) * std::max(0.0, 1.0 - 2.0 / std::max(2.0, weight[i] + weight[i + 1]));
}
// The pairs' variance, and Satterthwaite's degrees of freedom for Student's t over it: each pair's
// term is one degree of freedom of its own variance, so where a few pairs hold most of the sum
// (the strata of the heaviest clusters, whose work spans orders of magnitude) t with a degree per
// pair makes the interval too narrow. (sum of the terms)^2 / sum of their squares lies between 1
// and the pairs (the pairs where every term is 0).
struct PairsVariance {
    double v = 0, degrees = 0;
};
PairsVariance collapsed_pairs(const std::vector<double>& d, const std::vector<double>& weight) {
    PairsVariance p;
    double vv = 0;
    for (size_t i = 0; i + 1 < d.size(); i += 2) {
        const double g = pair_variance(d, weight, i);
        p.v += g, vv += g * g;
    }
    p.degrees = vv > 0 ? p.v * p.v / vv : double(d.size() / 2);
    return p;
}

}  // namespace

double t95(double degrees) {
    return boost::math::quantile(boost::math::complement(boost::math::students_t(std::max(1.0, degrees)), 0.025));
}

PairedDifference paired_work_difference(const StrataWork& fast, const StrataWork& reference) {
    if (fast.work.size() != reference.work.size() || fast.weight != reference.weight)
        throw std::invalid_argument("paired strata: the two runs drew different strata (" + std::to_string(fast.work.size()) + " and " +
                                    std::to_string(reference.work.size()) + "), not one draw");
    double f = fast.first_wave, a = reference.first_wave;
    for (size_t h = 0; h < fast.work.size(); ++h) f += fast.work[h], a += reference.work[h];
    PairedDifference p;
    if (a <= 0) return p;
    const double r = f / a;
    p.difference = r - 1.0;
    p.pairs = uint32_t(fast.work.size() / 2);
    // Each collapsed pair's share of the variance, of one degree of freedom each. Where a few
    // pairs hold most of it (the heavy clusters' strata: residences spread over orders of
    // magnitude), Student's t with a degree per pair made the interval too narrow (91 % of the
    // draws of 20 and of 40 strata held a synthetic frame's ratio,
    // PairedWorkDifference.CoversAKnownFrameRatio; 97-98 % now): the degrees of freedom are
    // Satterthwaite's, (sum v)^2 / sum v^2, between 1 and the pairs.
    std::vector<double> residual(fast.work.size());
    for (size_t h = 0; h < residual.size(); ++h) residual[h] = fast.work[h] - r * reference.work[h];
    const PairsVariance v = collapsed_pairs(residual, fast.weight);
    p.degrees = v.degrees;
    p.half_width = p.pairs ? t95(p.degrees) * std::sqrt(v.v) / a : 0.0;
    return p;
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
    e.strata_work = {certain_work, work, weight};
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
    // Student's t with Satterthwaite's degrees of freedom (collapsed_pairs): with a degree per pair
    // the interval held a synthetic frame's total in 88 % of 2,000 draws with 10 and 20 strata, 93 %
    // with 40 (SampleEstimator.TheWorksIntervalCoversAKnownFrame), as --check-error's had.
    const PairsVariance pv = collapsed_pairs(residual, weight);
    double v = pv.v;
    e.variance_pairs = uint32_t(work.size() / 2);
    e.variance_degrees = pv.degrees;
    if (ratio) v *= (rest_nodes / drawn_nodes) * (rest_nodes / drawn_nodes);
    e.relative_se = sampled && e.work_estimate > 0 ? std::sqrt(v) / e.work_estimate : 0.0;
    // Shares of node fetches: ratio estimates over the strata, residual variance by collapsed
    // pairs, Student's t with the pairs' own Satterthwaite degrees.
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
        const PairsVariance rv = collapsed_pairs(res, weight);
        const double half = sampled ? t95(rv.degrees) * std::sqrt(rv.v) / sd : 0.0;
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

double interval_half_width(double sampling, double model_error, double extrapolation_gap, double first_reads_gap, double design_bias) {
    const double model = 1.96 * std::sqrt(2.0) * model_error, gap = 1.96 * extrapolation_gap;
    return std::sqrt(sampling * sampling + model * model + gap * gap + first_reads_gap * first_reads_gap + design_bias * design_bias);
}

double SampleEstimate::relative_half_width(double cycles_simulated) const {
    return interval_half_width(t95(variance_degrees) * relative_se, model_error(cycles_simulated), extrapolation_gap(), first_reads_gap(), design_bias);
}

}  // namespace rtu
