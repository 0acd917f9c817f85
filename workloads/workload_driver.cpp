#include "workload_driver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "input_error.h"

namespace rtu {

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

ShaderTiming shader_timing(const HwConfig& hw, const Workload& workload) {
    ShaderTiming t;
    t.shade = hw.shade_latency;
    t.launch = hw.launch_latency;
    t.resident = hw.resident_warps;
    t.intersection = hw.intersection_latency;
    t.contention = hw.shader_contention;
    t.shaders = workload.runs_shaders();
    return t;
}

WorkloadDriver::WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, const ShaderTiming& timing, WarpSelection* selection)
    : workload_(workload), timing_(timing), ready_(sms), selection_(selection) {
    timing_.shaders = timing.shaders && workload.runs_shaders();
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
    if (selection_ && !warps_.empty()) {
        // Only the selected warps run, in the order given, bound to the SMs round robin anew.
        const std::vector<uint64_t> picked = selection_->select(Frame(warps_));
        std::vector<ShaderWarp> kept;
        kept.reserve(picked.size());
        for (uint64_t w : picked) {
            ShaderWarp sw = std::move(warps_.at(w));
            sw.sm = uint32_t(kept.size() % sms);
            kept.push_back(std::move(sw));
        }
        warps_ = std::move(kept);
        for (uint32_t i = 0; i < warps_.size(); ++i)
            for (const Thread& t : warps_[i].threads) path_warp_[t.path] = i;
    }
    launched_ = timing_.resident ? std::min<size_t>(warps_.size(), size_t(sms) * timing_.resident) : warps_.size();
    // The first warps of an SM begin their shader code together, each beside all the others.
    std::vector<uint32_t> on_sm(sms, 0);
    for (uint32_t i = 0; i < launched_; ++i) ++on_sm[warps_[i].sm];
    if (timing_.contention > 0 && timing_.shaders) shading_.resize(sms);
    for (uint32_t i = 0; i < launched_; ++i) {
        const uint64_t at = timing_.first(on_sm[warps_[i].sm] - 1);
        if (!shading_.empty()) shading_[warps_[i].sm].add(at);
        enqueue(i, at);
    }
    live_warps_ = warps_.size();
}

void WorkloadDriver::enqueue(uint32_t warp, uint64_t ready_at) { ready_[warps_[warp].sm].insert({ready_at, warp}); }

void WorkloadDriver::shade(uint32_t warp, uint64_t now, uint64_t cycles) {
    if (shading_.empty()) {  // no contention (or no shader code): the code takes its own time
        enqueue(warp, now + cycles);
        return;
    }
    ShaderCodeEnds<uint64_t>& sm = shading_[warps_[warp].sm];
    const uint64_t at = now + timing_.contended(cycles, sm.beside(now));
    sm.add(at);
    enqueue(warp, at);
}

uint64_t WorkloadDriver::earliest_ready(uint32_t sm) const { return ready_[sm].empty() ? ~0ull : ready_[sm].begin()->first; }

std::optional<std::vector<WarpRay>> WorkloadDriver::next_trace(uint32_t sm, uint64_t now) {
    auto& q = ready_[sm];
    while (!q.empty() && q.begin()->first <= now) {
        const uint32_t wi = q.begin()->second;
        q.erase(q.begin());
        ShaderWarp& sw = warps_[wi];
        // A warp issues its next trace only once the last has retired: its traces so far are done.
        if (selection_) selection_->trace_starts(wi, sm, sw.traces_done);
        std::vector<WarpRay> rays;
        std::vector<RetiredRay> invalid;
        // The warp's threads trace together; those further on (a higher phase) wait for the
        // others (WorkRay::phase).
        uint32_t phase = ~0u;
        for (const Thread& t : sw.threads)
            if (!t.pending.empty()) phase = std::min(phase, t.pending.front().phase);
        for (Thread& t : sw.threads) {
            if (t.pending.empty() || t.pending.front().phase != phase) continue;
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
        if (rec.r.hit.hit) {
            rec.r.hit.t = std::ldexp(rec.r.hit.t, -rec.scale);
            rec.r.hit.app_t = std::ldexp(rec.r.hit.app_t, -rec.scale);
        }
        rec.r.nodes_visited = rr.nodes_visited;
        summary_.rays += 1;
        summary_.invalid += !rec.r.valid;
        summary_.hits += rec.r.hit.hit;
        summary_.nodes_visited += rr.nodes_visited;
        summary_.l1_miss_nodes += rr.l1_miss_nodes;
        summary_.dram_nodes += rr.dram_nodes;
        summary_.max_nodes = std::max(summary_.max_nodes, rr.nodes_visited);
        ShaderWarp& sw = warps_[rec.warp];
        sw.loop = std::max(sw.loop, rr.candidates);
        if (selection_) selection_->ray_retired(rec.warp, rr);
        last_progress_ = now;
        follow.clear();
        workload_.complete(rec.work, rec.r.hit, follow);
        for (const WorkRay& f : follow) {
            auto it = std::find_if(sw.threads.begin(), sw.threads.end(), [&](const Thread& t) { return t.path == f.path; });
            it->pending.push_back(f);
        }
        if (--sw.in_flight == 0) {
            // The trace left the RT unit after `now - issued_at` cycles in a warp-buffer slot.
            ++sw.traces_done;
            if (selection_) selection_->trace_done(rec.warp, sw.sm, now, now - sw.issued_at);
            const bool more = std::any_of(sw.threads.begin(), sw.threads.end(), [](const Thread& t) { return !t.pending.empty(); });
            const uint32_t loop = sw.loop;
            sw.loop = 0;
            if (more) {
                shade(rec.warp, now, uint64_t(timing_.intersection) * loop + timing_.shade);
            } else {
                --live_warps_;
                if (selection_) selection_->warp_finished(live_warps_, now);
                if (launched_ < warps_.size()) {  // its place goes to the next warp of the frame, which shades first
                    warps_[launched_].sm = sw.sm;
                    shade(uint32_t(launched_++), now, timing_.shaders ? timing_.shade : 0);
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
