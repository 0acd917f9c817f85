// Tag, LRU and MSHR logic of a sector cache (L1 per SM, L2 slices): 128 B lines of 32 B
// sectors, N-way or fully associative, LRU replacement, MSHRs that merge requests to a pending
// sector up to a limit, and reservation fails when no MSHR or no replaceable line is left.
// Plain C++ (no SystemC); the tlm/ cache module drives it.
#pragma once
#include <array>
#include <cstdint>
#include <absl/container/flat_hash_map.h>
#include <absl/container/inlined_vector.h>
#include <vector>

#include "config.h"

namespace rtu {

enum class ReqKind : uint8_t { Demand = 0, Prefetch = 1 };
constexpr int kReqKinds = 2;

// Which cache of the hierarchy: the L1 of an SM (the RT unit reads it) or an L2 slice (DRAM
// below it).
enum class CacheRole : uint8_t { L1, L2 };

enum class CacheOutcome : uint8_t {
    Hit,              // sector present
    MshrHit,          // sector pending: merged into its MSHR
    SectorMiss,       // line present, sector absent: MSHR allocated, sector must be fetched
    LineMiss,         // line absent: line allocated (LRU victim evicted), MSHR allocated, fetch
    ReservationFail,  // no MSHR, merge limit reached, or every way of the set has pending sectors
};

struct CacheStats {
    uint64_t accesses = 0, hits = 0, mshr_hits = 0, sector_misses = 0, line_misses = 0, reservation_fails = 0;
    uint64_t fills = 0, evictions = 0;
    // Prefetch usefulness (counted under the demand kind that used them / the prefetch kind):
    uint64_t prefetch_fills = 0;     // sectors brought in by a prefetch (prefetch kind)
    uint64_t useful_prefetches = 0;  // prefetched sectors a demand read then used (demand kind)
    uint64_t late_prefetches = 0;    // of those, demand arrived while the prefetch was in flight
    uint64_t unused_evictions = 0;   // prefetched sectors evicted unused (prefetch kind)
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
    // The sector arrived: valid from now on; returns the tokens that waited on it (allocating
    // request first, then merged ones in arrival order) and frees the MSHR.
    Tokens fill(uint64_t sector_addr);
    // Functional warming (sampled simulation): the sector holding `addr` becomes valid and most
    // recently used at once, with no statistic counted; returns whether it was already valid.
    // A sector whose fetch is pending, or a set with every way pending, is left alone.
    bool warm(uint64_t addr);

    size_t mshrs_in_use() const { return mshr_.size(); }
    // LT bookkeeping: a read found valid in the tags whose data was still in flight at its
    // timestamp counts as an MSHR hit; a read that had to wait for a free MSHR counts one
    // reservation fail (as the retried access would in AT).
    void count_as_mshr_hit(ReqKind k) {
        --stats_[size_t(k)].hits;
        ++stats_[size_t(k)].mshr_hits;
    }
    // LT and interval (CacheBookings): a demand read found a prefetched sector still on its way.
    void count_late_prefetch() { ++stats_[size_t(ReqKind::Demand)].late_prefetches; }
    void count_reservation_fail(ReqKind k) {
        ++stats_[size_t(k)].accesses;
        ++stats_[size_t(k)].reservation_fails;
    }
    const CacheStats& stats(ReqKind k) const { return stats_[size_t(k)]; }
    CacheStats total() const;
    uint64_t lines() const { return ways_.size(); }

private:
    struct Way {
        uint64_t line = ~0ull;  // line address; ~0 = invalid
        uint32_t valid = 0, pending = 0;  // sector bit masks
        uint32_t prefetched = 0;          // filled by a prefetch and not yet read by a demand
        uint32_t prev = kNone, next = kNone;  // recency list of the set (front: most recently used)
    };
    struct Set {
        uint32_t head = kNone, tail = kNone;  // way indices
        uint32_t unused = 0;                  // ways [unused, assoc) were never taken
    };
    static constexpr uint32_t kNone = ~0u;
    void touch(Way& w);  // most recently used now
    void link_front(Set& s, uint32_t way);
    struct Mshr {
        Tokens tokens;
        bool prefetch = false;   // allocated by a prefetch
        bool demanded = false;   // a demand read merged into it
    };
    Way* find(uint64_t line);
    Way* allocate(uint64_t line, CacheStats* st);

    uint32_t line_, sector_, assoc_, sets_, mshrs_, merge_;
    std::vector<Way> ways_;  // set-major: set s owns ways [s*assoc, (s+1)*assoc)
    std::vector<Set> set_;
    absl::flat_hash_map<uint64_t, uint32_t> where_;  // line address -> way index
    absl::flat_hash_map<uint64_t, Mshr> mshr_;       // sector address -> waiting tokens
    std::array<CacheStats, kReqKinds> stats_{};
};

}  // namespace rtu
