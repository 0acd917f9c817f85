#include "sector_cache.h"

#include <stdexcept>

namespace rtu {

SectorCache::SectorCache(const CacheConfig& c)
    : line_(c.line), sector_(c.sector), mshrs_(c.mshrs), merge_(c.mshr_merge) {
    const uint64_t lines = c.size_bytes / c.line;
    assoc_ = c.assoc ? c.assoc : uint32_t(lines);
    sets_ = uint32_t(lines / assoc_);
    if (line_ / sector_ > 32) throw std::invalid_argument("at most 32 sectors per line");
    ways_.resize(lines);
    where_.reserve(lines * 2);
}

SectorCache::Way* SectorCache::find(uint64_t line) {
    auto it = where_.find(line);
    return it == where_.end() ? nullptr : &ways_[it->second];
}

CacheStats SectorCache::total() const {
    CacheStats t;
    for (const CacheStats& s : stats_) {
        t.accesses += s.accesses;
        t.hits += s.hits;
        t.mshr_hits += s.mshr_hits;
        t.sector_misses += s.sector_misses;
        t.line_misses += s.line_misses;
        t.reservation_fails += s.reservation_fails;
        t.fills += s.fills;
        t.evictions += s.evictions;
        t.prefetch_fills += s.prefetch_fills;
        t.useful_prefetches += s.useful_prefetches;
        t.late_prefetches += s.late_prefetches;
        t.unused_evictions += s.unused_evictions;
    }
    return t;
}

CacheOutcome SectorCache::read(uint64_t addr, uint64_t token, ReqKind kind) {
    CacheStats& st = stats_[size_t(kind)];
    ++st.accesses;
    const uint64_t line = addr / line_ * line_;
    const uint64_t sector = sector_of(addr);
    const uint32_t bit = 1u << ((addr - line) / sector_);
    Way* w = find(line);
    if (w && (w->valid & bit)) {
        w->lru = ++clock_;
        ++st.hits;
        if (kind == ReqKind::Demand && (w->prefetched & bit)) {
            w->prefetched &= ~bit;
            ++st.useful_prefetches;
        }
        return CacheOutcome::Hit;
    }
    if (w && (w->pending & bit)) {
        Mshr& m = mshr_.at(sector);
        if (m.tokens.size() >= merge_) {
            ++st.reservation_fails;
            return CacheOutcome::ReservationFail;
        }
        m.tokens.push_back(token);
        w->lru = ++clock_;
        ++st.mshr_hits;
        if (kind == ReqKind::Demand && m.prefetch && !m.demanded) {
            m.demanded = true;
            ++st.useful_prefetches;
            ++st.late_prefetches;
        }
        return CacheOutcome::MshrHit;
    }
    if (mshr_.size() >= mshrs_) {
        ++st.reservation_fails;
        return CacheOutcome::ReservationFail;
    }
    CacheOutcome out = CacheOutcome::SectorMiss;
    if (!w) {
        w = allocate(line, &st);
        if (!w) {
            ++st.reservation_fails;
            return CacheOutcome::ReservationFail;
        }
        out = CacheOutcome::LineMiss;
    }
    w->pending |= bit;
    w->lru = ++clock_;
    Mshr& m = mshr_[sector];
    m.tokens.push_back(token);
    m.prefetch = kind == ReqKind::Prefetch;
    if (out == CacheOutcome::LineMiss) ++st.line_misses;
    else ++st.sector_misses;
    return out;
}

// The LRU victim among the set's ways that have no pending sector, emptied and given to `line`;
// null if every way has a pending sector. Counts the eviction into `st` when given.
SectorCache::Way* SectorCache::allocate(uint64_t line, CacheStats* st) {
    const uint64_t set = (line / line_) % sets_;
    Way* victim = nullptr;
    for (uint64_t i = set * assoc_; i < (set + 1) * assoc_; ++i) {
        Way& c = ways_[i];
        if (c.pending) continue;
        if (!victim || c.line == ~0ull || (victim->line != ~0ull && c.lru < victim->lru)) victim = &c;
        if (c.line == ~0ull) break;
    }
    if (!victim) return nullptr;
    if (victim->line != ~0ull) {
        where_.erase(victim->line);
        if (st) {
            if (victim->valid) ++st->evictions;
            stats_[size_t(ReqKind::Prefetch)].unused_evictions += uint64_t(__builtin_popcount(victim->prefetched));
        }
    }
    victim->line = line;
    victim->valid = 0;
    victim->pending = 0;
    victim->prefetched = 0;
    where_[line] = uint32_t(victim - ways_.data());
    return victim;
}

bool SectorCache::warm(uint64_t addr) {
    const uint64_t line = addr / line_ * line_;
    const uint32_t bit = 1u << ((addr - line) / sector_);
    Way* w = find(line);
    if (w && (w->valid & bit)) {
        w->lru = ++clock_;
        return true;
    }
    if (w && (w->pending & bit)) return false;
    if (!w && !(w = allocate(line, nullptr))) return false;
    w->valid |= bit;
    w->lru = ++clock_;
    return false;
}

SectorCache::Tokens SectorCache::fill(uint64_t sector_addr) {
    auto it = mshr_.find(sector_addr);
    if (it == mshr_.end()) throw std::logic_error("fill of a sector without MSHR");
    Tokens tokens = std::move(it->second.tokens);
    const bool unused_prefetch = it->second.prefetch && !it->second.demanded;
    const bool by_prefetch = it->second.prefetch;
    mshr_.erase(it);
    const uint64_t line = sector_addr / line_ * line_;
    Way* w = find(line);
    if (!w) throw std::logic_error("fill of a sector whose line was evicted while pending");
    const uint32_t bit = 1u << ((sector_addr - line) / sector_);
    w->pending &= ~bit;
    w->valid |= bit;
    if (unused_prefetch) w->prefetched |= bit;
    ++stats_[0].fills;
    if (by_prefetch) ++stats_[size_t(ReqKind::Prefetch)].prefetch_fills;
    return tokens;
}

}  // namespace rtu
