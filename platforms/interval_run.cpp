#include "interval_run.h"

#include <queue>

#include "model/interval_gpu.h"
#include "timing_stats.h"

namespace rtu {

TimingResult run_interval(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt) {
    IntervalGpu gpu(cfg, image, opt.order);
    gpu.set_shader_reads(cfg.shader_reads_of(workload.runs_shaders()));
    const std::unique_ptr<FrameSample> sample = frame_sample(cfg, image, opt, nullptr, workload);
    // Sampled run: when an SM starts a simulated cluster, its caches are warmed with its node
    // fetches of the clusters skipped before it (its L1, then L2 on an L1 miss).
    if (sample)
        sample->on_warm = [&gpu, sector = cfg.l1.sector](const std::vector<WarmFetch>& fetches) {
            for (const WarmFetch& f : fetches)
                for (uint32_t o = 0; o < f.bytes; o += sector) gpu.warm(f.sm, f.addr + o);
        };
    WorkloadDriver driver(workload, cfg.sms, cfg.warp_size, shader_timing(cfg, workload), sample.get(), opt.begun.get());
    driver.keep_rays(opt.keep_rays);

    // Warp-buffer slots by the cycle they are free (then by SM: deterministic order). A slot whose
    // SM has no trace ready and none coming yet idles until one of the SM's traces retires.
    using Slot = std::pair<uint64_t, uint32_t>;
    std::priority_queue<Slot, std::vector<Slot>, std::greater<Slot>> free_slots;
    for (uint32_t sm = 0; sm < cfg.sms; ++sm)
        for (uint32_t w = 0; w < cfg.warp_buffer; ++w) free_slots.push({0, sm});
    std::vector<uint32_t> idle(cfg.sms, 0);
    std::vector<IntervalGpu::Finished> finished;
    uint64_t end = 0;
    TimingProgress progress(opt.progress);
    bool interrupted = false;
    // The statistics of what has been simulated: the frame's up to the last ray retired, `upto`
    // (`partial`: rays are still in flight; no estimate is made). Reads the model, changes nothing.
    auto so_far = [&](uint64_t upto, bool partial) {
        TimingResult r;
        r.cycles = r.cycles_simulated = upto;  // the frame ends when its last ray retires
        r.interrupted = partial;
        take_estimate(r, sample.get(), driver);
        r.rays = driver.results();
        r.summary = driver.summary();
        r.counts.rt = gpu.rt_stats();
        for (const CacheBookings& c : gpu.l1()) r.counts.l1.push_back(c.tags().counts());
        for (const CacheBookings& c : gpu.l2()) r.counts.l2.push_back(c.tags().counts());
        r.counts.dram = gpu.dram_stats();
        r.counts.cycles_simulated = upto;
        r.counts.core_period_fs = double(gpu.core_period_fs());
        r.counts.memory_cycles = double(gpu.memory_cycle(upto));
        return r;
    };
    for (uint64_t step = 1;; ++step) {
        if ((step & 4095) == 0) {  // a clean point: between two events
            if (opt.stop.requested()) {
                interrupted = true;
                break;
            }
            if (opt.snapshot && opt.stop.snapshot_requested()) opt.snapshot(so_far(end, true));
        }
        const uint64_t slot_at = free_slots.empty() ? ~0ull : free_slots.top().first, fetch_at = gpu.next_event();
        if (slot_at == ~0ull && fetch_at == ~0ull) break;
        finished.clear();
        if (slot_at <= fetch_at) {  // a slot frees: it takes its SM's next ready trace
            const auto [now, sm] = free_slots.top();
            free_slots.pop();
            auto trace = driver.next_trace(sm, now);
            if (trace) {
                gpu.start_trace(sm, *trace, now, finished);
            } else {
                const uint64_t r = driver.earliest_ready(sm);
                if (r != ~0ull)
                    free_slots.push({std::max(r, now + 1), sm});
                else
                    ++idle[sm];
            }
        } else {
            gpu.run_next(finished, slot_at);
        }
        for (IntervalGpu::Finished& f : finished) {
            driver.retire(f.sm, f.rays, f.end);
            end = std::max(end, f.end);
            free_slots.push({f.end + 1, f.sm});  // the slot takes its next trace in the following cycle
            // The warp's next trace is known now: idle slots of the SM look again.
            const uint64_t r = driver.earliest_ready(f.sm);
            for (; idle[f.sm] > 0 && r != ~0ull; --idle[f.sm]) free_slots.push({std::max(r, f.end + 1), f.sm});
        }
        if (!finished.empty()) progress.update(end, driver);
    }
    progress.finish();

    TimingResult r = so_far(end, interrupted);
    if (interrupted) return r;  // rays are in flight: the invariants of a whole frame do not hold
    if (!driver.finished() || driver.rays_retired() != driver.rays_issued()) r.invariant_failures.push_back("not every ray retired");
    for (const std::string& f : counter_invariants(r.counts, r.summary)) r.invariant_failures.push_back(f);
    return r;
}

}  // namespace rtu
