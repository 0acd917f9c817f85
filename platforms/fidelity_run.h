// The one dispatch from a fidelity to the engine that runs it, shared by rtsim (run_simulation)
// and the SoC peripheral (include/rtunit/peripheral.h). Plain C++ (no SystemC).
// - functional: no timing; platforms/functional_run.h.
// - interval: one event per node fetch, no SystemC kernel (platforms/interval_run.h).
// - AT, LT: the RT complex on SystemC. rtsim elaborates a GpuPlatform of its own for the run (one
//   per process); the peripheral has elaborated its RT complex inside the user's platform, whose
//   clocks and memory its jobs wait on, so it runs its jobs there (Engine::SystemC) and calls
//   run_timing for the interval fidelity only.
#pragma once
#include <string>

#include "model/fidelity.h"
#include "timing_run.h"

namespace rtu {

enum class Engine { Functional, Interval, SystemC };
Engine engine_of(Fidelity f);

// `what` names the option in the message of a bad name (e.g. "--fidelity"); throws
// std::invalid_argument naming the allowed values.
Fidelity parse_fidelity(const std::string& name, const std::string& what);

// A timing run (opt.fidelity interval, at or lt) of `workload` on `image`; std::invalid_argument
// for what the interval fidelity does not model (IntervalGpu).
TimingResult run_timing(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt);

}  // namespace rtu
