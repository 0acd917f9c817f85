#include "segment_threads.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <iostream>
#include <mutex>

#include "fidelity_run.h"
#include "model/on_threads.h"
#include "sampling/prepass.h"

namespace rtu {

std::vector<SegmentRun> run_segment_threads(const HwConfig& hw, const BvhImage& image, const std::function<std::unique_ptr<Workload>()>& fresh,
                                            const TimingOptions& opt, unsigned threads, const std::vector<IdentityKey>& identity,
                                            std::optional<PrepassResult>& prepass, bool quiet, double* prepass_s) {
    const uint32_t segments = opt.sample_segments;
    // The one workload instance the pre-pass and every segment's warming trace (PrepassWorkload:
    // a segment thread does not hold a copy of the frame's paths for its warming).
    const auto traced = opt.sample_workload ? std::make_shared<PrepassWorkload>(opt.sample_workload) : nullptr;
    // The frame's design and pre-pass first, on every thread, as the merge makes them (a sample
    // drawn with kNoSegment simulates no warp); from the plan file where one is kept, into it
    // where it is not.
    {
        TimingOptions o = opt;
        o.sample_segment = SamplingOptions::kNoSegment;
        o.threads = std::max(1u, threads);
        o.prepass_workload = traced;
        const std::unique_ptr<Workload> workload = fresh();
        SamplingOptions s = sampling_options(hw, image, o, nullptr);
        const auto load = s.load_prepass;
        const auto save = s.save_prepass;
        s.load_prepass = [&] {
            std::optional<PrepassResult> p = load ? load() : std::nullopt;
            if (p) prepass = *p;
            return p;
        };
        s.save_prepass = [&](const PrepassResult& p) {
            if (save) save(p);
            prepass = p;
        };
        FrameSample sample(s, hw.sms, shader_timing(hw, *workload));
        const WorkloadDriver driver(*workload, hw.sms, hw.warp_size, shader_timing(hw, *workload), &sample);
        if (prepass_s) *prepass_s = sample.select_seconds();
    }
    if (!prepass) throw std::logic_error("--sample-segments: the frame's pre-pass was not made");
    const auto shared = std::make_shared<const PrepassResult>(*prepass);

    // Then the segments, up to `threads` at once, each on one thread (the pre-pass is made): the
    // next segment goes to the first thread free. Results land in their segment's slot. They
    // share one workload, begun here: each segment's warps are its own paths, which no other
    // segment touches (the warming traces the pre-pass's instance, `traced`), so a segment thread
    // holds its warps' state, not the frame's (at 1920x1080 a workload instance and its first
    // rays are about 270 MB).
    const std::unique_ptr<Workload> workload = fresh();
    auto begun = std::make_shared<std::vector<WorkRay>>();
    workload->begin(*begun);
    const uint32_t parallel = std::max(1u, std::min<uint32_t>(segments, threads));
    std::vector<std::optional<TimingResult>> results(segments);
    std::vector<std::exception_ptr> errors(segments);
    std::atomic<uint32_t> next{0};
    std::atomic<bool> failed{false};
    std::mutex log;
    on_threads(parallel, [&](unsigned) {
        for (uint32_t i; (i = next.fetch_add(1)) < segments;) {
            if (failed.load() || opt.stop.requested()) return;
            if (!quiet) {
                const std::lock_guard<std::mutex> lock(log);
                std::cerr << "segment " << i + 1 << " of " << segments << (parallel > 1 ? " started" : "") << "\n";
            }
            try {
                TimingOptions o = opt;
                o.sample_segment = i;
                o.threads = 1;
                o.prepass = shared;
                o.prepass_workload = traced;
                o.sample_plan.clear();
                o.progress = false;
                o.snapshot = nullptr;
                o.keep_rays = false;
                o.begun = begun;
                results[i] = run_timing(hw, image, *workload, o);
            } catch (...) {
                errors[i] = std::current_exception();
                failed.store(true);
                return;
            }
        }
    });
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
    if (opt.stop.requested()) throw Interrupted{opt.stop.signal()};

    // Each as its child's statistics file gives it to the merge (segment_file.cpp).
    nlohmann::json id;
    for (const IdentityKey& k : identity) id[k.name] = k.value;
    std::vector<SegmentRun> runs(segments);
    for (uint32_t i = 0; i < segments; ++i) {
        TimingResult& t = *results[i];
        if (t.interrupted) throw Interrupted{opt.stop.signal()};
        // What would make a segment's child exit with an error fails the run here too.
        if (t.stuck) throw std::runtime_error("segment " + std::to_string(i) + ": " + t.stuck_report);
        if (!t.invariant_failures.empty())
            throw std::runtime_error("segment " + std::to_string(i) + ": invariant violated: " + t.invariant_failures.front());
        SegmentRun& s = runs[i];
        s.header.index = i;
        s.header.count = segments;
        s.header.identity = id;
        s.cycles_simulated = t.cycles_simulated;
        s.payloads_allocated = t.payloads_allocated;
        s.summary = t.summary;
        s.counts = t.counts;
        s.counts.cycles_simulated = t.cycles_simulated;
        s.warps = std::move(t.segment_records);
    }
    return runs;
}

}  // namespace rtu
