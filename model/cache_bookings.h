// A sector cache (an L1 or an L2 slice) as the fast fidelities time it, LT and interval alike:
// requests come in any timestamp order (LT: SMs up to a quantum apart; interval: fetches booked
// ahead of their time), so the tags (SectorCache) are looked up and filled at once and every
// sector remembers the cycle its data arrives. Then a request sees what AT's cache would show it
// at its own timestamp:
// - a read of a sector still on its way waits for it (an MSHR hit, with the data's source);
//   past the MSHR's merge limit it is a reservation fail that retries when the sector arrives,
//   its requester's port held until then;
// - a read timestamped before the miss left takes the miss over (it would have been the one to
//   miss, and the later read the one to merge);
// - a miss waits for a free MSHR (counting a reservation fail if it had to);
// - with its own port, one lookup per cycle (booked by timestamp);
// - a demand read that finds a prefetch's sector still on its way counts a late prefetch.
// The level below is the caller's: lookup() says when a miss leaves, fill() when its data came.
// A cache that allocates its lines at the fill (`allocate_on_fill`, GPGPU-Sim's ON_FILL: the
// presets' streaming L1) takes a missed sector into its tags only when its data arrives: until
// then the line is absent (another sector's read of it is a line miss) and no victim has been
// chosen, and the victim is the replacement policy's choice at the arrival, after the reads of
// the cycles between, as in AT. The fills wait, in order of arrival, until a lookup (or the
// floor) reaches their cycle. Reads come in timestamp order only roughly (above), so a fill is
// applied at the first lookup at or after its cycle, whatever that lookup's order among reads of
// earlier timestamps still to come.
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <queue>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "calendar.h"
#include "config.h"
#include "sector_cache.h"

namespace rtu {

class CacheBookings {
public:
    // `hit_latency`: cycles from lookup to data on a hit; `own_port`: the cache takes one lookup per
    // cycle (false where the requester's port already sends at most one request per cycle).
    CacheBookings(const CacheConfig& cfg, uint32_t hit_latency, bool own_port);

    struct Lookup {
        enum Outcome : uint8_t { Hit, InFlight, Retry, Miss };
        Outcome outcome;
        uint64_t cycle;          // the lookup's cycle (at or after the request's, by the port)
        uint64_t ready;          // Hit, InFlight, Retry: the cycle the data is there; Miss: the cycle the miss leaves
        bool dram = false;       // InFlight: the data on its way comes from DRAM
        // Retry: the cycle the sector arrives; Miss: the cycle an MSHR frees when all were busy
        // (0: one was free). The requester's port is held until then.
        uint64_t retry_at = 0;
    };
    // A read of the sector holding `addr` at cycle `cycle` (at or after the floor).
    Lookup lookup(uint64_t addr, uint64_t cycle, ReqKind kind);
    // The data of the miss `miss` (lookup's answer for `addr`) arrives at `done`; `dram`: from DRAM.
    void fill(uint64_t addr, const Lookup& miss, uint64_t done, bool dram, ReqKind kind);
    // No lookup will be timestamped before `floor` again.
    void advance(uint64_t floor);

    // Every line invalid (SectorCache::invalidate); misses still in flight are forgotten, so call
    // only when every booked miss has arrived.
    void invalidate() {
        apply_fills(~0ull);
        tags_.invalidate();
        sectors_.clear();
    }
    SectorCache& tags() { return tags_; }
    const SectorCache& tags() const { return tags_; }
    size_t mshrs_in_use() const { return mshr_free_.size(); }

private:
    struct InFlightSector {  // a sector's miss left at `sent` and its data arrives at `at`
        uint64_t sent, at;
        bool dram;
        uint32_t merged = 0;    // reads merged into the miss while in flight
        bool prefetch = false;  // the miss is a prefetch's (until a demand read merges)
        uint64_t unfilled = 0;  // allocation at the fill: its place in the fills' queue until its data enters the tags
    };
    InFlightSector* in_flight(uint64_t sector, uint64_t cycle);
    InFlightSector* in_flight(InFlightSector& r, uint64_t cycle);
    uint64_t mshr_slot(uint64_t cycle, ReqKind kind);
    // Allocation at the fill: the fills that arrive by `cycle` enter the tags, in order of arrival.
    void apply_fills(uint64_t cycle);
    // The answer to a read of a sector still on its way (InFlight, or Retry past the merge limit).
    Lookup merge(InFlightSector& r, uint64_t c, ReqKind kind);

    CacheConfig cfg_;
    uint32_t hit_latency_;
    bool own_port_;
    SectorCache tags_;
    PortCalendar port_;
    absl::flat_hash_map<uint64_t, InFlightSector> sectors_;
    size_t prune_above_ = 0;  // size of sectors_ that triggers the next prune
    // Cycles the MSHRs in use free up.
    std::priority_queue<uint64_t, std::vector<uint64_t>, std::greater<uint64_t>> mshr_free_;
    uint64_t floor_ = 0, port_floor_ = 0;
    // Allocation at the fill: the misses whose data has not entered the tags, by arrival (cycle,
    // then order of booking; InFlightSector::unfilled names the entry). A miss taken over by an
    // earlier read arrives earlier than its place in the queue; a read that finds its data there
    // enters it at once.
    struct Deferred {
        uint64_t at, seq, sector;
        bool operator>(const Deferred& o) const { return at != o.at ? at > o.at : seq > o.seq; }
    };
    bool on_fill_;
    std::priority_queue<Deferred, std::vector<Deferred>, std::greater<Deferred>> deferred_;
    uint64_t deferred_seq_ = 0;
};

}  // namespace rtu
