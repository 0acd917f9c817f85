// The parts of a minimal SoC virtual platform around the RT-unit peripheral: a RAM, a router
// and a scripted bus master standing in for the CPU. The example platform (platforms/soc_vp.cpp)
// and the peripheral's tests are built from them. Plain TLM-2.0 base protocol, b_transport and
// transport_dbg; nothing here knows the RT unit beyond its register header.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_initiator_socket.h>
#include <tlm_utils/multi_passthrough_target_socket.h>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

namespace rtu::vp {

// A plain access's payload: `len` bytes at `addr`, streaming width `len`, `be` a byte-enable
// mask of `len` bytes or null, the response status not yet set.
inline void set_access(tlm::tlm_generic_payload& t, tlm::tlm_command cmd, uint64_t addr, void* data, unsigned len, unsigned char* be = nullptr) {
    t.set_command(cmd);
    t.set_address(addr);
    t.set_data_ptr(static_cast<unsigned char*>(data));
    t.set_data_length(len);
    t.set_streaming_width(len);
    t.set_byte_enable_ptr(be);
    if (be) t.set_byte_enable_length(len);
    t.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
}

// Memory at [base, base + size): b_transport annotated with a latency plus the bytes over a
// bandwidth, transport_dbg in zero time, DMI (read and write, the same latency per access) when
// `dmi` is on. Addresses in a fault range answer TLM_ADDRESS_ERROR_RESPONSE and are never granted
// (to test an initiator's error path). Counts what it served, and what broke the base protocol's
// rules for blocking transport (`violations`).
class Ram : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<Ram, 32> in{"in"};
    bool dmi = true;
    uint64_t writes = 0, bytes_read = 0, transactions = 0, dmi_grants = 0, violations = 0;
    sc_core::sc_time last_write_done;  // when the latest write's annotated delay ends
    std::function<void(const tlm::tlm_generic_payload&)> observe;  // if set, sees every blocking transport (a test's view)
    // A target that synchronises as a quantum keeper would: when the initiator's annotated time
    // reaches the global quantum, it waits it out inside b_transport (TLM-2.0 allows that) and
    // answers with the rest of the latency.
    bool sync_at_quantum = false;

    Ram(sc_core::sc_module_name n, uint64_t base, uint64_t size, sc_core::sc_time latency = sc_core::sc_time(50, sc_core::SC_NS),
        double bytes_per_ns = 16.0)
        : sc_module(n), base_(base), bytes_(size, 0), latency_(latency), bytes_per_ns_(bytes_per_ns) {
        in.register_b_transport(this, &Ram::b_transport);
        in.register_transport_dbg(this, &Ram::transport_dbg);
        in.register_get_direct_mem_ptr(this, &Ram::get_direct_mem_ptr);
    }
    uint64_t base() const { return base_; }
    uint8_t* at(uint64_t addr) { return bytes_.data() + (addr - base_); }
    bool inside(uint64_t a, uint64_t n) const { return a >= base_ && n <= bytes_.size() && a - base_ <= bytes_.size() - n; }
    // [from, to) answers errors from now on (empty: none); granted DMI regions are withdrawn.
    void set_fault(uint64_t from, uint64_t to) {
        fault_from_ = from;
        fault_to_ = to;
        invalidate_dmi();
    }
    void invalidate_dmi() { in->invalidate_direct_mem_ptr(0, ~sc_dt::uint64(0)); }

private:
    bool faulty(uint64_t a, uint64_t n) const { return a < fault_to_ && a + n > fault_from_; }
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& d) {
        const uint64_t a = t.get_address(), n = t.get_data_length();
        ++transactions;
        if (observe) observe(t);
        // What an initiator must give a blocking transport (IEEE 1666-2011, 14.17-14.19).
        if (n == 0 || t.get_streaming_width() != n || t.get_response_status() != tlm::TLM_INCOMPLETE_RESPONSE ||
            t.get_command() == tlm::TLM_IGNORE_COMMAND || !t.get_data_ptr())
            ++violations;
        if (!inside(a, n) || faulty(a, n) || t.get_byte_enable_ptr()) return t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
        if (t.is_read()) std::memcpy(t.get_data_ptr(), at(a), n);
        else std::memcpy(at(a), t.get_data_ptr(), n);
        if (sync_at_quantum && d >= tlm::tlm_global_quantum::instance().get() && d > sc_core::SC_ZERO_TIME) {
            wait(d);
            d = sc_core::SC_ZERO_TIME;
        }
        d += latency_ + sc_core::sc_time(double(n) / bytes_per_ns_, sc_core::SC_NS);
        if (t.is_write()) {
            ++writes;
            last_write_done = sc_core::sc_time_stamp() + d;
        } else {
            bytes_read += n;
        }
        t.set_dmi_allowed(dmi);
        t.set_response_status(tlm::TLM_OK_RESPONSE);
    }
    // The whole memory, or the part of it on the address's side of the fault range.
    bool get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& d) {
        const uint64_t a = t.get_address();
        uint64_t lo = base_, hi = base_ + bytes_.size() - 1;
        if (!dmi || !inside(a, 1) || faulty(a, 1)) return false;
        if (fault_to_ > fault_from_) {
            if (a < fault_from_) hi = std::min(hi, fault_from_ - 1);
            else lo = std::max(lo, fault_to_);
        }
        d.set_dmi_ptr(at(lo));
        d.set_start_address(lo);
        d.set_end_address(hi);
        d.allow_read_write();
        d.set_read_latency(latency_);
        d.set_write_latency(latency_);
        ++dmi_grants;
        return true;
    }
    unsigned transport_dbg(tlm::tlm_generic_payload& t) {
        const uint64_t a = t.get_address(), n = t.get_data_length();
        if (!inside(a, n)) return 0;
        if (t.is_read()) std::memcpy(t.get_data_ptr(), at(a), n);
        else std::memcpy(at(a), t.get_data_ptr(), n);
        return unsigned(n);
    }
    uint64_t base_, fault_from_ = ~0ull, fault_to_ = 0;
    std::vector<uint8_t> bytes_;
    sc_core::sc_time latency_;
    double bytes_per_ns_;
};

// A router: any number of initiators on `in`, targets bound to `out` in the order of map();
// forwards b_transport, transport_dbg and DMI requests to the target whose range holds the
// address, with the address unchanged (absolute addressing; a grant is clipped to the range), and
// a target's DMI invalidation to every initiator; elsewhere an address error.
class Router : public sc_core::sc_module {
public:
    tlm_utils::multi_passthrough_target_socket<Router, 32> in{"in"};
    tlm_utils::multi_passthrough_initiator_socket<Router, 32> out{"out"};

    explicit Router(sc_core::sc_module_name n) : sc_module(n) {
        in.register_b_transport(this, &Router::b_transport);
        in.register_transport_dbg(this, &Router::transport_dbg);
        in.register_get_direct_mem_ptr(this, &Router::get_direct_mem_ptr);
        out.register_invalidate_direct_mem_ptr(this, &Router::invalidate_direct_mem_ptr);
    }
    // The next target bound to `out` answers [base, base + size).
    void map(uint64_t base, uint64_t size) { ranges_.push_back({base, size}); }

private:
    int route(uint64_t a) const {
        for (size_t i = 0; i < ranges_.size(); ++i)
            if (a >= ranges_[i].first && a - ranges_[i].first < ranges_[i].second) return int(i);
        return -1;
    }
    void b_transport(int, tlm::tlm_generic_payload& t, sc_core::sc_time& d) {
        const int r = route(t.get_address());
        if (r < 0) return t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
        out[r]->b_transport(t, d);
    }
    unsigned transport_dbg(int, tlm::tlm_generic_payload& t) {
        const int r = route(t.get_address());
        return r < 0 ? 0 : out[r]->transport_dbg(t);
    }
    bool get_direct_mem_ptr(int, tlm::tlm_generic_payload& t, tlm::tlm_dmi& d) {
        const int r = route(t.get_address());
        if (r < 0 || !out[r]->get_direct_mem_ptr(t, d)) return false;
        const auto [base, size] = ranges_[size_t(r)];
        if (d.get_start_address() < base) {
            d.set_dmi_ptr(d.get_dmi_ptr() + (base - d.get_start_address()));
            d.set_start_address(base);
        }
        d.set_end_address(std::min<uint64_t>(d.get_end_address(), base + size - 1));
        return true;
    }
    void invalidate_direct_mem_ptr(int, sc_dt::uint64 start, sc_dt::uint64 end) {
        for (unsigned i = 0; i < in.size(); ++i) in[i]->invalidate_direct_mem_ptr(start, end);
    }
    std::vector<std::pair<uint64_t, uint64_t>> ranges_;
};

// The CPU stand-in: a script on an SC_THREAD issuing 32-bit register accesses by b_transport
// (each access's annotated delay waited out) or transport_dbg, and waiting for an interrupt.
class Cpu : public sc_core::sc_module {
public:
    tlm_utils::simple_initiator_socket<Cpu, 32> bus{"bus"};
    sc_core::sc_in<bool> irq{"irq"};
    std::function<void()> script;
    bool finished = false;

    SC_HAS_PROCESS(Cpu);
    explicit Cpu(sc_core::sc_module_name n) : sc_module(n) { SC_THREAD(run); }

    // One access of `len` bytes at `addr` (`be`: a byte-enable mask, or null).
    tlm::tlm_response_status access(tlm::tlm_command cmd, uint64_t addr, void* data, unsigned len, bool debug = false,
                                    unsigned char* be = nullptr) {
        tlm::tlm_generic_payload t;
        set_access(t, cmd, addr, data, len, be);
        if (debug) {  // transport_dbg answers with a count: all of it or an error
            const unsigned n = bus->transport_dbg(t);
            if (n == len) return tlm::TLM_OK_RESPONSE;
            return t.is_response_error() ? t.get_response_status() : tlm::TLM_ADDRESS_ERROR_RESPONSE;
        }
        sc_core::sc_time d = sc_core::SC_ZERO_TIME;
        bus->b_transport(t, d);
        wait(d);
        return t.get_response_status();
    }
    // 32- and 64-bit (LO then HI) reads and writes of the register at `reg_base + off`; `ok`
    // turns false on an error response.
    uint64_t reg_base = 0;
    uint32_t rd(uint32_t off) {
        uint32_t v = 0;
        ok = access(tlm::TLM_READ_COMMAND, reg_base + off, &v, 4) == tlm::TLM_OK_RESPONSE && ok;
        return v;
    }
    uint64_t rd64(uint32_t lo) {
        const uint64_t l = rd(lo);
        return l | uint64_t(rd(lo + 4)) << 32;
    }
    void wr(uint32_t off, uint32_t v) { ok = access(tlm::TLM_WRITE_COMMAND, reg_base + off, &v, 4) == tlm::TLM_OK_RESPONSE && ok; }
    void wr64(uint32_t lo, uint64_t v) {
        wr(lo, uint32_t(v));
        wr(lo + 4, uint32_t(v >> 32));
    }
    // Bytes in or out of memory in zero time (as a platform's loader does).
    void load(uint64_t addr, const void* data, size_t n) { debug_bytes(tlm::TLM_WRITE_COMMAND, addr, const_cast<void*>(data), n); }
    void fetch(uint64_t addr, void* data, size_t n) { debug_bytes(tlm::TLM_READ_COMMAND, addr, data, n); }
    // Waits for the interrupt line to be high, at most `limit`; returns whether it is.
    bool wait_irq(sc_core::sc_time limit = sc_core::sc_time(1, sc_core::SC_SEC)) {
        if (!irq.read()) wait(limit, irq.posedge_event());
        return irq.read();
    }
    bool ok = true;  // every register access so far answered OK

private:
    void run() {
        if (script) script();
        finished = true;
    }
    void debug_bytes(tlm::tlm_command cmd, uint64_t addr, void* data, size_t n) {
        for (size_t done = 0; done < n;) {
            const unsigned len = unsigned(std::min<size_t>(n - done, 1u << 20));
            ok = access(cmd, addr + done, static_cast<uint8_t*>(data) + done, len, true) == tlm::TLM_OK_RESPONSE && ok;
            done += len;
        }
    }
};

}  // namespace rtu::vp
