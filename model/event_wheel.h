// A queue of timed events handed out in order of (at, seq), the same order as a min-heap on that
// pair, for event times that mostly fall within a short window after the earliest one (the
// interval fidelity's node fetches: a few hundred cycles ahead at most). Events in the window
// [base, base + kWindow) sit in one FIFO per cycle; `seq` must grow with every push (a
// scheduling counter), so each FIFO is in seq order. Events outside the window, before it or
// beyond it, go to a heap, and pop takes the smaller of the two fronts, so any push order is
// handed out exactly as the heap alone would. T needs fields `at` and `seq`.
#pragma once
#include <cstdint>
#include <queue>
#include <vector>

namespace rtu {

template <class T>
class EventWheel {
public:
    static constexpr uint64_t kWindow = 1024;  // cycles; a power of two

    bool empty() const { return in_wheel_ == 0 && far_.empty(); }
    size_t size() const { return in_wheel_ + far_.size(); }

    void push(const T& e) {
        if (e.at >= base_ && e.at < base_ + kWindow) {
            buckets_[e.at & (kWindow - 1)].items.push_back(e);
            ++in_wheel_;
        } else {
            far_.push(e);
        }
    }
    // The next event; the queue must not be empty.
    const T& top() const {
        const T* w = wheel_front();
        if (!w) return far_.top();
        if (far_.empty() || before(*w, far_.top())) return *w;
        return far_.top();
    }
    void pop() {
        const T* w = wheel_front();
        if (w && (far_.empty() || before(*w, far_.top()))) {
            Bucket& b = buckets_[base_ & (kWindow - 1)];
            if (++b.head == b.items.size()) {
                b.items.clear();
                b.head = 0;
            }
            --in_wheel_;
        } else {
            // An empty window may start anywhere: move it to the time handed out, so that the
            // events scheduled from it land in the window again.
            if (in_wheel_ == 0 && far_.top().at > base_) base_ = far_.top().at;
            far_.pop();
        }
    }

private:
    struct Bucket {
        std::vector<T> items;
        size_t head = 0;
    };
    struct Later {
        bool operator()(const T& a, const T& b) const { return before(b, a); }
    };
    static bool before(const T& a, const T& b) { return a.at != b.at ? a.at < b.at : a.seq < b.seq; }

    // The first event of the earliest non-empty cycle of the window, moving the window up to it
    // (every event in the window is at or after base_, so nothing is passed over).
    const T* wheel_front() const {
        if (in_wheel_ == 0) return nullptr;
        while (buckets_[base_ & (kWindow - 1)].items.empty()) ++base_;
        const Bucket& b = buckets_[base_ & (kWindow - 1)];
        return &b.items[b.head];
    }

    std::vector<Bucket> buckets_ = std::vector<Bucket>(kWindow);
    mutable uint64_t base_ = 0;  // moved by top() too, over empty cycles only
    size_t in_wheel_ = 0;
    std::priority_queue<T, std::vector<T>, Later> far_;
};

}  // namespace rtu
