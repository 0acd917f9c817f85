#include "workload_driver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "input_error.h"

namespace rtu {

namespace {

std::string percent(double x) {
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
    std::string msg = "--sample " + percent(o.rate) + " % of this frame's " + std::to_string(clusters) + " clusters of " +
                      std::to_string(cluster) + " shader warps (" + std::to_string(warps) + " warps) draws " +
                      std::to_string(planned.strata()) + " strata beside the first wave (simulated whole); a 95 % interval needs at least " +
                      std::to_string(kMinStrata) + " strata: ";
    if (rate < 1.0) msg += "use --sample " + percent(rate) + " % or more (--sample " + std::to_string(rate).substr(0, 5) + "), ";
    msg += "a frame of at least " + std::to_string(uint64_t(std::ceil(need / std::max(o.rate, 1e-9))) * cluster) +
           " shader warps at this rate, or --sample-unchecked for an estimate without an interval";
    throw InputError(msg);
}

}  // namespace

class WorkloadDriver::Frame : public FrameWarps {
public:
    explicit Frame(const std::vector<ShaderWarp>& warps) : warps_(warps) {}
    size_t warps() const override { return warps_.size(); }
    uint32_t sm(size_t w) const override { return warps_[w].sm; }
    void threads(size_t w, std::vector<uint32_t>& paths, std::vector<RayQueue>& first) const override {
        const ShaderWarp& sw = warps_[w];
        paths.resize(sw.threads.size());
        first.resize(std::max(first.size(), sw.threads.size()));
        for (size_t i = 0; i < sw.threads.size(); ++i) {
            paths[i] = sw.threads[i].path;
            first[i] = sw.threads[i].pending;
        }
    }

private:
    const std::vector<ShaderWarp>& warps_;
};

WorkloadDriver::WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency, uint32_t resident_warps,
                               const SamplingOptions& sampling)
    : workload_(workload), shade_(shade_latency), ready_(sms),
      estimator_({sms, std::max<uint32_t>(1, sampling.capacity / std::max<uint32_t>(1, sms)), shade_latency, resident_warps},
                 sampling.capacity) {
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
    records_of_warps_.assign(warps_.size(), WarpRecord{});
    if (sampling.rate < 1.0 && !warps_.empty()) {
        sampled_ = true;
        const uint64_t cluster = std::max<uint32_t>(1, sampling.capacity);
        check_sample_size(SampleDesign(warps_.size(), cluster, sampling.rate, sampling.seed), warps_.size(), cluster, sampling);
        // The pre-pass's critical paths per warp, and per cluster their sum: the work the
        // clusters are stratified by.
        PrepassResult prepass;
        std::vector<double> cluster_work;
        const bool traced = sampling.make_workload && sampling.trace;
        std::optional<PrepassWorkloads> workloads;
        if (traced) {
            workloads.emplace(sampling);
            std::optional<PrepassResult> kept = sampling.load_prepass ? sampling.load_prepass() : std::nullopt;
            if (kept && kept->trace_nodes.size() != warps_.size())
                throw InputError("the sample plan holds " + std::to_string(kept->trace_nodes.size()) + " shader warps, this frame " +
                                 std::to_string(warps_.size()));
            if (kept) {
                prepass = std::move(*kept);
            } else {
                prepass = run_prepass(Frame(warps_), sampling, *workloads);
                if (sampling.save_prepass) sampling.save_prepass(prepass);
            }
            cluster_work.assign((warps_.size() + cluster - 1) / cluster, 0.0);
            for (size_t w = 0; w < prepass.trace_nodes.size(); ++w)
                for (uint32_t n : prepass.trace_nodes[w]) cluster_work[w / cluster] += n;
        }
        SampleDesign design(warps_.size(), cluster, sampling.rate, sampling.seed, cluster_work);
        // Never an estimate of 0 (or of the first wave alone) for a frame with work beyond it: a
        // draw of no stratum cannot extrapolate, checked or not.
        if (design.strata() == 0 && !design.census())
            throw InputError("--sample " + percent(sampling.rate) + " % of this frame's " + std::to_string(design.clusters()) +
                             " clusters of " + std::to_string(cluster) + " shader warps draws no cluster beside the first wave, so " +
                             "nothing stands for the rest of the frame's work; sample more (--sample " +
                             std::to_string(std::ceil(1000.0 * 1.5 / double(design.clusters())) / 1000.0).substr(0, 5) + " or more)");
        design_ = {cluster, design.strata(), design.first_wave_clusters(), design.empty_clusters(),
                   design.strata() >= kMinStrata || design.census()};
        if (sampling.segments > 1) {
            if (sampling.segments > design.simulated().size())
                throw InputError("--sample-segments " + std::to_string(sampling.segments) + ": this sample simulates " +
                                 std::to_string(design.simulated().size()) + " clusters, and a segment needs one at least; use " +
                                 std::to_string(design.simulated().size()) + " segments or fewer");
            const uint64_t per_segment = design.simulated().size() / sampling.segments;
            if (per_segment < kMinSegmentClusters) {
                if (!sampling.unchecked)
                    throw InputError("--sample-segments " + std::to_string(sampling.segments) + ": this sample simulates " +
                                     std::to_string(design.simulated().size()) + " clusters, " + std::to_string(per_segment) +
                                     " per segment; a segment needs " + std::to_string(kMinSegmentClusters) +
                                     " for the interval (fewer ran 4-11 % off, docs/sampling.md): " +
                                     (design.simulated().size() >= 2 * kMinSegmentClusters
                                          ? "use --sample-segments " + std::to_string(design.simulated().size() / kMinSegmentClusters) + " or fewer, "
                                          : std::string("too few to split; use ")) +
                                     "a larger sample or frame, or --sample-unchecked for an estimate without an interval");
                design_.has_interval = false;
            }
            if (sampling.segment != SamplingOptions::kNoSegment && sampling.segment >= sampling.segments)
                throw InputError("--segment " + std::to_string(sampling.segment) + ": the segments are numbered 0.." +
                                 std::to_string(sampling.segments - 1));
            design.split(sampling.segments);
        }
        // A cluster this run simulates: every one, or those of its segment.
        auto simulated_here = [&](size_t i) { return design.segments() == 1 || design.segment_of(i) == sampling.segment; };
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
            // "Warming the first traces apart".
            std::vector<std::vector<WarmFetch>> fetches = warming_fetches(Frame(warps_), sampling, design, *workloads);
            warm_.assign(fetches.size(), std::vector<Warming>(resident_warps ? 1 : sms));
            for (size_t i = 0; i < fetches.size(); ++i) {
                for (const WarmFetch& f : fetches[i]) {
                    Warming& w = warm_[i][resident_warps ? 0 : f.sm];
                    (resident_warps || f.trace == 0 ? w.first : w.later).push_back(f);
                }
                std::vector<WarmFetch>().swap(fetches[i]);
            }
        }
        std::vector<ShaderWarp> kept;
        std::vector<WarpRecord> kept_records;
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
                    const std::vector<uint32_t>& first = prepass.first_reads(resident_warps == 0);  // the order the frame runs in
                    if (w < first.size()) rec.first_reads = first[w];
                }
                if (design.segments() > 1) {
                    segment_ends_[design.segment_of(i)] = ++drawn;
                    // What the merge expects of each segment: kept by the merge's driver only.
                    if (sampling.segment == SamplingOptions::kNoSegment) merge_records_.push_back(rec);
                }
                if (!simulated_here(i)) continue;
                ShaderWarp sw = std::move(warps_[w]);
                sw.sm = uint32_t(kept.size() % sms);
                sw.cluster = uint32_t(i);
                kept.push_back(std::move(sw));
                kept_records.push_back(std::move(rec));
            }
        if (traced) estimator_.set_prepass(std::move(prepass));
        warps_ = std::move(kept);
        records_of_warps_ = std::move(kept_records);
        for (uint32_t i = 0; i < warps_.size(); ++i)
            for (const Thread& t : warps_[i].threads) path_warp_[t.path] = i;
    }
    launched_ = resident_warps ? std::min<size_t>(warps_.size(), size_t(sms) * resident_warps) : warps_.size();
    for (uint32_t i = 0; i < launched_; ++i) enqueue(i, 0);
    live_warps_ = warps_.size();
}

WorkloadDriver::Estimate WorkloadDriver::estimate() const {
    Estimate e = estimator_.estimate(records_of_warps_, warps_total_, sampled_);
    e.design = design_;
    return e;
}

WorkloadDriver::Estimate WorkloadDriver::merge(const std::vector<std::vector<WarpRecord>>& segments) const {
    if (segment_ends_.empty() || segments.size() != segment_ends_.size())
        throw InputError("merging " + std::to_string(segments.size()) + " segments of a sample drawn in " +
                         std::to_string(segment_ends_.size()) + " segments");
    if (merge_records_.size() != segment_ends_.back())
        throw std::logic_error("WorkloadDriver::merge needs a driver drawn with SamplingOptions::kNoSegment");
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
    Estimate e = estimator_.estimate(all, warps_total_, true, segment_ends_);
    e.design = design_;
    return e;
}

void WorkloadDriver::enqueue(uint32_t warp, uint64_t ready_at) { ready_[warps_[warp].sm].insert({ready_at, warp}); }

uint64_t WorkloadDriver::earliest_ready(uint32_t sm) const { return ready_[sm].empty() ? ~0ull : ready_[sm].begin()->first; }

std::optional<std::vector<WarpRay>> WorkloadDriver::next_trace(uint32_t sm, uint64_t now) {
    auto& q = ready_[sm];
    while (!q.empty() && q.begin()->first <= now) {
        const uint32_t wi = q.begin()->second;
        q.erase(q.begin());
        ShaderWarp& sw = warps_[wi];
        if (sw.cluster < warm_.size()) {
            Warming& w = warm_[sw.cluster][warm_[sw.cluster].size() == 1 ? 0 : sm];
            // This SM's first trace of a simulated cluster, or (in rounds) its first later trace. A
            // warp issues its next trace only once the last has retired, so its traces so far are
            // its record's traces_done.
            std::vector<WarmFetch>& mine = records_of_warps_[wi].traces_done == 0 ? w.first : w.later;
            if (!mine.empty()) {
                if (on_warm) on_warm(mine);
                std::vector<WarmFetch>().swap(mine);
            }
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
        WarpRecord& wr = records_of_warps_[rec.warp];
        wr.nodes += rr.nodes_visited;
        wr.l1_miss_nodes += rr.l1_miss_nodes;
        wr.dram_nodes += rr.dram_nodes;
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
            wr.sm = sw.sm;
            wr.last_done = double(now);
            estimator_.on_trace_done(wr, double(now - sw.issued_at));
            const bool more = std::any_of(sw.threads.begin(), sw.threads.end(), [](const Thread& t) { return !t.pending.empty(); });
            if (more) {
                enqueue(rec.warp, now + shade_);
            } else {
                estimator_.on_warp_finished(--live_warps_, now);
                if (launched_ < warps_.size()) {  // its place goes to the next warp of the frame
                    warps_[launched_].sm = sw.sm;
                    enqueue(uint32_t(launched_++), now);
                }
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
