// Clock domains: the core clock (RT units, caches, crossbar) and the memory clock (DRAM).
// rtsim sets the time resolution to 1 fs so that both periods are represented closely.
// Cycle 0 of both clocks is at the epoch: time 0 in rtsim; an SoC peripheral sets it once, to its
// first job's start, so that its RT complex runs that job exactly as rtsim runs a frame from 0
// (tlm/rt_complex.h). Times before the epoch are cycle 0.
#pragma once
#include <cmath>
#include <algorithm>
#include <cstdint>

#include <systemc>

namespace rtu {

class ClockDomain {
public:
    // The period in whole ticks of the kernel's time resolution: exact to 1 fs in rtsim (which
    // sets that resolution); a platform with a coarser one (1 ps, SystemC's default) gets the
    // period rounded to it (732.601 ps -> 733 ps at 1365 MHz).
    explicit ClockDomain(double mhz)
        : tick_fs_(std::llround(sc_core::sc_get_time_resolution().to_seconds() * 1e15)),
          period_ticks_(std::max<int64_t>(1, std::llround(1e9 / mhz / double(tick_fs_)))),
          period_(sc_core::sc_time::from_value(period_ticks_)) {}
    void set_epoch(const sc_core::sc_time& t) { epoch_ = t.value(); }
    sc_core::sc_time epoch() const { return sc_core::sc_time::from_value(epoch_); }
    const sc_core::sc_time& period() const { return period_; }
    // The cycle at or after time t (the next clock edge).
    uint64_t cycle_at_or_after(const sc_core::sc_time& t) const {
        const uint64_t ticks = since_epoch(t);
        return (ticks + period_ticks_ - 1) / period_ticks_;
    }
    uint64_t cycle_at_or_before(const sc_core::sc_time& t) const { return since_epoch(t) / period_ticks_; }
    sc_core::sc_time time_of(uint64_t cycle) const { return sc_core::sc_time::from_value(epoch_ + cycle * period_ticks_); }
    uint64_t period_fs() const { return period_ticks_ * tick_fs_; }

private:
    uint64_t since_epoch(const sc_core::sc_time& t) const { return t.value() > epoch_ ? t.value() - epoch_ : 0; }
    uint64_t tick_fs_, period_ticks_, epoch_ = 0;  // epoch_ in ticks
    sc_core::sc_time period_;
};

}  // namespace rtu
