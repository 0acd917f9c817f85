// The RT complex's own queue of timed events (AT). The SystemC kernel runs the processes due at the
// same time in an order of its own: its timed queue is a heap, not first-in first-out for equal
// times, so any other process in the simulation (rtsim's monitor, an SoC's CPU, a second RT complex)
// changes which of two same-cycle interactions of the RT complex comes first, and with it AT's
// cycles (wknd primary rays 24x24: 1,955 cycles in rtsim, 1,962 without its monitor; an SoC
// peripheral's job 899 against rtsim's 914 on the same rays).
//
// So the AT modules of one RT complex have no processes of their own. Each of their event
// handlers is an OrderedEvent of one OrderedEvents queue, which has one method process: at each
// time it runs the handlers due in the order (time, rank, notification). The rank is the
// event's: 0 for the memory side (caches, crossbar, DRAM), above 0 for the RT units, so that a
// cycle's deliveries (responses, END_REQ) reach an RT unit before that unit's cycle runs, as LT's
// RT unit takes the responses due before its cycle (tlm/rt_unit.cpp). The RT units rank among
// themselves by the cycle, as LT steps them (tlm/rt_complex.cpp: SM c mod n first in cycle c),
// since they share the trace source. A handler notified for the current time runs after those
// already due of its rank or below, as a delta notification would. The order is the complex's
// own, whatever else runs in the simulation; the kernel decides only when the queue's process
// runs among the other processes of that time, which nothing inside the complex can see.
//
// An OrderedEvent keeps sc_event's rule for a notification already pending: the earlier one wins
// (a later notification is dropped, an earlier one replaces it).
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <systemc>

namespace rtu {

class OrderedEvents;

class OrderedEvent {
public:
    // `rank`: the handler's rank among those due at a kernel time (sc_time value); none: 0.
    OrderedEvent(OrderedEvents& queue, std::function<void()> handler, std::function<uint32_t(uint64_t)> rank = {})
        : queue_(queue), handler_(std::move(handler)), rank_(std::move(rank)) {}
    OrderedEvent(const OrderedEvent&) = delete;
    OrderedEvent& operator=(const OrderedEvent&) = delete;
    // The handler runs `delay` from now (SC_ZERO_TIME: at this time, after the handlers already due).
    inline void notify(const sc_core::sc_time& delay);

private:
    friend class OrderedEvents;
    OrderedEvents& queue_;
    std::function<void()> handler_;
    std::function<uint32_t(uint64_t)> rank_;
    bool pending_ = false;
    uint64_t at_ = 0;          // kernel time (sc_time value) of the pending notification
    uint64_t generation_ = 0;  // which queue entry is the pending one (replaced ones are skipped)
};

class OrderedEvents : public sc_core::sc_module {
public:
    SC_HAS_PROCESS(OrderedEvents);
    explicit OrderedEvents(sc_core::sc_module_name name) : sc_module(name), wake_("wake") {
        SC_METHOD(run);  // also at initialization: handlers notified during elaboration run at time 0
        sensitive << wake_;
    }
    bool empty() const { return times_.empty(); }

private:
    friend class OrderedEvent;
    // The kernel time (sc_time value): while the queue's process runs, the time it was woken at
    // (the kernel's time cannot move inside a process), without a call into the kernel.
    uint64_t now() const { return running_ ? now_ : sc_core::sc_time_stamp().value(); }
    struct Entry {
        OrderedEvent* event;
        uint64_t generation;
    };
    // The handlers notified for one time: a FIFO per rank. Appending keeps each FIFO in
    // notification order, so taking the lowest rank's front each time runs them in the order
    // (rank, notification). Buckets are reused, their vectors keeping their capacity.
    struct Bucket {
        std::vector<std::vector<Entry>> by_rank;
        std::vector<size_t> head;
        uint32_t lowest = ~0u;
        void add(uint32_t rank, const Entry& e) {
            if (rank >= by_rank.size()) {
                by_rank.resize(rank + 1);
                head.resize(rank + 1);
            }
            by_rank[rank].push_back(e);
            lowest = std::min(lowest, rank);
        }
        // The next entry in order, or null when none is left (then the bucket is empty again).
        const Entry* next() {
            for (; lowest < by_rank.size(); ++lowest) {
                if (head[lowest] < by_rank[lowest].size()) return &by_rank[lowest][head[lowest]++];
                by_rank[lowest].clear();
                head[lowest] = 0;
            }
            lowest = ~0u;
            return nullptr;
        }
    };

    // Most notifications are for the current time (a zero delay) or the next core clock edge, so
    // the last bucket used is kept at hand.
    Bucket& bucket(uint64_t at) {
        if (last_ && at == last_at_) return *last_;
        // times_ is sorted latest first: the earliest time is at the back.
        auto it = std::lower_bound(times_.begin(), times_.end(), at, [](const Time& t, uint64_t a) { return t.at > a; });
        if (it == times_.end() || it->at != at) {
            Bucket* b;
            if (free_.empty()) {
                buckets_.emplace_back(new Bucket);
                b = buckets_.back().get();
            } else {
                b = free_.back();
                free_.pop_back();
            }
            it = times_.insert(it, Time{at, b});
        }
        last_at_ = at;
        last_ = it->bucket;
        return *last_;
    }
    void push(OrderedEvent& e, uint64_t at) {
        bucket(at).add(e.rank_ ? e.rank_(at) : 0u, {&e, e.generation_});
        // Inside run() the loop takes it (or re-arms for it); during elaboration run() comes at
        // initialization. Otherwise (a call from another process) the kernel keeps the earliest
        // notification of wake_.
        if (!running_ && sc_core::sc_is_running()) arm();
    }
    void arm() {
        if (times_.empty()) return;
        const uint64_t now = sc_core::sc_time_stamp().value();
        const uint64_t at = times_.back().at;
        wake_.notify(at > now ? sc_core::sc_time::from_value(at - now) : sc_core::SC_ZERO_TIME);
    }
    void run() {
        now_ = sc_core::sc_time_stamp().value();
        running_ = true;
        // Handlers of this time notified while it runs join its bucket, which stays in the list
        // until it is empty (a later time's insertion never moves it: it is the earliest, at the back).
        while (!times_.empty() && times_.back().at <= now_) {
            Bucket* b = times_.back().bucket;
            while (const Entry* e = b->next()) {
                OrderedEvent& ev = *e->event;
                if (!ev.pending_ || ev.generation_ != e->generation) continue;  // replaced by an earlier notification
                ev.pending_ = false;
                ev.handler_();
            }
            if (last_ == b) last_ = nullptr;
            times_.pop_back();
            free_.push_back(b);
        }
        running_ = false;
        arm();
    }

    sc_core::sc_event wake_;
    // The kernel times with handlers due, latest first, each with its handlers. They are few: an
    // event has at most one notification pending (a replaced one's entry stays, skipped, until
    // its time comes), and the complex has a handful of events per module. So a sorted vector,
    // whose earliest entry leaves from the back, does without a tree's node per time.
    struct Time {
        uint64_t at;
        Bucket* bucket;
    };
    std::vector<Time> times_;
    std::vector<std::unique_ptr<Bucket>> buckets_;
    std::vector<Bucket*> free_;
    uint64_t last_at_ = 0;
    Bucket* last_ = nullptr;
    bool running_ = false;
    uint64_t now_ = 0;  // the time run() was woken at (valid while running_)
};

inline void OrderedEvent::notify(const sc_core::sc_time& delay) {
    const uint64_t at = queue_.now() + delay.value();  // sc_time's sum is its values' sum
    if (pending_ && at_ <= at) return;  // an earlier (or the same) notification is pending
    pending_ = true;
    at_ = at;
    ++generation_;
    queue_.push(*this, at);
}

}  // namespace rtu
