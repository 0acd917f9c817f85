// The interval fidelity (docs/interval.md): the GPU of the timing model with one event per node
// fetch (model/interval_gpu.h) instead of cycle stepping, driven by the same workload driver as
// AT and LT: warp-buffer slots take traces in the order they come free, and a trace's rays
// retire when its slowest thread is done. No SystemC kernel: slot-free events and the GPU's
// fetch events, merged in time order.
#pragma once
#include "timing_run.h"

namespace rtu {

// Uses `fidelity`-independent options only: order, progress, keep_rays and sampling. Throws
// std::invalid_argument for what the interval fidelity does not model (IntervalGpu).
TimingResult run_interval(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt);

}  // namespace rtu
