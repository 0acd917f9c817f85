#include "plan.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "workloads/input_error.h"

namespace rtu {

namespace {
// Version 3 ends with a 64-bit FNV-1a checksum of every byte before it (a damaged plan is
// refused); version 2 added the first reads per warp (after the warps). Older plans are refused
// by name.
constexpr char kPlanMagic[8] = {'R', 'T', 'U', 'P', 'L', 'A', 'N', '3'};
constexpr char kPlanMagicV2[8] = {'R', 'T', 'U', 'P', 'L', 'A', 'N', '2'};
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

std::string plan_bytes(const std::string& identity, const PrepassResult& p) {
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
    put(out, fnv1a(out.data(), out.size()), 8);
    return out;
}

std::optional<PrepassResult> read_plan(const std::string& file, const std::string& identity) {
    std::ifstream in(file, std::ios::binary);
    if (!in) return std::nullopt;
    std::stringstream buf;
    buf << in.rdbuf();
    std::string data = buf.str();
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
    if (data.compare(0, sizeof kPlanMagicV2, kPlanMagicV2, sizeof kPlanMagicV2) == 0)
        throw InputError(file + ": a sample plan of an older rtsim (version 2, without a checksum); remove it, and the next run writes it again");
    if (data.compare(0, sizeof kPlanMagic, kPlanMagic, sizeof kPlanMagic) != 0)
        throw InputError(file + ": not a sample plan (rtsim --sample-plan writes them)");
    // The checksum first: a damaged plan is refused before any of its figures is believed.
    need(sizeof kPlanMagic + 8, "checksum");
    uint64_t sum = 0;
    std::memcpy(&sum, data.data() + data.size() - 8, 8);
    data.resize(data.size() - 8);
    if (sum != fnv1a(data.data(), data.size()))
        throw InputError(file + ": a damaged sample plan (its checksum does not match its bytes); remove it, and the next run writes it again");
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

}  // namespace rtu
