// --timeline FILE.json: one warp-buffer slot's threads through the run, as Chrome trace events
// (the Trace Event Format's JSON object form, which Perfetto and chrome://tracing open). One track
// per thread (pid: the SM, tid: the thread); a span per status the thread was in: "schedule"
// (waiting for the warp scheduler), "fetch" (waiting for a node read, named by where it was
// served: L1 hit, L1 miss, DRAM), "test" (the node's intersection tests); an instant event per
// prefetch chunk its TTP state machine picked. Time is in core cycles, written as the format's
// microseconds (so 1 us on the axis is 1 cycle). Reading the RT unit changes nothing
// (RtsimTiming.TimelineChangesNoStatistic).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/rt_unit_core.h"

namespace rtu {

class Timeline {
public:
    Timeline(uint32_t sm, uint32_t slot, uint32_t warp_size) : sm_(sm), slot_(slot), open_(warp_size) {}
    // After cycle `cycle` of the unit: spans end where a thread's status (or warp) changed.
    void sample(const RtUnitCore& core, uint64_t cycle);
    // A prefetch chunk generated on behalf of thread `thread` of slot `slot`.
    void prefetch(uint32_t slot, uint32_t thread, uint64_t addr, uint64_t cycle);
    // The trace, spans still open ending at `end`.
    std::string json(uint64_t end) const;

private:
    struct Open {
        RtUnitCore::ThreadView view;
        uint64_t since = 0;
    };
    // Appends the span of `o` up to `end` (if it has one) to `out`, a comma-separated event list.
    void append_span(std::string& out, uint32_t thread, const Open& o, uint64_t end) const;

    uint32_t sm_, slot_;
    std::vector<Open> open_;
    std::string events_;  // the closed spans and instants, comma-separated JSON objects
};

}  // namespace rtu
