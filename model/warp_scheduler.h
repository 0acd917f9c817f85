// The RT unit's warp scheduler (paper section 2.3): each cycle it picks one warp of the warp
// buffer whose threads are ready to read their next node, and those threads' reads go to the
// memory access queue. The policy (rt.warp_scheduler):
//  - round robin: the first warp with ready threads after the one picked last;
//  - oldest first: the warp that entered the warp buffer first, among those with ready threads
//    (the TTP authors' RT unit: the first non-stalled warp in the order of its instruction's uid,
//    shader.cc l.3254-3267).
// Plain C++.
#pragma once
#include <cstdint>

#include "config.h"

namespace rtu {

class WarpScheduler {
public:
    WarpScheduler(uint32_t slots, WarpOrder order) : slots_(slots), order_(order) {}
    // The warp-buffer slot picked this cycle, or -1; `has_ready(slot)` tells whether a slot holds a
    // warp with ready threads, `age(slot)` when its warp entered the buffer (smaller: older).
    template <class HasReady, class Age>
    int pick(HasReady has_ready, Age age) {
        if (order_ == WarpOrder::OldestFirst) {
            int best = -1;
            for (uint32_t s = 0; s < slots_; ++s)
                if (has_ready(s) && (best < 0 || age(s) < age(uint32_t(best)))) best = int(s);
            return best;
        }
        for (uint32_t k = 0; k < slots_; ++k) {
            const uint32_t s = (next_ + k) % slots_;
            if (!has_ready(s)) continue;
            next_ = s + 1;
            return int(s);
        }
        return -1;
    }

private:
    uint32_t slots_, next_ = 0;
    WarpOrder order_;
};

}  // namespace rtu
