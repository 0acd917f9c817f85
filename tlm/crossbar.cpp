#include "crossbar.h"

namespace rtu {

using namespace sc_core;

Crossbar::Crossbar(sc_module_name name, const AddressMap& map, uint32_t slices, uint32_t latency, const ClockDomain& clock,
                   Fidelity fidelity, OrderedEvents& events)
    : sc_module(name), in("from_l1"), out("to_l2"), map_(map), latency_(latency), clock_(clock), outputs_(slices),
      req_due_(events, [this] { forward_requests(); }), resp_due_(events, [this] { forward_responses(); }), req_peq_(req_due_),
      resp_peq_(resp_due_) {
    if (fidelity == Fidelity::AT) {
        in.register_nb_transport_fw(this, &Crossbar::nb_transport_fw);
        out.register_nb_transport_bw(this, &Crossbar::nb_transport_bw);
    } else {
        in.register_b_transport(this, &Crossbar::b_transport);
    }
}

tlm::tlm_sync_enum Crossbar::nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    if (ph == tlm::END_RESP) return tlm::TLM_COMPLETED;
    if (ph != tlm::BEGIN_REQ) SC_REPORT_FATAL(name(), "unexpected phase on the forward path");
    ext(t).source = uint32_t(id);
    t.acquire();
    req_peq_.notify(t, clock_.period() * double(latency_));
    ph = tlm::END_REQ;  // buffered in the crossbar
    return tlm::TLM_UPDATED;
}

void Crossbar::forward_requests() {
    while (tlm::tlm_generic_payload* t = req_peq_.get_next_transaction()) {
        const uint32_t s = slice_of(t->get_address());
        outputs_[s].queue.push_back(t);
        send(s);
    }
}

void Crossbar::send(uint32_t s) {
    Output& o = outputs_[s];
    while (!o.waiting_end_req && !o.queue.empty()) {
        tlm::tlm_generic_payload* t = o.queue.front();
        tlm::tlm_phase ph = tlm::BEGIN_REQ;
        sc_time d = SC_ZERO_TIME;
        const tlm::tlm_sync_enum r = out[s]->nb_transport_fw(*t, ph, d);
        if (r == tlm::TLM_UPDATED && ph == tlm::END_REQ) {
            o.queue.pop_front();
        } else if (r == tlm::TLM_ACCEPTED) {
            o.waiting_end_req = true;
        } else {
            SC_REPORT_FATAL(name(), "unexpected reply to BEGIN_REQ");
        }
    }
}

tlm::tlm_sync_enum Crossbar::nb_transport_bw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    if (ph == tlm::END_REQ) {
        outputs_[id].waiting_end_req = false;
        outputs_[id].queue.pop_front();
        send(uint32_t(id));
        return tlm::TLM_ACCEPTED;
    }
    if (ph != tlm::BEGIN_RESP) SC_REPORT_FATAL(name(), "unexpected phase on the backward path");
    resp_peq_.notify(t, clock_.period() * double(latency_));
    return tlm::TLM_COMPLETED;  // the payload stays ours (acquired on the way in) until forwarded
}

void Crossbar::forward_responses() {
    while (tlm::tlm_generic_payload* t = resp_peq_.get_next_transaction()) send_response(in[ext(*t).source], *t, name());
}

void Crossbar::b_transport(int id, tlm::tlm_generic_payload& t, sc_time& d) {
    ext(t).source = uint32_t(id);
    d += clock_.period() * double(latency_);
    out[slice_of(t.get_address())]->b_transport(t, d);
    d += clock_.period() * double(latency_);
}

}  // namespace rtu
