// Booking of a shared resource by request timestamp (LT fidelity): a request asks for `len`
// cycles starting at its own timestamp and gets the earliest free gap at or after it, whatever
// order the requests arrive in. Bookings behind simulated time are dropped as it advances.
#pragma once
#include <cstdint>
#include <iterator>
#include <map>

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

}  // namespace rtu
