#include "rtu_registers.h"

#include <cstring>

namespace rtu {

namespace {

bool is_perf(uint32_t off) { return off >= RTU_PERF_BUSY_CYCLES && off < RTU_PERF_MEM_BYTES_WR + 8; }

}  // namespace

RtuRegisters::Access RtuRegisters::access_of(uint32_t off) {
    if (off % 4 != 0 || off >= RTU_APERTURE_BYTES) return Access::Unmapped;
    if (is_perf(off)) return Access::RO;
    switch (off) {
        case RTU_ID: case RTU_VERSION: case RTU_CONFIG0: case RTU_CONFIG1: case RTU_STATUS: case RTU_ERR_CODE:
        case RTU_ERR_ADDR_LO: case RTU_ERR_ADDR_HI:
            return Access::RO;
        case RTU_INT_STATUS: return Access::W1C;
        case RTU_INT_SET: return Access::WO;
        case RTU_CTRL: case RTU_INT_ENABLE: case RTU_DESC_ADDR_LO: case RTU_DESC_ADDR_HI: case RTU_BVH_BASE_LO:
        case RTU_BVH_BASE_HI: case RTU_BVH_SIZE_LO: case RTU_BVH_SIZE_HI: case RTU_RAY_BASE_LO: case RTU_RAY_BASE_HI:
        case RTU_RAY_COUNT: case RTU_STRIDES: case RTU_HIT_BASE_LO: case RTU_HIT_BASE_HI: case RTU_JOB_FLAGS: case RTU_JOB_ID:
        case RTU_MAX_CHAIN: case RTU_PERF_CTRL: case RTU_SCRATCH:
            return Access::RW;
        default: return Access::Unmapped;
    }
}

bool RtuRegisters::is_pair(uint32_t off) {
    if (is_perf(off)) return (off - RTU_PERF_BUSY_CYCLES) % 8 == 0;
    switch (off) {
        case RTU_ERR_ADDR_LO: case RTU_DESC_ADDR_LO: case RTU_BVH_BASE_LO: case RTU_BVH_SIZE_LO: case RTU_RAY_BASE_LO:
        case RTU_HIT_BASE_LO:
            return true;
        default: return false;
    }
}

RtuRegisters::RtuRegisters(uint32_t config0, uint32_t config1) : config0_(config0), config1_(config1) { reset(); }

void RtuRegisters::reset() {
    r_.fill(0);
    r_[RTU_STRIDES / 4] = (uint32_t(sizeof(rtu_hit)) << 16) | uint32_t(sizeof(rtu_ray));
    r_[RTU_MAX_CHAIN / 4] = 65536;
    r_[RTU_PERF_CTRL / 4] = RTU_PERF_ENABLE;
    state = State{};
    int_status = 0;
    perf.fill(0);
    latched_hi_.fill(0);
}

uint32_t RtuRegisters::read_word(uint32_t off, bool debug) {
    if (is_perf(off)) {
        const uint32_t i = perf_index(off);
        if ((off - RTU_PERF_BUSY_CYCLES) % 8 == 0) {  // LO: latches HI
            if (!debug) latched_hi_[i] = uint32_t(perf[i] >> 32);
            return uint32_t(perf[i]);
        }
        return debug ? uint32_t(perf[i] >> 32) : latched_hi_[i];
    }
    switch (off) {
        case RTU_ID: return RTU_ID_VALUE;
        case RTU_VERSION: return RTU_VERSION_VALUE;
        case RTU_CONFIG0: return config0_;
        case RTU_CONFIG1: return config1_;
        case RTU_CTRL: return r_[off / 4] & RTU_CTRL_MODE_CHAIN;  // the command bits clear themselves
        case RTU_STATUS:
            return (state.busy ? RTU_STATUS_BUSY : 0u) | (state.done ? RTU_STATUS_DONE : 0u) | (state.error ? RTU_STATUS_ERROR : 0u) |
                   (state.aborted ? RTU_STATUS_ABORTED : 0u) | (state.start_ignored ? RTU_STATUS_START_IGNORED : 0u) |
                   (state.err_code & 0xFFu) << 8 | (state.descs_done < 0xFFFFu ? state.descs_done : 0xFFFFu) << 16;
        case RTU_ERR_CODE: return state.err_code;
        case RTU_ERR_ADDR_LO: return uint32_t(state.err_addr);
        case RTU_ERR_ADDR_HI: return uint32_t(state.err_addr >> 32);
        case RTU_INT_STATUS: return int_status;
        case RTU_PERF_CTRL: return r_[off / 4] & (RTU_PERF_ENABLE | RTU_PERF_FREEZE);
        default: return r_[off / 4];
    }
}

void RtuRegisters::write_word(uint32_t off, uint32_t v, Commands& c) {
    switch (off) {
        case RTU_CTRL:
            r_[off / 4] = v & RTU_CTRL_MODE_CHAIN;
            c.start = c.start || (v & RTU_CTRL_START);
            c.abort = c.abort || (v & RTU_CTRL_ABORT);
            c.soft_reset = c.soft_reset || (v & RTU_CTRL_SOFT_RESET);
            return;
        case RTU_INT_STATUS:
            int_status &= ~v;
            c.irq_changed = true;
            return;
        case RTU_INT_SET:
            int_status |= v & RTU_INT_ALL;
            c.irq_changed = true;
            return;
        case RTU_INT_ENABLE:
            r_[off / 4] = v & RTU_INT_ALL;
            c.irq_changed = true;
            return;
        case RTU_PERF_CTRL:
            if (v & RTU_PERF_CLEAR) {
                perf.fill(0);
                latched_hi_.fill(0);
            }
            r_[off / 4] = v & (RTU_PERF_ENABLE | RTU_PERF_FREEZE);
            return;
        default: r_[off / 4] = v;
    }
}

RtuRegisters::Commands RtuRegisters::access(tlm::tlm_generic_payload& t, uint32_t off, bool debug) {
    Commands c;
    const unsigned len = t.get_data_length();
    if (t.get_byte_enable_ptr()) return t.set_response_status(tlm::TLM_BYTE_ENABLE_ERROR_RESPONSE), c;
    if (t.get_command() == tlm::TLM_IGNORE_COMMAND) return t.set_response_status(tlm::TLM_OK_RESPONSE), c;
    if (access_of(off) == Access::Unmapped) return t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE), c;
    const bool single = len == 4 && off % 4 == 0, both = len == 8 && is_pair(off);
    if ((!single && !both) || t.get_streaming_width() < len) return t.set_response_status(tlm::TLM_BURST_ERROR_RESPONSE), c;
    const bool write = t.get_command() == tlm::TLM_WRITE_COMMAND;
    for (unsigned w = 0; w < len / 4; ++w) {
        const Access a = access_of(off + 4 * w);
        if (write ? a == Access::RO : a == Access::WO) return t.set_response_status(tlm::TLM_COMMAND_ERROR_RESPONSE), c;
    }
    unsigned char* data = t.get_data_ptr();
    for (unsigned w = 0; w < len / 4; ++w) {
        uint32_t v = 0;
        if (write) {
            std::memcpy(&v, data + 4 * w, 4);
            const uint32_t o = off + 4 * w;
            if (!debug) write_word(o, v, c);
            else if (o != RTU_CTRL && o != RTU_INT_ENABLE && o != RTU_PERF_CTRL && access_of(o) == Access::RW) r_[o / 4] = v;
        } else {
            v = read_word(off + 4 * w, debug);
            std::memcpy(data + 4 * w, &v, 4);
        }
    }
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    return c;
}

}  // namespace rtu
