#include "mem_bridge.h"

#include <algorithm>

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

sc_time MemBridge::read(tlm::tlm_generic_payload& t, const sc_time& issued) {
    sc_time latency = SC_ZERO_TIME;  // asked with no offset: the memory's latency from now
    if (reader_.read_line(t.get_address(), t.get_data_length(), latency) > 0) ++reads_;
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    ext(t).dram = true;
    // The answer on the memory clock's edge, as the DRAM's: the caches count in cycles.
    const sc_time now = sc_time_stamp();
    return clock_.time_of(clock_.cycle_at_or_after(std::max(issued, now) + latency)) - now;
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
        resp_peq_.notify(*t, read(*t, sc_time_stamp()));
    }
}

void MemBridge::respond() {
    while (tlm::tlm_generic_payload* t = resp_peq_.get_next_transaction()) send_response(in[ext(*t).source], *t, name());
}

// LT: the read is issued at `now + d` (the complex runs ahead of the kernel within its window).
// The system memory is asked with no offset, for its latency from now, and the answer is placed
// at the read's own time plus that latency (read()). Asked with the offset, a target that
// synchronises as a quantum keeper does (it waits the offset out inside b_transport once the
// offset reaches the global quantum) moved the kernel past cycles the complex still had to step
// in its window, and LT's cycles came to depend on the quantum (the example platform's RAM with
// `sync_at_quantum`: 3,134 and 3,355 cycles at global quanta of 1 and 10 ns against 2,643 at
// 1 us; test SocVp.SharedPathCyclesDoNotDependOnTheQuantum). The price: a memory whose latency
// depends on when it is asked sees the read up to one window early (the smaller of
// `sim.quantum` and the global quantum).
void MemBridge::b_transport(int id, tlm::tlm_generic_payload& t, sc_time& d) {
    const sc_time before = sc_time_stamp();
    ext(t).source = uint32_t(id);
    d = read(t, before + d);
    if (sc_time_stamp() != before && !warned_wait_) {
        warned_wait_ = true;
        SC_REPORT_WARNING(name(), "the system memory waited inside b_transport although asked with no time offset: the LT RT complex runs "
                                  "ahead of simulated time and needs a memory that annotates its latency instead (or use the AT fidelity); "
                                  "its cycles are not to be trusted");
    }
}

}  // namespace rtu
