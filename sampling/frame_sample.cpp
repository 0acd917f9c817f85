#include "frame_sample.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "workloads/input_error.h"

namespace rtu {
namespace {

std::string percent_digits(double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", 100.0 * x);
    return b;
}

// A sample of fewer than kMinStrata drawn strata has too few pairs to estimate its variance
// from (and its interval would shrink to the schedule model's term alone): refuse it, naming the
// smallest rate and frame that work. `planned`: the design before the pre-pass (no cluster known
// to be empty). A sample that simulates every cluster needs no interval.
void check_sample_size(const SampleDesign& planned, uint64_t warps, uint64_t cluster, const SamplingOptions& o) {
    if (planned.strata() >= kMinStrata || planned.census() || o.unchecked) return;
    const uint64_t clusters = planned.clusters();
    // n strata need round(clusters x rate) >= 1 + n (the first wave is one cluster, simulated
    // whole); the 0.5 is llround's. Before the pre-pass no cluster is known to be empty.
    const double need = double(1 + kMinStrata) - 0.5;
    const double rate = rate_for_strata(clusters, clusters - 1, kMinStrata).value_or(1.0);
    std::string msg = "--sample " + percent_digits(o.rate) + " % of this frame's " + std::to_string(clusters) + " clusters of " +
                      std::to_string(cluster) + " shader warps (" + std::to_string(warps) + " warps) draws " +
                      std::to_string(planned.strata()) + " strata beside the first wave (simulated whole); a 95 % interval needs at least " +
                      std::to_string(kMinStrata) + " strata: ";
    if (rate < 1.0) msg += "use --sample " + percent_digits(rate) + " % or more (--sample " + std::to_string(rate).substr(0, 5) + "), ";
    msg += "a frame of at least " + std::to_string(uint64_t(std::ceil(need / std::max(o.rate, 1e-9))) * cluster) +
           " shader warps at this rate, or --sample-unchecked for an estimate without an interval";
    throw InputError(msg);
}

// Never an estimate of 0 (or of the first wave alone) for a frame with work beyond it: a draw of
// no stratum cannot extrapolate, checked or not.
void check_draws_a_stratum(const SampleDesign& design, uint64_t cluster, const SamplingOptions& o) {
    if (design.strata() > 0 || design.census()) return;
    throw InputError("--sample " + percent_digits(o.rate) + " % of this frame's " + std::to_string(design.clusters()) + " clusters of " +
                     std::to_string(cluster) + " shader warps draws no cluster beside the first wave, so " +
                     "nothing stands for the rest of the frame's work; sample more (--sample " +
                     std::to_string(std::ceil(1000.0 * 1.5 / double(design.clusters())) / 1000.0).substr(0, 5) + " or more)");
}

// A split sample needs kMinSegmentClusters simulated clusters per segment for its interval;
// returns whether it has them (fewer: refused unless unchecked).
bool check_segments(const SampleDesign& design, const SamplingOptions& o) {
    const uint64_t simulated = design.simulated().size();
    if (o.segments > simulated)
        throw InputError("--sample-segments " + std::to_string(o.segments) + ": this sample simulates " + std::to_string(simulated) +
                         " clusters, and a segment needs one at least; use " + std::to_string(simulated) + " segments or fewer");
    const uint64_t per_segment = simulated / o.segments;
    const bool enough = per_segment >= kMinSegmentClusters;
    if (!enough && !o.unchecked)
        throw InputError("--sample-segments " + std::to_string(o.segments) + ": this sample simulates " + std::to_string(simulated) +
                         " clusters, " + std::to_string(per_segment) + " per segment; a segment needs " + std::to_string(kMinSegmentClusters) +
                         " for the interval (fewer ran 4-11 % off, docs/sampling.md): " +
                         (simulated >= 2 * kMinSegmentClusters ? "use --sample-segments " + std::to_string(simulated / kMinSegmentClusters) + " or fewer, "
                                                               : std::string("too few to split; use ")) +
                         "a larger sample or frame, or --sample-unchecked for an estimate without an interval");
    if (o.segment != SamplingOptions::kNoSegment && o.segment >= o.segments)
        throw InputError("--segment " + std::to_string(o.segment) + ": the segments are numbered 0.." + std::to_string(o.segments - 1));
    return enough;
}

}  // namespace

FrameSample::FrameSample(const SamplingOptions& opt, uint32_t sms, const ShaderTiming& timing)
    : opt_(opt), sms_(sms), resident_(timing.resident),
      estimator_({sms, std::max<uint32_t>(1, opt.capacity / std::max<uint32_t>(1, sms)), timing.shade, timing.resident, timing.first(),
                  timing.shaders ? timing.shade : 0, timing.contention},
                 opt.capacity) {}

std::vector<uint64_t> FrameSample::select(const FrameWarps& frame) {
    const auto t0 = std::chrono::steady_clock::now();
    const SamplingOptions& o = opt_;
    const uint64_t warps = frame.warps(), cluster = std::max<uint32_t>(1, o.cluster ? o.cluster : o.capacity);
    warps_total_ = warps;
    sampled_ = true;
    check_sample_size(SampleDesign(warps, cluster, o.rate, o.seed), warps, cluster, o);
    // The pre-pass's critical paths per warp, and per cluster their sum: the work the clusters
    // are stratified by.
    PrepassResult prepass;
    std::vector<double> cluster_work;
    const bool traced = o.make_workload && o.trace;
    std::shared_ptr<PrepassWorkload> workload;
    if (traced) {
        workload = o.shared_workload ? o.shared_workload : std::make_shared<PrepassWorkload>(o.make_workload);
        std::optional<PrepassResult> kept = o.load_prepass ? o.load_prepass() : std::nullopt;
        if (kept && kept->trace_nodes.size() != warps)
            throw InputError("the sample plan holds " + std::to_string(kept->trace_nodes.size()) + " shader warps, this frame " +
                             std::to_string(warps));
        if (kept) {
            prepass = std::move(*kept);
        } else {
            prepass = run_prepass(frame, o, *workload);
            if (o.save_prepass) o.save_prepass(prepass);
        }
        cluster_work.assign((warps + cluster - 1) / cluster, 0.0);
        for (size_t w = 0; w < prepass.trace_nodes.size(); ++w)
            for (uint32_t n : prepass.trace_nodes[w]) cluster_work[w / cluster] += n;
    }
    SampleDesign design(warps, cluster, o.rate, o.seed, cluster_work);
    check_draws_a_stratum(design, cluster, o);
    design_ = {cluster, design.strata(), design.first_wave_clusters(), design.empty_clusters(), design.strata() >= kMinStrata || design.census()};
    if (o.segments > 1) {
        if (!check_segments(design, o)) design_.has_interval = false;
        design.split(o.segments);
    }
    // The caches are warmed with the last node fetches of the clusters skipped before a
    // simulated cluster (a segment's first cluster: of every warp before it).
    if (traced) {
        // Each SM's L1 is warmed when that SM takes its first trace of the cluster: the SMs go
        // through their warps at their own pace (all are ready at cycle 0), and one of cheap
        // warps may start a cluster long before an SM of costly warps does; warming the
        // lagging SM then would fill its L1 before it has finished its previous cluster. With
        // a limit of resident warps a warp's SM is decided only as it starts, so the first SM
        // to start the cluster warms them all.
        // Without that limit the frame runs in rounds, and the skipped warps' first traces are
        // replayed apart from their later ones (Warming): replaying every trace of the skipped
        // warps at the cluster's start gave its camera rays an L1 that the frame's bounces had
        // filled (ship, path tracing 256x256: 0.139 of node fetches missed L1 in the sample
        // on average, 0.117 in the frame) and handed the first touches of the cluster's bounces
        // to the uncounted skipped warps (wknd: 0.0024 against 0.0050); docs/sampling.md,
        // "Warming".
        std::vector<std::vector<WarmFetch>> fetches = warming_fetches(frame, o, design, *workload);
        warm_.assign(fetches.size(), std::vector<Warming>(resident_ ? 1 : sms_));
        for (size_t i = 0; i < fetches.size(); ++i) {
            for (const WarmFetch& f : fetches[i]) {
                Warming& w = warm_[i][resident_ ? 0 : f.sm];
                (resident_ || f.trace == 0 ? w.first : w.later).push_back(f);
            }
            std::vector<WarmFetch>().swap(fetches[i]);
        }
    }
    // A cluster this run simulates: every one, or those of its segment.
    auto simulated_here = [&](size_t i) { return design.segments() == 1 || design.segment_of(i) == o.segment; };
    std::vector<uint64_t> kept;
    if (design.segments() > 1) segment_ends_.assign(design.segments(), 0);
    size_t drawn = 0;  // warps of the design so far, in frame order
    for (size_t i = 0; i < design.simulated().size(); ++i)
        for (uint64_t w = design.first_warp(i); w < design.end_warp(i); ++w) {
            WarpRecord rec;
            rec.weight = design.simulated()[i].weight;
            rec.stratum = design.simulated()[i].stratum;
            rec.frame_warp = w;
            if (traced) {
                rec.trace_nodes = prepass.trace_nodes[w];  // the estimator keeps the frame's
                for (uint32_t n : rec.trace_nodes) rec.critical_nodes += n;
                const std::vector<uint32_t>& first = prepass.first_reads(resident_ == 0);  // the order the frame runs in
                if (w < first.size()) rec.first_reads = first[w];
            }
            if (design.segments() > 1) {
                segment_ends_[design.segment_of(i)] = ++drawn;
                // What the merge expects of each segment: kept by the merge's sample only.
                if (o.segment == SamplingOptions::kNoSegment) merge_records_.push_back(rec);
            }
            if (!simulated_here(i)) continue;
            kept.push_back(w);
            cluster_of_.push_back(uint32_t(i));
            records_.push_back(std::move(rec));
        }
    if (traced) estimator_.set_prepass(std::move(prepass));
    select_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return kept;
}

void FrameSample::trace_starts(uint32_t kept, uint32_t sm, uint32_t trace) {
    const uint32_t c = cluster_of_[kept];
    if (c >= warm_.size()) return;
    // This SM's first trace of a simulated cluster, or (in rounds) its first later trace.
    Warming& w = warm_[c][warm_[c].size() == 1 ? 0 : sm];
    std::vector<WarmFetch>& mine = trace == 0 ? w.first : w.later;
    if (mine.empty()) return;
    if (on_warm) on_warm(mine);
    std::vector<WarmFetch>().swap(mine);
}

void FrameSample::ray_retired(uint32_t kept, const RetiredRay& ray) {
    WarpRecord& wr = records_[kept];
    wr.nodes += ray.nodes_visited;
    wr.l1_miss_nodes += ray.l1_miss_nodes;
    wr.dram_nodes += ray.dram_nodes;
}

void FrameSample::trace_done(uint32_t kept, uint32_t sm, uint64_t now, uint64_t residence) {
    // The trace's residence in the RT unit is the warp's work (cycles of a warp-buffer slot),
    // which is what the GPU's throughput is made of.
    WarpRecord& wr = records_[kept];
    wr.sm = sm;
    wr.last_done = double(now);
    estimator_.on_trace_done(wr, double(residence));
}

void FrameSample::warp_finished(uint64_t unfinished, uint64_t now) { estimator_.on_warp_finished(unfinished, now); }

SampleEstimate FrameSample::estimate() const {
    SampleEstimate e = estimator_.estimate(records_, warps_total_, sampled_);
    e.design = design_;
    return e;
}

SampleEstimate FrameSample::merge(const std::vector<std::vector<WarpRecord>>& segments) const {
    if (segment_ends_.empty() || segments.size() != segment_ends_.size())
        throw InputError("merging " + std::to_string(segments.size()) + " segments of a sample drawn in " +
                         std::to_string(segment_ends_.size()) + " segments");
    if (merge_records_.size() != segment_ends_.back())
        throw std::logic_error("FrameSample::merge needs a sample drawn with SamplingOptions::kNoSegment");
    std::vector<WarpRecord> all = merge_records_;
    size_t at = 0;
    for (size_t s = 0; s < segments.size(); ++s) {
        const size_t expected = segment_ends_[s] - at;
        if (segments[s].size() != expected)
            throw InputError("segment " + std::to_string(s) + " simulated " + std::to_string(segments[s].size()) +
                             " shader warps where this sample's segment has " + std::to_string(expected) +
                             ": it is not a segment of the same frame, sample and seed");
        for (const WarpRecord& r : segments[s]) {
            WarpRecord& w = all[at++];
            if (r.frame_warp != w.frame_warp || r.residences.size() > w.trace_nodes.size())
                throw InputError("segment " + std::to_string(s) + " holds shader warp " + std::to_string(r.frame_warp) + " where warp " +
                                 std::to_string(w.frame_warp) + " was drawn: it is not a segment of the same frame, sample and seed");
            w.work = r.work;
            w.nodes = r.nodes;
            w.l1_miss_nodes = r.l1_miss_nodes;
            w.dram_nodes = r.dram_nodes;
            w.residences = r.residences;
            w.traces_done = uint32_t(r.residences.size());
            w.sm = r.sm;
            w.last_done = r.last_done;
        }
    }
    SampleEstimate e = estimator_.estimate(all, warps_total_, true, segment_ends_);
    e.design = design_;
    return e;
}

}  // namespace rtu
