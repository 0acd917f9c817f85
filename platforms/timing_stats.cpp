#include "timing_stats.h"

#include <algorithm>
#include <iostream>

#include "model/prefetcher.h"

namespace rtu {
namespace {

double ratio(double a, double b) { return b > 0 ? a / b : 0.0; }

// A cache's totals and derived figures, with the per-instance counters beside them.
void write_cache(StatsOut out, const std::vector<CacheCounts>& per, const char* per_name, const char* per_what,
                 uint64_t node_fetches) {
    const CacheCounts t = total(per);
    out.counters(t);
    auto miss_rate = [](const CacheAccessCounts& s) {
        const uint64_t misses = s.sector_misses + s.line_misses;
        return s.accesses ? double(misses + s.mshr_hits) / double(s.accesses - s.reservation_fails + (s.accesses == s.reservation_fails)) : 0.0;
    };
    out.child("demand").value("miss_rate", miss_rate(t.demand), "ratio",
                              "(sector and line misses + MSHR hits) / lookups that were not reservation fails");
    out.child("prefetch").value("miss_rate", miss_rate(t.prefetch), "ratio",
                                "(sector and line misses + MSHR hits) / lookups that were not reservation fails");
    out.child("shader").value("miss_rate", miss_rate(t.shader), "ratio",
                              "(sector and line misses + MSHR hits) / lookups that were not reservation fails");
    // RT-read misses per kilo node fetch: the paper's MPKI with node fetches for instructions.
    out.value("rt_misses_per_kilo_node_fetch",
              ratio(1000.0 * double(t.demand.sector_misses + t.demand.line_misses + t.demand.mshr_hits), double(node_fetches)),
              "misses / 1000 node reads", "demand misses (sector, line, MSHR hits) per 1000 node reads (the paper's MPKI)");
    out.instances(per_name, per, per_what);
}

}  // namespace

std::vector<std::string> counter_invariants(const HierarchyCounts& h, const WorkloadDriver::RaySummary& sum) {
    std::vector<std::string> fail;
    for (const std::vector<CacheCounts>* caches : {&h.l1, &h.l2})
        for (const CacheCounts& c : *caches)
            for (const CacheAccessCounts* s : {&c.demand, &c.prefetch})
                if (s->accesses != s->hits + s->mshr_hits + s->sector_misses + s->line_misses + s->reservation_fails) {
                    fail.push_back("cache counters do not add up");
                    return fail;
                }
    const RtUnitStats rt = total(h.rt);
    if (rt.prefetch_queue.sent != rt.prefetch_queue.answered)
        fail.push_back(std::to_string(rt.prefetch_queue.sent) + " prefetches sent but " + std::to_string(rt.prefetch_queue.answered) + " answered");
    if (rt.chunk_requests != rt.responses)
        fail.push_back("RT units sent " + std::to_string(rt.chunk_requests) + " requests but drained " + std::to_string(rt.responses) + " responses");
    if (rt.node_fetches != sum.nodes_visited)
        fail.push_back("RT units read " + std::to_string(rt.node_fetches) + " nodes but the rays visited " + std::to_string(sum.nodes_visited));
    return fail;
}

void write_hierarchy(StatsOut& out, const HwConfig& cfg, const HierarchyCounts& h, const WorkloadDriver::RaySummary& sum,
                     double energy_scale) {
    const RtUnitStats rt = total(h.rt);
    {
        StatsOut u = out.child("rt_unit", "the RT units (paper section 2.3), summed over the SMs");
        u.counters(rt);
        // Of the simulated rays' node fetches (a sampled run's frame estimate is under sampling).
        const double nodes = double(std::max<uint64_t>(1, sum.nodes_visited));
        u.value("node_fetch_l1_miss_share", double(sum.l1_miss_nodes) / nodes, "ratio", "share of node reads not served by L1");
        u.value("node_fetch_dram_share", double(sum.dram_nodes) / nodes, "ratio", "share of node reads served by DRAM");
        u.value("l1_misses_with_next_queued_share", ratio(double(rt.l1_misses_with_next_queued), double(sum.l1_miss_nodes)), "ratio",
                "l1_misses_with_next_queued / node reads not served by L1 (paper Figure 'bfs_trend' with BFS: 70.42 % mean)");
        const double threads = double(rt.thread_cycles.total());
        StatsOut s = u.child("thread_status", "shares of the thread slots' resident cycles (paper Figure 1)");
        for (const Counter<ThreadCycles>& c : ThreadCycles::kCounters)
            s.value(c.name, ratio(double(rt.thread_cycles.*c.member), threads), "ratio", c.what);
        u.instances("per_sm", h.rt, "the same counters per SM");
    }
    write_cache(out.child("l1", "the SMs' L1 data caches, summed"), h.l1, "per_sm", "the same counters per SM", rt.node_fetches);
    write_cache(out.child("l2", "the L2 slices, summed"), h.l2, "per_slice", "the same counters per L2 slice", rt.node_fetches);
    {
        // The paper's prefetch figures (section 6), ours: accuracy = prefetched sectors later read
        // by a demand / sectors prefetched; efficiency = prefetches that missed both the cache and
        // its MSHRs with an MSHR free / all prefetches. The authors' code (gpu-cache.cc l.833-838):
        // accuracy = (sectors prefetched - unused lines) / sectors prefetched, coverage = (sectors
        // prefetched - unused lines) / demand misses (line and sector) of the same run, where an
        // unused line is one evicted with the flags of PrefetchedSectorCounts::authors_unused_lines
        // (lines still in the cache at the end count as used).
        StatsOut p = out.child("prefetch", "the prefetcher's effect on the caches (paper section 6)");
        p.value("prefetcher", prefetcher_name(cfg.prefetch.kind), "", "none, ttp, park, treelet, perfect-up or perfect-down");
        for (const auto& [name, per] : {std::pair<const char*, const std::vector<CacheCounts>*>{"l1", &h.l1}, {"l2", &h.l2}}) {
            const CacheCounts c = total(*per);
            StatsOut lv = p.child(name, name[1] == '1' ? "at the L1s" : "at the L2 slices");
            lv.value("accuracy", ratio(double(c.prefetched.useful), double(c.prefetched.fills)), "ratio",
                     "prefetched sectors later read by a demand request / sectors brought in by prefetches");
            lv.value("efficiency", ratio(double(c.prefetch.sector_misses + c.prefetch.line_misses), double(c.prefetch.accesses)), "ratio",
                     "prefetch lookups that missed cache and MSHRs with an MSHR free / prefetch lookups");
            const double authors_useful = double(c.prefetched.fills) - double(std::min(c.prefetched.fills, c.prefetched.authors_unused_lines));
            lv.value("authors_accuracy", ratio(authors_useful, double(c.prefetched.fills)), "ratio",
                     "the TTP authors' code: (sectors prefetched - unused lines) / sectors prefetched");
            lv.value("authors_coverage", ratio(authors_useful, double(c.demand.sector_misses + c.demand.line_misses)), "ratio",
                     "the TTP authors' code: (sectors prefetched - unused lines) / demand line and sector misses of the same run");
        }
    }
    const DramStats dram = total(h.dram);
    {
        StatsOut d = out.child("dram", "the DRAM channels, summed");
        d.counters(dram);
        d.value("bandwidth_utilisation", ratio(double(dram.data_cycles), h.memory_cycles * cfg.dram.channels), "ratio",
                "data-bus cycles / (simulated memory cycles x channels)");
        d.value("average_queue_wait", ratio(double(dram.queue_wait), double(dram.reads + dram.writes)), "memory cycles",
                "queue_wait per request");
        d.instances("per_channel", h.dram, "the same counters per channel");
    }
    // Energy from per-event energies: every L1 and L2 access (demand, prefetch and the shader
    // code's, retries included), DRAM bursts and activations, and static power over the frame's time.
    {
        const EnergyTable& e = cfg.energy;
        const CacheCounts l1 = total(h.l1), l2 = total(h.l2);
        // Of the simulated part; a sampled run's frame energy is total_j x the work scale.
        const double seconds = double(h.cycles_simulated) * h.core_period_fs * 1e-15;
        const uint64_t l1_acc = l1.demand.accesses + l1.prefetch.accesses + l1.shader.accesses;
        const uint64_t l2_acc = l2.demand.accesses + l2.prefetch.accesses + l2.shader.accesses;
        const uint64_t activates = dram.row_misses + dram.row_conflicts;
        const double dyn_pj = double(l1_acc) * e.l1_access_pj + double(l2_acc) * e.l2_access_pj + double(dram.reads) * e.dram_read_pj +
                              double(dram.writes) * e.dram_write_pj + double(activates) * e.dram_activate_pj;
        const double static_j = e.static_w * seconds;
        const double total_j = dyn_pj * 1e-12 + static_j;
        StatsOut en = out.child("energy", "from the per-event energies of docs/energy.md (the energy.* keys)");
        en.value("l1_j", double(l1_acc) * e.l1_access_pj * 1e-12, "J", "L1 lookups");
        en.value("l2_j", double(l2_acc) * e.l2_access_pj * 1e-12, "J", "L2 lookups, crossbar included");
        en.value("dram_j",
                 (double(dram.reads) * e.dram_read_pj + double(dram.writes) * e.dram_write_pj + double(activates) * e.dram_activate_pj) * 1e-12,
                 "J", "DRAM bursts and activations");
        en.value("static_j", static_j, "J", "static power over the simulated time");
        en.value("total_j", total_j, "J", "of the simulated part");
        en.value("seconds", seconds, "s", "simulated time");
        en.value("average_power_w", seconds > 0 ? total_j / seconds : 0.0, "W", "total_j / seconds");
        en.value("frame_total_j_estimate", total_j * energy_scale, "J", "total_j scaled to the frame's work (sampled runs; else total_j)");
    }
}

void TimingProgress::update(uint64_t cycle, const WorkloadDriver& driver) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_print_).count() <= 2.0) return;
    last_print_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    const double f = driver.fraction_done();
    std::cerr << "\r  cycle " << cycle << ", rays retired " << driver.rays_retired() << " (" << int(100 * f)
              << " % of pixel warps done), " << uint64_t(double(driver.rays_retired()) / std::max(wall, 1e-9)) << " rays/s";
    if (f > 0.02) std::cerr << ", ETA " << int(wall * (1.0 - f) / f) << " s";
    std::cerr << "   " << std::flush;
    printed_ = true;
}

void TimingProgress::finish() {
    if (printed_) std::cerr << "\n";
    printed_ = false;
}

void write_sampling(StatsOut& out, const SampleEstimate& est, double rate, uint64_t cycles, uint64_t cycles_simulated, const SampleWidth* width) {
    // Cycles and their 95 % interval: SampleEstimate (docs/sampling.md).
    // The interval is never below the cycles already simulated: the frame holds the sample's
    // work and more, so a symmetric interval reaching below them only says the estimate is
    // uncertain upward. Fewer than 2 strata (--sample-unchecked) leave no variance: no interval.
    const double c = double(cycles), h = c * est.relative_half_width(double(cycles_simulated));
    const bool has_interval = est.design.has_interval;
    StatsOut s = out.child("sampling", "a sampled run's estimate of the frame (docs/sampling.md)");
    s.value("rate", rate, "ratio", "the share of the frame asked for (--sample)");
    s.value("rate_simulated", est.warps_total ? double(est.warps_simulated) / double(est.warps_total) : 0.0, "ratio",
            "the share of the frame's warps simulated (whole clusters, one per stratum)");
    s.value("warps_total", est.warps_total, "shader warps", "of the frame");
    s.value("warps_simulated", est.warps_simulated, "shader warps", "simulated");
    s.value("cluster_warps", est.design.cluster_warps, "shader warps", "warps per cluster: those that run together (with a limit of resident warps the SMs' resident warps, else the RT units' warp-buffer slots)");
    s.value("strata", est.design.strata, "strata", "drawn strata (clusters sorted by the pre-pass's work), one cluster simulated each");
    s.value("first_wave_clusters", est.design.first_wave_clusters, "clusters", "the frame's first wave, simulated whole on cold caches");
    s.value("empty_clusters", est.design.empty_clusters, "clusters", "clusters that read no BVH node: no RT work, not simulated");
    s.value("cycles_simulated", cycles_simulated, "cycles", "of the simulated sample");
    s.value("work_simulated_residence_cycles", est.work_simulated, "slot-cycles", "warp-buffer residence of the simulated traces");
    s.value("estimator", est.schedule ? "schedule (functional pre-pass)" : "stratified", "", "which estimator made `cycles`");
    s.value("work_estimate_residence_cycles", est.work_estimate, "slot-cycles", "the frame's residence, estimated");
    s.value("work_estimate_stratified_residence_cycles", est.work_estimate_stratified, "slot-cycles", "the stratified estimate alone (ratio to the pre-pass's critical-path nodes)");
    s.value("critical_path_node_fetches_frame", est.critical_nodes_total, "node reads", "sum over the frame's traces of their longest ray (pre-pass)");
    s.value("prepass_threads", est.prepass_threads, "threads", "the pre-pass's threads");
    {
        StatsOut f = s.child("residence_fit", "a trace's residence = a + b x its critical path, fitted on the simulated traces");
        f.value("a", est.fit_a, "slot-cycles", "intercept");
        f.value("b_per_node", est.fit_b, "slot-cycles / node read", "slope");
        f.value("traces", est.fit_traces, "traces", "fitted on");
    }
    {
        StatsOut m = s.child("schedule_model_cycles", "the schedule model (sampling/schedule_model.h) on the fitted durations");
        m.value("frame", est.model_frame, "cycles", "of the whole frame");
        m.value("sample", est.model_sample, "cycles", "of the simulated sample");
    }
    s.value("saturated_until_cycle", est.saturated_until, "cycles", "while at least as many shader warps as the GPU holds were unfinished");
    s.value("work_done_saturated", est.work_saturated, "slot-cycles", "residence done by then");
    s.value("cycles_ci95", has_interval ? nlohmann::ordered_json{std::max(c - h, double(cycles_simulated)), c + h} : nlohmann::ordered_json(),
            "cycles", "95 % interval of the frame's cycles [low, high], low at least cycles_simulated; null without one (--sample-unchecked: fewer than 10 strata, or segments of fewer than 16 clusters)");
    {
        StatsOut w = s.child("strata_work", "the simulated residence by stratum, as --check-error pairs two runs of one draw");
        w.value("first_wave_residence_cycles", est.strata_work.first_wave, "slot-cycles", "the first wave's (weight 1)");
        w.value("residence_cycles", nlohmann::ordered_json(est.strata_work.work), "slot-cycles",
                "per drawn stratum, in stratum order: its cluster's residence x the stratum's weight");
        w.value("weights", nlohmann::ordered_json(est.strata_work.weight), "clusters", "per drawn stratum: the clusters it stands for");
    }
    s.value("relative_se", est.relative_se, "ratio", "standard error of the work estimate / the estimate");
    s.value("variance_pairs", est.variance_pairs, "pairs", "collapsed stratum pairs behind relative_se");
    s.value("variance_degrees", est.variance_degrees, "degrees of freedom",
            "Student's t's for relative_se: Satterthwaite's over the pairs, (sum of their variances)^2 / sum of their squares");
    for (const auto& [name, share, what] :
         {std::tuple<const char*, const SampleEstimate::Share*, const char*>{"node_fetch_l1_miss_share", &est.l1_miss_nodes, "the frame's share of node reads not served by L1"},
          {"node_fetch_dram_share", &est.dram_nodes, "the frame's share of node reads served by DRAM"}}) {
        StatsOut sh = s.child(name, what);
        sh.value("estimate", share->estimate, "ratio", "stratified ratio estimate");
        sh.value("ci95", nlohmann::ordered_json{share->lo, share->hi}, "ratio", "its 95 % interval [low, high]");
    }
    s.value("schedule_model_misfit", est.model_misfit(double(cycles_simulated)), "ratio", "|simulated cycles / schedule model of the sample - 1|");
    s.value("schedule_model_misfit_per_sm", nlohmann::ordered_json(est.misfit_per_sm), "ratio",
            "per SM: the cycle its last simulated trace left / the same in the schedule model of the sample - 1");
    s.value("schedule_model_error", est.model_error(double(cycles_simulated)), "ratio",
            "the model's error as the interval takes it: root mean square of the per-SM misfits (the misfit where there are none)");
    {
        StatsOut f = s.child("first_reads", "the frame's first reads of BVH nodes (compulsory L2 misses, pre-pass) against what the draw holds of them (docs/sampling.md, \"First reads\")");
        f.value("frame_beyond_first_wave", est.first_reads_rest, "nodes", "first read outside the first wave");
        f.value("estimate", est.first_reads_estimate, "nodes", "the same as the drawn clusters hold them per critical-path node (as the work is estimated)");
        f.value("cost", est.first_read_cost, "slot-cycles / node", "a first read's residence beyond the fit");
        f.value("cost_from", est.first_read_cost_of_first_wave ? "first wave" : "drawn clusters", "",
                "the drawn clusters' slope on first reads, or where they hold none the first wave's residence beyond the fit per first read");
        f.value("gap", est.first_reads_gap(), "ratio", "cost x |frame - estimate| / the work estimate: its term in the interval");
    }
    s.value("design_bias", est.design_bias, "ratio",
            "the sample design's bias bound in the interval: the largest bias beyond the draws' noise on the project's grids, for this workload (platforms/configs/sampling_bias.json)");
    if (width) {
        StatsOut w = s.child("width", "--sample-width: the rate planned from a pilot sample (docs/sampling.md, \"A sample of a given width\")");
        w.value("asked", width->asked, "ratio", "the 95 % half-width asked, relative to the cycles");
        w.value("pilots", width->pilots, "runs", "pilot samples: 1, or 2 where the first's floor reached the width asked but its model term might fall with more strata");
        w.value("pilot_rate", width->pilot_rate, "ratio", "the (last) pilot sample's share of the frame");
        w.value("pilot_strata", width->pilot_strata, "strata", "the (last) pilot's drawn strata");
        w.value("pilot_half_width", width->pilot_half_width, "ratio", "the relative half-width the (last) pilot stated");
        w.value("pilot_s", width->pilot_s, "s", "the pilots' wall time (interval: in this process; at, lt: child runs, each loading the scene, the first tracing the frame for the plan this run reads)");
        w.value("floor", width->floor, "ratio", "the (last) pilot's half-width without its sampling term: what no larger rate is taken to narrow");
        w.value("predicted", width->predicted, "ratio", "the half-width predicted for this run's strata");
        const double delivered = est.relative_half_width(double(cycles_simulated));
        w.value("delivered", delivered, "ratio", "the half-width this run states (its 95 % interval's, relative)");
        w.value("reached", delivered <= width->asked, "", "whether the run's half-width is within the one asked");
    }
}

}  // namespace rtu
