// The register block of the RT-unit peripheral (include/rtunit/rtu_regs.h): the registers'
// values and the access rules of a 32-bit register block on a TLM bus, without side effects of
// its own: it reports commands (START, ABORT, SOFT_RESET, ...) to the peripheral that owns it.
// Rules (docs/peripheral.md; the VCML convention): 4-byte aligned accesses, or one aligned
// 8-byte access to a 64-bit LO/HI pair; any other length or an unaligned one is a burst error, a
// byte-enable mask a byte-enable error, an unmapped offset an address error, a write to a
// read-only or a read of a write-only register a command error. Debug accesses follow the same
// rules but have no side effects: no latching, no write-1-to-clear, no command; a debug write
// stores into plain read-write registers only (not CTRL, INT_ENABLE or PERF_CTRL).
#pragma once
#include <array>
#include <cstdint>

#include <tlm>

#include <rtunit/rtu_regs.h>

namespace rtu {

class RtuRegisters {
public:
    enum class Access : uint8_t { Unmapped, RO, RW, WO, W1C };
    static Access access_of(uint32_t offset);
    // `offset` is the LO word of a 64-bit pair (an 8-byte access may take both words at once).
    static bool is_pair(uint32_t offset);

    RtuRegisters(uint32_t config0, uint32_t config1);
    // Every register at its reset value (SOFT_RESET); CONFIG0/1 stay.
    void reset();

    // What a write asked the peripheral to do.
    struct Commands {
        bool start = false, abort = false, soft_reset = false, irq_changed = false;
    };
    // One TLM access at `offset` into the aperture: checks the rules, reads or writes the words,
    // sets the response status. Returns the commands it carries (none for debug accesses).
    Commands access(tlm::tlm_generic_payload& t, uint32_t offset, bool debug);

    // Register storage as software wrote it (RW registers), and 64-bit pairs of it.
    uint32_t word(uint32_t offset) const { return r_[offset / 4]; }
    uint64_t pair(uint32_t lo) const { return uint64_t(r_[lo / 4]) | uint64_t(r_[lo / 4 + 1]) << 32; }

    // State the peripheral sets.
    struct State {
        bool busy = false, done = false, error = false, aborted = false, start_ignored = false;
        uint32_t err_code = 0;
        uint32_t descs_done = 0;  // descriptors completed in the current chain
        uint64_t err_addr = 0;
    } state;
    uint32_t int_status = 0;
    void raise(uint32_t int_bits) { int_status |= int_bits; }
    bool irq_level() const { return (int_status & r_[RTU_INT_ENABLE / 4]) != 0; }

    // Performance counters, by (offset - RTU_PERF_BUSY_CYCLES) / 8; counting() is false while
    // PERF_CTRL has ENABLE clear or FREEZE set.
    static constexpr uint32_t kPerfCounters = (RTU_PERF_MEM_BYTES_WR - RTU_PERF_BUSY_CYCLES) / 8 + 1;
    static constexpr uint32_t perf_index(uint32_t offset) { return (offset - RTU_PERF_BUSY_CYCLES) / 8; }
    std::array<uint64_t, kPerfCounters> perf{};
    bool counting() const { return (r_[RTU_PERF_CTRL / 4] & RTU_PERF_ENABLE) && !(r_[RTU_PERF_CTRL / 4] & RTU_PERF_FREEZE); }
    void count(uint32_t offset, uint64_t n) {
        if (counting()) perf[perf_index(offset)] += n;
    }
    void set_counter(uint32_t offset, uint64_t v) {
        if (counting()) perf[perf_index(offset)] = v;
    }

private:
    uint32_t read_word(uint32_t offset, bool debug);
    void write_word(uint32_t offset, uint32_t value, Commands& c);

    uint32_t config0_, config1_;
    std::array<uint32_t, RTU_APERTURE_BYTES / 4> r_{};
    std::array<uint32_t, kPerfCounters> latched_hi_{};  // HI halves latched by reading LO
};

}  // namespace rtu
