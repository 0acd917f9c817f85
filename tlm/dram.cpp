#include "dram.h"

#include <algorithm>

namespace rtu {

using namespace sc_core;

Dram::Dram(sc_module_name name, const DramConfig& cfg, const AddressMap& map, const ClockDomain& clock, const sc_time& core_period,
           Fidelity fidelity, OrderedEvents& events)
    : sc_module(name), in("from_l2"), cfg_(cfg), map_(map), clock_(clock), blocked_(cfg.channels),
      frontend_(core_period * double(cfg.frontend_latency)), wake_(events, [this] { schedule(); }),
      frontend_due_(events, [this] { leave_frontend(); }), resp_due_(events, [this] { respond(); }), frontend_peq_(frontend_due_),
      waiting_(cfg.channels), resp_peq_(resp_due_), lt_(cfg, map) {
    for (uint32_t c = 0; c < cfg.channels; ++c) channels_.emplace_back(cfg);
    if (fidelity == Fidelity::AT) {
        in.register_nb_transport_fw(this, &Dram::nb_transport_fw);
    } else {
        in.register_b_transport(this, &Dram::b_transport);
    }
}

std::vector<DramStats> Dram::stats() const {
    std::vector<DramStats> s = lt_.stats();  // LT's bookings (AT's are zero)
    for (size_t c = 0; c < channels_.size(); ++c) add(s[c], channels_[c].stats());
    return s;
}

size_t Dram::queue_depth() const {
    size_t n = 0;
    for (const DramChannel& c : channels_) n += c.depth();
    return n;
}

bool Dram::admit(tlm::tlm_generic_payload& t, uint64_t now) {
    const DramCoord at = map_.dram(t.get_address());
    DramChannel& ch = channels_[at.channel];
    if (ch.full()) return false;
    DramRequest r;
    r.addr = t.get_address();
    r.bytes = t.get_data_length();
    r.write = t.is_write();
    r.token = reinterpret_cast<uint64_t>(&t);
    r.arrival = now;
    r.at = at;
    ch.enqueue(r);
    return true;
}

tlm::tlm_sync_enum Dram::nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    if (ph == tlm::END_RESP) return tlm::TLM_COMPLETED;
    if (ph != tlm::BEGIN_REQ) SC_REPORT_FATAL(name(), "unexpected phase on the forward path");
    ext(t).source = uint32_t(id);
    t.acquire();
    if (cfg_.frontend_latency) {  // the latency queue takes every request at once
        frontend_peq_.notify(t, frontend_);
        ph = tlm::END_REQ;
        return tlm::TLM_UPDATED;
    }
    wake_.notify(SC_ZERO_TIME);
    if (admit(t, clock_.cycle_at_or_after(sc_time_stamp()))) {
        ph = tlm::END_REQ;
        return tlm::TLM_UPDATED;
    }
    blocked_[map_.dram(t.get_address()).channel].push_back(&t);
    return tlm::TLM_ACCEPTED;
}

// Out of the latency queue, in arrival order, into the channel's queue (or behind the requests
// of that channel still waiting for room).
void Dram::leave_frontend() {
    while (tlm::tlm_generic_payload* t = frontend_peq_.get_next_transaction()) {
        const uint32_t c = map_.dram(t->get_address()).channel;
        if (!waiting_[c].empty() || !admit(*t, clock_.cycle_at_or_after(sc_time_stamp()))) waiting_[c].push_back(t);
        wake_.notify(SC_ZERO_TIME);
    }
}

void Dram::schedule() {
    const uint64_t now = clock_.cycle_at_or_after(sc_time_stamp());
    uint64_t next = ~0ull;
    for (uint32_t c = 0; c < channels_.size(); ++c) {
        DramChannel& ch = channels_[c];
        if (ch.empty()) continue;
        const uint64_t decision = ch.next_decision();  // a scan of the banks: once
        if (decision > now) {
            next = std::min(next, decision);
            continue;
        }
        DramRequest r;
        uint64_t done;
        if (ch.schedule(now, &r, &done)) {
            auto* t = reinterpret_cast<tlm::tlm_generic_payload*>(r.token);
            resp_peq_.notify(*t, clock_.time_of(done) - sc_time_stamp());
        }
        // A queue slot may have freed (frfcfs_banks: when a bank takes a request, in a cycle
        // that may finish none): admit the oldest request waiting out of the latency queue, or
        // the oldest blocked request of this channel.
        if (!waiting_[c].empty() && admit(*waiting_[c].front(), now)) {
            waiting_[c].pop_front();
        } else if (!blocked_[c].empty() && admit(*blocked_[c].front(), now)) {
            tlm::tlm_generic_payload* b = blocked_[c].front();
            blocked_[c].pop_front();
            send_end_request(in[ext(*b).source], *b);
        }
        if (!ch.empty()) next = std::min(next, std::max(now + 1, ch.next_decision()));
    }
    if (next != ~0ull) wake_.notify(clock_.time_of(next) - sc_time_stamp());
}

void Dram::respond() {
    while (tlm::tlm_generic_payload* t = resp_peq_.get_next_transaction()) {
        t->set_response_status(tlm::TLM_OK_RESPONSE);
        ext(*t).dram = true;
        send_response(in[ext(*t).source], *t, name());
    }
}

void Dram::b_transport(int id, tlm::tlm_generic_payload& t, sc_time& d) {
    const uint64_t now = clock_.cycle_at_or_after(sc_time_stamp() + d + frontend_);
    const uint64_t horizon = clock_.cycle_at_or_before(sc_time_stamp());
    const uint64_t done = lt_.access(t.get_address(), t.get_data_length(), now, horizon);
    ext(t).dram = true;
    ext(t).source = uint32_t(id);
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    d = clock_.time_of(done) - sc_time_stamp();
}

}  // namespace rtu
