// The shader code's loads after each trace (workload.shader_reads): the SM's closest-hit, miss
// and ray-generation code reads data of its own (vertices, materials, the ray payload) through the
// same L1, L2 and DRAM as the RT unit. Modelled as `per_ray` 32 B sectors per ray of a retired
// trace, of data no cache holds (each read a sector of the SM's own region, above every BVH image,
// never read again), issued one per cycle per SM from the trace's end and waited for by nobody.
// The fraction of a sector carries from trace to trace, so that a frame reads per_ray x rays in
// all. Used by the AT and LT RT units (tlm/rt_unit.h) and the interval fidelity alike.
#pragma once
#include <cmath>
#include <cstdint>

#include "node_fetch.h"

namespace rtu {

class ShaderLoads {
public:
    static constexpr uint64_t kRegion = 1ull << 36, kRegionPerSm = 1ull << 32;

    void start(uint32_t sm, double per_ray) {
        per_ray_ = per_ray;
        next_ = kRegion + uint64_t(sm) * kRegionPerSm;
    }
    // A trace of `rays` rays retired.
    void owe(size_t rays) {
        if (per_ray_ <= 0) return;
        fraction_ += per_ray_ * double(rays);
        const double whole = std::floor(fraction_);
        owed_ += uint64_t(whole);
        fraction_ -= whole;
    }
    uint64_t owed() const { return owed_; }
    uint64_t next() const { return next_; }  // the next read's address
    void issued() {
        --owed_;
        next_ += kChunkBytes;
    }

private:
    double per_ray_ = 0, fraction_ = 0;
    uint64_t owed_ = 0, next_ = 0;
};

}  // namespace rtu
