// Booking of a shared resource by request timestamp (LT and interval fidelities): a request asks for `len`
// cycles starting at its own timestamp and gets the earliest free gap at or after it, whatever
// order the requests arrive in. Bookings behind simulated time are dropped as it advances.
#pragma once
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <utility>
#include <vector>

namespace rtu {

class Calendar {
public:
    // Books [s, s + len) with s >= start the earliest free gap; returns s. Bookings that end by
    // `horizon` are forgotten first: no request can be timestamped before it (in LT no
    // requester is behind simulated time).
    uint64_t book(uint64_t start, uint64_t len, uint64_t horizon = 0) {
        while (head_ < busy_.size() && busy_[head_].second <= horizon) ++head_;
        if (head_ > 64 && head_ * 2 > busy_.size()) compact();
        if (len == 0) return start;
        size_t i;
        const uint64_t s = find(start, len, &i);
        // [s, s + len) is free; bookings before i end by s, those from i start at s + len or later.
        // Merge with neighbours that touch it.
        const uint64_t e = s + len;
        const bool left = i > head_ && busy_[i - 1].second == s;
        const bool right = i < busy_.size() && busy_[i].first == e;
        if (left && right) {
            busy_[i - 1].second = busy_[i].second;
            busy_.erase(busy_.begin() + long(i));
        } else if (left) {
            busy_[i - 1].second = e;
        } else if (right) {
            busy_[i].first = s;
        } else {
            busy_.insert(busy_.begin() + long(i), Interval{s, e});
        }
        if (intervals() > 4096) prune();
        return s;
    }
    // The s that book(start, len) would return, left free.
    uint64_t first_free(uint64_t start, uint64_t len) const {
        size_t i;
        return len == 0 ? start : find(start, len, &i);
    }
    size_t intervals() const { return busy_.size() - head_; }

private:
    using Interval = std::pair<uint64_t, uint64_t>;  // [start, end)
    // The earliest free [s, s + len), s >= start and the floor; *at: the first booking after it.
    uint64_t find(uint64_t start, uint64_t len, size_t* at) const {
        uint64_t s = std::max(start, floor_);
        // The first booking that starts after s; the one before it may cover s.
        size_t i = size_t(std::upper_bound(busy_.begin() + long(head_), busy_.end(), s,
                                           [](uint64_t v, const Interval& x) { return v < x.first; }) -
                          busy_.begin());
        if (i > head_ && busy_[i - 1].second > s) s = busy_[i - 1].second;
        while (i < busy_.size() && busy_[i].first < s + len) {
            s = std::max(s, busy_[i].second);
            ++i;
        }
        *at = i;
        return s;
    }
    void compact() {
        busy_.erase(busy_.begin(), busy_.begin() + long(head_));
        head_ = 0;
    }
    void prune() {
        // Keep the newest half: requests are at most a quantum behind the newest bookings.
        const size_t keep_from = head_ + intervals() / 2;
        floor_ = std::max(floor_, busy_[keep_from].first);
        head_ = keep_from;
        compact();
    }
    // Disjoint bookings sorted by start; those before head_ are forgotten. A sorted vector: no
    // allocation per booking, and few bookings are live at once.
    std::vector<Interval> busy_;
    size_t head_ = 0;
    uint64_t floor_ = 0;
};

// A port that takes one request per cycle (the RT unit's request port, its response FIFO's
// drain, an L2 slice's lookup), booked by timestamp in any order as long as no request is
// timestamped before the floor (advance()). One bit per cycle in a ring of words that grows when
// a booking runs past it: O(1) for the usual booking near the floor, where Calendar searches its
// bookings.
class PortCalendar {
public:
    // The earliest free cycle at or after `t` (and the floor), now taken.
    uint64_t book(uint64_t t) {
        const uint64_t c = first_free(t);
        word(c >> 6) |= uint64_t(1) << (c & 63);
        return c;
    }
    // The earliest free cycle at or after `t` (and the floor), left free.
    uint64_t first_free(uint64_t t) {
        if (t < floor_) t = floor_;
        uint64_t w = t >> 6;
        uint64_t bits = word(w) | ((uint64_t(1) << (t & 63)) - 1);  // cycles before t count as taken
        while (bits == ~uint64_t(0)) bits = word(++w);
        return (w << 6) | unsigned(__builtin_ctzll(~bits));
    }
    // Takes every cycle of [from, to] (a port held by a request that waits for END_REQ).
    void hold(uint64_t from, uint64_t to) {
        for (uint64_t c = std::max(from, floor_); c <= to; ++c) word(c >> 6) |= uint64_t(1) << (c & 63);
    }
    // No booking will be timestamped before `floor` again: the ring's words behind it are reused.
    void advance(uint64_t floor) {
        if (floor <= floor_) return;
        const uint64_t from = floor_ >> 6, to = floor >> 6;
        if (to - from >= ring_.size()) {
            std::fill(ring_.begin(), ring_.end(), 0);
        } else {
            for (uint64_t w = from; w < to; ++w) ring_[w & (ring_.size() - 1)] = 0;
        }
        floor_ = floor;
    }

private:
    // The ring covers words [floor_ / 64, floor_ / 64 + size).
    uint64_t& word(uint64_t w) {
        while (w - (floor_ >> 6) >= ring_.size()) grow();
        return ring_[w & (ring_.size() - 1)];
    }
    void grow() {
        std::vector<uint64_t> bigger(ring_.size() * 2, 0);
        const uint64_t base = floor_ >> 6;
        for (uint64_t w = base; w < base + ring_.size(); ++w) bigger[w & (bigger.size() - 1)] = ring_[w & (ring_.size() - 1)];
        ring_.swap(bigger);
    }
    std::vector<uint64_t> ring_ = std::vector<uint64_t>(1024, 0);  // 65,536 cycles to start with
    uint64_t floor_ = 0;
};

}  // namespace rtu
