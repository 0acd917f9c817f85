// The DRAM: channels of banks (model/dram.h) behind one target socket per L2 slice. AT: the
// channels' FR-FCFS schedulers run in one handler on the RT complex's event queue
// (tlm/ordered_events.h) that sleeps until the next decision; a full
// channel queue holds END_REQ. With dram.frontend_latency a request first waits that many core
// cycles in a latency queue (GPGPU-Sim's dram_latency queue, accepted at once), then enters its
// channel's queue in arrival order when there is room. LT: the request's timestamp (plus the
// front-end latency) books its bank, the channel's command sequence and its data bus in
// calendars (model/dram.h, DramBookings), so that the order of calls does not matter.
#pragma once
#include <deque>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "clock.h"
#include "fifo_peq.h"
#include "model/dram.h"
#include "model/fidelity.h"
#include "payload.h"

namespace rtu {

class Dram : public sc_core::sc_module {
public:
    tlm_utils::multi_passthrough_target_socket<Dram> in;

    // `core_period`: the core clock's, in which dram.frontend_latency counts.
    Dram(sc_core::sc_module_name name, const DramConfig& cfg, const AddressMap& map, const ClockDomain& clock, const sc_core::sc_time& core_period,
         Fidelity fidelity, OrderedEvents& events);

    std::vector<DramStats> stats() const;  // per channel
    size_t queue_depth() const;

private:
    tlm::tlm_sync_enum nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    void b_transport(int id, tlm::tlm_generic_payload& t, sc_core::sc_time& d);
    void schedule();        // on wake_
    void respond();         // on the response queue's event
    void leave_frontend();  // on the latency queue's event
    bool admit(tlm::tlm_generic_payload& t, uint64_t now);

    DramConfig cfg_;
    AddressMap map_;
    const ClockDomain& clock_;
    std::vector<DramChannel> channels_;
    std::vector<std::deque<tlm::tlm_generic_payload*>> blocked_;  // per channel: END_REQ withheld
    sc_core::sc_time frontend_;                                   // the front-end latency
    OrderedEvent wake_, frontend_due_, resp_due_;
    FifoPeq<tlm::tlm_generic_payload> frontend_peq_;              // accepted, in the latency queue
    std::vector<std::deque<tlm::tlm_generic_payload*>> waiting_;  // per channel: out of it, the channel queue full
    TimedPeq<tlm::tlm_generic_payload> resp_peq_;
    DramBookings lt_;  // LT
};

}  // namespace rtu
