// Booking of a shared resource by request timestamp (LT fidelity): a request asks for `len`
// cycles starting at its own timestamp and gets the earliest free gap at or after it, whatever
// order the requests arrive in. Bookings behind simulated time are dropped as it advances.
#pragma once
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <map>
#include <vector>

namespace rtu {

class Calendar {
public:
    // Books [s, s + len) with s >= start the earliest free gap; returns s. Bookings that end by
    // `horizon` are forgotten first: no request can be timestamped before it (in LT no
    // requester is behind simulated time).
    uint64_t book(uint64_t start, uint64_t len, uint64_t horizon = 0) {
        while (!busy_.empty() && busy_.begin()->second <= horizon) busy_.erase(busy_.begin());
        if (len == 0) return start;
        uint64_t s = std::max(start, floor_);
        auto it = busy_.upper_bound(s);
        if (it != busy_.begin()) {
            auto prev = std::prev(it);
            if (prev->second > s) s = prev->second;
        }
        while (it != busy_.end() && it->first < s + len) {
            s = std::max(s, it->second);
            ++it;
        }
        // Merge with neighbours that touch the new interval.
        uint64_t b = s, e = s + len;
        auto right = busy_.find(e);
        if (right != busy_.end()) {
            e = right->second;
            busy_.erase(right);
        }
        auto after = busy_.upper_bound(b);
        if (after != busy_.begin()) {
            auto left = std::prev(after);
            if (left->second == b) {
                b = left->first;
                busy_.erase(left);
            }
        }
        busy_[b] = e;
        if (busy_.size() > 4096) prune();
        return s;
    }
    size_t intervals() const { return busy_.size(); }

private:
    void prune() {
        // Keep the newest half: requests are at most a quantum behind the newest bookings.
        auto it = busy_.begin();
        std::advance(it, long(busy_.size() / 2));
        floor_ = std::max(floor_, it->first);
        busy_.erase(busy_.begin(), it);
    }
    std::map<uint64_t, uint64_t> busy_;  // start -> end
    uint64_t floor_ = 0;
};

// A port that takes one request per cycle (the RT unit's request port, its response FIFO's
// drain, an L2 slice's lookup), booked by timestamp in any order as long as no request is
// timestamped before the floor (advance()). One bit per cycle in a ring of words that grows when
// a booking runs past it: O(1) for the usual booking near the floor, unlike Calendar's tree.
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

