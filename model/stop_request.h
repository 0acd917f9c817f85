// A request to stop a long run at its next clean point (rtsim sets it from SIGINT, SIGTERM and
// SIGHUP; docs/robustness.md), or for its statistics so far while it goes on (SIGUSR1). The
// owner of a flag stores a nonzero value from a signal handler; runs read it with a relaxed load
// where stopping leaves consistent statistics: between batches of rays (functional), between
// events (interval), at the monitor's wake-ups (AT, LT), between warps (the sampling pre-pass).
// Plain C++; no process-wide state of its own.
#pragma once
#include <atomic>

namespace rtu {

struct StopRequest {
    const std::atomic<int>* flag = nullptr;  // not owned; null: never stops
    bool requested() const { return flag && flag->load(std::memory_order_relaxed) != 0; }
    int signal() const { return flag ? flag->load(std::memory_order_relaxed) : 0; }
    // A request for the statistics so far, the run going on (rtsim sets it from SIGUSR1): true
    // once per request, read at the same clean points as a stop.
    std::atomic<int>* snapshot = nullptr;  // not owned; null: never asked
    bool snapshot_requested() const { return snapshot && snapshot->load(std::memory_order_relaxed) != 0 && snapshot->exchange(0) != 0; }
};

// Thrown where a stop request ends a run before it has anything to report (loading, building, the
// sampling pre-pass): the caller writes nothing.
struct Interrupted {
    int signal;
};

}  // namespace rtu
