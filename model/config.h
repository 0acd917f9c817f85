// Hardware configuration of the timing model: JSON presets (platforms/configs/*.json), a file,
// and single-key overrides (`--set key=value`). Every key is declared once in a schema with its
// type and allowed range; unknown keys, wrong types and impossible values are rejected with a
// message naming the key. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "address_map.h"
#include "dram_scheduler.h"
#include "prefetch_config.h"
#include "shader_loads.h"

namespace rtu {

struct ConfigError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct CacheConfig {
    uint64_t size_bytes;
    uint32_t assoc;  // 0 = fully associative
    uint32_t line, sector, mshrs, mshr_merge;
    uint32_t latency;  // a hit's latency to the requester (L1: rt.l1_hit_latency)
    SliceLocal local{};  // an L2 slice: its sets are indexed with the slice's own address
    bool ipoly = false;  // sets by GPGPU-Sim's IPOLY hash (l2.set_index) instead of linearly
    std::string replacement = "lru";  // the replacement policy's name (model/replacement.h)
    // A missing line takes its way when its data arrives (GPGPU-Sim's ON_FILL, which its streaming
    // L1 uses), not at the miss (ON_MISS): no way is held while a fetch is on its way.
    bool allocate_on_fill = false;
    // Misses waiting to leave for the level below (GPGPU-Sim's miss queue); a read that would send
    // a miss or join one is refused (a reservation fail) while `miss_queue` - 1 or more wait, as
    // GPGPU-Sim's miss_queue_full(1) refuses it (gpu-cache.cc l.1652). 0: unbounded.
    uint32_t miss_queue = 0;
};

struct DramConfig {
    uint32_t channels, banks, bus_bytes, burst, beats_per_cycle, queue, row_bytes;
    uint32_t frontend_latency;  // core cycles between the L2 and the scheduler's queue
    std::string address_map;    // "line" or a GPGPU-Sim mapping (model/address_map.h)
    // dram.scheduler (model/dram_scheduler.h): its name and the policy, shared by every channel.
    std::string scheduler_name = "frfcfs_banks";
    std::shared_ptr<const DramSchedulerPolicy> scheduler = dram_scheduler_kind("frfcfs_banks").make();
    bool per_bank() const { return scheduler->per_bank(); }
    // Takes the scheduler registered as `name` (std::invalid_argument for an unknown one).
    void set_scheduler(const std::string& name) {
        scheduler = dram_scheduler_kind(name).make();
        scheduler_name = name;
    }
    uint32_t tCL, tRCD, tRP, tRAS, tRC, tRRD, tCCD, tWL, tWR;  // memory clock cycles
};

// The RT unit's warp scheduling (rt.warp_scheduler; model/warp_scheduler.h).
enum class WarpOrder { RoundRobin, OldestFirst };

struct RtLatency {
    uint32_t ray_box, transform, leaf_descriptor, ray_triangle, triangle_hit, procedural;
    uint32_t structure;  // a BVH header's record (the image's at a ray's start, a BLAS's after its instance leaf)
};

// Per-event energies (see docs/energy.md for the figures and where they come from).
struct EnergyTable {
    double l1_access_pj, l2_access_pj, dram_read_pj, dram_write_pj, dram_activate_pj, static_w;
};

// The typed view of a validated configuration.
struct HwConfig {
    uint32_t sms;
    double core_mhz, memory_mhz;
    uint32_t warp_size, warp_buffer, l1_hit_latency, response_fifo;
    WarpOrder warp_order;       // which warp the RT unit's scheduler picks
    bool next_node_register;    // stock Vulkan-sim's register for the first hit child (default: every read a pop)
    bool leaf_descriptor_read;  // a primitive leaf read in two dependent steps (model/node_fetch.h)
    bool merge_in_flight;       // a read joins its warp's queued or in-flight read of the same chunk
    RtLatency lat;
    uint32_t shade_latency;
    uint32_t intersection_latency = 0;  // per iteration of a warp's intersection loop after a trace
    uint32_t launch_latency;
    double shader_contention = 0;  // the shader code's growth per other warp of the SM in shader code
    double shader_reads;      // sectors per ray the shader code reads after a trace (workload.shader_reads)
    double shader_lines_per_read;  // L1 lines those reads open per read (workload.shader_lines_per_read)
    uint32_t resident_warps;  // shader warps per SM at once (0: all)
    CacheConfig l1;
    uint32_t l2_slices;
    CacheConfig l2;  // per slice
    uint32_t xbar_latency;
    DramConfig dram;
    uint64_t quantum, watchdog, trace_window;  // core cycles
    PrefetchConfig prefetch;
    EnergyTable energy;
    // Where addresses live (L2 slice, DRAM channel, bank, row); checked by Config::resolve.
    AddressMap address_map() const { return AddressMap(dram.address_map, dram.channels, dram.banks, dram.row_bytes, l2_slices, l2.line); }
    // The shader code's reads of a frame that runs it (none for given rays, which run no shader code).
    ShaderReads shader_reads_of(bool runs_shaders) const { return {runs_shaders ? shader_reads : 0.0, shader_lines_per_read, l1.line}; }
};

class Config {
public:
    // A preset name (mobile, desktop, paper) or a JSON file path. Throws ConfigError.
    static Config load(const std::string& name_or_file);
    static std::vector<std::string> presets();
    // Every key: its name, unit and description.
    struct KeyInfo {
        std::string name;
        const char* unit;
        const char* what;
    };
    static std::vector<KeyInfo> keys();

    // key=value, e.g. "l1.size_kb=64"; the value is parsed as the key's type. Throws ConfigError.
    void set(const std::string& assignment);

    // Checks cross-key rules (sizes, powers of two, merges) and returns the typed view.
    HwConfig resolve() const;

    // The effective configuration as nested JSON (written into the stats file).
    nlohmann::ordered_json to_json() const;

private:
    void apply(const nlohmann::json& j, const std::string& prefix, const std::string& source);
    std::map<std::string, nlohmann::json> values_;
};

}  // namespace rtu
