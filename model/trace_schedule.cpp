#include "trace_schedule.h"

#include <algorithm>
#include <functional>
#include <queue>
#include <stdexcept>
#include <utility>

namespace rtu {

double schedule_cycles(const std::vector<std::vector<double>>& traces, const ScheduleShape& shape) {
    if (shape.sms == 0 || shape.slots == 0) throw std::invalid_argument("schedule_cycles: no RT unit or no slot");
    double end = 0;
    using Ready = std::pair<double, size_t>;  // (ready cycle, warp)
    for (uint32_t sm = 0; sm < shape.sms; ++sm) {
        std::priority_queue<Ready, std::vector<Ready>, std::greater<Ready>> ready;
        std::priority_queue<double, std::vector<double>, std::greater<double>> free_at;
        std::vector<size_t> next(traces.size(), 0);
        for (size_t w = sm; w < traces.size(); w += shape.sms)
            if (!traces[w].empty()) ready.push({0.0, w});
        for (uint32_t s = 0; s < shape.slots; ++s) free_at.push(0.0);
        while (!ready.empty()) {
            const auto [at, w] = ready.top();
            ready.pop();
            const double start = std::max(at, free_at.top());
            free_at.pop();
            const double done = start + traces[w][next[w]];
            free_at.push(done);
            end = std::max(end, done);
            if (++next[w] < traces[w].size()) ready.push({done + double(shape.shade), w});
        }
    }
    return end;
}

}  // namespace rtu
