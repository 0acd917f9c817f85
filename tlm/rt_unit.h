// The RT unit of one SM as a SystemC module: RtUnitCore (model/) behind one TLM-2.0 initiator
// socket to the SM's L1. AT: non-blocking transport, one 32 B request per cycle, a handler on the
// RT complex's event queue (tlm/ordered_events.h) that sleeps until its next event. LT: blocking
// transport; the unit has no process of its own: the RT complex (tlm/rt_complex.h) steps the
// units cycle by cycle, ahead of simulated time. Its traces come from a TraceSource
// (model/trace_source.h).
#pragma once
#include <functional>
#include <queue>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>

#include "clock.h"
#include "model/fidelity.h"
#include "model/rt_unit_core.h"
#include "model/shader_loads.h"
#include "model/trace_source.h"
#include "ordered_events.h"
#include "payload.h"

namespace rtu {

class RtUnit : public sc_core::sc_module {
public:
    tlm_utils::simple_initiator_socket<RtUnit> socket;

    // `events`: the RT complex's event queue, on which AT's handler runs.
    RtUnit(sc_core::sc_module_name name, uint32_t sm, const HwConfig& cfg, const BvhImage& image, TraversalOrder order,
           TraceSource& source, PayloadPool& pool, const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events,
           const Treelets* treelets = nullptr);

    RtUnitCore& core() { return core_; }
    // LT: the next cycle the unit has work in (~0: none, and none will come), and running its
    // cycles before `end`.
    uint64_t lt_next() const { return lt_.next; }
    void lt_run(uint64_t end);
    const RtUnitCore& core() const { return core_; }
    // New traces may be waiting at the trace source (RtComplex::start_job): AT wakes the unit,
    // LT has it look at the current cycle again. `new_epoch`: the clocks' cycle numbers have
    // just restarted (ClockDomain::set_epoch).
    void wake(bool new_epoch);
    // Called after every cycle the unit works (waveform sampling); may be empty.
    std::function<void(uint64_t cycle)> on_cycle;
    // The cycle the unit is working in (or last worked in).
    uint64_t current_cycle() const { return last_cycle_ == ~0ull ? 0 : last_cycle_; }
    // The shader code's loads after each trace (workload.shader_reads): `per_ray` sectors per ray
    // of a retired trace, of data no cache holds, handed one per cycle from the trace's end to
    // `read` (the SM's L1, Cache::shader_read), which may refuse one (retried the next cycle).
    void set_shader_reads(const ShaderReads& reads, std::function<bool(uint64_t addr, uint64_t cycle)> read);

private:
    void tick();     // AT
    void pull_work(uint64_t c);
    void admit_held_response(uint64_t c);
    tlm::tlm_sync_enum nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    tlm::tlm_generic_payload* make_payload(const ChunkRequest& r);
    void wake_at(uint64_t cycle);
    void retire(const std::vector<RetiredRay>& rays, uint64_t c);  // to the trace source; shader reads owed
    void shader_cycle(uint64_t c);  // one shader read, if any is owed

    ShaderLoads shader_;
    std::function<bool(uint64_t, uint64_t)> shader_read_;

    uint32_t sm_;
    RtUnitCore core_;
    const BvhImage& image_;
    TraceSource& source_;
    PayloadPool& pool_;
    const ClockDomain& clock_;
    bool waiting_end_req_ = false;
    tlm::tlm_generic_payload* held_response_ = nullptr;  // AT: BEGIN_RESP accepted, END_RESP withheld while the response FIFO is full
    // LT: what lt_run carries from one quantum to the next.
    struct LtResponse {
        uint64_t at;   // cycle the response reaches the FIFO
        uint64_t seq;  // order of sending: responses due the same cycle arrive in it
        uint64_t id;
        bool l1_miss, dram;
        bool operator>(const LtResponse& o) const { return at != o.at ? at > o.at : seq > o.seq; }
    };
    struct LtState {
        std::priority_queue<LtResponse, std::vector<LtResponse>, std::greater<LtResponse>> responses;
        uint64_t sent = 0;
        uint64_t port_free = 0;  // a reservation fail holds the request port until the L1 accepts
        uint64_t next = 0;       // the next cycle with work
    } lt_;
    uint64_t last_cycle_ = ~0ull;
    bool at_;
    OrderedEvent wake_;  // AT: runs tick
};

}  // namespace rtu
