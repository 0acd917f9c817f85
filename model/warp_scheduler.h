// The RT unit's warp scheduler (paper section 2.3): each cycle it picks one warp of the warp
// buffer whose threads are ready to read their next node, and those threads' reads go to the
// memory access queue. Round robin: the first warp with ready threads after the one picked last.
// Plain C++.
#pragma once
#include <cstdint>

namespace rtu {

class WarpScheduler {
public:
    explicit WarpScheduler(uint32_t slots) : slots_(slots) {}
    // The warp-buffer slot picked this cycle, or -1; `has_ready(slot)` tells whether a slot holds a
    // warp with ready threads.
    template <class HasReady>
    int pick(HasReady has_ready) {
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
};

}  // namespace rtu
