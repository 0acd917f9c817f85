#include "protocol_checker.h"

namespace rtu {

using namespace sc_core;

ProtocolChecker::ProtocolChecker(sc_module_name name) : sc_module(name), in("in"), out("out") {
    in.register_nb_transport_fw(this, &ProtocolChecker::nb_transport_fw);
    in.register_b_transport(this, &ProtocolChecker::b_transport);
    in.register_transport_dbg(this, &ProtocolChecker::transport_dbg);
    in.register_get_direct_mem_ptr(this, &ProtocolChecker::get_direct_mem_ptr);
    out.register_nb_transport_bw(this, &ProtocolChecker::nb_transport_bw);
    out.register_invalidate_direct_mem_ptr(this, &ProtocolChecker::invalidate_direct_mem_ptr);
}

void ProtocolChecker::violation(const std::string& what) {
    if (violations_.size() < 100) violations_.push_back(std::string(name()) + " at " + sc_time_stamp().to_string() + ": " + what);
}

// Moves transaction t into phase ph, checking order and the exclusion rules.
void ProtocolChecker::apply(tlm::tlm_generic_payload& t, tlm::tlm_phase ph, const char* path) {
    auto it = state_.find(&t);
    if (ph == tlm::BEGIN_REQ) {
        if (it != state_.end()) violation(std::string("BEGIN_REQ for a transaction already in progress (") + path + ")");
        if (open_request_) violation("BEGIN_REQ before END_REQ of the previous request (request exclusion)");
        if (!t.has_mm()) violation("payload without memory manager on nb_transport");
        if (t.get_data_length() == 0) violation("payload with zero data length");
        state_[&t] = Phase::Req;
        open_request_ = &t;
        ++transactions_;
        return;
    }
    if (it == state_.end()) {
        violation(std::string(ph.get_name()) + " for an unknown transaction (" + path + ")");
        return;
    }
    if (ph == tlm::END_REQ) {
        if (it->second != Phase::Req) violation("END_REQ out of order");
        it->second = Phase::ReqEnded;
        if (open_request_ == &t) open_request_ = nullptr;
    } else if (ph == tlm::BEGIN_RESP) {
        if (it->second == Phase::Resp) violation("second BEGIN_RESP");
        if (open_response_) violation("BEGIN_RESP before the previous response ended (response exclusion)");
        if (t.get_response_status() == tlm::TLM_INCOMPLETE_RESPONSE) violation("BEGIN_RESP with TLM_INCOMPLETE_RESPONSE");
        if (open_request_ == &t) open_request_ = nullptr;  // BEGIN_RESP implies END_REQ
        it->second = Phase::Resp;
        open_response_ = &t;
    } else if (ph == tlm::END_RESP) {
        if (it->second != Phase::Resp) violation("END_RESP before BEGIN_RESP");
        if (open_response_ == &t) open_response_ = nullptr;
        state_.erase(it);
    } else {
        violation("unknown phase");
    }
}

// TLM_COMPLETED ends the transaction whatever phase it was in.
void ProtocolChecker::complete(tlm::tlm_generic_payload& t) {
    if (open_request_ == &t) open_request_ = nullptr;
    if (open_response_ == &t) open_response_ = nullptr;
    state_.erase(&t);
}

void ProtocolChecker::pre_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before) {
    if (before != tlm::BEGIN_REQ && before != tlm::END_RESP) violation(std::string("forward path carries ") + before.get_name());
    apply(t, before, "forward call");
}

void ProtocolChecker::on_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret) {
    pre_fw(t, before);
    post_fw(t, before, after, ret);
}

void ProtocolChecker::post_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret) {
    if (ret == tlm::TLM_UPDATED) {
        if (before == tlm::END_RESP) violation("TLM_UPDATED returned for END_RESP");
        else if (after != tlm::END_REQ && after != tlm::BEGIN_RESP) violation(std::string("forward return updates phase to ") + after.get_name());
        else apply(t, after, "forward return");
    } else if (ret == tlm::TLM_COMPLETED) {
        complete(t);  // completed at once: END_REQ and the response are implied
    } else if (after != before) {
        violation("phase changed on a TLM_ACCEPTED return");
    }
}

void ProtocolChecker::pre_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before) {
    if (before != tlm::END_REQ && before != tlm::BEGIN_RESP) violation(std::string("backward path carries ") + before.get_name());
    apply(t, before, "backward call");
}

void ProtocolChecker::on_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret) {
    pre_bw(t, before);
    post_bw(t, before, after, ret);
}

void ProtocolChecker::post_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase before, tlm::tlm_phase after, tlm::tlm_sync_enum ret) {
    if (ret == tlm::TLM_UPDATED) {
        if (before != tlm::BEGIN_RESP || after != tlm::END_RESP) violation("backward return must update BEGIN_RESP to END_RESP only");
        else apply(t, after, "backward return");
    } else if (ret == tlm::TLM_COMPLETED) {
        if (before == tlm::END_REQ) violation("TLM_COMPLETED returned for END_REQ");
        complete(t);
    } else if (after != before) {
        violation("phase changed on a TLM_ACCEPTED return");
    }
}

tlm::tlm_sync_enum ProtocolChecker::nb_transport_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    const tlm::tlm_phase before = ph;
    pre_fw(t, before);
    const tlm::tlm_sync_enum r = out->nb_transport_fw(t, ph, d);
    post_fw(t, before, ph, r);
    return r;
}

tlm::tlm_sync_enum ProtocolChecker::nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    const tlm::tlm_phase before = ph;
    pre_bw(t, before);
    const tlm::tlm_sync_enum r = in->nb_transport_bw(t, ph, d);
    post_bw(t, before, ph, r);
    return r;
}

ProtocolChecker::Request ProtocolChecker::check_b_request(const tlm::tlm_generic_payload& t) {
    sc_process_handle p = sc_get_current_process_handle();
    if (p.valid() && p.proc_kind() == SC_METHOD_PROC_) violation("b_transport called from a method process (it may wait)");
    if (t.get_command() == tlm::TLM_IGNORE_COMMAND) violation("b_transport with TLM_IGNORE_COMMAND");
    if (!t.get_data_ptr()) violation("b_transport without a data pointer");
    if (t.get_data_length() == 0) violation("b_transport with zero data length");
    if (t.get_streaming_width() == 0) violation("b_transport with zero streaming width");
    if (t.get_byte_enable_ptr() && t.get_byte_enable_length() == 0) violation("byte-enable pointer with zero byte-enable length");
    if (t.get_response_status() != tlm::TLM_INCOMPLETE_RESPONSE)
        violation("b_transport handed over with response status " + t.get_response_string() + " (must be TLM_INCOMPLETE_RESPONSE)");
    ++transactions_;
    return {t.get_command(), t.get_data_ptr(), t.get_byte_enable_ptr(), t.get_data_length(), t.get_streaming_width(), t.get_byte_enable_length()};
}

void ProtocolChecker::check_b_response(const tlm::tlm_generic_payload& t, const Request& r) {
    if (t.get_response_status() == tlm::TLM_INCOMPLETE_RESPONSE) violation("b_transport returned TLM_INCOMPLETE_RESPONSE");
    if (t.get_command() != r.command || t.get_data_ptr() != r.data || t.get_data_length() != r.length ||
        t.get_streaming_width() != r.streaming_width || t.get_byte_enable_ptr() != r.byte_enable || t.get_byte_enable_length() != r.byte_enable_length)
        violation("the target changed the command, data pointer, data length, streaming width or byte enables");
}

void ProtocolChecker::check_dmi_grant(const tlm::tlm_generic_payload& t, const tlm::tlm_dmi& d) {
    if (t.get_address() < d.get_start_address() || t.get_address() > d.get_end_address())
        violation("a DMI grant that does not cover the transaction's address");
    if (!d.get_dmi_ptr()) violation("a DMI grant without a pointer");
    if (!d.is_read_allowed() && !d.is_write_allowed()) violation("a DMI grant that allows neither read nor write");
}

void ProtocolChecker::b_transport(tlm::tlm_generic_payload& t, sc_time& d) {
    const Request r = check_b_request(t);
    out->b_transport(t, d);
    check_b_response(t, r);
}

unsigned ProtocolChecker::transport_dbg(tlm::tlm_generic_payload& t) {
    const sc_time now = sc_time_stamp();
    const unsigned n = out->transport_dbg(t);
    if (n > t.get_data_length()) violation("transport_dbg returned more bytes than the data length");
    if (sc_time_stamp() != now) violation("transport_dbg took simulated time");
    return n;
}

bool ProtocolChecker::get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& d) {
    const bool granted = out->get_direct_mem_ptr(t, d);
    if (granted) check_dmi_grant(t, d);
    return granted;
}

void ProtocolChecker::invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end) { in->invalidate_direct_mem_ptr(start, end); }

}  // namespace rtu
