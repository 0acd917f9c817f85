#include "segment_file.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "model/stats.h"
#include "sampling/plan.h"
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

}  // namespace rtu
