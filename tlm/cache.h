// A sector cache (L1 of an SM, or one L2 slice) as a SystemC module: SectorCache (model/) behind
// a TLM-2.0 target socket (from the RT unit or the crossbar) and an initiator socket (towards
// L2 or DRAM). AT: one lookup per cycle; a reservation fail holds END_REQ until an MSHR frees,
// which stops the requester (base-protocol backpressure); its handlers run on the RT complex's
// event queue (tlm/ordered_events.h). LT: b_transport, timed by
// CacheBookings (model/cache_bookings.h, as the interval fidelity's caches are).
#pragma once
#include <deque>
#include <functional>
#include <vector>
#include <absl/container/flat_hash_map.h>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

#include "clock.h"
#include "fifo_peq.h"
#include "model/cache_bookings.h"
#include "model/fidelity.h"
#include "model/sector_cache.h"
#include "payload.h"

namespace rtu {

class Cache : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<Cache> in;
    tlm_utils::simple_initiator_socket<Cache> out;

    // An L1 marks responses as L1 misses when not hits; an L2 slice marks them as DRAM-served
    // when they came from below.
    Cache(sc_core::sc_module_name name, CacheRole role, const CacheConfig& cfg, uint32_t hit_latency, PayloadPool& pool,
          const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events);

    const SectorCache& tags() const { return lt_.tags(); }
    // Functional warming before a sampled run (SectorCache::warm); returns whether it hit.
    bool warm(uint64_t addr) { return tags_.warm(addr); }
    // Every line invalid, statistics kept (a new job's image; RtComplex::start_job).
    void invalidate() { lt_.invalidate(); }
    size_t mshrs_in_use() const { return fidelity_ == Fidelity::AT ? tags_.mshrs_in_use() : lt_.mshrs_in_use(); }
    // An L1's second port, the SM's shader code's loads (workload.shader_reads): a read of the
    // sector at `addr` that nobody waits for, filling the L1 (and below) as a demand read would.
    // AT: now; false on a reservation fail (the caller retries in a later cycle). LT: at core
    // cycle `cycle`, timed by the bookings. Not a TLM socket: the shader core is not a module.
    bool shader_read(uint64_t addr, uint64_t cycle);

private:
    // AT
    tlm::tlm_sync_enum nb_transport_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    tlm::tlm_sync_enum nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    bool lookup(uint64_t addr, const RtExtension& e, tlm::tlm_generic_payload* up);  // false: reservation fail
    void respond_later(tlm::tlm_generic_payload& t, bool hit);
    void send_responses();  // on respond_: one response per cycle
    void send_misses();     // on miss_event_: one miss per cycle downstream
    // LT
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& d);

    void retry_blocked();
    bool miss_queue_full() const;
    CacheRole role_;
    CacheConfig cfg_;
    uint32_t hit_latency_;
    CacheBookings lt_;   // LT's timing; its tags are AT's too
    SectorCache& tags_;
    PayloadPool& pool_;
    const ClockDomain& clock_;
    Fidelity fidelity_;

    uint64_t next_token_ = 1;
    absl::flat_hash_map<uint64_t, tlm::tlm_generic_payload*> waiting_;  // token -> upstream request
    tlm::tlm_generic_payload* blocked_ = nullptr;                      // held by a reservation fail
    // Responses on their way to the response port: hits after the hit latency, fills at once.
    // Each queue is in due order; together they hand out as one payload event queue would.
    // respond_ runs send_responses, for a response due or for the port's next cycle.
    OrderedEvent respond_, miss_event_;
    uint64_t resp_seq_ = 0;
    FifoPeq<tlm::tlm_generic_payload> hit_peq_, fill_peq_;
    std::deque<tlm::tlm_generic_payload*> resp_queue_;
    tlm::tlm_generic_payload* resp_open_ = nullptr;  // a response whose END_RESP the requester withholds
    uint64_t last_resp_cycle_ = ~0ull, last_miss_cycle_ = ~0ull;
    std::deque<std::pair<uint64_t, tlm::tlm_generic_payload*>> miss_queue_;  // (cycle it may leave, request)
    bool down_waiting_end_req_ = false;
    std::vector<unsigned char> no_data_;  // the shader reads' payload data (timing only)
};

}  // namespace rtu
