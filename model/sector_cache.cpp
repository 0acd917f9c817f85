#include "sector_cache.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace rtu {

SectorCache::SectorCache(const CacheConfig& c)
    : line_(c.line), sector_(c.sector), mshrs_(c.mshrs), merge_(c.mshr_merge), on_fill_(c.allocate_on_fill), local_(c.local), ipoly_(c.ipoly) {
    const uint64_t lines = c.size_bytes / c.line;
    assoc_ = c.assoc ? c.assoc : uint32_t(lines);
    sets_ = uint32_t(lines / assoc_);
    if (line_ / sector_ > 32) throw std::invalid_argument("at most 32 sectors per line");
    if (ipoly_ && sets_ != 16 && sets_ != 32 && sets_ != 64) throw std::invalid_argument("IPOLY set index needs 16, 32 or 64 sets");
    ways_.resize(lines);
    set_.resize(sets_);
    policy_ = replacement_kind(c.replacement).make(sets_, assoc_);
    where_.reserve(lines * 2);
}

uint64_t SectorCache::memory_bytes(const CacheConfig& c, uint64_t lines_used) {
    const uint64_t lines = c.size_bytes / c.line;
    const uint64_t sets = c.assoc ? lines / c.assoc : 1;
    // where_.reserve(2 x lines): absl's flat_hash_map keeps its load at most 7/8 and its capacity
    // a power of two minus one; a slot is the key and the value (16 B) plus one control byte.
    uint64_t slots = 1;
    while (slots * 7 < 2 * lines * 8) slots *= 2;
    const uint64_t slot_bytes = sizeof(std::pair<uint64_t, uint32_t>);
    const uint64_t used = std::min(lines, lines_used);
    const ReplacementKind& policy = replacement_kind(c.replacement);
    return lines * (sizeof(Way) + policy.bytes_per_way) + sets * (sizeof(Set) + policy.bytes_per_set) + slots +
           (lines ? used * slot_bytes * slots / lines : 0);
}

void SectorCache::touch(Way& w) {
    const uint32_t i = uint32_t(&w - ways_.data());
    policy_->touched(i / assoc_, i);
}

// An L2 slice indexes with its own address (the slice's digits taken out), so that every set
// is used; the IPOLY hash then XORs higher bits into the linear index (GPGPU-Sim's 'P').
uint32_t SectorCache::set_of(uint64_t line) const {
    const uint64_t local = local_(line) / line_;
    const uint32_t index = uint32_t(local % sets_);
    return ipoly_ ? ipoly_index(local / sets_, index, sets_) : index;
}

SectorCache::Way* SectorCache::find(uint64_t line) {
    auto it = where_.find(line);
    return it == where_.end() ? nullptr : &ways_[it->second];
}

SectorCache::Mshr* SectorCache::on_its_way(const Way* w, uint64_t sector, uint32_t bit) {
    if (!on_fill_) return w && (w->pending & bit) ? &mshr_pool_[mshr_.at(sector)] : nullptr;
    auto it = mshr_.find(sector);
    return it == mshr_.end() ? nullptr : &mshr_pool_[it->second];
}

SectorCache::Mshr& SectorCache::new_mshr(uint64_t sector) {
    uint32_t i;
    if (mshr_unused_.empty()) {
        i = uint32_t(mshr_pool_.size());
        mshr_pool_.emplace_back();
    } else {
        i = mshr_unused_.back();
        mshr_unused_.pop_back();
        // Cleared field by field (fill() moved its tokens out): assigning a fresh Mshr moved an
        // inline vector whose storage GCC saw as uninitialized (-Wmaybe-uninitialized).
        Mshr& m = mshr_pool_[i];
        m.tokens.clear();
        m.kind = ReqKind::Demand;
        m.prefetch = m.demanded = false;
    }
    mshr_.emplace(sector, i);
    return mshr_pool_[i];
}

bool SectorCache::would_miss(uint64_t addr) const {
    const auto [line, bit] = place_of(addr);
    const Way* w = find(line);
    return !(w && ((w->valid | (on_fill_ ? 0 : w->pending)) & bit));
}

CacheOutcome SectorCache::read(uint64_t addr, uint64_t token, ReqKind kind) {
    CacheAccessCounts& st = counts_.of(kind);
    ++st.accesses;
    const auto [line, bit] = place_of(addr);
    const uint64_t sector = sector_of(addr);
    Way* w = find(line);
    if (w && (w->valid & bit)) {
        touch(*w);
        ++st.hits;
        if (w->line_prefetched) w->way_accessed = true;  // any hit, demand or prefetch, as the authors
        if (kind == ReqKind::Demand && (w->prefetched & bit)) {
            w->prefetched &= ~bit;
            ++counts_.prefetched.useful;
        }
        return CacheOutcome::Hit;
    }
    // The sector on its way: its MSHR takes the read.
    if (Mshr* pending = on_its_way(w, sector, bit)) {
        Mshr& m = *pending;
        if (m.tokens.size() >= merge_) {
            ++st.reservation_fails;
            return CacheOutcome::ReservationFail;
        }
        m.tokens.push_back(token);
        // A read of a reserved sector uses its line (GPGPU-Sim's HIT_RESERVED); allocated at the
        // fill, nothing is reserved and the read is a miss that touches no line (gpu-cache.cc
        // l.346-375).
        if (!on_fill_) touch(*w);
        ++st.mshr_hits;
        if (kind == ReqKind::Demand && m.prefetch && !m.demanded) {
            m.demanded = true;
            ++counts_.prefetched.useful;
            ++counts_.prefetched.late;
        }
        return CacheOutcome::MshrHit;
    }
    if (mshr_.size() >= mshrs_) {
        ++st.reservation_fails;
        return CacheOutcome::ReservationFail;
    }
    const CacheOutcome out = w ? CacheOutcome::SectorMiss : CacheOutcome::LineMiss;
    if (!on_fill_) {
        if (!w && !(w = allocate(line, &st))) {
            ++st.reservation_fails;
            return CacheOutcome::ReservationFail;
        }
        w->pending |= bit;
        touch(*w);
    }
    Mshr& m = new_mshr(sector);
    m.tokens.push_back(token);
    m.kind = kind;
    m.prefetch = kind == ReqKind::Prefetch;
    if (out == CacheOutcome::LineMiss) ++st.line_misses;
    else ++st.sector_misses;
    return out;
}

// The replacement policy's victim among the set's ways that have no pending sector, emptied and
// given to `line`; null if every way has a pending sector. Counts the eviction into `st` when
// given.
SectorCache::Way* SectorCache::allocate(uint64_t line, CacheAccessCounts* st) {
    // Ways are taken into use in index order and never invalidated, so an unused way, if any, is
    // the set's next one; else the victim is the first way, in the policy's order, that has no
    // pending sector.
    const uint32_t set = set_of(line);
    Set& s = set_[set];
    Way* victim = nullptr;
    if (s.unused < assoc_) {
        const uint32_t i = uint32_t(set * assoc_ + s.unused++);
        victim = &ways_[i];
    } else {
        for (uint32_t i = policy_->first_victim(set); i != kNone; i = policy_->next_victim(set, i))
            if (!ways_[i].pending) {
                victim = &ways_[i];
                break;
            }
    }
    if (!victim) return nullptr;
    policy_->inserted(set, uint32_t(victim - ways_.data()));
    if (victim->line != ~0ull) {
        where_.erase(victim->line);
        if (st) {
            if (victim->valid) ++st->evictions;
            counts_.prefetched.unused_evictions += uint64_t(__builtin_popcount(victim->prefetched));
            counts_.prefetched.authors_unused_lines += victim->line_prefetched && !victim->way_accessed;
        }
    }
    victim->line = line;
    victim->valid = 0;
    victim->pending = 0;
    victim->prefetched = 0;
    victim->line_prefetched = false;
    where_[line] = uint32_t(victim - ways_.data());
    return victim;
}

void SectorCache::invalidate() {
    if (!mshr_.empty()) throw std::logic_error("cache invalidated with fetches pending");
    for (Way& w : ways_) {
        const bool accessed = w.way_accessed;  // the authors' flag stays with the way (above)
        w = Way{};
        w.way_accessed = accessed;
    }
    for (Set& s : set_) s = Set{};
    policy_->clear();
    where_.clear();
}

bool SectorCache::warm(uint64_t addr) {
    const auto [line, bit] = place_of(addr);
    Way* w = find(line);
    if (w && (w->valid & bit)) {
        touch(*w);
        return true;
    }
    if (on_its_way(w, sector_of(addr), bit)) return false;
    if (!w && !(w = allocate(line, nullptr))) return false;
    w->valid |= bit;
    touch(*w);
    return false;
}

SectorCache::Tokens SectorCache::fill(uint64_t sector_addr) {
    auto it = mshr_.find(sector_addr);
    if (it == mshr_.end()) throw std::logic_error("fill of a sector without MSHR");
    Mshr& m = mshr_pool_[it->second];
    Tokens tokens = std::move(m.tokens);
    const bool unused_prefetch = m.prefetch && !m.demanded;
    const bool by_prefetch = m.prefetch;
    const ReqKind kind = m.kind;
    mshr_unused_.push_back(it->second);
    mshr_.erase(it);
    const auto [line, bit] = place_of(sector_addr);
    Way* w = find(line);
    if (on_fill_) {
        // The line takes its way now (the policy's victim, never held: no way is pending), or its
        // sector is filled into the way it has; either way the line is used now (tag_array::fill,
        // gpu-cache.cc l.416-434).
        if (!w) w = allocate(line, &counts_.of(kind));
        touch(*w);
    } else if (!w) {
        throw std::logic_error("fill of a sector whose line was evicted while pending");
    }
    w->pending &= ~bit;
    w->valid |= bit;
    if (unused_prefetch) w->prefetched |= bit;
    w->line_prefetched = by_prefetch;  // every fill sets or clears it (gpu-cache.cc l.412, l.420)
    ++counts_.fills;
    if (by_prefetch) ++counts_.prefetched.fills;
    return tokens;
}

}  // namespace rtu
