#include "schedule_model.h"

#include <algorithm>
#include <functional>
#include <queue>
#include <stdexcept>
#include <utility>

namespace rtu {

namespace {

// With a limit of resident warps per SM: an event-driven run, since a finished warp's place on
// its SM goes to the next warp of the frame.
std::vector<double> schedule_resident(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape) {
    struct Event {
        double at;
        int kind;  // 0: a trace ends (its slot frees first), 1: a warp's next trace is ready
        uint32_t sm;
        size_t warp;
        bool operator>(const Event& o) const { return at != o.at ? at > o.at : kind != o.kind ? kind > o.kind : warp > o.warp; }
    };
    std::priority_queue<Event, std::vector<Event>, std::greater<Event>> events;
    using Ready = std::pair<double, size_t>;  // (ready cycle, warp)
    std::vector<std::priority_queue<Ready, std::vector<Ready>, std::greater<Ready>>> ready(shape.sms);
    std::vector<uint32_t> free_slots(shape.sms, shape.slots);
    std::vector<size_t> next(traces.size(), 0);
    size_t launched = 0;
    auto launch = [&](uint32_t sm, double at) {
        while (launched < traces.size() && traces[launched].empty()) ++launched;  // a warp without traces needs no place
        if (launched < traces.size()) events.push({at, 1, sm, launched++});
    };
    for (uint64_t k = 0; k < uint64_t(shape.sms) * shape.resident; ++k) launch(uint32_t(k % shape.sms), double(shape.first));
    std::vector<double> end(shape.sms, 0.0);
    while (!events.empty()) {
        const Event e = events.top();
        events.pop();
        if (e.kind == 0) {
            ++free_slots[e.sm];
            if (next[e.warp] < traces[e.warp].size())
                events.push({e.at + double(shape.shade), 1, e.sm, e.warp});
            else
                launch(e.sm, e.at + double(shape.lead));
        } else {
            ready[e.sm].push({e.at, e.warp});
        }
        // The SM's free slots take its ready traces, earliest first.
        while (free_slots[e.sm] > 0 && !ready[e.sm].empty() && ready[e.sm].top().first <= e.at) {
            const size_t w = ready[e.sm].top().second;
            ready[e.sm].pop();
            --free_slots[e.sm];
            const double done = e.at + traces[w][next[w]++];
            end[e.sm] = std::max(end[e.sm], done);
            events.push({done, 0, e.sm, w});
        }
    }
    return end;
}

}  // namespace

std::vector<double> schedule_sm_ends(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape) {
    if (shape.sms == 0 || shape.slots == 0) throw std::invalid_argument("schedule_cycles: no RT unit or no slot");
    if (shape.resident > 0) return schedule_resident(traces, shape);
    std::vector<double> end(shape.sms, 0.0);
    using Ready = std::pair<double, size_t>;  // (ready cycle, warp)
    for (uint32_t sm = 0; sm < shape.sms; ++sm) {
        std::priority_queue<Ready, std::vector<Ready>, std::greater<Ready>> ready;
        std::priority_queue<double, std::vector<double>, std::greater<double>> free_at;
        std::vector<size_t> next(traces.size(), 0);
        for (size_t w = sm; w < traces.size(); w += shape.sms)
            if (!traces[w].empty()) ready.push({double(shape.first), w});
        for (uint32_t s = 0; s < shape.slots; ++s) free_at.push(0.0);
        while (!ready.empty()) {
            const auto [at, w] = ready.top();
            ready.pop();
            const double start = std::max(at, free_at.top());
            free_at.pop();
            const double done = start + traces[w][next[w]];
            free_at.push(done);
            end[sm] = std::max(end[sm], done);
            if (++next[w] < traces[w].size()) ready.push({done + double(shape.shade), w});
        }
    }
    return end;
}

double schedule_cycles(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape) {
    const std::vector<double> end = schedule_sm_ends(traces, shape);
    return *std::max_element(end.begin(), end.end());
}

}  // namespace rtu
