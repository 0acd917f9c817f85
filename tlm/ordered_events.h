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
#include <cstdint>
#include <functional>
#include <queue>
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
    bool empty() const { return due_.empty(); }

private:
    friend class OrderedEvent;
    struct Entry {
        uint64_t at;
        uint32_t rank;
        uint64_t seq;
        OrderedEvent* event;
        uint64_t generation;
        bool operator>(const Entry& o) const {
            if (at != o.at) return at > o.at;
            return rank != o.rank ? rank > o.rank : seq > o.seq;
        }
    };

    void push(OrderedEvent& e, uint64_t at) {
        due_.push({at, e.rank_ ? e.rank_(at) : 0u, seq_++, &e, e.generation_});
        // Inside run() the loop takes it (or re-arms for it); during elaboration run() comes at
        // initialization. Otherwise (a call from another process) the kernel keeps the earliest
        // notification of wake_.
        if (!running_ && sc_core::sc_is_running()) arm();
    }
    void arm() {
        if (due_.empty()) return;
        const uint64_t now = sc_core::sc_time_stamp().value();
        const uint64_t at = due_.top().at;
        wake_.notify(at > now ? sc_core::sc_time::from_value(at - now) : sc_core::SC_ZERO_TIME);
    }
    void run() {
        const uint64_t now = sc_core::sc_time_stamp().value();
        running_ = true;
        while (!due_.empty() && due_.top().at <= now) {
            const Entry e = due_.top();
            due_.pop();
            OrderedEvent& ev = *e.event;
            if (!ev.pending_ || ev.generation_ != e.generation) continue;  // replaced by an earlier notification
            ev.pending_ = false;
            ev.handler_();
        }
        running_ = false;
        arm();
    }

    sc_core::sc_event wake_;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> due_;
    uint64_t seq_ = 0;
    bool running_ = false;
};

inline void OrderedEvent::notify(const sc_core::sc_time& delay) {
    const uint64_t at = (sc_core::sc_time_stamp() + delay).value();
    if (pending_ && at_ <= at) return;  // an earlier (or the same) notification is pending
    pending_ = true;
    at_ = at;
    ++generation_;
    queue_.push(*this, at);
}

}  // namespace rtu
