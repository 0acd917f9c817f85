#include "config.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "config_presets.h"  // generated from platforms/configs/*.json
#include "replacement.h"

namespace rtu {
namespace {

enum class Type { Int, Real, Text, Bool };
struct Key {
    const char* name;
    const char* unit;
    Type type;
    double min, max;
    bool pow2;
    const char* what;
};

// Every configuration key. Ranges are what the hardware model can represent.
const Key kSchema[] = {
    {"gpu.sms", "SMs", Type::Int, 1, 1024, false, "streaming multiprocessors, one RT unit each"},
    {"gpu.core_clock_mhz", "MHz", Type::Real, 1, 1e5, false, "core, interconnect and L2 clock"},
    {"gpu.memory_clock_mhz", "MHz", Type::Real, 1, 1e5, false, "DRAM command clock"},
    {"rt.warp_size", "threads", Type::Int, 1, 32, true, "threads per warp"},
    {"rt.warp_buffer", "warps", Type::Int, 1, 64, false, "warps resident in an RT unit"},
    {"rt.l1_hit_latency", "core cycles", Type::Int, 0, 1000, false, "extra cycles the RT unit waits on an L1 hit"},
    {"rt.next_node_register", "", Type::Bool, 0, 0, false, "stock Vulkan-sim's next-node register: the first hit child is read from it, not popped (false: every node read is a pop, as in the TTP authors' simulator)"},
    {"rt.leaf_descriptor_read", "", Type::Bool, 0, 0, false, "a primitive leaf is read in two dependent steps, its 8 B descriptor (one 32 B chunk) then the 64 B leaf, as in the TTP authors' simulator (false: both chunks at once)"},
    {"rt.merge_in_flight", "", Type::Bool, 0, 0, false, "a thread's node read joins a read of the same 32 B chunk that its warp has queued or in flight, as in the TTP authors' simulator (false: only reads scheduled together merge)"},
    {"rt.warp_scheduler", "", Type::Text, 0, 0, false, "which warp with ready threads the RT unit schedules each cycle: round_robin, or oldest_first (the TTP authors' RT unit)"},
    {"rt.response_fifo", "entries", Type::Int, 0, 1 << 20, false, "response FIFO entries (0: unbounded, as in Vulkan-sim); a full FIFO holds the L1's responses back"},
    {"rt.latency.ray_box", "core cycles", Type::Int, 0, 1000, false, "ray-box tests of an internal node"},
    {"rt.latency.transform", "core cycles", Type::Int, 0, 1000, false, "instance transform"},
    {"rt.latency.leaf_descriptor", "core cycles", Type::Int, 0, 1000, false, "leaf descriptor"},
    {"rt.latency.ray_triangle", "core cycles", Type::Int, 0, 1000, false, "ray-triangle test"},
    {"rt.latency.triangle_hit", "core cycles", Type::Int, 0, 1000, false, "triangle hit update"},
    {"rt.latency.procedural", "core cycles", Type::Int, 0, 1000, false, "procedural (sphere) test"},
    {"rt.latency.structure", "core cycles", Type::Int, 0, 1000, false, "a BVH header's record: the TLAS's at a ray's start, a BLAS's after an instance leaf (Vulkan-sim's STRUCTURE)"},
    {"workload.resident_warps", "shader warps", Type::Int, 0, 1 << 20, false, "shader warps an SM holds at once (CTAs of one warp); a finished warp's place goes to the next warp of the frame (0: every warp at once)"},
    {"workload.shade_latency", "core cycles", Type::Int, 0, 1e7, false, "cycles of shader code a shader warp runs before each of its traces (ray generation before the first; hit, miss and ray generation code before the others)"},
    {"workload.intersection_latency", "core cycles", Type::Int, 0, 1e7, false, "cycles of shader code per iteration of a shader warp's intersection loop, run after each trace and before the next: one intersection shader call per procedural leaf a ray reached, as many iterations as the warp's ray that reached the most, the others masked off (0: not modelled; triangle scenes have none)"},
    {"workload.shader_contention", "per warp", Type::Real, 0, 10, false, "how much the shader code of one warp slows for each other warp of its SM in shader code when it begins (the SIMT core's issue slots and pipelines shared): workload.shade_latency and the intersection loop's cycles grow by this fraction per such warp, counted at the moment the warp enters its shader code (0: a warp's shader code takes the same time whatever its SM runs)"},
    {"workload.shader_reads", "sectors per ray", Type::Real, 0, 1e4, false, "32 B sectors of data no cache holds that the shader code reads after each trace, per ray of the trace: issued from the trace's end, one per cycle, through the SM's L1 (a port of their own), L2 and DRAM, waited for by nobody (0: none; given rays, rtsim --rays and the peripheral's jobs, run no shader code and read none)"},
    {"workload.shader_lines_per_read", "lines per read", Type::Real, 0, 1, false, "L1 lines the shader code's reads (workload.shader_reads) open, per read: a read opens a line of its own or takes the next sector of the line the last one opened (1: every read its own line; 0.25: four sectors a line, the fewest a 128 B line allows)"},
    {"workload.launch_latency", "core cycles", Type::Int, 0, 1e7, false, "cycles from the frame's kernel launch to its first shader warp's start"},
    {"l1.size_kb", "KiB", Type::Int, 1, 1 << 20, true, "L1 data cache per SM"},
    {"l1.assoc", "ways", Type::Int, 0, 1 << 16, false, "ways (0: fully associative)"},
    {"l1.line", "bytes", Type::Int, 16, 4096, true, "line bytes"},
    {"l1.sector", "bytes", Type::Int, 16, 4096, true, "sector bytes"},
    {"l1.mshrs", "MSHRs", Type::Int, 1, 1 << 16, false, "miss status holding registers"},
    {"l1.mshr_merge", "requests", Type::Int, 1, 1024, false, "requests merged into one MSHR"},
    {"l1.replacement", "", Type::Text, 0, 0, false, "which line a new line replaces: lru, fifo, or a policy registered in code (model/replacement.h)"},
    {"l1.miss_queue", "misses", Type::Int, 0, 1 << 16, false, "misses waiting to leave for the L2 (GPGPU-Sim's miss queue): while this many less one wait, a read that would miss, or join a miss (allocation at fill), is refused and retried (0: unbounded)"},
    {"l1.allocation", "", Type::Text, 0, 0, false, "when a missing line takes its way: miss (the way is held, its sectors pending, from the miss on; a set whose ways are all pending refuses misses) or fill (when the data arrives; GPGPU-Sim's streaming L1)"},
    {"l2.slices", "slices", Type::Int, 1, 256, false, "L2 slices"},
    {"l2.slice_kb", "KiB", Type::Int, 1, 1 << 22, false, "capacity of one slice"},
    {"l2.assoc", "ways", Type::Int, 0, 1 << 16, false, "ways (0: fully associative)"},
    {"l2.line", "bytes", Type::Int, 16, 4096, true, "line bytes"},
    {"l2.sector", "bytes", Type::Int, 16, 4096, true, "sector bytes"},
    {"l2.mshrs", "MSHRs", Type::Int, 1, 1 << 16, false, "MSHRs per slice"},
    {"l2.mshr_merge", "requests", Type::Int, 1, 1024, false, "requests merged into one MSHR"},
    {"l2.latency", "core cycles", Type::Int, 0, 100000, false, "L2 hit latency (core cycles)"},
    {"l2.replacement", "", Type::Text, 0, 0, false, "which line a new line replaces: lru, fifo, or a policy registered in code (model/replacement.h)"},
    {"l2.miss_queue", "misses", Type::Int, 0, 1 << 16, false, "misses waiting to leave for DRAM, per slice (as l1.miss_queue)"},
    {"l2.allocation", "", Type::Text, 0, 0, false, "when a missing line takes its way: miss or fill (as l1.allocation)"},
    {"l2.set_index", "", Type::Text, 0, 0, false, "how a slice picks a line's set from the slice's own address: linear, or ipoly (GPGPU-Sim's IPOLY hash; 16, 32 or 64 sets)"},
    {"xbar.latency", "core cycles", Type::Int, 0, 10000, false, "crossbar latency each way (core cycles)"},
    {"dram.channels", "channels", Type::Int, 1, 256, false, "channels"},
    {"dram.banks", "banks", Type::Int, 1, 1024, true, "banks per channel"},
    {"dram.bus_bytes", "bytes", Type::Int, 1, 64, true, "data bus width per channel (bytes)"},
    {"dram.burst", "beats", Type::Int, 1, 64, true, "burst length: a transfer moves whole bursts of bus_bytes x burst bytes"},
    {"dram.beats_per_cycle", "beats", Type::Int, 1, 16, true, "data beats per memory (command) clock cycle: 2 for double data rate (GPGPU-Sim's dram_data_command_freq_ratio)"},
    {"dram.address_map", "", Type::Text, 0, 0, false, "'line' (lines round robin over slices and channels; a channel's lines fill a row, then the next bank) or a GPGPU-Sim mapping 'dramid@<bit>;<64 letters of R B C S 0>' (model/address_map.h)"},
    {"dram.frontend_latency", "core cycles", Type::Int, 0, 1e6, false, "cycles a request waits between the L2 and the DRAM scheduler's queue (GPGPU-Sim's dram_latency queue)"},
    {"dram.queue", "requests", Type::Int, 1, 1 << 16, false, "scheduler queue entries per channel"},
    {"dram.row_bytes", "bytes", Type::Int, 128, 1 << 20, true, "row (page) size"},
    {"dram.scheduler", "", Type::Text, 0, 0, false, "frfcfs_banks (GPGPU-Sim's FR-FCFS: every bank serves a request of its own, a command a cycle), frfcfs_channel (one request at a time per channel, open row first) or fcfs (one at a time, oldest first), or a scheduler registered in code; model/dram_scheduler.h"},
    {"dram.tCL", "memory cycles", Type::Int, 1, 1000, false, "CAS latency (memory cycles)"},
    {"dram.tRCD", "memory cycles", Type::Int, 1, 1000, false, "ACT to column command"},
    {"dram.tRP", "memory cycles", Type::Int, 1, 1000, false, "precharge"},
    {"dram.tRAS", "memory cycles", Type::Int, 1, 1000, false, "ACT to precharge"},
    {"dram.tRC", "memory cycles", Type::Int, 1, 1000, false, "ACT to ACT, same bank"},
    {"dram.tRRD", "memory cycles", Type::Int, 0, 1000, false, "ACT to ACT, other bank"},
    {"dram.tCCD", "memory cycles", Type::Int, 1, 1000, false, "column to column"},
    {"dram.tWL", "memory cycles", Type::Int, 0, 1000, false, "write latency"},
    {"dram.tWR", "memory cycles", Type::Int, 0, 1000, false, "write recovery"},
    {"prefetch.kind", "", Type::Text, 0, 0, false, "none, ttp, park, treelet, perfect-up, perfect-down"},
    {"prefetch.treelet_budget", "bytes", Type::Int, 64, 1 << 24, false, "Treelet: bytes per treelet"},
    {"prefetch.treelet_threshold", "ratio", Type::Real, 0, 1, false, "Treelet, popularity heuristic: share of the RT unit's threads heading for the most popular treelet before it is prefetched"},
    {"prefetch.treelet_heuristic", "", Type::Text, 0, 0, false, "Treelet: always (prefetch the RT unit's most popular treelet whenever it changes; the Treelet code's 0) or popularity (only above treelet_threshold; its 1)"},
    {"prefetch.treelet_layout", "", Type::Text, 0, 0, false, "Treelet traversal: bvh (nodes where the BVH builder put them) or contiguous (each treelet in a block of its own, for the memory system)"},
    {"prefetch.treelet_stride", "bytes", Type::Int, 0, 1 << 20, false, "Treelet, contiguous layout: bytes between treelet blocks beyond the budget (the Treelet code's treelet_remap_stride)"},
    {"prefetch.treelet_queue_limit", "entries", Type::Int, 1, 1 << 30, false, "Treelet: a treelet is enqueued only if its nodes plus the chunks already in the RT unit's prefetch queue are at most this (the Treelet code's max_prefetch_queue_size, which mixes the two units)"},
    {"prefetch.treelet_vote_period", "cycles", Type::Int, 1, 1 << 20, false, "Treelet: cycles between two votes for the most popular treelet (the Treelet code's prefetch_delay)"},
    {"prefetch.treelet_order", "", Type::Text, 0, 0, false, "treelet traversal, when its treelet is finished: treelets (into the treelet of the newest deferred node; every treelet finished before the next, Chou et al.'s design) or root-then-dfs (the Treelet code as both papers ran it: only the root treelet is kept to, every later node is read in DFS order)"},
    {"prefetch.ttp_depth_s1", "entries", Type::Int, 0, 64, false, "TTP (DFS; BFS under the trend policy): entries prefetched on the first pop after a push"},
    {"prefetch.ttp_depth_s2", "entries", Type::Int, 0, 64, false, "TTP (DFS; BFS under trend): on the second consecutive pop"},
    {"prefetch.ttp_depth_s3", "entries", Type::Int, 0, 64, false, "TTP (DFS; BFS under trend): on the third and later consecutive pops"},
    {"prefetch.bfs_n", "entries", Type::Int, 0, 64, false, "TTP (BFS), fixed policy: queue entries prefetched per pop"},
    {"prefetch.bfs_policy", "", Type::Text, 0, 0, false, "TTP (BFS): fixed (bfs_n entries from the queue's head a pop, the paper's section 4) or trend (the DFS state machine's ttp_depth_s1..s3 from the head, as the TTP authors' code runs BFS)"},
    {"prefetch.queue", "chunks", Type::Int, 0, 1 << 20, false, "prefetch queue entries per RT unit (0: unbounded, as the TTP authors' RT unit); a chunk that finds it full is dropped"},
    {"prefetch.thread_window", "nodes", Type::Int, 0, 1024, false, "TTP: a node among the thread's last this many prefetches is not prefetched again (0: off; the TTP authors' RT unit: 16)"},
    {"prefetch.priority_after", "core cycles", Type::Int, 0, 1e6, false, "0: prefetch only in cycles without demand; X: prefetch first if none sent in X cycles"},
    {"energy.l1_access_pj", "pJ", Type::Real, 0, 1e6, false, "energy of one 32 B L1 access (pJ)"},
    {"energy.l2_access_pj", "pJ", Type::Real, 0, 1e6, false, "energy of one 32 B L2 access incl. crossbar (pJ)"},
    {"energy.dram_read_pj", "pJ", Type::Real, 0, 1e7, false, "energy of one 32 B DRAM read burst (pJ)"},
    {"energy.dram_write_pj", "pJ", Type::Real, 0, 1e7, false, "energy of one 32 B DRAM write burst (pJ)"},
    {"energy.dram_activate_pj", "pJ", Type::Real, 0, 1e7, false, "energy of one row activation and precharge (pJ)"},
    {"energy.static_w", "W", Type::Real, 0, 1e4, false, "static power of the modelled RT units and memory system (W)"},
    {"sim.quantum", "core cycles", Type::Int, 1, 1e9, false, "LT quantum (core cycles)"},
    {"sim.watchdog", "core cycles", Type::Int, 1000, 1e12, false, "cycles without progress before the run is stopped"},
    {"sim.trace_window", "core cycles", Type::Int, 1, 1e9, false, "--vcd: cycles per sample of the windowed waveforms (L1/L2 MSHR occupancy and miss rate, DRAM bandwidth)"},
};

// Keys that earlier versions had, with why they are gone (a configuration naming one is refused
// with this reason rather than as unknown).
const std::pair<const char*, const char*> kRemoved[] = {
    {"rt.latency.header", "an internal node costs rt.latency.ray_box (Vulkan-sim's INTERNAL, one latency per record); the BVH header's "
                          "latency (Vulkan-sim's STRUCTURE) is rt.latency.structure, charged on the header's own read"},
    {"l1.latency", "the L1's load/store hit latency (Table 2: 20 cycles) applies to the shader core's loads, "
                   "which are not modelled; the RT unit's L1 hit latency is rt.l1_hit_latency (0: Vulkan-sim's RT unit reads L1 directly)"},
    {"dram.bank_groups", "bank groups only matter through a longer column-to-column delay within a group (tCCDL); "
                         "the authors' GDDR timing has tCCDL = tCCD = 4 (configs/tested-cfgs/MOBILE/gpgpusim.config l.158-159), "
                         "so it is not modelled"},
};

std::string removed_reason(const std::string& name) {
    for (const auto& [key, why] : kRemoved)
        if (name == key) return why;
    return "";
}

const Key* find_key(const std::string& name) {
    for (const Key& k : kSchema)
        if (name == k.name) return &k;
    return nullptr;
}

std::string near_keys(const std::string& name) {
    const std::string group = name.substr(0, name.find('.'));
    std::string out;
    for (const Key& k : kSchema)
        if (std::string(k.name).rfind(group + ".", 0) == 0) out += (out.empty() ? "" : ", ") + std::string(k.name);
    return out.empty() ? "see platforms/configs/mobile.json" : out;
}

nlohmann::json checked_value(const Key& k, const nlohmann::json& v, const std::string& source) {
    const std::string where = source + ": key '" + k.name + "'";
    if (k.type == Type::Text) {
        if (!v.is_string()) throw ConfigError(where + " must be a string, got " + v.dump());
        return v;
    }
    if (k.type == Type::Bool) {
        if (!v.is_boolean()) throw ConfigError(where + " must be true or false, got " + v.dump());
        return v;
    }
    if (!v.is_number()) throw ConfigError(where + " must be a number, got " + v.dump());
    const double d = v.get<double>();
    if (k.type == Type::Int && (d != std::floor(d))) throw ConfigError(where + " must be a whole number, got " + v.dump());
    if (!(d >= k.min && d <= k.max))
        throw ConfigError(where + " = " + v.dump() + " is out of range [" + nlohmann::json(k.min).dump() + ", " +
                          nlohmann::json(k.max).dump() + "] (" + k.what + ")");
    if (k.pow2) {
        const uint64_t u = uint64_t(d);
        if (u == 0 || (u & (u - 1))) throw ConfigError(where + " = " + v.dump() + " must be a power of two (" + k.what + ")");
    }
    return k.type == Type::Int ? nlohmann::json(uint64_t(d)) : nlohmann::json(d);
}

}  // namespace

std::vector<Config::KeyInfo> Config::keys() {
    std::vector<KeyInfo> v;
    for (const Key& k : kSchema) v.push_back({k.name, k.unit, k.what});
    return v;
}

std::vector<std::string> Config::presets() {
    std::vector<std::string> v;
    for (const auto& p : kConfigPresets) v.push_back(p.first);
    return v;
}

void Config::apply(const nlohmann::json& j, const std::string& prefix, const std::string& source) {
    if (!j.is_object()) throw ConfigError(source + ": expected a JSON object at '" + prefix + "'");
    for (auto it = j.begin(); it != j.end(); ++it) {
        if (!it.key().empty() && it.key()[0] == '_') continue;  // comments
        const std::string name = prefix.empty() ? it.key() : prefix + "." + it.key();
        if (it.value().is_object()) {
            apply(it.value(), name, source);
            continue;
        }
        const Key* k = find_key(name);
        if (!k && !removed_reason(name).empty())
            throw ConfigError(source + ": key '" + name + "' was removed: " + removed_reason(name));
        if (!k) throw ConfigError(source + ": unknown key '" + name + "' (known: " + near_keys(name) + ")");
        values_[name] = checked_value(*k, it.value(), source);
    }
}

Config Config::load(const std::string& name) {
    Config c;
    const auto base = nlohmann::json::parse(kConfigPresets.at("mobile"));
    c.apply(base, "", "preset mobile");
    std::string text, source;
    auto preset = kConfigPresets.find(name);
    if (preset != kConfigPresets.end()) {
        text = preset->second;
        source = "preset " + name;
    } else {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(name, ec)) {
            std::string names;
            for (const auto& p : presets()) names += (names.empty() ? "" : ", ") + p;
            throw ConfigError("--config '" + name + "': not a preset (" + names + ") and no such file");
        }
        std::ifstream in(name);
        std::stringstream ss;
        ss << in.rdbuf();
        text = ss.str();
        source = name;
    }
    // Nesting is checked before parsing: applying (and the parse's own recursion) would
    // overflow the stack on a file of 100 k nested objects (issue 16: SIGSEGV). A configuration
    // nests two levels; 32 leaves room for comments' structures.
    {
        constexpr int kMaxDepth = 32;
        int depth = 0;
        bool in_string = false, escaped = false;
        for (const char ch : text) {
            if (in_string) {
                if (escaped) escaped = false;
                else if (ch == '\\') escaped = true;
                else if (ch == '"') in_string = false;
            } else if (ch == '"') {
                in_string = true;
            } else if (ch == '{' || ch == '[') {
                if (++depth > kMaxDepth)
                    throw ConfigError(source + ": nested deeper than " + std::to_string(kMaxDepth) + " levels (a configuration nests two)");
            } else if (ch == '}' || ch == ']') {
                --depth;
            }
        }
    }
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {  // parse errors, and numbers out of range (1e400)
        throw ConfigError(source + ": not valid JSON: " + e.what());
    }
    c.apply(j, "", source);
    c.resolve();  // cross-key rules
    return c;
}

void Config::set(const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos) throw ConfigError("--set '" + assignment + "': expected key=value");
    const std::string name = assignment.substr(0, eq), text = assignment.substr(eq + 1);
    const Key* k = find_key(name);
    if (!k && !removed_reason(name).empty()) throw ConfigError("--set: key '" + name + "' was removed: " + removed_reason(name));
    if (!k) throw ConfigError("--set: unknown key '" + name + "' (known: " + near_keys(name) + ")");
    nlohmann::json v;
    if (k->type == Type::Text) {
        v = text;
    } else if (k->type == Type::Bool) {
        if (text == "true" || text == "1") v = true;
        else if (text == "false" || text == "0") v = false;
        else throw ConfigError("--set: key '" + name + "' needs true or false, got '" + text + "'");
    } else {
        try {
            size_t used = 0;
            const double d = std::stod(text, &used);
            if (used != text.size()) throw std::invalid_argument("trailing");
            v = d;
        } catch (const std::exception&) {
            throw ConfigError("--set: key '" + name + "' needs a number, got '" + text + "'");
        }
        // stod reads "nan" and "inf", which JSON cannot hold (they would print as null): said here
        // with the text as given.
        if (!std::isfinite(v.get<double>()))
            throw ConfigError("--set: key '" + name + "' needs a finite number, got '" + text + "'");
    }
    values_[name] = checked_value(*k, v, "--set");
}

HwConfig Config::resolve() const {
    auto num = [&](const char* key) { return values_.at(key).get<double>(); };
    auto u32 = [&](const char* key) { return uint32_t(values_.at(key).get<uint64_t>()); };
    HwConfig h;
    h.sms = u32("gpu.sms");
    h.core_mhz = num("gpu.core_clock_mhz");
    h.memory_mhz = num("gpu.memory_clock_mhz");
    h.warp_size = u32("rt.warp_size");
    h.warp_buffer = u32("rt.warp_buffer");
    h.l1_hit_latency = u32("rt.l1_hit_latency");
    h.response_fifo = u32("rt.response_fifo");
    const std::string order = values_.at("rt.warp_scheduler").get<std::string>();
    if (order != "round_robin" && order != "oldest_first")
        throw ConfigError("key 'rt.warp_scheduler' = '" + order + "': allowed are round_robin, oldest_first");
    h.warp_order = order == "oldest_first" ? WarpOrder::OldestFirst : WarpOrder::RoundRobin;
    h.next_node_register = values_.at("rt.next_node_register").get<bool>();
    h.leaf_descriptor_read = values_.at("rt.leaf_descriptor_read").get<bool>();
    h.merge_in_flight = values_.at("rt.merge_in_flight").get<bool>();
    h.lat = {u32("rt.latency.ray_box"), u32("rt.latency.transform"),
             u32("rt.latency.leaf_descriptor"), u32("rt.latency.ray_triangle"), u32("rt.latency.triangle_hit"),
             u32("rt.latency.procedural"), u32("rt.latency.structure")};
    h.shade_latency = u32("workload.shade_latency");
    h.intersection_latency = u32("workload.intersection_latency");
    h.launch_latency = u32("workload.launch_latency");
    h.shader_contention = num("workload.shader_contention");
    h.shader_reads = num("workload.shader_reads");
    h.shader_lines_per_read = num("workload.shader_lines_per_read");
    h.resident_warps = u32("workload.resident_warps");
    // `latency`: what a hit costs the cache's requester (the RT unit at an L1).
    auto cache = [&](const std::string& p, uint64_t kb, uint32_t latency) {
        CacheConfig c;
        c.size_bytes = kb * 1024;
        c.assoc = u32((p + ".assoc").c_str());
        c.line = u32((p + ".line").c_str());
        c.sector = u32((p + ".sector").c_str());
        c.mshrs = u32((p + ".mshrs").c_str());
        c.mshr_merge = u32((p + ".mshr_merge").c_str());
        c.miss_queue = u32((p + ".miss_queue").c_str());
        if (c.miss_queue == 1)
            throw ConfigError("key '" + p + ".miss_queue' = 1 refuses every miss (a miss is refused while the queue holds this many less one); allowed are 0 (unbounded) or 2 and more");
        c.latency = latency;
        c.replacement = values_.at(p + ".replacement").get<std::string>();
        try {
            replacement_kind(c.replacement);
        } catch (const std::invalid_argument& e) {
            throw ConfigError("key '" + p + ".replacement': " + e.what());
        }
        const std::string allocation = values_.at(p + ".allocation").get<std::string>();
        if (allocation != "miss" && allocation != "fill")
            throw ConfigError("key '" + p + ".allocation' = '" + allocation + "': allowed are miss, fill");
        c.allocate_on_fill = allocation == "fill";
        if (c.sector > c.line) throw ConfigError("key '" + p + ".sector' (" + std::to_string(c.sector) + ") must not exceed '" + p + ".line' (" + std::to_string(c.line) + ")");
        const uint64_t lines = c.size_bytes / c.line;
        if (lines == 0 || c.size_bytes % c.line) throw ConfigError("key '" + p + ".size' must be a multiple of '" + p + ".line'");
        if (c.assoc && (lines % c.assoc || c.assoc > lines))
            throw ConfigError("key '" + p + ".assoc' (" + std::to_string(c.assoc) + ") must divide the " + std::to_string(lines) + " lines");
        if (c.assoc && ((lines / c.assoc) & (lines / c.assoc - 1)))
            throw ConfigError("key '" + p + ".assoc': the number of sets (" + std::to_string(lines / c.assoc) + ") must be a power of two");
        if (c.mshr_merge > c.mshrs)
            throw ConfigError("key '" + p + ".mshr_merge' (" + std::to_string(c.mshr_merge) + ") exceeds '" + p + ".mshrs' (" + std::to_string(c.mshrs) + ")");
        return c;
    };
    h.l1 = cache("l1", values_.at("l1.size_kb").get<uint64_t>(), h.l1_hit_latency);
    h.l2_slices = u32("l2.slices");
    h.l2 = cache("l2", values_.at("l2.slice_kb").get<uint64_t>(), u32("l2.latency"));
    if (h.l1.line != h.l2.line || h.l1.sector != h.l2.sector)
        throw ConfigError("keys 'l1.line'/'l1.sector' must equal 'l2.line'/'l2.sector'");
    h.xbar_latency = u32("xbar.latency");
    DramConfig& d = h.dram;
    d.channels = u32("dram.channels");
    d.banks = u32("dram.banks");
    d.bus_bytes = u32("dram.bus_bytes");
    d.burst = u32("dram.burst");
    d.beats_per_cycle = u32("dram.beats_per_cycle");
    d.queue = u32("dram.queue");
    d.frontend_latency = u32("dram.frontend_latency");
    d.row_bytes = u32("dram.row_bytes");
    const std::string sched = values_.at("dram.scheduler").get<std::string>();
    if (sched == "frfcfs")  // its meaning until 2026-11-27; a silent change would mislabel results
        throw ConfigError("key 'dram.scheduler' = 'frfcfs': since 2026-11-27 say which: frfcfs_banks (GPGPU-Sim's, every bank serving its "
                          "own request; the presets') or frfcfs_channel (one request at a time per channel, what 'frfcfs' was)");
    try {
        d.set_scheduler(sched);
    } catch (const std::invalid_argument& e) {
        throw ConfigError(std::string("key 'dram.scheduler': ") + e.what());
    }
    d.tCL = u32("dram.tCL");
    d.tRCD = u32("dram.tRCD");
    d.tRP = u32("dram.tRP");
    d.tRAS = u32("dram.tRAS");
    d.tRC = u32("dram.tRC");
    d.tRRD = u32("dram.tRRD");
    d.tCCD = u32("dram.tCCD");
    d.tWL = u32("dram.tWL");
    d.tWR = u32("dram.tWR");
    if (d.row_bytes < h.l2.line) throw ConfigError("key 'dram.row_bytes' must be at least one cache line");
    d.address_map = values_.at("dram.address_map").get<std::string>();
    try {
        h.l2.local = h.address_map().slice_local();
    } catch (const std::invalid_argument& e) {
        throw ConfigError(std::string("key ") + e.what());
    }
    const std::string set_index = values_.at("l2.set_index").get<std::string>();
    if (set_index != "linear" && set_index != "ipoly") throw ConfigError("key 'l2.set_index' = '" + set_index + "': allowed are linear, ipoly");
    h.l2.ipoly = set_index == "ipoly";
    const uint64_t l2_sets = h.l2.size_bytes / h.l2.line / (h.l2.assoc ? h.l2.assoc : h.l2.size_bytes / h.l2.line);
    if (h.l2.ipoly && l2_sets != 16 && l2_sets != 32 && l2_sets != 64)
        throw ConfigError("key 'l2.set_index' = 'ipoly' needs 16, 32 or 64 sets per slice; the L2 slice has " + std::to_string(l2_sets));
    if (d.tRC < d.tRAS) throw ConfigError("key 'dram.tRC' (" + std::to_string(d.tRC) + ") must be at least 'dram.tRAS' (" + std::to_string(d.tRAS) + ")");
    try {
        h.prefetch.kind = parse_prefetcher(values_.at("prefetch.kind").get<std::string>());
    } catch (const std::invalid_argument& e) {
        throw ConfigError(std::string("key 'prefetch.kind': ") + e.what());
    }
    h.prefetch.depth = {u32("prefetch.ttp_depth_s1"), u32("prefetch.ttp_depth_s2"), u32("prefetch.ttp_depth_s3")};
    h.prefetch.bfs_n = u32("prefetch.bfs_n");
    const std::string bfs_policy = values_.at("prefetch.bfs_policy").get<std::string>();
    if (bfs_policy != "fixed" && bfs_policy != "trend")
        throw ConfigError("key 'prefetch.bfs_policy' = '" + bfs_policy + "': allowed are fixed, trend");
    h.prefetch.bfs_policy = bfs_policy == "fixed" ? BfsPolicy::Fixed : BfsPolicy::Trend;
    h.prefetch.priority_after = u32("prefetch.priority_after");
    h.prefetch.queue = u32("prefetch.queue");
    h.prefetch.thread_window = u32("prefetch.thread_window");
    h.prefetch.treelet_budget = u32("prefetch.treelet_budget");
    h.prefetch.treelet_threshold = num("prefetch.treelet_threshold");
    const std::string heuristic = values_.at("prefetch.treelet_heuristic").get<std::string>();
    if (heuristic != "always" && heuristic != "popularity")
        throw ConfigError("key 'prefetch.treelet_heuristic' = '" + heuristic + "': allowed are always, popularity");
    h.prefetch.treelet_heuristic = heuristic == "always" ? TreeletHeuristic::Always : TreeletHeuristic::Popularity;
    const std::string layout = values_.at("prefetch.treelet_layout").get<std::string>();
    if (layout != "bvh" && layout != "contiguous") throw ConfigError("key 'prefetch.treelet_layout' = '" + layout + "': allowed are bvh, contiguous");
    h.prefetch.treelet_contiguous = layout == "contiguous";
    h.prefetch.treelet_stride = u32("prefetch.treelet_stride");
    h.prefetch.treelet_queue_limit = u32("prefetch.treelet_queue_limit");
    h.prefetch.treelet_vote_period = u32("prefetch.treelet_vote_period");
    const std::string treelet_order = values_.at("prefetch.treelet_order").get<std::string>();
    if (treelet_order != "treelets" && treelet_order != "root-then-dfs")
        throw ConfigError("key 'prefetch.treelet_order' = '" + treelet_order + "': allowed are treelets, root-then-dfs");
    h.prefetch.treelet_order = treelet_order == "treelets" ? TreeletOrder::Treelets : TreeletOrder::RootThenDfs;
    h.energy = {num("energy.l1_access_pj"), num("energy.l2_access_pj"), num("energy.dram_read_pj"),
                num("energy.dram_write_pj"), num("energy.dram_activate_pj"), num("energy.static_w")};
    h.quantum = values_.at("sim.quantum").get<uint64_t>();
    h.watchdog = values_.at("sim.watchdog").get<uint64_t>();
    h.trace_window = values_.at("sim.trace_window").get<uint64_t>();
    return h;
}

nlohmann::ordered_json Config::to_json() const {
    nlohmann::ordered_json j;
    for (const Key& k : kSchema) {
        nlohmann::ordered_json* node = &j;
        std::string name = k.name;
        size_t pos;
        while ((pos = name.find('.')) != std::string::npos) {
            node = &(*node)[name.substr(0, pos)];
            name = name.substr(pos + 1);
        }
        (*node)[name] = values_.at(k.name);
    }
    return j;
}

}  // namespace rtu
