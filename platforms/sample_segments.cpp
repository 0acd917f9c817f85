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
#include "output.h"
#include "timing_stats.h"
#include "workloads/input_error.h"

namespace rtu {
namespace {

// A counter group (model/stats.h) as JSON and back, field by field from its own list.
// A whole number in [0, max] (nlohmann's get<uint64_t> of a negative or fractional number, or of
// one beyond the type, would wrap or be undefined); any other value is bad input.
uint64_t whole(const nlohmann::json& j, uint64_t max = UINT64_MAX) {
    if (!j.is_number_unsigned()) throw InputError("expected a whole number, found " + j.dump().substr(0, 40));
    const uint64_t v = j.get<uint64_t>();
    if (v > max) throw InputError(std::to_string(v) + " is more than " + std::to_string(max));
    return v;
}

double real(const nlohmann::json& j) {
    if (!j.is_number()) throw InputError("expected a number, found " + j.dump().substr(0, 40));
    return j.get<double>();
}

template <class G>
void group_from(const nlohmann::json& j, G& g) {
    if constexpr (HasCounters<G>::value)
        for (const Counter<G>& c : G::kCounters) g.*c.member = whole(j.at(c.name));
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
    // Per simulated warp: its index in the frame, its rays' node reads (and of them those that
    // missed L1 / went to DRAM), and each trace's residence in whole cycles, so that the file
    // reads back bit for bit. The rest (stratum, weight, critical paths) the merge draws again.
    nlohmann::ordered_json warps = nlohmann::ordered_json::array();
    for (const WarpRecord& w : r.segment_records)
        warps.push_back({w.frame_warp, w.nodes, w.l1_miss_nodes, w.dram_nodes, w.residences, w.sm, w.last_done});
    o.json()["warps"] = std::move(warps);
    o.note("warps", "",
           "per simulated warp: [frame warp, node reads, of them L1 misses, of them DRAM reads, [each trace's residence in cycles], "
           "its SM, the cycle its last trace left]");
}

namespace {
// Version 2 adds the first reads per warp (after the warps); a version-1 plan is refused by name.
constexpr char kPlanMagic[8] = {'R', 'T', 'U', 'P', 'L', 'A', 'N', '2'};
constexpr char kPlanMagicV1[8] = {'R', 'T', 'U', 'P', 'L', 'A', 'N', '1'};

void put(std::string& out, uint64_t v, size_t bytes) { out.append(reinterpret_cast<const char*>(&v), bytes); }
}  // namespace

uint64_t fnv1a(const void* data, size_t n, uint64_t h) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

std::string plan_file(const std::string& given, const std::string& identity) {
    if (given.empty()) return given;
    std::error_code ec;
    if (given.back() != '/' && !std::filesystem::is_directory(given, ec)) return given;
    char name[32];
    std::snprintf(name, sizeof name, "plan-%016llx.bin", static_cast<unsigned long long>(fnv1a(identity.data(), identity.size())));
    return (std::filesystem::path(given) / name).string();
}

void write_plan(const std::string& file, const std::string& identity, const PrepassResult& p) {
    std::string out(kPlanMagic, sizeof kPlanMagic);
    put(out, identity.size(), 8);
    out += identity;
    put(out, p.trace_nodes.size(), 8);
    put(out, p.threads, 4);
    // Each list of uint32 after its length, in `bytes` bytes.
    auto put_words = [&](const std::vector<uint32_t>& v, size_t bytes) {
        put(out, v.size(), bytes);
        out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(uint32_t));
    };
    for (const std::vector<uint32_t>& w : p.trace_nodes) put_words(w, 4);
    for (const std::vector<uint32_t>* f : {&p.first_reads_in_rounds, &p.first_reads_by_warp}) put_words(*f, 8);  // 0 or one per warp
    write_file_atomic(file, out);  // several segment tasks may write the same plan at once: whole files only
}

std::optional<PrepassResult> read_plan(const std::string& file, const std::string& identity) {
    std::ifstream in(file, std::ios::binary);
    if (!in) return std::nullopt;
    std::stringstream buf;
    buf << in.rdbuf();
    const std::string data = buf.str();
    size_t at = 0;
    auto need = [&](size_t n, const char* what) {
        if (data.size() - at < n) throw InputError(file + ": a sample plan cut short (in its " + what + ")");
    };
    auto get = [&](size_t bytes, const char* what) {
        need(bytes, what);
        uint64_t v = 0;
        std::memcpy(&v, data.data() + at, bytes);
        at += bytes;
        return v;
    };
    need(sizeof kPlanMagic, "header");
    if (data.compare(0, sizeof kPlanMagicV1, kPlanMagicV1, sizeof kPlanMagicV1) == 0)
        throw InputError(file + ": a sample plan of an older rtsim (version 1, without the first reads of nodes); remove it, and the next run writes it again");
    if (data.compare(0, sizeof kPlanMagic, kPlanMagic, sizeof kPlanMagic) != 0)
        throw InputError(file + ": not a sample plan (rtsim --sample-plan writes them)");
    at = sizeof kPlanMagic;
    const uint64_t id_size = get(8, "header");
    need(id_size, "identity");
    const std::string theirs = data.substr(at, id_size);
    at += id_size;
    if (theirs != identity)
        throw InputError(file + ": a sample plan of another frame or configuration: it has\n" + theirs + "this run has\n" + identity +
                         "(remove it, or give another --sample-plan file)");
    PrepassResult p;
    const uint64_t warps = get(8, "header");
    p.threads = unsigned(get(4, "header"));
    if (warps > (data.size() - at) / 4) throw InputError(file + ": a sample plan of " + std::to_string(warps) + " warps in " + std::to_string(data.size()) + " bytes");
    auto get_words = [&](std::vector<uint32_t>& v, uint64_t n, const char* what) {  // n uint32 into v
        need(n * sizeof(uint32_t), what);
        v.resize(n);
        if (n) std::memcpy(v.data(), data.data() + at, n * sizeof(uint32_t));  // an empty vector's data() may be null
        at += n * sizeof(uint32_t);
    };
    p.trace_nodes.resize(warps);
    for (std::vector<uint32_t>& w : p.trace_nodes) get_words(w, get(4, "warps"), "warps");
    for (std::vector<uint32_t>* f : {&p.first_reads_in_rounds, &p.first_reads_by_warp}) {
        const uint64_t firsts = get(8, "first reads");
        if (firsts != 0 && firsts != warps)
            throw InputError(file + ": a sample plan with first reads of " + std::to_string(firsts) + " warps for its " + std::to_string(warps));
        get_words(*f, firsts, "first reads");
    }
    if (at != data.size()) throw InputError(file + ": " + std::to_string(data.size() - at) + " bytes after the sample plan's first reads");
    p.critical_nodes_total = critical_nodes_total(p.trace_nodes);
    return p;
}

SegmentRun read_segment(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file + ": cannot read (a segment's --stats file from rtsim --segment)");
    std::stringstream text;
    text << in.rdbuf();
    SegmentRun s;
    try {
        // Our own files nest 5 levels; a deeper one is not one of them (and must not exhaust the stack).
        const nlohmann::json stats = nlohmann::json::parse(text.str(), [](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
            if (depth > 16) throw InputError("nested deeper than 16 levels");
            return true;
        });
        if (!stats.is_object() || !stats.contains("segment"))
            throw InputError("no \"segment\" section: not the statistics of one segment (rtsim --sample-segments K --segment I)");
        const nlohmann::json& j = stats.at("segment");
        s.index = uint32_t(whole(j.at("index"), 4095));
        s.count = uint32_t(whole(j.at("count"), 4096));
        s.identity = j.at("identity");
        s.cycles_simulated = whole(j.at("cycles_simulated"));
        s.payloads_allocated = whole(j.at("payloads_allocated"));
        s.summary.rays = whole(stats.at("rays"));
        s.summary.invalid = whole(stats.at("invalid_rays"));
        s.summary.hits = whole(stats.at("hits"));
        s.summary.nodes_visited = whole(stats.at("nodes_visited"));
        s.summary.max_nodes = uint32_t(whole(stats.at("max_nodes_per_ray"), UINT32_MAX));
        s.summary.l1_miss_nodes = whole(j.at("l1_miss_nodes"));
        s.summary.dram_nodes = whole(j.at("dram_nodes"));
        // The counters per instance, as the timing section lists them.
        const nlohmann::json& t = stats.at("timing");
        s.counts.rt = groups_from<RtUnitStats>(t.at("rt_unit").at("per_sm"));
        s.counts.l1 = groups_from<CacheCounts>(t.at("l1").at("per_sm"));
        s.counts.l2 = groups_from<CacheCounts>(t.at("l2").at("per_slice"));
        s.counts.dram = groups_from<DramStats>(t.at("dram").at("per_channel"));
        s.counts.memory_cycles = real(j.at("memory_cycles"));
        s.counts.core_period_fs = real(j.at("core_period_fs"));
        s.counts.cycles_simulated = s.cycles_simulated;
        for (const nlohmann::json& w : j.at("warps")) {
            WarpRecord rec;
            rec.frame_warp = whole(w.at(0));
            rec.nodes = real(w.at(1));
            rec.l1_miss_nodes = real(w.at(2));
            rec.dram_nodes = real(w.at(3));
            for (const nlohmann::json& r : w.at(4)) {
                const double d = real(r);
                if (!(d >= 0 && d <= 1e15 && d == std::floor(d)))
                    throw InputError("shader warp " + std::to_string(rec.frame_warp) + ": a residence of " + r.dump() + " cycles (whole cycles expected)");
                rec.residences.push_back(d);
                rec.work += d;  // as on_trace_done sums them
            }
            // Its SM and when its last trace left (the per-SM misfit of the schedule model): absent
            // in the files of older versions, which then give none.
            if (w.size() >= 7) {
                rec.sm = uint32_t(whole(w.at(5), UINT32_MAX));
                const double at = real(w.at(6));
                if (!(at >= -1 && at <= 1e15 && at == std::floor(at)))
                    throw InputError("shader warp " + std::to_string(rec.frame_warp) + ": its last trace left at cycle " + w.at(6).dump() +
                                     " (a whole cycle expected, or -1 for none)");
                rec.last_done = at;
            }
            s.warps.push_back(std::move(rec));
        }
    } catch (const InputError& e) {
        throw InputError(file + ": " + e.what());
    } catch (const nlohmann::json::exception& e) {
        throw InputError(file + ": not a segment's statistics: " + e.what());
    }
    return s;
}

TimingResult merge_segments(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt,
                            std::vector<SegmentRun> segments, const std::vector<IdentityKey>& identity) {
    const uint32_t count = opt.sample_segments;
    if (segments.size() != count)
        throw InputError("--merge-segments: " + std::to_string(segments.size()) + " files for " + std::to_string(count) +
                         " segments (--sample-segments): give each segment's statistics once");
    std::sort(segments.begin(), segments.end(), [](const SegmentRun& a, const SegmentRun& b) { return a.index < b.index; });
    for (uint32_t i = 0; i < count; ++i) {
        const SegmentRun& s = segments[i];
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
    // The design and the pre-pass again (deterministic), no warp simulated.
    const std::unique_ptr<Treelets> treelets = traversal_treelets(cfg, image, opt.order);
    TimingOptions o = opt;
    o.sample_segment = SamplingOptions::kNoSegment;
    WorkloadDriver driver(workload, cfg.sms, cfg.warp_size, cfg.shade_latency, cfg.resident_warps, sampling_options(cfg, image, o, treelets.get()));
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
    r.estimate = driver.merge(records);
    r.cycles = uint64_t(std::llround(r.estimate.cycles_estimate(double(r.cycles_simulated))));
    for (const std::string& f : counter_invariants(r.counts, r.summary)) r.invariant_failures.push_back(f);
    return r;
}

}  // namespace rtu
