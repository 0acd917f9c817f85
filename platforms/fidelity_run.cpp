#include "fidelity_run.h"

#include <stdexcept>

#include "gpu_platform.h"
#include "interval_run.h"

namespace rtu {

Engine engine_of(Fidelity f) {
    switch (f) {
        case Fidelity::Functional: return Engine::Functional;
        case Fidelity::Interval: return Engine::Interval;
        case Fidelity::AT:
        case Fidelity::LT: return Engine::SystemC;
    }
    throw std::logic_error("engine_of: unknown fidelity");
}

Fidelity parse_fidelity(const std::string& name, const std::string& what) {
    for (Fidelity f : {Fidelity::Functional, Fidelity::AT, Fidelity::LT, Fidelity::Interval})
        if (name == fidelity_name(f)) return f;
    throw std::invalid_argument(what + " '" + name + "': allowed are functional, at, lt, interval");
}

TimingResult run_timing(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt) {
    switch (engine_of(opt.fidelity)) {
        case Engine::Interval: return run_interval(cfg, image, workload, opt);
        case Engine::SystemC: return GpuPlatform(cfg, image, workload, opt).run();
        case Engine::Functional: break;
    }
    throw std::logic_error("run_timing: the functional fidelity has no timing run");
}

}  // namespace rtu
