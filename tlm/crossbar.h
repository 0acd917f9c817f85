// Crossbar between the SMs' L1s and the L2 slices: a request goes to its address's slice
// (AddressMap::slice, model/address_map.h); the response goes back to the L1 it came from. Each output serialises its requests
// (one BEGIN_REQ outstanding per socket, as the base protocol requires); both directions add
// the configured latency.
#pragma once
#include <deque>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_initiator_socket.h>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "clock.h"
#include "fifo_peq.h"
#include "model/address_map.h"
#include "model/fidelity.h"
#include "payload.h"

namespace rtu {

class Crossbar : public sc_core::sc_module {
public:
    tlm_utils::multi_passthrough_target_socket<Crossbar> in;      // from L1s
    tlm_utils::multi_passthrough_initiator_socket<Crossbar> out;  // to L2 slices

    // `events`: the RT complex's event queue (tlm/ordered_events.h), on which AT's handlers run.
    Crossbar(sc_core::sc_module_name name, const AddressMap& map, uint32_t slices, uint32_t latency, const ClockDomain& clock,
             Fidelity fidelity, OrderedEvents& events);
    uint32_t slice_of(uint64_t addr) const { return map_.slice(addr); }

private:
    tlm::tlm_sync_enum nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    tlm::tlm_sync_enum nb_transport_bw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    void b_transport(int id, tlm::tlm_generic_payload& t, sc_core::sc_time& d);
    void send(uint32_t slice);
    void forward_requests();
    void forward_responses();

    AddressMap map_;
    uint32_t latency_;
    const ClockDomain& clock_;
    struct Output {
        std::deque<tlm::tlm_generic_payload*> queue;
        bool waiting_end_req = false;
    };
    std::vector<Output> outputs_;
    OrderedEvent req_due_, resp_due_;  // run forward_requests, forward_responses
    FifoPeq<tlm::tlm_generic_payload> req_peq_, resp_peq_;  // fixed latency: due in queue order
};

}  // namespace rtu
