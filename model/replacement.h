// A cache's replacement policy (l1.replacement, l2.replacement): which line of a set a new line
// replaces. The cache (model/sector_cache.h) takes unused ways first, tells the policy of every use
// of a way, and asks it for the set's ways in the order it would evict them, skipping ways with a
// pending sector. Every fidelity's caches are SectorCaches (AT's tlm/cache.h, LT's and the
// interval fidelity's CacheBookings), so one policy object per cache is timed the same way in
// AT, LT and interval. A new policy is one class and one register_replacement call
// (docs/timing.md, "Memory policies"). Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace rtu {

class ReplacementPolicy {
public:
    static constexpr uint32_t kNone = ~0u;
    virtual ~ReplacementPolicy() = default;
    // Ways are numbered set-major over the cache: set s owns ways [s x assoc, (s + 1) x assoc).
    // Way `way` of set `set` took a new line (it is used at once after; by default a use).
    virtual void inserted(uint32_t set, uint32_t way) { touched(set, way); }
    // It was used: a hit, a merge into its MSHR, the miss that allocated it, a sector warmed into it.
    virtual void touched(uint32_t set, uint32_t way) = 0;
    // The set's ways that hold a line, in the order the policy would evict them: the first, and
    // the one after `way`; kNone past the last.
    virtual uint32_t first_victim(uint32_t set) const = 0;
    virtual uint32_t next_victim(uint32_t set, uint32_t way) const = 0;
    // Every way forgotten (the cache was invalidated).
    virtual void clear() = 0;
};

struct ReplacementKind {
    std::string name, what;
    uint32_t bytes_per_way = 0, bytes_per_set = 0;  // host memory (memory estimates before elaboration)
    // A policy for a cache of `sets` sets of `assoc` ways.
    std::function<std::unique_ptr<ReplacementPolicy>(uint32_t sets, uint32_t assoc)> make;
};

// Registers a policy under its name (replaces one of the same name); returns true, so that a
// translation unit can register one at static initialisation.
bool register_replacement(ReplacementKind kind);
// The policy registered as `name`; std::invalid_argument naming the known ones otherwise.
const ReplacementKind& replacement_kind(const std::string& name);
std::vector<std::string> replacement_names();

}  // namespace rtu
