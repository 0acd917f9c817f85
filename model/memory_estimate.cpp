#include "memory_estimate.h"

#include <algorithm>
#include <cstdio>

#include "sector_cache.h"

namespace rtu {

namespace {

// Per-unit costs measured as peak resident memory (/usr/bin/time %M) of rtsim on 2026-11-24
// (Release build, cornell, primary rays), the one-unit difference of two runs:
// - per SM: --set gpu.sms=1024 against gpu.sms=8 on an 8x8 frame: AT 373 KiB, LT 366 KiB,
//   interval 39 KiB per SM; less the default L1 (9 KiB, counted as tags below). AT and LT are
//   mostly the RT unit's ring of chunks in flight (8192 slots of 40 B, model/rt_unit_core.h);
// - per thread in flight (SMs x warp-buffer slots x warp size, at most the frame's paths):
//   --set gpu.sms=1024 --set rt.warp_buffer=64 against gpu.sms=8, 1448x1448 at 1 spp: 2.3 KiB
//   (interval) to 2.5 KiB (AT) per thread: three std::deque (traversal stack, deferred entries,
//   recent prefetches) of a 512 B block and a 64 B map each, and the thread's state. Measured
//   again on 2026-12-03 for the interval fidelity, whose chunks in flight now wait in a queue for
//   the response FIFO's drain (model/interval_gpu.h): 3.3 KiB per thread (rtsim 3d0f1e4: 2.7 KiB);
// - per path: the 8-SM run above against an 8x8 frame: 167 B per path (the first rays, the
//   shader warps and their records in the workload driver).
constexpr uint64_t kPerSmSystemC = 364 << 10, kPerSmInterval = 30 << 10;
constexpr uint64_t kPerThreadSystemC = 2560, kPerThreadInterval = 3400;
constexpr uint64_t kPerPath = 176;
// Functional: cornell primary rays (one ray a path) at 1024x1024 against 64x64, 298 B a path
// (the traced ray kept, its pixel, the workload's state); path tracing keeps every bounce's ray
// (1,230 B a path on cornell), so this is a lower bound.
constexpr uint64_t kPerFunctionalPath = 298;

}  // namespace

uint64_t MemoryEstimate::total() const {
    uint64_t t = 0;
    for (const Part& p : parts) t += p.bytes;
    return t;
}

std::string format_bytes(uint64_t bytes) {
    char b[32];
    const double v = double(bytes);
    if (v >= double(1ull << 40)) std::snprintf(b, sizeof b, "%.1f TiB", v / double(1ull << 40));
    else if (v >= double(1ull << 30)) std::snprintf(b, sizeof b, "%.1f GiB", v / double(1ull << 30));
    else if (v >= double(1ull << 20)) std::snprintf(b, sizeof b, "%.1f MiB", v / double(1ull << 20));
    else std::snprintf(b, sizeof b, "%.0f KiB", v / 1024.0);
    return b;
}

std::string MemoryEstimate::largest(size_t n) const {
    std::string s;
    for (size_t i = 0; i < parts.size() && i < n; ++i) s += (i ? ", " : "") + parts[i].what + " " + format_bytes(parts[i].bytes);
    return s;
}

MemoryEstimate estimate_memory(const HwConfig& cfg, Fidelity fidelity, uint64_t paths, uint64_t image_bytes) {
    MemoryEstimate e;
    // Each part names the configuration keys it grows with.
    const auto tags = [&](const std::string& name, const std::string& count_key, uint64_t count, const std::string& size_key,
                          const CacheConfig& c) {
        const uint64_t used = (image_bytes + c.line - 1) / c.line;
        e.parts.push_back({name + " tags (" + count_key + " " + std::to_string(count) + " x " + size_key + " " +
                               std::to_string(c.size_bytes >> 10) + " KiB in " + std::to_string(c.line) + " B lines)",
                           count * SectorCache::memory_bytes(c, used)});
    };
    tags("L1", "gpu.sms", cfg.sms, "l1.size_kb", cfg.l1);
    tags("L2", "l2.slices", cfg.l2_slices, "l2.slice_kb", cfg.l2);
    const uint64_t per_sm = fidelity == Fidelity::Interval ? kPerSmInterval : kPerSmSystemC;
    e.parts.push_back({"RT units (gpu.sms " + std::to_string(cfg.sms) + ")", cfg.sms * per_sm});
    const uint64_t threads = std::min<uint64_t>(uint64_t(cfg.sms) * cfg.warp_buffer * cfg.warp_size, paths);
    e.parts.push_back({"threads in flight (gpu.sms x rt.warp_buffer x rt.warp_size, at most the frame's paths: " + std::to_string(threads) + ")",
                       threads * (fidelity == Fidelity::Interval ? kPerThreadInterval : kPerThreadSystemC)});
    e.parts.push_back({"the frame's paths (width x height x spp, or the ray file's rays: " + std::to_string(paths) + ")", paths * kPerPath});
    std::stable_sort(e.parts.begin(), e.parts.end(), [](const MemoryEstimate::Part& a, const MemoryEstimate::Part& b) { return a.bytes > b.bytes; });
    return e;
}

MemoryEstimate estimate_functional_memory(uint64_t paths) {
    MemoryEstimate e;
    e.parts.push_back({"the frame's traced rays, at least one a path (width x height x spp, or the ray file's rays: " + std::to_string(paths) + ")",
                       paths * kPerFunctionalPath});
    return e;
}

}  // namespace rtu
