#include "schedule_model.h"

#include <algorithm>
#include <functional>
#include <queue>
#include <stdexcept>
#include <utility>

#include "workloads/warp_selection.h"

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
    auto more = [&] {  // skips the warps without traces (they need no place): is there a next warp?
        while (launched < traces.size() && traces[launched].empty()) ++launched;
        return launched < traces.size();
    };
    auto launch = [&](uint32_t sm, double at) { events.push({at, 1, sm, launched++}); };
    // With contention, per SM its warps in shader code, counted as the workload driver counts them.
    std::vector<ShaderCodeEnds<double>> shading(shape.contention > 0 ? shape.sms : 0);
    auto shade = [&](uint32_t sm, double now, double cycles) {
        if (shading.empty() || cycles <= 0) return now + cycles;
        const double at = now + cycles * (1.0 + shape.contention * double(shading[sm].beside(now)));
        shading[sm].add(at);
        return at;
    };
    // The first warps: those with traces, in order, round robin; an SM's begin their code together.
    const uint64_t with_traces = uint64_t(std::count_if(traces.begin(), traces.end(), [](const auto& t) { return !t.empty(); }));
    const uint64_t first_warps = std::min(with_traces, uint64_t(shape.sms) * shape.resident);
    for (uint64_t k = 0; k < first_warps && more(); ++k) {
        const uint32_t sm = uint32_t(k % shape.sms);
        const uint64_t others = first_warps / shape.sms + (sm < first_warps % shape.sms) - 1;
        const double at = double(shape.first) + double(shape.lead) * shape.contention * double(others);
        if (!shading.empty() && shape.lead > 0) shading[sm].add(at);
        launch(sm, at);
    }
    std::vector<double> end(shape.sms, 0.0);
    while (!events.empty()) {
        const Event e = events.top();
        events.pop();
        if (e.kind == 0) {
            ++free_slots[e.sm];
            if (next[e.warp] < traces[e.warp].size())
                events.push({shade(e.sm, e.at, double(shape.shade)), 1, e.sm, e.warp});
            else if (more())
                launch(e.sm, shade(e.sm, e.at, double(shape.lead)));
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
    if (shape.contention > 0) throw std::invalid_argument("schedule_cycles: shader contention needs a limit of resident warps");
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
