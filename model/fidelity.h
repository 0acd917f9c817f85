// The four fidelities of the model (docs/timing.md): one type for the run entry point, the
// SystemC modules (which take AT or LT) and the reports. Plain C++ (no SystemC).
#pragma once
#include <stdexcept>
#include <string>

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

// Throws std::invalid_argument naming the allowed values.
inline Fidelity parse_fidelity(const std::string& name) {
    for (Fidelity f : {Fidelity::Functional, Fidelity::AT, Fidelity::LT, Fidelity::Interval})
        if (name == fidelity_name(f)) return f;
    throw std::invalid_argument("--fidelity '" + name + "': allowed are functional, at, lt, interval");
}

inline bool is_timing(Fidelity f) { return f != Fidelity::Functional; }

}  // namespace rtu
