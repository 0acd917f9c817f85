#include "driver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rtu {

WorkloadDriver::WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, uint32_t shade_latency,
                               double sample_rate, uint64_t seed, uint32_t cluster, uint32_t capacity)
    : workload_(workload), shade_(shade_latency), ready_(sms), capacity_(capacity) {
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
        std::vector<ShaderWarp> kept;
        for (uint64_t h = 0; h < n; ++h) {
            const uint64_t lo = h * n_all / n, hi = (h + 1) * n_all / n;
            Rng rng(seed, h, 0x5A3B1E);
            const uint64_t pick = lo + rng.next() % (hi - lo);
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

WorkloadDriver::Estimate WorkloadDriver::estimate() const {
    Estimate e;
    e.warps_total = warps_total_;
    e.warps_simulated = warps_.size();
    std::vector<double> weighted;  // per stratum: its cluster's work x the stratum's size
    for (const ShaderWarp& w : warps_) {
        e.work_simulated += w.work;
        e.work_estimate += w.weight * w.work;
        if (weighted.size() <= w.stratum) weighted.resize(w.stratum + 1, 0.0);
        weighted[w.stratum] += w.weight * w.work;
    }
    // One sample per stratum: the variance comes from collapsing neighbouring strata in pairs,
    // sum over pairs of (W_a - W_b)^2 (Cochran, Sampling Techniques, 5A.12).
    double v = 0;
    for (size_t i = 0; i + 1 < weighted.size(); i += 2) v += (weighted[i] - weighted[i + 1]) * (weighted[i] - weighted[i + 1]);
    e.relative_se = sampled_ && e.work_estimate > 0 ? std::sqrt(v) / e.work_estimate : 0.0;
    e.saturated_until = saturated_until_;
    e.work_saturated = work_saturated_;
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
            const uint64_t key = records_.size();
            records_.push_back(rec);
            if (!rec.r.valid) {
                // Invalid rays never reach the RT unit: a miss, counted.
                ++invalid_;
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
        ++retired_;
        last_progress_ = now;
        follow.clear();
        workload_.complete(rec.work, rec.r.hit, follow);
        ShaderWarp& sw = warps_[rec.warp];
        for (const WorkRay& f : follow) {
            auto it = std::find_if(sw.threads.begin(), sw.threads.end(), [&](const Thread& t) { return t.path == f.path; });
            it->pending.push_back(f);
        }
        if (--sw.in_flight == 0) {
            // The trace left the RT unit: its residence there is the warp's work (cycles of a
            // warp-buffer slot), which is what the GPU's throughput is made of.
            const double residence = double(now - sw.issued_at);
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
    }
    (void)sm;
}

std::vector<TracedRay> WorkloadDriver::results() const {
    std::vector<TracedRay> out;
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
