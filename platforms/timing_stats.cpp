#include "timing_stats.h"

#include <algorithm>
#include <iostream>

namespace rtu {

namespace {

nlohmann::ordered_json cache_json(const CacheStats& s) {
    const uint64_t misses = s.sector_misses + s.line_misses;
    return {{"accesses", s.accesses},
            {"hits", s.hits},
            {"mshr_hits", s.mshr_hits},
            {"sector_misses", s.sector_misses},
            {"line_misses", s.line_misses},
            {"reservation_fails", s.reservation_fails},
            {"miss_rate", s.accesses ? double(misses + s.mshr_hits) / double(s.accesses - s.reservation_fails + (s.accesses == s.reservation_fails)) : 0.0},
            {"evictions", s.evictions},
            {"prefetch_fills", s.prefetch_fills},
            {"useful_prefetches", s.useful_prefetches},
            {"late_prefetches", s.late_prefetches},
            {"unused_prefetch_evictions", s.unused_evictions}};
}

// Prefetch figures of one cache level (paper section 6): accuracy = prefetched sectors later
// used by a demand read / sectors prefetched; efficiency = prefetches that missed both the
// cache and its MSHRs with an MSHR free / all prefetches; the full response breakdown.
nlohmann::ordered_json prefetch_json(const CacheStats& demand, const CacheStats& pf) {
    const uint64_t missed = pf.sector_misses + pf.line_misses;
    return {{"issued", pf.accesses},
            {"response", {{"hit", pf.hits}, {"mshr_hit", pf.mshr_hits}, {"mshr_miss_free_entry", missed},
                          {"reservation_fail", pf.reservation_fails}}},
            {"accuracy", pf.prefetch_fills ? double(demand.useful_prefetches) / double(pf.prefetch_fills) : 0.0},
            {"efficiency", pf.accesses ? double(missed) / double(pf.accesses) : 0.0},
            {"useful", demand.useful_prefetches},
            {"late", demand.late_prefetches},
            {"unused_evictions", pf.unused_evictions}};
}

}  // namespace

void add(CacheStats& a, const CacheStats& b) {
    a.accesses += b.accesses;
    a.hits += b.hits;
    a.mshr_hits += b.mshr_hits;
    a.sector_misses += b.sector_misses;
    a.line_misses += b.line_misses;
    a.reservation_fails += b.reservation_fails;
    a.fills += b.fills;
    a.evictions += b.evictions;
    a.prefetch_fills += b.prefetch_fills;
    a.useful_prefetches += b.useful_prefetches;
    a.late_prefetches += b.late_prefetches;
    a.unused_evictions += b.unused_evictions;
}

void add(RtUnitStats& a, const RtUnitStats& b) {
    a.warps += b.warps;
    a.rays += b.rays;
    a.node_fetches += b.node_fetches;
    a.chunk_requests += b.chunk_requests;
    a.coalesced += b.coalesced;
    a.responses += b.responses;
    for (size_t i = 0; i < a.thread_cycles.size(); ++i) a.thread_cycles[i] += b.thread_cycles[i];
    for (size_t i = 0; i < 5; ++i) {
        a.streak_fetches[i] += b.streak_fetches[i];
        a.streak_l1_misses[i] += b.streak_l1_misses[i];
        a.streak_dram_misses[i] += b.streak_dram_misses[i];
    }
    a.max_response_fifo = std::max(a.max_response_fifo, b.max_response_fifo);
    a.max_request_queue = std::max(a.max_request_queue, b.max_request_queue);
    a.prefetches_generated += b.prefetches_generated;
    a.prefetch_duplicates += b.prefetch_duplicates;
    a.prefetches_sent += b.prefetches_sent;
    a.prefetch_responses += b.prefetch_responses;
    a.perfect_hits += b.perfect_hits;
    a.prefetches_expired += b.prefetches_expired;
}

void hierarchy_json(nlohmann::ordered_json& j, const HwConfig& cfg, const HierarchyCounts& h,
                    const WorkloadDriver::RaySummary& sum, double energy_scale) {
    j["rt_unit"] = {{"warps", h.rt.warps}, {"rays", h.rt.rays}, {"node_fetches", h.rt.node_fetches},
                    {"chunk_requests", h.rt.chunk_requests}, {"coalesced_fetches", h.rt.coalesced},
                    {"max_response_fifo", h.rt.max_response_fifo}, {"max_request_queue", h.rt.max_request_queue}};
    {
        // Of the simulated rays' node fetches (a sampled run's frame estimate is under sampling).
        const double nodes = double(std::max<uint64_t>(1, sum.nodes_visited));
        j["rt_unit"]["node_fetch_l1_miss_share"] = double(sum.l1_miss_nodes) / nodes;
        j["rt_unit"]["node_fetch_dram_share"] = double(sum.dram_nodes) / nodes;
    }
    const double thread_total = double(h.rt.thread_cycles[0] + h.rt.thread_cycles[1] + h.rt.thread_cycles[2] + h.rt.thread_cycles[3]);
    auto frac = [&](ThreadStatus s) { return thread_total > 0 ? double(h.rt.thread_cycles[size_t(s)]) / thread_total : 0.0; };
    j["rt_unit"]["thread_status"] = {{"unit", "share of resident thread-cycles"},
                                     {"waiting_to_be_scheduled", frac(ThreadStatus::WaitSchedule)},
                                     {"waiting_on_memory", frac(ThreadStatus::WaitMemory)},
                                     {"in_math", frac(ThreadStatus::InMath)},
                                     {"done_waiting_for_warp", frac(ThreadStatus::Idle)}};
    nlohmann::ordered_json streak = nlohmann::ordered_json::array();
    const char* names[5] = {"not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"};
    for (int i = 0; i < 5; ++i)
        streak.push_back({{"class", names[i]}, {"node_fetches", h.rt.streak_fetches[i]}, {"l1_misses", h.rt.streak_l1_misses[i]},
                          {"dram_misses", h.rt.streak_dram_misses[i]}});
    j["pop_streak"] = streak;
    j["l1"] = {{"demand", cache_json(h.l1[0])}, {"prefetch", cache_json(h.l1[1])}};
    j["l2"] = {{"demand", cache_json(h.l2[0])}, {"prefetch", cache_json(h.l2[1])}};
    // RT-read misses per kilo node fetch: the paper's MPKI with node fetches for instructions.
    auto mpkf = [&](const CacheStats& d) {
        return h.rt.node_fetches ? 1000.0 * double(d.sector_misses + d.line_misses + d.mshr_hits) / double(h.rt.node_fetches) : 0.0;
    };
    j["l1"]["rt_misses_per_kilo_node_fetch"] = mpkf(h.l1[0]);
    j["l2"]["rt_misses_per_kilo_node_fetch"] = mpkf(h.l2[0]);
    j["prefetch"] = {{"prefetcher", prefetcher_name(cfg.prefetch.kind)},
                     {"generated", h.rt.prefetches_generated},
                     {"duplicates_dropped", h.rt.prefetch_duplicates},
                     {"sent", h.rt.prefetches_sent},
                     {"expired_unsent", h.rt.prefetches_expired},
                     {"perfect_hits", h.rt.perfect_hits},
                     {"l1", prefetch_json(h.l1[0], h.l1[1])},
                     {"l2", prefetch_json(h.l2[0], h.l2[1])}};
    j["dram"] = {{"reads", h.dram.reads}, {"writes", h.dram.writes}, {"bytes", h.dram.bytes}, {"row_hits", h.dram.row_hits},
                 {"row_misses", h.dram.row_misses}, {"row_conflicts", h.dram.row_conflicts},
                 {"bandwidth_utilisation", h.memory_cycles > 0 ? double(h.dram.data_cycles) / (h.memory_cycles * cfg.dram.channels) : 0.0},
                 {"avg_queue_wait_mem_cycles", h.dram.reads + h.dram.writes ? double(h.dram.queue_wait) / double(h.dram.reads + h.dram.writes) : 0.0}};
    // Energy from per-event energies: every L1 and L2 access (demand and prefetch, retries
    // included), DRAM bursts and activations, and static power over the frame's time.
    {
        const EnergyTable& e = cfg.energy;
        // Of the simulated part; a sampled run's frame energy is total_j x the work scale.
        const double seconds = double(h.cycles_simulated) * h.core_period_fs * 1e-15;
        const uint64_t l1_acc = h.l1[0].accesses + h.l1[1].accesses, l2_acc = h.l2[0].accesses + h.l2[1].accesses;
        const uint64_t activates = h.dram.row_misses + h.dram.row_conflicts;
        const double dyn_pj = double(l1_acc) * e.l1_access_pj + double(l2_acc) * e.l2_access_pj +
                              double(h.dram.reads) * e.dram_read_pj + double(h.dram.writes) * e.dram_write_pj +
                              double(activates) * e.dram_activate_pj;
        const double static_j = e.static_w * seconds;
        const double total_j = dyn_pj * 1e-12 + static_j;
        j["energy"] = {{"l1_j", double(l1_acc) * e.l1_access_pj * 1e-12},
                       {"l2_j", double(l2_acc) * e.l2_access_pj * 1e-12},
                       {"dram_j", (double(h.dram.reads) * e.dram_read_pj + double(h.dram.writes) * e.dram_write_pj + double(activates) * e.dram_activate_pj) * 1e-12},
                       {"static_j", static_j},
                       {"total_j", total_j},
                       {"seconds", seconds},
                       {"average_power_w", seconds > 0 ? total_j / seconds : 0.0},
                       {"frame_total_j_estimate", total_j * energy_scale}};
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

void sampling_json(nlohmann::ordered_json& j, const WorkloadDriver::Estimate& est, double rate, uint64_t cycles,
                   uint64_t cycles_simulated) {
    // Cycles and their 95 % interval: WorkloadDriver::Estimate (docs/sampling.md).
    const double c = double(cycles), h = c * est.relative_half_width(double(cycles_simulated));
    j["sampling"] = {{"rate", rate},
                     {"warps_total", est.warps_total},
                     {"warps_simulated", est.warps_simulated},
                     {"cycles_simulated", cycles_simulated},
                     {"work_simulated_residence_cycles", est.work_simulated},
                     {"estimator", est.schedule ? "schedule (functional pre-pass)" : "stratified"},
                     {"work_estimate_residence_cycles", est.work_estimate},
                     {"work_estimate_stratified_residence_cycles", est.work_estimate_stratified},
                     {"critical_path_node_fetches_frame", est.critical_nodes_total},
                     {"prepass_threads", est.prepass_threads},
                     {"residence_fit", {{"a", est.fit_a}, {"b_per_node", est.fit_b}, {"traces", est.fit_traces}}},
                     {"schedule_model_cycles", {{"frame", est.model_frame}, {"sample", est.model_sample}}},
                     {"cycles_estimate", cycles},
                     {"saturated_until_cycle", est.saturated_until},
                     {"work_done_saturated", est.work_saturated},
                     {"cycles_ci95", {c - h, c + h}},
                     {"relative_se", est.relative_se},
                     {"variance_pairs", est.variance_pairs},
                     {"node_fetch_l1_miss_share", {{"estimate", est.l1_miss_nodes.estimate}, {"ci95", {est.l1_miss_nodes.lo, est.l1_miss_nodes.hi}}}},
                     {"node_fetch_dram_share", {{"estimate", est.dram_nodes.estimate}, {"ci95", {est.dram_nodes.lo, est.dram_nodes.hi}}}},
                     {"schedule_model_misfit", est.model_misfit(double(cycles_simulated))}};
}

}  // namespace rtu
