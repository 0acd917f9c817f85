// The trace source of the RT-unit peripheral: hands the RT complex the traces of the current
// job, made by a workload driver over the job's rays exactly as rtsim's driver makes them from a
// ray file (warp w = rays [32w, 32w + 32) on SM w % sms, invalid rays answered as misses), and
// says when the job's last ray has retired. ABORT stops it handing out traces; the job then ends
// when the traces already in the RT units have left.
#pragma once
#include <memory>

#include <systemc>

#include "tlm/clock.h"
#include "model/trace_source.h"
#include "workloads/workload_driver.h"

namespace rtu {

class JobFeeder : public TraceSource {
public:
    // The RT complex's core clock, once it exists (it is built with this feeder as its source).
    void set_clock(const ClockDomain& clock) { clock_ = &clock; }
    // A new job's driver (kept until the next); `done` is notified at the simulated time its last
    // ray retires.
    void start(std::unique_ptr<WorkloadDriver> driver) {
        driver_ = std::move(driver);
        aborted_ = false;
        if (driver_->finished()) done.notify(sc_core::SC_ZERO_TIME);
    }
    void abort() {
        if (!driver_ || aborted_) return;
        aborted_ = true;
        if (in_flight() == 0) done.notify(sc_core::SC_ZERO_TIME);
    }
    bool aborted() const { return aborted_; }
    const WorkloadDriver* driver() const { return driver_.get(); }

    std::optional<std::vector<WarpRay>> next_trace(uint32_t sm, uint64_t now) override {
        if (!driver_ || aborted_) return std::nullopt;
        auto t = driver_->next_trace(sm, now);
        if (driver_->finished()) notify_at(now);  // a last trace of invalid rays only retires at once
        return t;
    }
    uint64_t earliest_ready(uint32_t sm) const override { return driver_ && !aborted_ ? driver_->earliest_ready(sm) : ~0ull; }
    void retire(uint32_t sm, const std::vector<RetiredRay>& rays, uint64_t now) override {
        driver_->retire(sm, rays, now);
        if (driver_->finished() || (aborted_ && in_flight() == 0)) notify_at(now);
    }

    sc_core::sc_event done;

private:
    uint64_t in_flight() const { return driver_->rays_issued() - driver_->rays_retired(); }
    // LT runs ahead of simulated time: the event fires at the cycle's time, never before it.
    void notify_at(uint64_t cycle) {
        const sc_core::sc_time t = clock_->time_of(cycle), now = sc_core::sc_time_stamp();
        done.notify(t > now ? t - now : sc_core::SC_ZERO_TIME);
    }

    const ClockDomain* clock_ = nullptr;
    std::unique_ptr<WorkloadDriver> driver_;
    bool aborted_ = false;
};

}  // namespace rtu
