// A checker of the TLM-2.0 base protocol (IEEE 1666-2011, section 15), inserted between an
// initiator and a target socket in AT runs. It forwards every call unchanged and records a
// violation of these rules:
//  - a payload has a memory manager (nb_transport needs one) and a data length;
//  - the forward path carries only BEGIN_REQ and END_RESP, the backward path only END_REQ and
//    BEGIN_RESP (a return value may update the phase to the next one in sequence);
//  - phases of one transaction follow BEGIN_REQ, END_REQ, BEGIN_RESP, END_RESP in order, where
//    END_REQ may be skipped by BEGIN_RESP and END_RESP by a TLM_COMPLETED return;
//  - request exclusion: no BEGIN_REQ while an earlier request on the socket has not reached
//    END_REQ (or BEGIN_RESP); response exclusion: no BEGIN_RESP while an earlier response has
//    not ended (END_RESP or TLM_COMPLETED);
//  - BEGIN_RESP carries a response status other than TLM_INCOMPLETE_RESPONSE;
//  - at the end of simulation no transaction is left open.
// (Debian does not ship Accellera's TLM checker; this one is written from the standard.)
#pragma once
#include <string>
#include <unordered_map>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

namespace rtu {

class ProtocolChecker : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<ProtocolChecker> in;
    tlm_utils::simple_initiator_socket<ProtocolChecker> out;

    explicit ProtocolChecker(sc_core::sc_module_name name);

    const std::vector<std::string>& violations() const { return violations_; }
    uint64_t transactions() const { return transactions_; }
    // Transactions still open (call at the end of simulation).
    size_t open() const { return state_.size(); }

    // The checks on their own, for tests that drive a sequence by hand.
    void on_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret);
    void on_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret);

private:
    enum class Phase { Req, ReqEnded, Resp };
    tlm::tlm_sync_enum nb_transport_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    tlm::tlm_sync_enum nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& d);
    void apply(tlm::tlm_generic_payload& t, tlm::tlm_phase ph, const char* path);
    void pre_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before);
    void post_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret);
    void pre_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before);
    void post_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret);
    void violation(const std::string& what);
    void complete(tlm::tlm_generic_payload& t);

    std::unordered_map<tlm::tlm_generic_payload*, Phase> state_;
    tlm::tlm_generic_payload* open_request_ = nullptr;   // request not yet at END_REQ
    tlm::tlm_generic_payload* open_response_ = nullptr;  // response not yet ended
    std::vector<std::string> violations_;
    uint64_t transactions_ = 0;
};

}  // namespace rtu
