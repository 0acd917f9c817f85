// The shared memory path's end of the RT complex: in place of the DRAM, the target of the L2
// slices' misses, which it hands to the system memory of the platform around the complex (an SoC
// peripheral's `mem` socket) through a LineReader. The caches keep their image offsets; the
// reader turns an offset into a system address, so only the memory's timing is the SoC's.
//   AT: each request is accepted at once (END_REQ), read by the bridge's thread with a blocking
//       transport in arrival order (one at a time; a memory that annotates its latency without
//       waiting serves them overlapped), and answered at the next memory-clock edge at or after
//       the read's annotated time.
//   LT: the blocking transport goes straight through; the answer is the same clock edge. The LT
//       RT complex runs ahead of simulated time, so the memory must annotate its latency rather
//       than wait inside b_transport (a wait there is reported, once, as a warning).
#pragma once
#include <cstdint>
#include <deque>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "clock.h"
#include "fifo_peq.h"
#include "model/fidelity.h"

namespace rtu {

// Reads `bytes` at image offset `offset` from the platform's memory, as a blocking transport
// that adds the memory's latency to `delay` (and may wait, in AT), and returns how many bytes it
// read (fewer where the line runs past the image, none beyond it). What the bytes were and
// whether the read failed is the reader's business (a peripheral records a fault for its job);
// the RT complex traverses its own copy of the image either way.
class LineReader {
public:
    virtual ~LineReader() = default;
    virtual uint32_t read_line(uint64_t offset, uint32_t bytes, sc_core::sc_time& delay) = 0;
};

class MemBridge : public sc_core::sc_module {
public:
    tlm_utils::multi_passthrough_target_socket<MemBridge> in;

    // `clock`: the memory clock, whose edges the answers come on. `events`: the RT complex's event
    // queue (tlm/ordered_events.h), on which the answers are delivered in AT.
    MemBridge(sc_core::sc_module_name name, LineReader& reader, const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events);
    SC_HAS_PROCESS(MemBridge);

    uint64_t reads() const { return reads_; }  // reads on the platform's memory

private:
    tlm::tlm_sync_enum nb_transport_fw(int id, tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    void b_transport(int id, tlm::tlm_generic_payload& t, sc_core::sc_time& d);
    void read_requests();  // SC_THREAD (AT)
    void respond();        // on the response queue's event (AT)
    // The line of `t`, issued at the absolute time `issued`, read through the reader (asked with
    // no time offset: the memory's latency from now); returns the time from now to the
    // memory-clock edge of its answer, at or after `issued` (or now, if later) + that latency.
    sc_core::sc_time read(tlm::tlm_generic_payload& t, const sc_core::sc_time& issued);

    LineReader& reader_;
    const ClockDomain& clock_;
    std::deque<tlm::tlm_generic_payload*> requests_;  // AT: accepted, not yet read
    sc_core::sc_event request_;
    OrderedEvent resp_due_;
    TimedPeq<tlm::tlm_generic_payload> resp_peq_;
    uint64_t reads_ = 0;
    bool warned_wait_ = false;
};

}  // namespace rtu
