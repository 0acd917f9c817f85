// Transaction payloads of the memory hierarchy: a pooled memory manager (tlm_mm_interface) and
// the extension every payload carries (who asked, for what, where it was served).
#pragma once
#include <cstdint>
#include <vector>

#include <systemc>
#include <tlm>

#include "model/sector_cache.h"

namespace rtu {

enum class Requester : uint8_t { RtUnit, L1, L2 };

struct RtExtension : tlm::tlm_extension<RtExtension> {
    Requester requester = Requester::RtUnit;  // who issued this payload
    uint32_t sm = 0, warp = 0, thread = 0;    // thread: the first of the warp's threads waiting on the node
    uint64_t id = 0;          // the requester's id for this request (RT unit chunk id, cache token)
    ReqKind kind = ReqKind::Demand;
    uint8_t streak = 0;       // pop-streak class of the node fetch
    bool l1_miss = false;     // set on the way back: not served by L1
    bool dram = false;        // set on the way back: served by DRAM
    uint32_t source = 0;      // crossbar/DRAM: which input port it came from
    // LT, set on the way back by the L1: a reservation fail withheld the request's acceptance
    // (AT's END_REQ) until this cycle, and the requester sends nothing before it.
    uint64_t accepted_at = 0;

    tlm::tlm_extension_base* clone() const override { return new RtExtension(*this); }
    void copy_from(const tlm::tlm_extension_base& e) override { *this = static_cast<const RtExtension&>(e); }
};

// Pooled payloads: acquire() hands out a payload with a cleared RtExtension and reference
// count 1; the last release() returns it to the pool. Counts what is outstanding, so that a run
// can check that every request got its response.
class PayloadPool : public tlm::tlm_mm_interface {
public:
    ~PayloadPool() override;
    tlm::tlm_generic_payload* acquire(uint64_t addr, uint32_t bytes, unsigned char* data);
    void free(tlm::tlm_generic_payload* t) override;
    uint64_t outstanding() const { return outstanding_; }
    uint64_t allocated() const { return all_.size(); }

private:
    std::vector<tlm::tlm_generic_payload*> free_, all_;
    uint64_t outstanding_ = 0;
};

// The target side of the base protocol as every module here uses it, on a backward interface:
// END_REQ for a request whose acceptance was withheld (backpressure), and BEGIN_RESP, whose
// phase every requester here ends at once (TLM_COMPLETED); the sender then lets go of the
// payload. `who` names the sender in the fatal report if a requester does not complete.
void send_end_request(tlm::tlm_bw_transport_if<>* bw, tlm::tlm_generic_payload& t);
void send_response(tlm::tlm_bw_transport_if<>* bw, tlm::tlm_generic_payload& t, const char* who);

inline RtExtension& ext(tlm::tlm_generic_payload& t) {
    RtExtension* e = nullptr;
    t.get_extension(e);
    return *e;
}

}  // namespace rtu
