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
// Blocking transport (b_transport), as the SoC peripheral's register and memory sockets use it:
//  - it is called from a thread process (it may wait), never from a method process;
//  - the initiator hands over a command other than TLM_IGNORE_COMMAND, a data pointer, a data
//    length and a streaming width above 0, a byte-enable length above 0 where there is a
//    byte-enable pointer, and the response status TLM_INCOMPLETE_RESPONSE;
//  - the target sets a response status other than TLM_INCOMPLETE_RESPONSE, and leaves the
//    command, data pointer, data length, streaming width and byte enables as it found them.
// Debug transport and DMI are forwarded both ways; transport_dbg returns at most the data length
// and takes no simulated time; a DMI grant covers the transaction's address, with a pointer and
// read or write access.
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
    // A blocking transport's attributes as the initiator handed them over (check_b_request), and
    // the target's answer against them (check_b_response).
    struct Request {
        tlm::tlm_command command;
        unsigned char *data, *byte_enable;
        unsigned length, streaming_width, byte_enable_length;
    };
    Request check_b_request(const tlm::tlm_generic_payload& t);
    void check_b_response(const tlm::tlm_generic_payload& t, const Request& before);
    void check_dmi_grant(const tlm::tlm_generic_payload& t, const tlm::tlm_dmi& d);

private:
    enum class Phase { Req, ReqEnded, Resp };
    tlm::tlm_sync_enum nb_transport_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    tlm::tlm_sync_enum nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_core::sc_time& d);
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& d);
    unsigned transport_dbg(tlm::tlm_generic_payload& t);
    bool get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& d);
    void invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end);
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
