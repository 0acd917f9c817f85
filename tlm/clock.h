// Clock domains: the core clock (RT units, caches, crossbar) and the memory clock (DRAM).
// rtsim sets the time resolution to 1 fs so that both periods are represented closely.
// Cycle 0 of both clocks is at the epoch: time 0 in rtsim; an SoC peripheral sets it once, to its
// first job's start, so that its RT complex runs that job exactly as rtsim runs a frame from 0
// (tlm/rt_complex.h). Times before the epoch are cycle 0.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include <systemc>

namespace rtu {

class ClockDomain {
public:
    // The period in whole ticks of the kernel's time resolution: exact to 1 fs in rtsim (which
    // sets that resolution); a platform with a coarser one (1 ps, SystemC's default) gets the
    // period rounded to it (732.601 ps -> 733 ps at 1365 MHz).
    // A period the resolution represents otherwise than 1 fs does, rtsim's resolution (SystemC's
    // default 1 ps: 733 ps against 732.601 at 1365 MHz, 0.055 %, so that 3,300 cycles of such a
    // clock are 3,302 exact ones), is warned about at elaboration (report "rtunit/clock"): the
    // cycles of a platform at that resolution drift from rtsim's without another word.
    explicit ClockDomain(double mhz)
        : tick_fs_(std::llround(sc_core::sc_get_time_resolution().to_seconds() * 1e15)),
          period_ticks_(std::max<int64_t>(1, std::llround(1e9 / mhz / double(tick_fs_)))),
          period_(sc_core::sc_time::from_value(period_ticks_)) {
        const double exact_fs = 1e9 / mhz, off = double(period_ticks_ * tick_fs_) / exact_fs - 1.0;
        if (int64_t(period_ticks_ * tick_fs_) != std::max<int64_t>(1, std::llround(exact_fs))) {
            char msg[320];
            std::snprintf(msg, sizeof msg,
                          "the %g MHz clock's period of %.3f ps is %.3f ps at SystemC's time resolution of %g ps (%+.4f %%: the "
                          "cycles drift from rtsim's); call sc_core::sc_set_time_resolution(1, sc_core::SC_FS) before elaboration",
                          mhz, exact_fs / 1e3, double(period_ticks_ * tick_fs_) / 1e3, double(tick_fs_) / 1e3, off * 100.0);
            SC_REPORT_WARNING("rtunit/clock", msg);
        }
    }
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
