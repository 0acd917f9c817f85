// The one hook through which a sampled run (sampling/frame_sample.h) works on the workload
// driver: it sees the frame's shader warps once, picks the ones to simulate, and is told as each
// of them starts a trace, retires a ray, ends a trace and finishes. The driver itself knows
// nothing of strata, estimates or warming. Plain C++ (no SystemC).
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <queue>
#include <vector>

#include "model/trace_source.h"
#include "ray_queue.h"

namespace rtu {

// How shader warps take their time outside the RT unit (workload.* keys): each runs `shade`
// cycles of shader code before each of its traces, and after a trace first `intersection` cycles
// per iteration of its intersection loop (RetiredRay::candidates: as many iterations as the
// trace's ray with the most); the first warps start `launch` cycles into the frame (the kernel
// launch); an SM holds `resident` warps at once (0: all of them). A workload whose rays are given
// (a ray file) runs no shader code: `first` is then 0, the delay before a warp's first trace
// (else launch + shade). With `contention`, a warp's shader code (its shade and its loop) takes
// 1 + contention x n times as long, n being the other warps of its SM in shader code when it
// begins (the first warps of an SM begin together: n is their number less one).
struct ShaderTiming {
    uint32_t shade = 0, launch = 0, resident = 0, intersection = 0;
    double contention = 0;
    bool shaders = true;
    // `cycles` of shader code begun beside `others` warps in theirs, rounded to the nearest cycle.
    // Floating point: the factor is one multiply-add on small values (others < 2^32, contention
    // <= 10), and cycles x factor stays far below 2^53, so the product is within a few ulps of the
    // exact value; a last-bit difference (a fused multiply-add on another target) could change the
    // result only at an exact half-cycle tie.
    uint64_t contended(uint64_t cycles, uint32_t others) const {
        if (contention <= 0 || others == 0) return cycles;
        const double factor = 1.0 + contention * double(others);
        return uint64_t(std::llround(double(cycles) * factor));
    }
    uint64_t first(uint32_t others = 0) const { return shaders ? uint64_t(launch) + contended(shade, others) : 0; }
};

// The warps of one SM in shader code, for ShaderTiming::contention: when each one's code ends. A
// warp that begins its code at `now` runs beside those whose code ends later. Shared by the
// workload driver (cycles) and the sample's schedule model (sampling/schedule_model.h, doubles).
template <class Cycle>
class ShaderCodeEnds {
public:
    // The warps still in shader code at `now` (those whose code ended by then are dropped).
    uint32_t beside(Cycle now) {
        while (!ends_.empty() && ends_.top() <= now) ends_.pop();
        return uint32_t(ends_.size());
    }
    void add(Cycle end) { ends_.push(end); }

private:
    std::priority_queue<Cycle, std::vector<Cycle>, std::greater<Cycle>> ends_;
};

// The frame's shader warps, as the driver packed them, in frame order.
class FrameWarps {
public:
    virtual ~FrameWarps() = default;
    virtual size_t warps() const = 0;
    virtual uint32_t sm(size_t warp) const = 0;
    // The warp's threads' paths and first rays, in thread order (resized to its thread count).
    virtual void threads(size_t warp, std::vector<uint32_t>& paths, std::vector<RayQueue>& first) const = 0;
};

class WarpSelection {
public:
    virtual ~WarpSelection() = default;
    // Once, before anything runs: the frame warps to simulate, in the order they run (indices
    // into `frame`). The driver numbers them 0, 1, ... in that order ("kept" below).
    virtual std::vector<uint64_t> select(const FrameWarps& frame) = 0;
    // Kept warp `kept` takes its trace number `trace` (0: its first) on SM `sm`, before any of
    // its rays is issued.
    virtual void trace_starts(uint32_t kept, uint32_t sm, uint32_t trace) = 0;
    // One of its rays left the RT unit.
    virtual void ray_retired(uint32_t kept, const RetiredRay& ray) = 0;
    // Its trace left the RT unit of SM `sm` at cycle `now` after `residence` cycles there.
    virtual void trace_done(uint32_t kept, uint32_t sm, uint64_t now, uint64_t residence) = 0;
    // A kept warp finished its last trace at `now`, leaving `unfinished` warps.
    virtual void warp_finished(uint64_t unfinished, uint64_t now) = 0;
};

}  // namespace rtu
