// Clock domains: the core clock (RT units, caches, crossbar) and the memory clock (DRAM).
// Simulated time resolution is 1 fs so that both periods are represented closely.
#pragma once
#include <cmath>
#include <cstdint>

#include <systemc>

namespace rtu {

class ClockDomain {
public:
    explicit ClockDomain(double mhz) : period_fs_(std::llround(1e9 / mhz)), period_(double(period_fs_), sc_core::SC_FS) {}
    const sc_core::sc_time& period() const { return period_; }
    // The cycle at or after time t (the next clock edge).
    uint64_t cycle_at_or_after(const sc_core::sc_time& t) const {
        const uint64_t fs = t.value();  // time resolution is 1 fs
        return (fs + period_fs_ - 1) / period_fs_;
    }
    uint64_t cycle_at_or_before(const sc_core::sc_time& t) const { return t.value() / period_fs_; }
    sc_core::sc_time time_of(uint64_t cycle) const { return sc_core::sc_time::from_value(cycle * period_fs_); }
    uint64_t period_fs() const { return period_fs_; }

private:
    uint64_t period_fs_;
    sc_core::sc_time period_;
};

}  // namespace rtu
