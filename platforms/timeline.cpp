#include "timeline.h"

#include <cinttypes>
#include <cstdio>

namespace rtu {

namespace {
const char* span_name(const RtUnitCore::ThreadView& v) {
    switch (v.status) {
        case ThreadStatus::WaitSchedule: return "schedule";
        case ThreadStatus::WaitMemory: return v.dram ? "fetch: DRAM" : v.l1_miss ? "fetch: L1 miss" : "fetch: L1 hit";
        case ThreadStatus::InMath: return "test";
        default: return "";
    }
}
}  // namespace

void Timeline::append_span(std::string& out, uint32_t thread, const Open& o, uint64_t end) const {
    if (o.view.status == ThreadStatus::Idle || end <= o.since) return;
    char e[320];
    std::snprintf(e, sizeof e,
                  "%s{\"name\":\"%s\",\"cat\":\"thread\",\"ph\":\"X\",\"ts\":%" PRIu64 ",\"dur\":%" PRIu64
                  ",\"pid\":%u,\"tid\":%u,\"args\":{\"warp\":%" PRIu64 ",\"node\":%" PRIu64 "}}",
                  out.empty() ? "" : ",\n", span_name(o.view), o.since, end - o.since, sm_, thread, o.view.warp, o.view.node);
    out += e;
}

void Timeline::sample(const RtUnitCore& core, uint64_t cycle) {
    for (uint32_t t = 0; t < open_.size(); ++t) {
        const RtUnitCore::ThreadView v = core.thread_view(slot_, t);
        Open& o = open_[t];
        // A fetch's span is named by where it was served, known once it is whole: the status that
        // follows it. So the view is refreshed while the status stays, and a span closes on the
        // next cycle's change (the changes of a cycle are all seen after it).
        if (v.status == o.view.status && v.warp == o.view.warp && (v.status != ThreadStatus::WaitMemory || v.node == o.view.node)) {
            o.view.l1_miss = v.l1_miss;
            o.view.dram = v.dram;
            continue;
        }
        if (o.view.status == ThreadStatus::WaitMemory) {  // the served flags of the read just ended
            o.view.l1_miss = v.l1_miss;
            o.view.dram = v.dram;
        }
        append_span(events_, t, o, cycle);
        o = {v, cycle};
    }
}

void Timeline::prefetch(uint32_t slot, uint32_t thread, uint64_t addr, uint64_t cycle) {
    if (slot != slot_) return;
    char e[240];
    std::snprintf(e, sizeof e,
                  "%s{\"name\":\"prefetch\",\"cat\":\"ttp\",\"ph\":\"i\",\"s\":\"t\",\"ts\":%" PRIu64 ",\"pid\":%u,\"tid\":%u,\"args\":{\"chunk\":%" PRIu64 "}}",
                  events_.empty() ? "" : ",\n", cycle, sm_, thread, addr);
    events_ += e;
}

std::string Timeline::json(uint64_t end) const {
    char meta[200];
    std::snprintf(meta, sizeof meta, "{\"name\":\"process_name\",\"ph\":\"M\",\"pid\":%u,\"args\":{\"name\":\"RT unit %u, warp-buffer slot %u\"}}", sm_,
                  sm_, slot_);
    std::string events = meta;  // then the closed spans and instants, then the spans still open
    if (!events_.empty()) events.append(",\n").append(events_);
    for (uint32_t t = 0; t < open_.size(); ++t) append_span(events, t, open_[t], end);
    return "{\"displayTimeUnit\":\"ns\",\"otherData\":{\"time_unit\":\"1 us on the time axis = 1 core cycle\"},\n\"traceEvents\":[" + events + "]}\n";
}

}  // namespace rtu
