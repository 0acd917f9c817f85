// A request to stop a long run at its next clean point (rtsim sets it from SIGINT and SIGTERM;
// docs/robustness.md). The owner of the flag stores a nonzero value (the signal number) from a
// signal handler; runs read it with a relaxed load where stopping leaves consistent statistics:
// between rays (functional), between events (interval), at the monitor's wake-ups (AT, LT),
// between warps (the sampling pre-pass). Plain C++; no process-wide state of its own.
#pragma once
#include <atomic>

namespace rtu {

struct StopRequest {
    const std::atomic<int>* flag = nullptr;  // not owned; null: never stops
    bool requested() const { return flag && flag->load(std::memory_order_relaxed) != 0; }
    int signal() const { return flag ? flag->load(std::memory_order_relaxed) : 0; }
};

// Thrown where a stop request ends a run before it has anything to report (loading, building, the
// sampling pre-pass): the caller writes nothing.
struct Interrupted {
    int signal;
};

}  // namespace rtu
