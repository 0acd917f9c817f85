// A payload event queue for producers whose deliveries come due in the order they are queued
// (a fixed latency per queue): the same interface and delivery order as
// tlm_utils::peq_with_get, without its ordered map (one tree node allocated and freed per
// transaction). Out-of-order use is a logic error, never silent.
#pragma once
#include <cstdint>
#include <deque>
#include <stdexcept>

#include <systemc>

namespace rtu {

template <class T>
class FifoPeq {
public:
    explicit FifoPeq(const char* name) : own_event_(name), event_(&own_event_), seq_(&own_seq_) {}
    // Queues that merge (merge_next) share one event and one sequence counter, so that they
    // notify and hand out exactly as a single peq_with_get holding both would (same event
    // notifications, so the kernel runs processes in the same order).
    FifoPeq(sc_core::sc_event& shared, uint64_t& sequence) : event_(&shared), seq_(&sequence) {}

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
    sc_core::sc_event& get_event() { return *event_; }

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

    sc_core::sc_event own_event_;
    sc_core::sc_event* event_;
    std::deque<Entry> q_;
    uint64_t own_seq_ = 0;
    uint64_t* seq_;
};

}  // namespace rtu
