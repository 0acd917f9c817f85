#include "sample_segments.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "model/stats.h"
#include "model/treelet.h"
#include "sampling/plan.h"
#include "timing_stats.h"
#include "workloads/input_error.h"

namespace rtu {
namespace {

// A counter group (model/stats.h) as JSON and back, field by field from its own list.
template <class G>
void group_from(const nlohmann::json& j, G& g) {
    if constexpr (HasCounters<G>::value)
        for (const Counter<G>& c : G::kCounters) g.*c.member = json_whole(j.at(c.name));
    if constexpr (HasParts<G>::value) G::parts([&](const char* name, auto member, const char*) { group_from(j.at(name), g.*member); });
}

template <class G>
std::vector<G> groups_from(const nlohmann::json& a) {
    std::vector<G> v(a.size());
    for (size_t i = 0; i < v.size(); ++i) group_from(a.at(i), v[i]);
    return v;
}

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

namespace {
// The checksum of `doc` with its segment.checksum emptied (the key keeps its place: ordered JSON
// dumps keys in the order written, and numbers print back as they were read, integers exactly and
// doubles by nlohmann's shortest round-trip form, so a reader's dump is the writer's) and without
// the keys that measure the host (wall time, speed, memory) or name the run (its provenance: the
// command line), which the merge does not read: the same segment run twice, or with another
// --stats or --sample-plan path, has the same checksum.
std::string segment_checksum(nlohmann::ordered_json doc) {
    doc["segment"]["checksum"] = "";
    for (const char* host : {"time_s", "simulation_rate", "memory_mb", "provenance"}) doc.erase(host);
    const std::string text = doc.dump();
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a(text.data(), text.size())));
    return hex;
}
}  // namespace

void seal_segment(nlohmann::ordered_json& stats) {
    if (!stats.contains("segment")) return;
    stats["segment"]["checksum"] = segment_checksum(stats);
}

SegmentRun read_segment(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file + ": cannot read (a segment's --stats file from rtsim --segment)");
    std::stringstream text;
    text << in.rdbuf();
    SegmentRun s;
    try {
        // Our own files nest 5 levels; a deeper one is not one of them (and must not exhaust the stack).
        const nlohmann::ordered_json doc = nlohmann::ordered_json::parse(text.str(), [](int depth, nlohmann::ordered_json::parse_event_t, nlohmann::ordered_json&) {
            if (depth > 16) throw InputError("nested deeper than 16 levels");
            return true;
        });
        // The checksum before any figure is believed.
        if (doc.is_object() && doc.contains("segment") && doc["segment"].is_object()) {
            const nlohmann::ordered_json& sum = doc["segment"].contains("checksum") ? doc["segment"]["checksum"] : nlohmann::ordered_json();
            if (!sum.is_string() || sum.get<std::string>().empty())
                throw InputError("a segment's statistics without a checksum (from an older rtsim?); run the segment again");
            if (sum.get<std::string>() != segment_checksum(doc))
                throw InputError("a damaged segment file (its checksum does not match its contents); run the segment again");
        }
        const nlohmann::json stats = doc;
        if (!stats.is_object() || !stats.contains("segment"))
            throw InputError("no \"segment\" section: not the statistics of one segment (rtsim --sample-segments K --segment I)");
        const nlohmann::json& j = stats.at("segment");
        s.header.index = uint32_t(json_whole(j.at("index"), 4095));
        s.header.count = uint32_t(json_whole(j.at("count"), 4096));
        s.header.identity = j.at("identity");
        s.cycles_simulated = json_whole(j.at("cycles_simulated"));
        s.payloads_allocated = json_whole(j.at("payloads_allocated"));
        s.summary.rays = json_whole(stats.at("rays"));
        s.summary.invalid = json_whole(stats.at("invalid_rays"));
        s.summary.hits = json_whole(stats.at("hits"));
        s.summary.nodes_visited = json_whole(stats.at("nodes_visited"));
        s.summary.max_nodes = uint32_t(json_whole(stats.at("max_nodes_per_ray"), UINT32_MAX));
        s.summary.l1_miss_nodes = json_whole(j.at("l1_miss_nodes"));
        s.summary.dram_nodes = json_whole(j.at("dram_nodes"));
        // The counters per instance, as the timing section lists them.
        const nlohmann::json& t = stats.at("timing");
        s.counts.rt = groups_from<RtUnitStats>(t.at("rt_unit").at("per_sm"));
        s.counts.l1 = groups_from<CacheCounts>(t.at("l1").at("per_sm"));
        s.counts.l2 = groups_from<CacheCounts>(t.at("l2").at("per_slice"));
        s.counts.dram = groups_from<DramStats>(t.at("dram").at("per_channel"));
        s.counts.memory_cycles = json_real(j.at("memory_cycles"));
        s.counts.core_period_fs = json_real(j.at("core_period_fs"));
        s.counts.cycles_simulated = s.cycles_simulated;
        s.warps = segment_warps_from_json(j.at("warps"));
    } catch (const InputError& e) {
        throw InputError(file + ": " + e.what());
    } catch (const nlohmann::json::exception& e) {
        throw InputError(file + ": not a segment's statistics: " + e.what());
    }
    return s;
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
    r.cycles = uint64_t(std::llround(r.estimate.cycles_estimate(double(r.cycles_simulated))));
    for (const std::string& f : counter_invariants(r.counts, r.summary)) r.invariant_failures.push_back(f);
    return r;
}

}  // namespace rtu
