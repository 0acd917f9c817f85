// --sample-segments K in the interval fidelity (docs/sampling.md, "Segments"): the segments
// simulated on threads of this process instead of child processes. The interval fidelity is plain
// C++, so several of its runs can share one process (AT and LT elaborate a SystemC platform,
// once per process, and keep their children): every segment reads the same scene and BVH image,
// and the frame's pre-pass is made once, before the segments, and handed to them and to the
// merge in memory. The segments share one workload, begun once (each runs its own paths), and each
// has its own driver and GPU. What a segment gives the merge is what a child's statistics file
// gives (SegmentRun), so the merged statistics are the same, bit for bit, as those of the
// segments' files (RtsimSampling.SegmentsMergedEqualTheSingleProcessRun).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "model/bvh_image.h"
#include "model/config.h"
#include "segment_file.h"
#include "timing_run.h"
#include "sampling/prepass.h"
#include "workloads/rays.h"

namespace rtu {

// Segments 0..count-1 of the sample `opt` describes (count: opt.sample_segments), up to
// `threads` at once, after the frame's pre-pass on all `threads` (or read from its plan,
// opt.sample_plan, and written to it where it was not there). `fresh` makes a workload instance
// (one per segment); `identity` is the run's segment identity. `prepass` (out): the frame's pre-pass, for the merge. A stop
// requested (opt.stop) ends every segment at its next clean point and throws Interrupted; after a
// segment fails no other starts, and its error is thrown (the lowest segment's first).
std::vector<SegmentRun> run_segment_threads(const HwConfig& hw, const BvhImage& image, const std::function<std::unique_ptr<Workload>()>& fresh,
                                            const TimingOptions& opt, unsigned threads, const std::vector<IdentityKey>& identity,
                                            std::optional<PrepassResult>& prepass, bool quiet, double* prepass_s = nullptr);

}  // namespace rtu
