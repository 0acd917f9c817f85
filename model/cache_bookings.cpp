#include "cache_bookings.h"

#include <algorithm>

namespace rtu {

CacheBookings::CacheBookings(const CacheConfig& cfg, uint32_t hit_latency, bool own_port)
    : cfg_(cfg), hit_latency_(hit_latency), own_port_(own_port), tags_(cfg), on_fill_(cfg.allocate_on_fill) {}

void CacheBookings::apply_fills(uint64_t cycle) {
    while (!deferred_.empty() && deferred_.top().at <= cycle) {
        const Deferred d = deferred_.top();
        deferred_.pop();
        const auto f = sectors_.find(d.sector);
        if (f == sectors_.end() || f->second.unfilled != d.seq) continue;  // entered at a read already
        f->second.unfilled = 0;
        tags_.fill(d.sector);
    }
}

void CacheBookings::advance(uint64_t floor) {
    if (floor <= floor_) return;
    floor_ = floor;
    if (on_fill_) apply_fills(floor);
    // The port's ring is recycled every 1,024 cycles: bookings come at or after the floor anyway.
    if (own_port_ && floor >= port_floor_ + 1024) {
        port_floor_ = floor;
        port_.advance(floor);
    }
}

// The miss of `sector` still in flight at `cycle`, or null when its data is there. A read
// timestamped before the miss left takes the miss over.
CacheBookings::InFlightSector* CacheBookings::in_flight(uint64_t sector, uint64_t cycle) {
    auto f = sectors_.find(sector);
    return f == sectors_.end() ? nullptr : in_flight(f->second, cycle);
}

CacheBookings::InFlightSector* CacheBookings::in_flight(InFlightSector& r, uint64_t cycle) {
    if (r.at <= cycle) return nullptr;
    if (cycle < r.sent) {
        r.at = cycle + (r.at - r.sent);
        r.sent = cycle;
    }
    return &r;
}

// The cycle at or after `c` a miss gets an MSHR (counting a reservation fail if it had to wait).
uint64_t CacheBookings::mshr_slot(uint64_t c, ReqKind kind) {
    while (!mshr_free_.empty() && mshr_free_.top() <= c) mshr_free_.pop();
    if (mshr_free_.size() < cfg_.mshrs) return c;
    tags_.count_reservation_fail(kind);
    const uint64_t t = mshr_free_.top();
    mshr_free_.pop();
    return t;
}

CacheBookings::Lookup CacheBookings::lookup(uint64_t addr, uint64_t cycle, ReqKind kind) {
    const uint64_t c = own_port_ ? port_.book(cycle) : cycle;  // one lookup per cycle
    const uint64_t sector = tags_.sector_of(addr);
    auto f = sectors_.end();  // allocation at the fill: the sector's entry, looked up once per read
    if (on_fill_) {
        apply_fills(c);
        f = sectors_.find(sector);
        if (f != sectors_.end() && f->second.unfilled) {
            // On its way and not in the tags: the read merges into its miss and touches no line
            // (GPGPU-Sim's ON_FILL has no reserved line to hit, gpu-cache.cc l.346-375).
            InFlightSector* r = in_flight(f->second, c);
            if (r && r->at > c + hit_latency_) {
                tags_.count_read_of_unfilled(kind);
                return merge(*r, c, kind);
            }
            f->second.unfilled = 0;  // its data is there (its miss was taken over by an earlier read)
            tags_.fill(sector);
        }
    }
    // The tags hold no pending sector here (a miss is filled at once, or allocated at the fill
    // and answered above until it is), so they answer a hit or a miss, never a reservation fail.
    if (tags_.read(addr, 0, kind) != CacheOutcome::Hit) {
        // Every MSHR busy: the miss waits for the first to free (a reservation fail), and the
        // requester's port with it, as AT withholds END_REQ until then.
        const uint64_t slot = mshr_slot(c, kind);
        Lookup l{Lookup::Miss, c, slot + hit_latency_};
        if (slot > c) {
            l.retry_at = slot;
            if (own_port_) port_.hold(c + 1, slot);
        }
        return l;
    }
    InFlightSector* r = !on_fill_ ? in_flight(sector, c) : f == sectors_.end() ? nullptr : in_flight(f->second, c);
    if (!r || r->at <= c + hit_latency_) return {Lookup::Hit, c, c + hit_latency_};
    return merge(*r, c, kind);
}

CacheBookings::Lookup CacheBookings::merge(InFlightSector& r, uint64_t c, ReqKind kind) {
    if (r.merged + 1 >= cfg_.mshr_merge) {
        // The MSHR holds its limit of requests: a reservation fail. The read retries when the
        // sector arrives (then a hit), and the requester's port waits for it.
        tags_.count_reservation_fail(kind);
        if (own_port_) port_.hold(c + 1, r.at);
        Lookup l{Lookup::Retry, c, r.at + hit_latency_};
        l.retry_at = r.at;
        return l;
    }
    ++r.merged;
    tags_.count_as_mshr_hit(kind);
    if (kind == ReqKind::Demand && r.prefetch) {
        tags_.count_late_prefetch();  // the demand found the prefetch still on its way
        r.prefetch = false;
    }
    return {Lookup::InFlight, c, r.at, r.dram};
}

// Sectors whose data arrived by the floor are plain hits for every later read: they are
// forgotten when the map has grown to twice its size after the last pruning (and to at least 64
// entries), so that pruning costs O(1) per read and the map stays about the size of the misses
// in flight, small enough for the host's caches (at 4 entries per cache line an L2 slice's map
// grew to hundreds of thousands, and its lookups missed the host's caches).
void CacheBookings::fill(uint64_t addr, const Lookup& miss, uint64_t done, bool dram, ReqKind kind) {
    const uint64_t sector = tags_.sector_of(addr);
    mshr_free_.push(done);
    if (on_fill_) {
        // The miss holds the tags' MSHR until its data enters them, which may be later than its
        // MSHR's end here (apply_fills): MSHRs are counted by time (mshr_slot), and the tags' own
        // count is no limit. (AT uses these tags without lookup() or fill(), and keeps it.)
        tags_.lift_mshr_limit();
        deferred_.push({done, ++deferred_seq_, sector});
    } else {
        tags_.fill(sector);
    }
    sectors_[sector] = {miss.cycle, done, dram, 0, kind == ReqKind::Prefetch, on_fill_ ? deferred_seq_ : 0};
    if (sectors_.size() <= std::max<size_t>(prune_above_, 64)) return;
    for (auto it = sectors_.begin(); it != sectors_.end();) {
        if (it->second.at <= floor_ && !it->second.unfilled)  // (an unfilled one waits for its fill)
            sectors_.erase(it++);
        else
            ++it;
    }
    prune_above_ = 2 * sectors_.size();
    // A prune walks the table's capacity, which erasing never gives back: after a burst of misses
    // a table of a few live sectors in thousands of slots was walked every few dozen fills (party,
    // interval: 10 % of the run in this function). Shrink it to what the live sectors need.
    if (sectors_.capacity() > 8 * std::max<size_t>(prune_above_, 64)) sectors_.rehash(0);
}

}  // namespace rtu
