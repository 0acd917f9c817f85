#include "gpu_platform.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <systemc>

#include "model/treelet.h"
#include "timeline.h"
#include "timing_stats.h"
#include "tlm/rt_complex.h"
#include "workloads/workload_driver.h"

namespace rtu {

using namespace sc_core;

// Watchdog and progress. It wakes every `period` cycles only while rays are
// still in flight, so an idle platform has no pending events and sc_start() returns. (Outside an
// anonymous namespace: GpuPlatform::Impl, declared in the header, holds one.)
class PlatformMonitor : public sc_module {
public:
    SC_HAS_PROCESS(PlatformMonitor);
    PlatformMonitor(sc_module_name n, WorkloadDriver& driver, const ClockDomain& clock, uint64_t watchdog, bool show_progress,
                    uint64_t period, StopRequest stop)
        : sc_module(n), progress(show_progress), driver_(driver), clock_(clock), watchdog_(watchdog), period_(period), stop_(stop) {
        SC_METHOD(check);
    }
    bool stuck = false;
    // Stopped by the stop request at `stopped_at` (a core cycle): the run's clean point, since the
    // monitor's wake-ups do not depend on the request (reading it adds no event).
    bool interrupted = false;
    uint64_t stopped_at = 0;
    std::string report;
    std::function<std::string()> describe_stuck;
    std::function<void(uint64_t)> snapshot;  // the statistics so far at a core cycle (SIGUSR1)
    TimingProgress progress;

private:
    void check() {
        const uint64_t c = clock_.cycle_at_or_before(sc_time_stamp());
        if (driver_.finished()) return;
        if (stop_.requested()) {
            interrupted = true;
            stopped_at = c;
            sc_stop();
            return;
        }
        if (snapshot && stop_.snapshot_requested()) snapshot(c);
        if (c > driver_.last_progress() + watchdog_) {
            stuck = true;
            report = "no ray retired for " + std::to_string(c - driver_.last_progress()) + " cycles (sim.watchdog = " +
                     std::to_string(watchdog_) + "); oldest trace: " + driver_.oldest_in_flight() +
                     (describe_stuck ? "; " + describe_stuck() : std::string());
            sc_stop();
            return;
        }
        progress.update(c, driver_);
        next_trigger(clock_.period() * double(period_));
    }

    WorkloadDriver& driver_;
    const ClockDomain& clock_;
    uint64_t watchdog_;
    uint64_t period_;
    StopRequest stop_;
};

struct GpuPlatform::Impl {
    HwConfig cfg;
    const BvhImage& image;
    TimingOptions opt;
    std::unique_ptr<Treelets> treelets;  // before the driver: its pre-pass traverses with them
    std::unique_ptr<FrameSample> sample;  // before the driver, which takes it as its warp selection
    WorkloadDriver driver;
    RtComplex gpu;
    const ClockDomain &core, &mem;
    std::unique_ptr<PlatformMonitor> monitor;
    sc_trace_file* tf = nullptr;
    // Traced values (sampled into the VCD when tracing is on).
    struct RtTrace {
        int warps = 0, maq = 0, fifo = 0, active = 0;
        int picked = -1, ready = 0, prefetch_queue = 0;  // the warp scheduler; the prefetch queue
        int sent = 0, dropped = 0, late = 0;              // TTP's prefetches in the last window
        uint64_t sent_before = 0, dropped_before = 0, late_before = 0;
    };
    std::vector<RtTrace> rt_trace;
    std::vector<int> l1_mshr, l2_mshr;
    std::vector<double> l1_missrate, l2_missrate;
    std::vector<CacheAccessCounts> l1_prev, l2_prev;
    int dram_queue = 0;
    double dram_bw = 0;
    uint64_t dram_prev_busy = 0;
    std::vector<int> stack_depth, ttp_state;
    // The windowed values (caches, DRAM) are sampled by the first RT unit to tick at or after a
    // window's end, so that tracing adds no event of its own. (Until 2026-11-26 an extra timed
    // event at the same time as the model's reordered the kernel's same-time processes and changed
    // the results; the RT complex now orders its own, tlm/ordered_events.h.)
    std::function<void(uint64_t)> sample_windows;
    std::unique_ptr<Timeline> timeline;  // --timeline
    uint64_t last_sample = 0, next_sample = 0;

    Impl(const HwConfig& c, const BvhImage& img, Workload& w, const TimingOptions& o)
        : cfg(c), image(img), opt(o),
          // Treelet traversal (and with it the Treelet prefetcher, which needs it) works on treelets.
          treelets(traversal_treelets(c, img, o.order)),
          sample(frame_sample(c, img, o, treelets.get(), w)),
          driver(w, c.sms, c.warp_size, shader_timing(c, w), sample.get(), o.begun.get()),
          gpu("gpu", c, img, o.order, driver, o.fidelity, treelets.get(), o.check_protocol),
          core(gpu.core_clock()),
          mem(gpu.memory_clock()) {}

    // The statistics of what has been simulated up to core cycle `cycles` (`partial`: rays are
    // still in flight, and no estimate is made). At the run's end (`at_end`) each thread's cycles
    // are first accounted up to `cycles`; a snapshot on the way (SIGUSR1) only reads, so that it
    // changes nothing: its threads' cycles count up to each one's last change of status (in LT an
    // RT unit runs ahead of the monitor's time, and accounting to an earlier cycle would change
    // the final figures).
    TimingResult so_far(uint64_t cycles, bool partial, bool at_end) {
        TimingResult r;
        r.cycles_simulated = r.cycles = cycles;
        r.interrupted = partial;
        take_estimate(r, sample.get(), driver);
        r.rays = driver.results();
        r.summary = driver.summary();
        r.counts.cycles_simulated = cycles;
        r.counts.core_period_fs = double(core.period_fs());
        r.counts.memory_cycles = double(cycles) * double(core.period_fs()) / double(mem.period_fs());
        for (const auto& u : gpu.rt_units()) {
            if (at_end) u->core().account(cycles);
            r.counts.rt.push_back(u->core().stats());
        }
        for (const auto& c : gpu.l1()) r.counts.l1.push_back(c->tags().counts());
        for (const auto& c : gpu.l2()) r.counts.l2.push_back(c->tags().counts());
        r.counts.dram = gpu.dram().stats();
        r.payloads_allocated = gpu.pool().allocated();
        return r;
    }
};

// rtsim's platform: the RT complex fed by the workload driver, the monitor, the waveforms. Its
// process-wide settings (report actions, time resolution) are rtsim's sc_main's; the LT quantum
// is the RT units' own (tlm/rt_unit.h).
GpuPlatform::GpuPlatform(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt)
    : impl_(new Impl(cfg, image, workload, opt)) {
    Impl& m = *impl_;
    m.driver.keep_rays(opt.keep_rays);
    // Given rays (a ray file) run no shader code, and so no shader reads.
    m.gpu.set_shader_reads(cfg.shader_reads_of(workload.runs_shaders()));
    // Sampled run: when an SM starts a simulated cluster, its caches are warmed with its node
    // fetches of the clusters skipped before it (its L1, then L2 on an L1 miss).
    if (m.sample)
        m.sample->on_warm = [impl = impl_.get(), sector = cfg.l1.sector](const std::vector<WarmFetch>& fetches) {
            for (const WarmFetch& f : fetches)
                for (uint32_t o = 0; o < f.bytes; o += sector)
                    impl->gpu.warm(f.sm, (impl->treelets ? impl->treelets->placed(f.addr) : f.addr) + o);
        };

    if (!opt.vcd.empty()) {
        m.tf = sc_create_vcd_trace_file(opt.vcd.c_str());
        m.tf->set_time_unit(1, SC_FS);  // the kernel resolution: clock periods are not whole ps
        m.rt_trace.resize(cfg.sms);
        for (uint32_t s = 0; s < cfg.sms; ++s) {
            const std::string p = "rt_unit_" + std::to_string(s) + ".";
            sc_trace(m.tf, m.rt_trace[s].warps, p + "warp_buffer_occupancy");
            sc_trace(m.tf, m.rt_trace[s].maq, p + "memory_access_queue_depth");
            sc_trace(m.tf, m.rt_trace[s].fifo, p + "response_fifo_depth");
            sc_trace(m.tf, m.rt_trace[s].active, p + "active_threads");
            sc_trace(m.tf, m.rt_trace[s].picked, p + "warp_scheduler.picked_slot");
            sc_trace(m.tf, m.rt_trace[s].ready, p + "warp_scheduler.ready_warps");
            sc_trace(m.tf, m.rt_trace[s].prefetch_queue, p + "prefetch_queue_depth");
            sc_trace(m.tf, m.rt_trace[s].sent, p + "ttp.prefetches_sent_window");
            sc_trace(m.tf, m.rt_trace[s].dropped, p + "ttp.prefetches_dropped_window");
            sc_trace(m.tf, m.rt_trace[s].late, p + "ttp.prefetches_late_window");
            RtUnit* unit = m.gpu.rt_units()[s].get();
            Impl::RtTrace* tr = &m.rt_trace[s];
            const bool traced_warp = int(s) == opt.trace_sm;
            if (traced_warp) {
                m.stack_depth.assign(cfg.warp_size, -1);
                m.ttp_state.assign(cfg.warp_size, -1);
                for (uint32_t t = 0; t < cfg.warp_size; ++t) {
                    const std::string thread = p + "warp" + std::to_string(opt.trace_warp) + ".thread" + std::to_string(t);
                    sc_trace(m.tf, m.stack_depth[t], thread + ".stack_depth");
                    sc_trace(m.tf, m.ttp_state[t], thread + ".ttp_state");
                }
            }
            Impl* impl = &m;
            unit->on_cycle = [unit, tr, traced_warp, impl](uint64_t cycle) {
                if (cycle >= impl->next_sample) {
                    impl->sample_windows(cycle);
                    impl->next_sample = (cycle / impl->cfg.trace_window + 1) * impl->cfg.trace_window;
                }
                const RtUnitCore& c = unit->core();
                tr->warps = int(c.warp_buffer_occupancy());
                tr->maq = int(c.memory_access_queue_depth());
                tr->fifo = int(c.response_fifo_depth());
                tr->active = int(c.active_threads());
                tr->picked = c.picked_slot(cycle);
                tr->ready = int(c.ready_warps());
                tr->prefetch_queue = int(c.prefetch_queue_depth());
                if (traced_warp)
                    for (size_t t = 0; t < impl->stack_depth.size(); ++t) {
                        impl->stack_depth[t] = c.stack_depth(uint32_t(impl->opt.trace_warp), uint32_t(t));
                        impl->ttp_state[t] = c.ttp_state(uint32_t(impl->opt.trace_warp), uint32_t(t));
                    }
            };
        }
        auto trace_caches = [&](const std::vector<std::unique_ptr<Cache>>& caches, std::vector<int>& mshr,
                                std::vector<double>& rate, std::vector<CacheAccessCounts>& prev, const std::string& prefix) {
            mshr.assign(caches.size(), 0);
            rate.assign(caches.size(), 0.0);
            prev.assign(caches.size(), CacheAccessCounts{});
            for (size_t i = 0; i < caches.size(); ++i) {
                sc_trace(m.tf, mshr[i], prefix + std::to_string(i) + ".mshr_occupancy");
                sc_trace(m.tf, rate[i], prefix + std::to_string(i) + ".miss_rate_window");
            }
        };
        trace_caches(m.gpu.l1(), m.l1_mshr, m.l1_missrate, m.l1_prev, "l1_");
        trace_caches(m.gpu.l2(), m.l2_mshr, m.l2_missrate, m.l2_prev, "l2_");
        sc_trace(m.tf, m.dram_queue, "dram.queue_depth");
        sc_trace(m.tf, m.dram_bw, "dram.bandwidth_utilisation_window");
        Impl* impl = &m;
        m.next_sample = cfg.trace_window;
        m.sample_windows = [impl](uint64_t cycle) {
            if (cycle <= impl->last_sample) return;
            auto upd = [](const std::vector<std::unique_ptr<Cache>>& caches, std::vector<int>& mshr, std::vector<double>& rate,
                          std::vector<CacheAccessCounts>& prev) {
                for (size_t i = 0; i < caches.size(); ++i) {
                    CacheAccessCounts now = caches[i]->tags().counts().demand;
                    add(now, caches[i]->tags().counts().prefetch);
                    const uint64_t acc = now.accesses - prev[i].accesses;
                    const uint64_t miss = (now.sector_misses + now.line_misses + now.mshr_hits) -
                                          (prev[i].sector_misses + prev[i].line_misses + prev[i].mshr_hits);
                    rate[i] = acc ? double(miss) / double(acc) : 0.0;
                    mshr[i] = int(caches[i]->mshrs_in_use());
                    prev[i] = now;
                }
            };
            upd(impl->gpu.l1(), impl->l1_mshr, impl->l1_missrate, impl->l1_prev);
            upd(impl->gpu.l2(), impl->l2_mshr, impl->l2_missrate, impl->l2_prev);
            impl->dram_queue = int(impl->gpu.dram().queue_depth());
            const uint64_t busy = total(impl->gpu.dram().stats()).data_cycles;
            const double window_mem = double(cycle - impl->last_sample) * impl->core.period_fs() / double(impl->mem.period_fs());
            impl->dram_bw = double(busy - impl->dram_prev_busy) / (window_mem * impl->cfg.dram.channels);
            impl->dram_prev_busy = busy;
            // TTP's prefetches per RT unit in the window: sent, dropped (a recent pick of the
            // thread, a chunk already waiting, a full queue, a deadline passed) and late (a demand
            // read came while the prefetched sector was on its way, at the unit's L1).
            for (size_t u = 0; u < impl->rt_trace.size(); ++u) {
                Impl::RtTrace& tr = impl->rt_trace[u];
                const PrefetchQueueCounts& q = impl->gpu.rt_units()[u]->core().stats().prefetch_queue;
                const uint64_t dropped = q.window_dropped + q.duplicates_dropped + q.full_dropped + q.expired_unsent;
                const uint64_t late = impl->gpu.l1()[u]->tags().counts().prefetched.late;
                tr.sent = int(q.sent - tr.sent_before);
                tr.dropped = int(dropped - tr.dropped_before);
                tr.late = int(late - tr.late_before);
                tr.sent_before = q.sent;
                tr.dropped_before = dropped;
                tr.late_before = late;
            }
            impl->last_sample = cycle;
        };
    }
    // The monitor's period does not depend on tracing (see sample_windows).
    const uint64_t period = std::max<uint64_t>(1, std::min<uint64_t>(cfg.watchdog / 4, 100000));
    m.monitor.reset(new PlatformMonitor("monitor", m.driver, m.core, cfg.watchdog, opt.progress, period, opt.stop));
    if (opt.snapshot)
        m.monitor->snapshot = [this](uint64_t c) {
            Impl& i = *impl_;
            i.opt.snapshot(i.so_far(std::max(i.driver.last_progress(), c), true, false));
        };
    // --timeline: the chosen slot's threads after each cycle of its RT unit, and the prefetches
    // its TTP picks for them; reading changes nothing.
    if (opt.timeline) {
        RtUnit* unit = m.gpu.rt_units().at(opt.timeline_sm).get();
        m.timeline = std::make_unique<Timeline>(opt.timeline_sm, opt.timeline_slot, cfg.warp_size);
        Timeline* tl = m.timeline.get();
        unit->on_cycle = [unit, tl, traced = std::move(unit->on_cycle)](uint64_t cycle) {
            if (traced) traced(cycle);
            tl->sample(unit->core(), cycle);
        };
        unit->core().on_prefetch_generated = [unit, tl](const ChunkRequest& r) { tl->prefetch(r.warp, r.thread, r.addr, unit->current_cycle()); };
    }
    m.monitor->describe_stuck = [this]() {
        std::string s;
        for (const auto& u : impl_->gpu.rt_units()) {
            const RtUnitCore& c = u->core();
            if (c.warps_resident())
                s += std::string(u->name()) + ": " + std::to_string(c.warps_resident()) + " warps, " +
                     std::to_string(c.memory_access_queue_depth()) + " queued requests; ";
        }
        return s;
    };
}

namespace {

// SystemC ends a VCD with a bare "#TIME" line: the kernel's time at the end, which is the
// monitor's next wake-up (up to 100,000 cycles after the frame's last ray: a 32x32 cornell frame
// of 4 us ended at 73 us), so a viewer's zoom-to-fit showed the frame in its first 5 %. That line
// carries no value change; without it the trace ends at its last change, where the frame does.
void trim_vcd_end(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return;
    std::fseek(f, 0, SEEK_END);
    const long size = std::ftell(f);
    const long tail = std::min<long>(size, 64);
    std::string end(size_t(tail), '\0');
    std::fseek(f, size - tail, SEEK_SET);
    const size_t got = std::fread(end.data(), 1, end.size(), f);
    std::fclose(f);
    if (got != end.size()) return;
    size_t stop = end.find_last_not_of("\n");
    if (stop == std::string::npos) return;
    const size_t line = end.rfind('\n', stop);
    if (line == std::string::npos || end[line + 1] != '#') return;  // the last line is not a bare timestamp
    std::error_code ec;
    std::filesystem::resize_file(path, uint64_t(size - tail) + line + 1, ec);
}

}  // namespace

GpuPlatform::~GpuPlatform() {
    if (impl_->tf) {
        sc_close_vcd_trace_file(impl_->tf);
        trim_vcd_end(impl_->opt.vcd + ".vcd");
    }
}

TimingResult GpuPlatform::run() {
    Impl& m = *impl_;
    sc_start();
    m.monitor->progress.finish();
    // The frame ends when its last ray retires (the monitor may wake once more after that).
    TimingResult r = m.so_far(m.monitor->interrupted ? std::max(m.driver.last_progress(), m.monitor->stopped_at) : m.driver.last_progress(),
                              m.monitor->interrupted, true);
    if (m.timeline) r.timeline = m.timeline->json(r.cycles_simulated);
    r.stuck = m.monitor->stuck;
    r.stuck_report = m.monitor->report;
    if (!r.stuck && !r.interrupted && !m.driver.finished()) {
        r.stuck = true;
        r.stuck_report = "simulation ran out of events with rays outstanding; oldest trace: " + m.driver.oldest_in_flight();
    }
    for (const auto& c : m.gpu.checkers()) {
        r.protocol_transactions += c->transactions();
        r.protocol_violations.insert(r.protocol_violations.end(), c->violations().begin(), c->violations().end());
        if (!r.stuck && !r.interrupted && c->open()) r.protocol_violations.push_back(std::string(c->name()) + ": " + std::to_string(c->open()) + " transactions left open");
    }
    // Invariants (of a whole frame: an interrupted run has rays in flight).
    if (!r.stuck && !r.interrupted) {
        if (m.gpu.pool().outstanding() != 0) r.invariant_failures.push_back(std::to_string(m.gpu.pool().outstanding()) + " requests never got their response");
        if (m.driver.rays_retired() != m.driver.rays_issued()) r.invariant_failures.push_back("not every ray retired");
        for (const std::string& f : counter_invariants(r.counts, r.summary)) r.invariant_failures.push_back(f);
    }
    return r;
}

}  // namespace rtu
