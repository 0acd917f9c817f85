#include "rt_unit.h"

#include <algorithm>
#include <queue>

namespace rtu {

using namespace sc_core;

RtUnit::RtUnit(sc_module_name name, uint32_t sm, const HwConfig& cfg, const BvhImage& image, TraversalOrder order,
               TraceSource& source, PayloadPool& pool, const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events,
               const Treelets* treelets)
    : sc_module(name), socket("to_l1"), sm_(sm), core_(cfg, image, order, treelets), image_(image), source_(source), pool_(pool),
      clock_(clock), at_(fidelity == Fidelity::AT),
      // After the memory side's handlers of the same time (its deliveries first), and among the RT
      // units as LT steps them: SM c mod n first in cycle c (tlm/ordered_events.h).
      wake_(events, [this] { tick(); },
            [this, n = cfg.sms](uint64_t t) {
                const uint64_t c = clock_.cycle_at_or_after(sc_time::from_value(t));
                return uint32_t(1 + (sm_ + n - c % n) % n);
            }) {
    if (at_) {
        socket.register_nb_transport_bw(this, &RtUnit::nb_transport_bw);
        wake_.notify(SC_ZERO_TIME);  // runs once at time 0, then only when woken
    }  // LT: the RT complex steps it (lt_run)
}

void RtUnit::set_shader_reads(const ShaderReads& reads, std::function<bool(uint64_t, uint64_t)> read) {
    shader_.start(sm_, reads);
    shader_read_ = std::move(read);
}

void RtUnit::retire(const std::vector<RetiredRay>& rays, uint64_t c) {
    if (rays.empty()) return;
    source_.retire(sm_, rays, c);
    shader_.owe(rays.size());
}

void RtUnit::shader_cycle(uint64_t c) {
    if (shader_.owed() == 0 || !shader_read_(shader_.next(), c)) return;
    shader_.issued();
    core_.count_shader_read();
}

void RtUnit::wake_at(uint64_t cycle) {
    const sc_time t = clock_.time_of(cycle);
    wake_.notify(t > sc_time_stamp() ? t - sc_time_stamp() : SC_ZERO_TIME);
}

void RtUnit::wake(bool new_epoch) {
    const uint64_t c = clock_.cycle_at_or_after(sc_time_stamp());
    if (new_epoch) last_cycle_ = ~0ull;  // the cycle numbers restarted: cycle 0 is yet to run
    lt_.next = std::min(lt_.next, c);
    if (at_) wake_at(c);
}

tlm::tlm_generic_payload* RtUnit::make_payload(const ChunkRequest& r) {
    // Data comes straight from the backing store (the BVH image); timing from the transaction.
    auto* t = pool_.acquire(r.addr, kChunkBytes, const_cast<unsigned char*>(image_.at(r.image_addr, kChunkBytes)));
    RtExtension& e = ext(*t);
    e.sm = sm_;
    e.warp = r.warp;
    e.thread = r.thread;
    e.id = r.id;
    e.kind = r.prefetch ? ReqKind::Prefetch : ReqKind::Demand;
    e.streak = r.streak;
    return t;
}

void RtUnit::pull_work(uint64_t c) {
    while (core_.has_free_slot()) {
        auto trace = source_.next_trace(sm_, c);
        if (!trace) break;
        core_.accept_warp(*trace, c);
    }
}

void RtUnit::tick() {
    const uint64_t c = clock_.cycle_at_or_after(sc_time_stamp());
    if (clock_.time_of(c) != sc_time_stamp()) return wake_at(c);  // align to the clock edge
    if (c != last_cycle_) {
        last_cycle_ = c;
        pull_work(c);
        // At most one 32 B request leaves per cycle.
        if (!waiting_end_req_ && core_.has_request(c)) {
            tlm::tlm_generic_payload* t = make_payload(core_.front_request(c));
            tlm::tlm_phase ph = tlm::BEGIN_REQ;
            sc_time d = SC_ZERO_TIME;
            const tlm::tlm_sync_enum s = socket->nb_transport_fw(*t, ph, d);
            if (s == tlm::TLM_UPDATED && ph == tlm::END_REQ) {
                core_.pop_request(c);
            } else if (s == tlm::TLM_ACCEPTED) {
                waiting_end_req_ = true;
            } else {
                SC_REPORT_FATAL(name(), "unexpected reply to BEGIN_REQ");
            }
        }
        core_.cycle(c);
        admit_held_response(c);
        retire(core_.take_retired(), c);
        shader_cycle(c);
        if (on_cycle) on_cycle(c);
    }
    uint64_t next = core_.next_event(c);
    if (!waiting_end_req_ && core_.has_request(c + 1)) next = c + 1;
    if (shader_.owed()) next = std::min(next, c + 1);
    if (core_.has_free_slot()) {
        const uint64_t r = source_.earliest_ready(sm_);
        if (r != ~0ull) next = std::min(next, std::max(c + 1, r));
    }
    if (next != ~0ull) wake_at(next);
}

tlm::tlm_sync_enum RtUnit::nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    const uint64_t c = clock_.cycle_at_or_after(sc_time_stamp() + d);
    if (ph == tlm::END_REQ) {
        waiting_end_req_ = false;
        core_.pop_request(c);
        wake_at(std::max(c, last_cycle_ == ~0ull ? 0 : last_cycle_ + 1));
        return tlm::TLM_ACCEPTED;
    }
    if (ph == tlm::BEGIN_RESP) {
        const RtExtension& e = ext(t);
        if (!core_.takes_response()) {
            // The response FIFO is full: the response waits in the L1, which sends no other
            // until END_RESP (the base protocol's response exclusion).
            held_response_ = &t;
            return tlm::TLM_ACCEPTED;
        }
        core_.on_response(e.id, e.l1_miss, e.dram, c);
        t.release();
        wake_at(std::max(c, last_cycle_ == ~0ull ? 0 : last_cycle_ + 1));
        return tlm::TLM_COMPLETED;
    }
    SC_REPORT_FATAL(name(), "unexpected phase on the backward path");
    return tlm::TLM_COMPLETED;
}

// A response held back by a full response FIFO comes in once the FIFO has drained one.
void RtUnit::admit_held_response(uint64_t c) {
    if (!held_response_ || !core_.takes_response()) return;
    tlm::tlm_generic_payload* t = held_response_;
    held_response_ = nullptr;
    const RtExtension& e = ext(*t);
    core_.on_response(e.id, e.l1_miss, e.dram, c);
    tlm::tlm_phase ph = tlm::END_RESP;
    sc_time d = SC_ZERO_TIME;
    socket->nb_transport_fw(*t, ph, d);
    t->release();
}

// LT: the unit's cycles from its next one up to `end` (exclusive), sending its requests by
// blocking transport annotated with their cycle's offset from the current simulated time.
void RtUnit::lt_run(uint64_t end) {
    LtState& st = lt_;
    uint64_t c = st.next;
    while (c < end) {
        last_cycle_ = c;
        // Responses due enter the response FIFO while it has room (the rest wait in the L1).
        while (!st.responses.empty() && st.responses.top().at <= c && core_.takes_response()) {
            core_.on_response(st.responses.top().id, st.responses.top().l1_miss, st.responses.top().dram, c);
            st.responses.pop();
        }
        pull_work(c);
        if (c >= st.port_free && core_.has_request(c)) {
            tlm::tlm_generic_payload* t = make_payload(core_.front_request(c));
            sc_time d = clock_.time_of(c) - sc_time_stamp();
            socket->b_transport(*t, d);
            const RtExtension& e = ext(*t);
            st.port_free = e.accepted_at + 1;
            st.responses.push({std::max(c + 1, clock_.cycle_at_or_after(sc_time_stamp() + d)), st.sent++, e.id, e.l1_miss, e.dram});
            t->release();
            core_.pop_request(c);
        }
        core_.cycle(c);
        retire(core_.take_retired(), c);
        shader_cycle(c);
        if (on_cycle) on_cycle(c);

        uint64_t next = core_.next_event(c);
        if (core_.has_request(c + 1)) next = std::max(c + 1, st.port_free);
        if (shader_.owed()) next = std::min(next, c + 1);  // the shader port has its own cycles
        if (!st.responses.empty()) next = std::min(next, std::max(c + 1, st.responses.top().at));
        if (core_.has_free_slot()) {
            const uint64_t r = source_.earliest_ready(sm_);
            if (r != ~0ull) next = std::min(next, std::max(c + 1, r));
        }
        c = next;  // ~0: nothing in flight and no trace will come for this SM
    }
    st.next = c;
}

}  // namespace rtu
