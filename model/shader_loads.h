// The shader code's loads after each trace (workload.shader_reads): the SM's closest-hit, miss
// and ray-generation code reads data of its own (vertices, materials, the ray payload) through the
// same L1, L2 and DRAM as the RT unit. Modelled as `per_ray` 32 B sectors per ray of a retired
// trace, of data no cache holds (each read a sector of the SM's own region, above every BVH image,
// never read again), issued one per cycle per SM from the trace's end and waited for by nobody.
// The fraction of a sector carries from trace to trace, so that a frame reads per_ray x rays in
// all. Their sectors are scattered as the application's are (workload.shader_lines_per_read): a
// read opens a line of its own, or takes the next sector of the line the last one opened, so that
// the reads open `lines_per_read` L1 lines per read in all. Used by the AT and LT RT units
// (tlm/rt_unit.h) and the interval fidelity alike.
#pragma once
#include <cmath>
#include <cstdint>

#include "node_fetch.h"

namespace rtu {

// What the shader code reads (HwConfig's workload.shader_reads and workload.shader_lines_per_read,
// the L1's line bytes).
struct ShaderReads {
    double per_ray = 0;         // sectors per ray of a retired trace (0: none)
    double lines_per_read = 1;  // lines the reads open, per read (1 / sectors per line, at most 1)
    uint32_t line_bytes = 128;  // the L1's line
};

class ShaderLoads {
public:
    static constexpr uint64_t kRegion = 1ull << 36, kRegionPerSm = 1ull << 32;

    void start(uint32_t sm, const ShaderReads& r) {
        r_ = r;
        next_ = kRegion + uint64_t(sm) * kRegionPerSm;
        opened_ = 1;  // the first read opens the region's first line
        reads_ = 1;
    }
    // A trace of `rays` rays retired.
    void owe(size_t rays) {
        if (r_.per_ray <= 0) return;
        fraction_ += r_.per_ray * double(rays);
        const double whole = std::floor(fraction_);
        owed_ += uint64_t(whole);
        fraction_ -= whole;
    }
    uint64_t owed() const { return owed_; }
    uint64_t next() const { return next_; }  // the next read's address
    void issued() {
        --owed_;
        // The next read opens a line when the reads so far, that one included, owe one more
        // (lines_per_read x reads above the lines opened) or the open line has no sector left;
        // else it takes the open line's next sector. Counts, not a running sum of fractions, so
        // that the choice is exact whatever the frame's length: 0.25 lines per read (four sectors
        // a line) opens a line every fourth read.
        ++reads_;
        const bool line_full = (next_ + kChunkBytes) % r_.line_bytes == 0;  // the open line's last sector read
        if (double(opened_) < r_.lines_per_read * double(reads_) || line_full) {
            next_ = (next_ / r_.line_bytes + 1) * r_.line_bytes;
            ++opened_;
        } else {
            next_ += kChunkBytes;
        }
    }

private:
    ShaderReads r_;
    double fraction_ = 0;
    uint64_t owed_ = 0, next_ = 0, opened_ = 0, reads_ = 0;
};

}  // namespace rtu
