// Drives one DRAM channel (model/dram.h) over timed requests as the DRAM module does: shared by
// the tests that work its schedule by hand (test_memory_model.cpp) and the test that every
// configuration key is read (test_rtsim.cpp).
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <vector>

#include "model/dram.h"

namespace rtu::test {

// Each request enters the queue at its `arrival` (requests in arrival order); returns each one's
// end of data by token. `every_cycle`: run every memory cycle instead of jumping to
// next_decision(), which must give the same answers if the jumps skip only cycles where nothing
// can issue.
inline std::map<uint64_t, uint64_t> drive_channel(const DramConfig& cfg, const std::vector<DramRequest>& requests,
                                                  bool every_cycle = false) {
    DramChannel ch(cfg);
    std::map<uint64_t, uint64_t> done;
    size_t next_arrival = 0;
    for (uint64_t t = 0; next_arrival < requests.size() || !ch.empty();) {
        for (; next_arrival < requests.size() && requests[next_arrival].arrival <= t; ++next_arrival) ch.enqueue(requests[next_arrival]);
        DramRequest out;
        uint64_t end;
        if (!ch.empty() && ch.next_decision() <= t && ch.schedule(t, &out, &end)) done[out.token] = end;
        uint64_t next = next_arrival < requests.size() ? requests[next_arrival].arrival : ~0ull;
        if (!ch.empty()) next = std::min(next, every_cycle ? t + 1 : std::max(t + 1, ch.next_decision()));
        t = next;
    }
    return done;
}

}  // namespace rtu::test
