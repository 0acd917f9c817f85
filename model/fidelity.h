// The four fidelities of the model (docs/timing.md): one type for the run entry point, the
// SystemC modules (which take AT or LT) and the reports. Plain C++ (no SystemC).
#pragma once

namespace rtu {

enum class Fidelity {
    Functional,  // every ray traced to completion, no time
    AT,          // the reference timing model: TLM-2.0 non-blocking transport, event-driven
    LT,          // loosely timed: blocking transport, quantum keeper, resources booked by timestamp
    Interval,    // one event per node fetch, no SystemC kernel
};

inline const char* fidelity_name(Fidelity f) {
    switch (f) {
        case Fidelity::Functional: return "functional";
        case Fidelity::AT: return "at";
        case Fidelity::LT: return "lt";
        case Fidelity::Interval: return "interval";
    }
    return "?";
}

// Parsed by parse_fidelity (platforms/fidelity_run.h), with the engine that runs each.
inline bool is_timing(Fidelity f) { return f != Fidelity::Functional; }

}  // namespace rtu
