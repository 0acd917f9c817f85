// Payload event queues on an OrderedEvent (tlm/ordered_events.h), whose handler takes the
// payloads due with get_next_transaction, as tlm_utils::peq_with_get's process would.
//  - FifoPeq: for producers whose deliveries come due in the order they are queued (a fixed
//    latency per queue), without peq_with_get's ordered map (one tree node allocated and freed
//    per transaction). Out-of-order use is a logic error, never silent.
//  - TimedPeq: any order of due times (the DRAM's answers); payloads due at the same time leave
//    in the order they were queued.
#pragma once
#include <cstdint>
#include <deque>
#include <queue>
#include <stdexcept>
#include <vector>

#include <systemc>

#include "ordered_events.h"

namespace rtu {

template <class T>
class FifoPeq {
public:
    explicit FifoPeq(OrderedEvent& event) : event_(&event), seq_(&own_seq_) {}
    // Queues that merge (merge_next) share one event and one sequence counter, so that they
    // notify and hand out exactly as a single peq_with_get holding both would.
    FifoPeq(OrderedEvent& shared, uint64_t& sequence) : event_(&shared), seq_(&sequence) {}

    void notify(T& t, const sc_core::sc_time& delay) {
        const sc_core::sc_time at = sc_core::sc_time_stamp() + delay;
        if (!q_.empty() && at < q_.back().at) throw std::logic_error("FifoPeq: a delivery due before the one queued last");
        q_.push_back({at, (*seq_)++, &t});
        event_->notify(delay);
    }
    // The next payload due by now, or nullptr (then the event is notified for the next one).
    T* get_next_transaction() {
        if (q_.empty()) return nullptr;
        const sc_core::sc_time now = sc_core::sc_time_stamp();
        if (q_.front().at > now) {
            event_->notify(q_.front().at - now);
            return nullptr;
        }
        T* t = q_.front().t;
        q_.pop_front();
        return t;
    }

    // Of two queues sharing an event and a sequence counter: the payload due by now that one
    // peq_with_get holding both would hand out next, or nullptr (the shared event is then
    // notified for the earlier of the two fronts, as that peq_with_get would notify it).
    static T* merge_next(FifoPeq& a, FifoPeq& b) {
        const sc_core::sc_time now = sc_core::sc_time_stamp();
        const bool da = a.due(now), db = b.due(now);
        if (da && db) return a.before(b) ? a.get_next_transaction() : b.get_next_transaction();
        if (da) return a.get_next_transaction();
        if (db) return b.get_next_transaction();
        // Neither is due: notify for the earlier of the two fronts only.
        if (!a.q_.empty() && (b.q_.empty() || a.before(b))) return a.get_next_transaction();
        return b.get_next_transaction();
    }

private:
    struct Entry {
        sc_core::sc_time at;
        uint64_t seq;
        T* t;
    };
    bool due(const sc_core::sc_time& now) const { return !q_.empty() && q_.front().at <= now; }
    bool before(const FifoPeq& o) const {
        return q_.front().at < o.q_.front().at || (q_.front().at == o.q_.front().at && q_.front().seq < o.q_.front().seq);
    }

    OrderedEvent* event_;
    std::deque<Entry> q_;
    uint64_t own_seq_ = 0;
    uint64_t* seq_;
};

template <class T>
class TimedPeq {
public:
    explicit TimedPeq(OrderedEvent& event) : event_(event) {}
    void notify(T& t, const sc_core::sc_time& delay) {
        const uint64_t at = (sc_core::sc_time_stamp() + delay).value();
        q_.push({at, seq_++, &t});
        event_.notify(delay);
    }
    // The next payload due by now, or nullptr (then the event is notified for the next one).
    T* get_next_transaction() {
        if (q_.empty()) return nullptr;
        const uint64_t now = sc_core::sc_time_stamp().value();
        if (q_.top().at > now) {
            event_.notify(sc_core::sc_time::from_value(q_.top().at - now));
            return nullptr;
        }
        T* t = q_.top().t;
        q_.pop();
        return t;
    }

private:
    struct Entry {
        uint64_t at, seq;
        T* t;
        bool operator>(const Entry& o) const { return at != o.at ? at > o.at : seq > o.seq; }
    };
    OrderedEvent& event_;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> q_;
    uint64_t seq_ = 0;
};

}  // namespace rtu
