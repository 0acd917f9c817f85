#include "payload.h"

namespace rtu {

PayloadPool::~PayloadPool() {
    for (tlm::tlm_generic_payload* t : all_) delete t;  // the payload's destructor frees its extensions
}

tlm::tlm_generic_payload* PayloadPool::acquire(uint64_t addr, uint32_t bytes, unsigned char* data) {
    tlm::tlm_generic_payload* t;
    if (free_.empty()) {
        t = new tlm::tlm_generic_payload(this);
        t->set_extension(new RtExtension);
        all_.push_back(t);
    } else {
        t = free_.back();
        free_.pop_back();
    }
    ext(*t) = RtExtension{};
    t->set_command(tlm::TLM_READ_COMMAND);
    t->set_address(addr);
    t->set_data_length(bytes);
    t->set_streaming_width(bytes);
    t->set_data_ptr(data);
    t->set_byte_enable_ptr(nullptr);
    t->set_dmi_allowed(false);
    t->set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    t->acquire();
    ++outstanding_;
    return t;
}

void send_end_request(tlm::tlm_bw_transport_if<>* bw, tlm::tlm_generic_payload& t) {
    tlm::tlm_phase ph = tlm::END_REQ;
    sc_core::sc_time d = sc_core::SC_ZERO_TIME;
    bw->nb_transport_bw(t, ph, d);
}

void send_response(tlm::tlm_bw_transport_if<>* bw, tlm::tlm_generic_payload& t, const char* who) {
    tlm::tlm_phase ph = tlm::BEGIN_RESP;
    sc_core::sc_time d = sc_core::SC_ZERO_TIME;
    if (bw->nb_transport_bw(t, ph, d) != tlm::TLM_COMPLETED)
        SC_REPORT_FATAL(who, "requester must complete the response phase at once");
    t.release();
}

void PayloadPool::free(tlm::tlm_generic_payload* t) {
    --outstanding_;
    free_.push_back(t);
}

}  // namespace rtu
