// A path's rays waiting for their trace, first in first out. A vector and a read position: one
// small allocation per path (a std::deque takes 512 B even for one ray, 270 MB for a 512x512
// frame at 2 spp).
#pragma once
#include <cstddef>
#include <vector>

#include "rays.h"

namespace rtu {

class RayQueue {
public:
    bool empty() const { return head_ == rays_.size(); }
    const WorkRay& front() const { return rays_[head_]; }
    void pop_front() {
        if (++head_ == rays_.size()) rays_.clear(), head_ = 0;
    }
    void push_back(const WorkRay& r) { rays_.push_back(r); }
    void clear() {  // keeps its allocation (a queue refilled for each warp allocates once)
        rays_.clear();
        head_ = 0;
    }

private:
    std::vector<WorkRay> rays_;
    size_t head_ = 0;
};

}  // namespace rtu
