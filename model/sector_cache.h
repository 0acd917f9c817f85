// Tag and MSHR logic of a sector cache (L1 per SM, L2 slices): 128 B lines of 32 B sectors,
// N-way or fully associative, a replacement policy chosen by configuration (model/replacement.h;
// the presets' LRU), MSHRs that merge requests to a pending sector up to a limit, and reservation
// fails when no MSHR is left. A missing line takes its way at the miss (GPGPU-Sim's ON_MISS: the
// way is held while its sectors are pending, and a set whose ways are all pending refuses the
// miss) or when its data arrives (ON_FILL, `allocate_on_fill`: the victim is chosen then, and no
// way is ever held).
// Plain C++ (no SystemC); the tlm/ cache module drives it.
#pragma once
#include <array>
#include <cstdint>
#include <absl/container/flat_hash_map.h>
#include <absl/container/inlined_vector.h>
#include <vector>

#include "config.h"
#include "replacement.h"
#include "stats.h"

namespace rtu {

// Demand: the RT unit's node reads; Prefetch: a prefetcher's; Shader: the SM's shader code's loads
// (workload.shader_reads), which nothing in the model waits for.
enum class ReqKind : uint8_t { Demand = 0, Prefetch = 1, Shader = 2 };
constexpr int kReqKinds = 3;

// Which cache of the hierarchy: the L1 of an SM (the RT unit reads it) or an L2 slice (DRAM
// below it).
enum class CacheRole : uint8_t { L1, L2 };

enum class CacheOutcome : uint8_t {
    Hit,              // sector present
    MshrHit,          // sector pending: merged into its MSHR
    SectorMiss,       // line present, sector absent: MSHR allocated, sector must be fetched
    LineMiss,         // line absent: MSHR allocated, fetch; the line allocated (the policy's victim evicted) now or at the fill
    ReservationFail,  // no MSHR, merge limit reached, or (allocation at the miss) every way of the set has pending sectors
};

// Lookups of one requester kind (demand or prefetch).
struct CacheAccessCounts {
    uint64_t accesses = 0, hits = 0, mshr_hits = 0, sector_misses = 0, line_misses = 0, reservation_fails = 0, evictions = 0;
    static constexpr Counter<CacheAccessCounts> kCounters[] = {
        {"accesses", &CacheAccessCounts::accesses, "lookups", "lookups (a request retried after a reservation fail counts each time)"},
        {"hits", &CacheAccessCounts::hits, "lookups", "found the sector valid"},
        {"mshr_hits", &CacheAccessCounts::mshr_hits, "lookups", "found the sector on its way and merged into its MSHR"},
        {"sector_misses", &CacheAccessCounts::sector_misses, "lookups", "line present, sector absent: fetched from below"},
        {"line_misses", &CacheAccessCounts::line_misses, "lookups", "line absent: the sector fetched and a line allocated (the policy's victim evicted), at the miss or at the fill (l1/l2.allocation)"},
        {"reservation_fails", &CacheAccessCounts::reservation_fails, "lookups", "no MSHR, merge limit reached, every way of the set pending (allocation at the miss), or the miss queue full (l1/l2.miss_queue, AT): retried later"},
        {"evictions", &CacheAccessCounts::evictions, "lines", "lines with valid sectors evicted by this kind's line misses (at the miss, or at the fill with l1/l2.allocation = fill)"},
    };
};

// Sectors brought in by prefetches, and whether demand reads used them.
struct PrefetchedSectorCounts {
    uint64_t fills = 0, useful = 0, late = 0, unused_evictions = 0;
    uint64_t authors_unused_lines = 0;
    static constexpr Counter<PrefetchedSectorCounts> kCounters[] = {
        {"fills", &PrefetchedSectorCounts::fills, "sectors", "sectors brought in by a prefetch"},
        {"useful", &PrefetchedSectorCounts::useful, "sectors", "of them, read by a demand request (at most once each)"},
        {"late", &PrefetchedSectorCounts::late, "sectors", "of the useful ones, the demand read came while the prefetch was on its way"},
        {"unused_evictions", &PrefetchedSectorCounts::unused_evictions, "sectors", "prefetched sectors evicted before any demand read"},
        {"authors_unused_lines", &PrefetchedSectorCounts::authors_unused_lines, "lines",
         "the TTP authors' count of unused prefetches (gpu-cache.cc l.1646): lines evicted whose last fill was a prefetch's and whose way never had a hit while its line was so marked"},
    };
};

// One cache (an SM's L1 or an L2 slice).
struct CacheCounts {
    CacheAccessCounts demand, prefetch, shader;
    uint64_t fills = 0;
    PrefetchedSectorCounts prefetched;
    CacheAccessCounts& of(ReqKind k) { return k == ReqKind::Demand ? demand : k == ReqKind::Prefetch ? prefetch : shader; }
    const CacheAccessCounts& of(ReqKind k) const { return k == ReqKind::Demand ? demand : k == ReqKind::Prefetch ? prefetch : shader; }
    static constexpr Counter<CacheCounts> kCounters[] = {
        {"fills", &CacheCounts::fills, "sectors", "sectors filled from below (demand, prefetch and shader reads)"},
    };
    static constexpr bool kParts = true;
    template <class F>
    static void parts(F&& f) {
        f("demand", &CacheCounts::demand, "demand lookups (node reads)");
        f("prefetch", &CacheCounts::prefetch, "prefetch lookups (the paper's response breakdown: hits, mshr_hits, sector and line misses with an MSHR free, reservation fails)");
        f("shader", &CacheCounts::shader, "the shader code's loads (workload.shader_reads; none unless set)");
        f("prefetched", &CacheCounts::prefetched, "prefetched sectors and their use");
    }
};

class SectorCache {
public:
    using Tokens = absl::InlinedVector<uint64_t, 8>;  // requests waiting on one sector (merge limit 8 by default)

    explicit SectorCache(const CacheConfig& c);

    uint64_t sector_of(uint64_t addr) const { return addr & ~uint64_t(sector_ - 1); }
    // Looks up a read of the sector holding `addr` on behalf of request `token`. On SectorMiss
    // and LineMiss the caller fetches the sector and calls fill(); on ReservationFail nothing
    // changed and the caller retries later.
    CacheOutcome read(uint64_t addr, uint64_t token, ReqKind kind);
    // Whether a read of `addr` now would send a miss below or join one on its way as a miss
    // (allocated at the fill, a sector on its way is not in its line: GPGPU-Sim's streaming L1
    // probes a miss), rather than hit or merge into a reserved sector.
    bool would_miss(uint64_t addr) const;
    // The sector arrived: valid from now on; returns the tokens that waited on it (allocating
    // request first, then merged ones in arrival order) and frees the MSHR.
    Tokens fill(uint64_t sector_addr);
    // Functional warming (sampled simulation): the sector holding `addr` becomes valid and most
    // recently used at once, with no statistic counted; returns whether it was already valid.
    // A sector whose fetch is pending, or (allocation at the miss) a set with every way pending,
    // is left alone.
    bool warm(uint64_t addr);

    // Every line invalid, as after a reset (statistics kept); no fetch may be pending.
    void invalidate();

    size_t mshrs_in_use() const { return mshr_.size(); }
    // LT and interval (CacheBookings) count MSHRs by time; with the allocation at the fill their
    // misses stay in these tags until their data enters them, which is no limit of the cache's.
    void lift_mshr_limit() { mshrs_ = ~0u; }
    // LT and interval (CacheBookings), a cache allocated at the fill: a read of a sector on its
    // way that the tags do not hold yet, counted as a read the tags answered with a hit (which
    // the caller then recounts: count_as_mshr_hit, count_reservation_fail), touching no line.
    void count_read_of_unfilled(ReqKind k) {
        ++counts_.of(k).accesses;
        ++counts_.of(k).hits;
    }
    // LT bookkeeping: a read found valid in the tags whose data was still in flight at its
    // timestamp counts as an MSHR hit; a read that had to wait for a free MSHR counts one
    // reservation fail (as the retried access would in AT).
    void count_as_mshr_hit(ReqKind k) {
        --counts_.of(k).hits;
        ++counts_.of(k).mshr_hits;
    }
    // LT and interval (CacheBookings): a demand read found a prefetched sector still on its way.
    void count_late_prefetch() { ++counts_.prefetched.late; }
    void count_reservation_fail(ReqKind k) {
        ++counts_.of(k).accesses;
        ++counts_.of(k).reservation_fails;
    }
    const CacheCounts& counts() const { return counts_; }
    const CacheAccessCounts& stats(ReqKind k) const { return counts_.of(k); }
    uint64_t lines() const { return ways_.size(); }
    // Host memory a cache of `c` holds once `lines_used` of its lines have been filled (a memory
    // estimate before elaboration, model/memory_estimate.h): its ways and sets, and its line map's
    // slots, of which the constructor touches the control bytes and each filled line about
    // slots / lines whole slots (they are spread over the table by the hash).
    static uint64_t memory_bytes(const CacheConfig& c, uint64_t lines_used);

private:
    struct Way {
        uint64_t line = ~0ull;  // line address; ~0 = invalid
        uint32_t valid = 0, pending = 0;  // sector bit masks
        uint32_t prefetched = 0;          // filled by a prefetch and not yet read by a demand
        // The TTP authors' line flags (gpu-cache.h l.158-160): the line's last fill was a
        // prefetch's; a hit found the line so marked. The second is never cleared, as theirs
        // (set only in the constructor), so it stays with the way across lines.
        bool line_prefetched = false, way_accessed = false;
    };
    struct Set {
        uint32_t unused = 0;  // ways [unused, assoc) were never taken
    };
    static constexpr uint32_t kNone = ReplacementPolicy::kNone;
    void touch(Way& w);  // used now (the replacement policy is told)
    struct Mshr {
        Tokens tokens;
        ReqKind kind = ReqKind::Demand;  // the allocating request's
        bool prefetch = false;   // allocated by a prefetch
        bool demanded = false;   // a demand read merged into it
    };
    Way* find(uint64_t line);
    const Way* find(uint64_t line) const { return const_cast<SectorCache*>(this)->find(line); }
    // Where the sector holding `addr` lives: its line's address and its bit in the line's masks.
    struct Place {
        uint64_t line;
        uint32_t bit;
    };
    Place place_of(uint64_t addr) const {
        const uint64_t line = addr / line_ * line_;
        return {line, 1u << ((addr - line) / sector_)};
    }
    // The MSHR of `sector` (at `bit` of way `w`, null if its line is absent) while its data is on
    // its way, or null. Allocated at the miss, the sector is pending in its way; allocated at the
    // fill, only the MSHR knows it (the line may be absent).
    Mshr* on_its_way(const Way* w, uint64_t sector, uint32_t bit);
    Way* allocate(uint64_t line, CacheAccessCounts* st);

    uint32_t set_of(uint64_t line) const;  // the set a line goes to
    uint32_t line_, sector_, assoc_, sets_, mshrs_, merge_;
    bool on_fill_;  // lines allocated when their data arrives
    SliceLocal local_;
    bool ipoly_;
    std::vector<Way> ways_;  // set-major: set s owns ways [s*assoc, (s+1)*assoc)
    std::vector<Set> set_;
    std::unique_ptr<ReplacementPolicy> policy_;
    absl::flat_hash_map<uint64_t, uint32_t> where_;  // line address -> way index
    // sector address -> its MSHR's place in mshr_pool_. The MSHRs (88 B each, their tokens
    // inline) live in a pool whose freed places are reused last in, first out, so that a miss
    // writes an MSHR the host's caches hold and the map's slots stay 16 B: with the MSHRs in the
    // map's slots, the first touch of a new slot took 43 % of read()'s time in the interval
    // fidelity on party (docs/performance.md, "Earlier speed work").
    absl::flat_hash_map<uint64_t, uint32_t> mshr_;
    std::vector<Mshr> mshr_pool_;
    std::vector<uint32_t> mshr_unused_;  // places in mshr_pool_ free for the next miss
    Mshr& new_mshr(uint64_t sector);     // a cleared MSHR for the miss of `sector`
    CacheCounts counts_;
};

}  // namespace rtu
