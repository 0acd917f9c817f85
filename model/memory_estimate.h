// Host memory a timing run will need, estimated before its model is elaborated, so that a
// configuration of maximal sizes is refused with a message (rtsim exit 2) instead of exhausting
// the machine (docs/robustness.md). Plain C++.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "config.h"
#include "fidelity.h"

namespace rtu {

struct MemoryEstimate {
    struct Part {
        std::string what;  // e.g. "L2 tags: 4 slices x 512 KiB"
        uint64_t bytes;
    };
    std::vector<Part> parts;  // largest first
    uint64_t total() const;
    // The largest parts, for a message: "L2 tags (...) 32.0 GiB, ..." (at most `n`).
    std::string largest(size_t n = 3) const;
};

// `paths`: the frame's pixel samples (or rays of a ray file); `image_bytes`: the BVH image (the
// most lines a cache can fill with node data). Scene and image are not included (they are
// resident already when the estimate is made).
MemoryEstimate estimate_memory(const HwConfig& cfg, Fidelity fidelity, uint64_t paths, uint64_t image_bytes);
// The functional fidelity: every traced ray is kept (hits, verification), at least one a path.
MemoryEstimate estimate_functional_memory(uint64_t paths);

std::string format_bytes(uint64_t bytes);  // "1.5 GiB" (KiB to TiB)

}  // namespace rtu
