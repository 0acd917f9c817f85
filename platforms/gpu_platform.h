// The GPU platform of the timing model: the only place where modules are wired together.
//   WorkloadDriver -> RtUnit[sm] -> L1[sm] -> Crossbar -> L2[slice] -> Dram
// Built from a HwConfig, elaborated once per process, run with sc_start().
#pragma once
#include <memory>

#include "timing_run.h"

namespace rtu {

class GpuPlatform {
public:
    GpuPlatform(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt);
    ~GpuPlatform();
    // Runs the simulation to the end (call once per process: SystemC elaborates once).
    TimingResult run();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtu
