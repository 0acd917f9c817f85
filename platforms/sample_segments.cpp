#include "sample_segments.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "model/stats.h"
#include "model/treelet.h"
#include "timing_stats.h"
#include "workloads/input_error.h"

namespace rtu {
namespace {

// Per instance a += b; the instances must match (the same configuration).
template <class G>
void add_each(std::vector<G>& a, const std::vector<G>& b, const char* what) {
    if (a.size() != b.size()) throw InputError(std::string("segments with different numbers of ") + what);
    for (size_t i = 0; i < a.size(); ++i) add(a[i], b[i]);
}

}  // namespace

void write_segment(StatsOut& out, const TimingResult& r, uint32_t index, uint32_t count, const std::vector<IdentityKey>& identity) {
    StatsOut o = out.child("segment", "one segment of a split sampled run (--segment): what --merge-segments reads (docs/sampling.md)");
    o.value("index", index, "", "this segment's number, 0..count-1");
    o.value("count", count, "segments", "--sample-segments");
    StatsOut id = o.child("identity", "the frame, sample and configuration: equal in every segment of one run");
    for (const IdentityKey& k : identity) id.value(k.name.c_str(), k.value, "", k.what.c_str());
    o.value("cycles_simulated", r.cycles_simulated, "core cycles", "this segment's simulated cycles (cycles above, too)");
    o.value("memory_cycles", r.counts.memory_cycles, "memory cycles", "of the simulated time (DRAM bandwidth utilisation)");
    o.value("core_period_fs", r.counts.core_period_fs, "fs", "the core clock's period (static energy)");
    o.value("l1_miss_nodes", r.summary.l1_miss_nodes, "node reads", "the simulated rays' node reads not served by L1");
    o.value("dram_nodes", r.summary.dram_nodes, "node reads", "the simulated rays' node reads served by DRAM");
    o.value("payloads_allocated", r.payloads_allocated, "payloads", "TLM payloads the pool made (AT, LT; 0: interval)");
    o.json()["warps"] = segment_warps_json(r.segment_records);
    o.note("warps", "", kSegmentWarpsNote);
    o.value("checksum", std::string(), "", "FNV-1a (64 bits, hex) of the file's compact JSON with this key empty and without time_s, simulation_rate, memory_mb and provenance: a file changed since it was written is refused by --merge-segments");
}

TimingResult merge_segments(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt,
                            std::vector<SegmentRun> segments, const std::vector<IdentityKey>& identity) {
    std::sort(segments.begin(), segments.end(), [](const SegmentRun& a, const SegmentRun& b) { return a.header.index < b.header.index; });
    std::vector<SegmentHeader> headers;
    for (const SegmentRun& s : segments) headers.push_back(s.header);
    check_segment_set(headers, opt.sample_segments, identity);
    // The design and the pre-pass again (deterministic), no warp simulated.
    const std::unique_ptr<Treelets> treelets = traversal_treelets(cfg, image, opt.order);
    TimingOptions o = opt;
    o.sample_segment = SamplingOptions::kNoSegment;
    FrameSample sample(sampling_options(cfg, image, o, treelets.get()), cfg.sms, shader_timing(cfg, workload));
    const WorkloadDriver driver(workload, cfg.sms, cfg.warp_size, shader_timing(cfg, workload), &sample);
    std::vector<std::vector<WarpRecord>> records;
    TimingResult r;
    r.counts = segments[0].counts;
    r.counts.cycles_simulated = 0;
    r.counts.memory_cycles = 0;
    for (size_t i = 0; i < segments.size(); ++i) {
        SegmentRun& s = segments[i];
        if (i > 0) {
            add_each(r.counts.rt, s.counts.rt, "RT units");
            add_each(r.counts.l1, s.counts.l1, "L1 caches");
            add_each(r.counts.l2, s.counts.l2, "L2 slices");
            add_each(r.counts.dram, s.counts.dram, "DRAM channels");
        }
        r.counts.cycles_simulated += s.cycles_simulated;
        r.counts.memory_cycles += s.counts.memory_cycles;
        r.cycles_simulated += s.cycles_simulated;
        r.payloads_allocated += s.payloads_allocated;
        r.summary.rays += s.summary.rays;
        r.summary.invalid += s.summary.invalid;
        r.summary.hits += s.summary.hits;
        r.summary.nodes_visited += s.summary.nodes_visited;
        r.summary.l1_miss_nodes += s.summary.l1_miss_nodes;
        r.summary.dram_nodes += s.summary.dram_nodes;
        r.summary.max_nodes = std::max(r.summary.max_nodes, s.summary.max_nodes);
        records.push_back(std::move(s.warps));
    }
    r.sampled = true;
    r.estimate = sample.merge(records);
    r.prepass_s = sample.select_seconds();
    r.cycles = uint64_t(std::llround(r.estimate.cycles_estimate(double(r.cycles_simulated))));
    for (const std::string& f : counter_invariants(r.counts, r.summary)) r.invariant_failures.push_back(f);
    return r;
}

}  // namespace rtu
