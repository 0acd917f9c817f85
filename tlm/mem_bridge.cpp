#include "mem_bridge.h"

#include "payload.h"

namespace rtu {

using namespace sc_core;

MemBridge::MemBridge(sc_module_name name, LineReader& reader, const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events)
    : sc_module(name), in("from_l2"), reader_(reader), clock_(clock), resp_due_(events, [this] { respond(); }), resp_peq_(resp_due_) {
    if (fidelity == Fidelity::AT) {
        in.register_nb_transport_fw(this, &MemBridge::nb_transport_fw);
        SC_THREAD(read_requests);
    } else {
        in.register_b_transport(this, &MemBridge::b_transport);
    }
}

void MemBridge::read(tlm::tlm_generic_payload& t, sc_time& d) {
    if (reader_.read_line(t.get_address(), t.get_data_length(), d) > 0) ++reads_;
    // The answer on the memory clock's edge, as the DRAM's: the caches count in cycles.
    d = clock_.time_of(clock_.cycle_at_or_after(sc_time_stamp() + d)) - sc_time_stamp();
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    ext(t).dram = true;
}

// The L2 sends its misses with no annotated delay (`d` is zero).
tlm::tlm_sync_enum MemBridge::nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time&) {
    if (ph == tlm::END_RESP) return tlm::TLM_COMPLETED;
    if (ph != tlm::BEGIN_REQ) SC_REPORT_FATAL(name(), "unexpected phase on the forward path");
    ext(t).source = uint32_t(id);
    t.acquire();
    requests_.push_back(&t);
    request_.notify(SC_ZERO_TIME);
    ph = tlm::END_REQ;  // taken at once: the memory's own queueing is in its latency
    return tlm::TLM_UPDATED;
}

void MemBridge::read_requests() {
    for (;;) {
        while (requests_.empty()) wait(request_);
        tlm::tlm_generic_payload* t = requests_.front();
        requests_.pop_front();
        sc_time d = SC_ZERO_TIME;
        read(*t, d);
        resp_peq_.notify(*t, d);
    }
}

void MemBridge::respond() {
    while (tlm::tlm_generic_payload* t = resp_peq_.get_next_transaction()) send_response(in[ext(*t).source], *t, name());
}

void MemBridge::b_transport(int id, tlm::tlm_generic_payload& t, sc_time& d) {
    const sc_time before = sc_time_stamp();
    ext(t).source = uint32_t(id);
    read(t, d);
    if (sc_time_stamp() != before && !warned_wait_) {
        warned_wait_ = true;
        SC_REPORT_WARNING(name(), "the system memory waited inside b_transport: the LT RT complex runs ahead of simulated time and needs "
                                  "a memory that annotates its latency instead (or use the AT fidelity); its cycles are not to be trusted");
    }
}

}  // namespace rtu
