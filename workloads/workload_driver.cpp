#include "workload_driver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "input_error.h"

namespace rtu {

// The frame's shader warps as the workload's first rays lay them out: its paths in the order of
// their first ray, each run of warp_size of them (neighbouring pixels) one shader warp, bound to
// the SMs round robin; a path's first rays in the order given. Read by a selection, and by the
// driver to make the warps it runs: a warp's threads (with a queue of rays each) are made only
// for the warps that run, so a sample does not hold the frame's queues (a sampled 1920x1080 frame
// held about 120 bytes a path in them, in every segment that ran at once).
class WorkloadDriver::Frame : public FrameWarps {
public:
    Frame(const std::vector<WorkRay>& first, uint32_t warp_size, uint32_t sms) : first_(&first), warp_size_(warp_size), sms_(sms) {
        uint32_t max_path = 0;
        for (const WorkRay& w : first) max_path = std::max(max_path, w.path);
        std::vector<uint32_t> rank(first.empty() ? 0 : size_t(max_path) + 1, ~0u);  // path -> its place in paths_
        for (const WorkRay& w : first)
            if (rank[w.path] == ~0u) {
                rank[w.path] = uint32_t(paths_.size());
                paths_.push_back(w.path);
            }
        // A path's rays together, in the order given (the frame workloads give one per path, in
        // path order: they are taken as they are).
        auto by_rank = [&](const WorkRay& a, const WorkRay& b) { return rank[a.path] < rank[b.path]; };
        if (!std::is_sorted(first.begin(), first.end(), by_rank)) {
            sorted_ = first;
            std::stable_sort(sorted_.begin(), sorted_.end(), by_rank);
            first_ = &sorted_;
        }
        start_.assign(paths_.size() + 1, 0);
        for (const WorkRay& w : first) ++start_[rank[w.path] + 1];
        for (size_t r = 0; r < paths_.size(); ++r) start_[r + 1] += start_[r];
    }
    size_t warps() const override { return (paths_.size() + warp_size_ - 1) / warp_size_; }
    uint32_t sm(size_t w) const override { return uint32_t(w % sms_); }
    void threads(size_t w, std::vector<uint32_t>& paths, std::vector<RayQueue>& first) const override {
        const size_t begin = w * warp_size_, n = std::min<size_t>(warp_size_, paths_.size() - begin);
        paths.resize(n);
        first.resize(std::max(first.size(), n));
        for (size_t i = 0; i < n; ++i) {
            paths[i] = paths_[begin + i];
            fill(first[i], begin + i);
        }
    }
    // Shader warp `w` of the frame, on SM `sm`, its threads holding their first rays.
    ShaderWarp warp(size_t w, uint32_t sm) const {
        if (w >= warps()) throw std::out_of_range("a selection picked shader warp " + std::to_string(w) + " of " + std::to_string(warps()));
        ShaderWarp sw;
        sw.sm = sm;
        const size_t begin = w * warp_size_, n = std::min<size_t>(warp_size_, paths_.size() - begin);
        sw.threads.reserve(n);
        for (size_t i = 0; i < n; ++i) {
            sw.threads.push_back(Thread{paths_[begin + i], 0, {}});
            fill(sw.threads.back().pending, begin + i);
        }
        return sw;
    }

private:
    // `q` holds the first rays of the path at `rank`, and nothing else.
    void fill(RayQueue& q, size_t rank) const {
        q.clear();
        for (uint32_t i = start_[rank]; i < start_[rank + 1]; ++i) q.push_back((*first_)[i]);
    }
    const std::vector<WorkRay>* first_;  // the first rays given, or sorted_
    std::vector<WorkRay> sorted_;        // the first rays by path, where they were not given so
    uint32_t warp_size_, sms_;
    std::vector<uint32_t> paths_;  // in the order of their first ray
    std::vector<uint32_t> start_;  // per path (by that order): its rays are first_[start_[r], start_[r + 1])
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

WorkloadDriver::WorkloadDriver(Workload& workload, uint32_t sms, uint32_t warp_size, const ShaderTiming& timing, WarpSelection* selection,
                               const std::vector<WorkRay>* begun)
    : workload_(workload), timing_(timing), ready_(sms), selection_(selection) {
    timing_.shaders = timing.shaders && workload.runs_shaders();
    std::vector<WorkRay> own;
    if (!begun) workload_.begin(own);
    {
        const Frame frame(begun ? *begun : own, warp_size, sms);
        warps_total_ = frame.warps();
        if (selection_ && warps_total_) {
            // Only the selected warps run, in the order given, bound to the SMs round robin anew.
            const std::vector<uint64_t> picked = selection_->select(frame);
            warps_.reserve(picked.size());
            for (uint64_t w : picked) warps_.push_back(frame.warp(w, uint32_t(warps_.size() % sms)));
        } else {
            warps_.reserve(warps_total_);
            for (uint64_t w = 0; w < warps_total_; ++w) warps_.push_back(frame.warp(w, uint32_t(w % sms)));
        }
    }
    std::vector<WorkRay>().swap(own);
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
