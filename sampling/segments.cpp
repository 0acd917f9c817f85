#include "segments.h"

#include <cmath>

#include "workloads/input_error.h"

namespace rtu {

uint64_t json_whole(const nlohmann::json& j, uint64_t max) {
    if (!j.is_number_unsigned()) throw InputError("expected a whole number, found " + j.dump().substr(0, 40));
    const uint64_t v = j.get<uint64_t>();
    if (v > max) throw InputError(std::to_string(v) + " is more than " + std::to_string(max));
    return v;
}

double json_real(const nlohmann::json& j) {
    if (!j.is_number()) throw InputError("expected a number, found " + j.dump().substr(0, 40));
    return j.get<double>();
}

const char* const kSegmentWarpsNote =
    "per simulated warp: [frame warp, node reads, of them L1 misses, of them DRAM reads, [each trace's residence in cycles], "
    "its SM, the cycle its last trace left]";

nlohmann::ordered_json segment_warps_json(const std::vector<WarpRecord>& warps) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const WarpRecord& w : warps) out.push_back({w.frame_warp, w.nodes, w.l1_miss_nodes, w.dram_nodes, w.residences, w.sm, w.last_done});
    return out;
}

std::vector<WarpRecord> segment_warps_from_json(const nlohmann::json& warps) {
    std::vector<WarpRecord> out;
    for (const nlohmann::json& w : warps) {
        WarpRecord rec;
        rec.frame_warp = json_whole(w.at(0));
        rec.nodes = json_real(w.at(1));
        rec.l1_miss_nodes = json_real(w.at(2));
        rec.dram_nodes = json_real(w.at(3));
        for (const nlohmann::json& r : w.at(4)) {
            const double d = json_real(r);
            if (!(d >= 0 && d <= 1e15 && d == std::floor(d)))
                throw InputError("shader warp " + std::to_string(rec.frame_warp) + ": a residence of " + r.dump() + " cycles (whole cycles expected)");
            rec.residences.push_back(d);
            rec.work += d;  // as SampleEstimator::on_trace_done sums them
        }
        // Its SM and when its last trace left (the per-SM misfit of the schedule model): absent
        // in the files of older versions, which then give none.
        if (w.size() >= 7) {
            rec.sm = uint32_t(json_whole(w.at(5), UINT32_MAX));
            const double at = json_real(w.at(6));
            if (!(at >= -1 && at <= 1e15 && at == std::floor(at)))
                throw InputError("shader warp " + std::to_string(rec.frame_warp) + ": its last trace left at cycle " + w.at(6).dump() +
                                 " (a whole cycle expected, or -1 for none)");
            rec.last_done = at;
        }
        out.push_back(std::move(rec));
    }
    return out;
}

void check_segment_set(const std::vector<SegmentHeader>& segments, uint32_t count, const std::vector<IdentityKey>& identity) {
    if (segments.size() != count)
        throw InputError("--merge-segments: " + std::to_string(segments.size()) + " files for " + std::to_string(count) +
                         " segments (--sample-segments): give each segment's statistics once");
    for (uint32_t i = 0; i < count; ++i) {
        const SegmentHeader& s = segments[i];
        if (s.count != count) throw InputError("--merge-segments: a file holds segment " + std::to_string(s.index) + " of " + std::to_string(s.count) + ", not of " + std::to_string(count));
        if (s.index != i) throw InputError("--merge-segments: segment " + std::to_string(i) + " is missing (or another one is given twice)");
        for (const IdentityKey& k : identity) {
            const auto it = s.identity.find(k.name);
            const std::string theirs = it == s.identity.end() || !it->is_string() ? std::string("nothing") : it->get<std::string>();
            if (theirs != k.value)
                throw InputError("--merge-segments: segment " + std::to_string(i) + " is of another run: its " + k.name + " is '" + theirs +
                                 "', this run's '" + k.value + "' (" + k.what + ")");
        }
    }
}

}  // namespace rtu
