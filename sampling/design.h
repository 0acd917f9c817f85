// The sample design (docs/sampling.md): which clusters of shader warps a sampled run simulates,
// one per stratum, and how many strata an interval needs. Plain C++ (no SystemC).
#pragma once
#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

namespace rtu {

// Drawn strata a sample needs for its interval (collapsed pairs: 5 pairs, Student's t with 5
// degrees of freedom, 2.57).
constexpr uint64_t kMinStrata = 10;

// Drawn strata below which a run's error estimate says its interval rests on few strata and names
// the rate that draws this many. 30 is the aim (a normal-theory interval from fewer draws
// leans on the clusters' costs being near normal). Measured after it was set (docs/sampling.md,
// "How many strata"): over 384 sampled runs of five grids, intervals of 10-29 strata covered 96 %
// with 4 misses narrower than +-10 %, those of 30 or more 99 % with 1.
constexpr uint64_t kAimStrata = 30;

// A frame's clusters of `cluster_warps` shader warps (the last one may hold fewer), and of them the
// candidates a sample draws from: neither the first wave nor empty.
struct FrameClusters {
    uint64_t clusters = 0, candidates = 0;
    FrameClusters(uint64_t warps_total, uint64_t cluster_warps, uint64_t first_wave_clusters, uint64_t empty_clusters)
        : clusters((warps_total + std::max<uint64_t>(1, cluster_warps) - 1) / std::max<uint64_t>(1, cluster_warps)),
          candidates(clusters - std::min(clusters, first_wave_clusters + empty_clusters)) {}
};

// The smallest rate, rounded up to 0.1 %, at which a frame of `clusters` clusters (the first wave
// among them; `candidates` of them neither the first wave nor empty) draws `strata` strata, or
// none where it has fewer candidates than that. A design simulates round(clusters x rate)
// clusters, the first wave one of them (SampleDesign).
std::optional<double> rate_for_strata(uint64_t clusters, uint64_t candidates, uint64_t strata);

// Simulated clusters a segment of a split sample needs for its interval: each segment pays its own
// start and drain, which the schedule model carries only in part. Measured (docs/sampling.md,
// "Segments"): with 16 or more per segment the split estimate erred as the continuous one did
// (mean 2.2-3.5 %, every interval covering); with 8, 4.4 % and 7 of 8 covering; with 4, 7.4 %
// and 5 of 8.
constexpr uint64_t kMinSegmentClusters = 16;

// One simulated cluster of a sample.
struct SampledCluster {
    uint64_t cluster;  // its index in the frame
    uint32_t stratum;  // the drawn stratum it stands for; kCertain for the first wave
    double weight;     // clusters of the frame it stands for
    static constexpr uint32_t kCertain = ~0u;
};

// The sample of a frame of `warps` shader warps in clusters of `cluster`, the first of them with
// work the first wave. `work`: per cluster, the pre-pass's critical-path node reads (empty: no
// pre-pass, or not run yet; strata by position, no cluster is known to be empty, and cluster 0
// is the first wave).
class SampleDesign {
public:
    SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed, const std::vector<double>& work = {});
    // Drawn strata (the first wave and the empty clusters are not strata).
    uint64_t strata() const { return strata_; }
    uint64_t clusters() const { return clusters_; }
    uint64_t empty_clusters() const { return empty_; }
    uint64_t first_wave_clusters() const { return certain_; }
    // Every cluster is simulated or known to be empty: the sample is the frame.
    bool census() const { return strata_ == candidates_; }
    // The simulated clusters in frame order.
    const std::vector<SampledCluster>& simulated() const { return sim_; }
    uint64_t first_warp(size_t i) const { return sim_[i].cluster * cluster_; }
    uint64_t end_warp(size_t i) const { return std::min(warps_, (sim_[i].cluster + 1) * cluster_); }
    // Per warp of the frame, the simulated cluster (index into simulated()) whose start its
    // fetches warm: the warps between the previous simulated cluster and it; ~0 otherwise.
    std::vector<uint32_t> feeds() const;
    // Splits the simulated clusters, in frame order, into `k` segments of consecutive ones
    // (sizes differing by one at most; the first wave in segment 0). Needs 1 <= k <= simulated().size().
    void split(uint32_t k);
    uint32_t segments() const { return segments_; }
    uint32_t segment_of(size_t i) const { return uint32_t(i * segments_ / sim_.size()); }
    // The first simulated cluster of its segment: its segment runs from cold caches, so it is
    // warmed from the frame's first warp on (the clusters simulated in earlier segments included).
    bool starts_segment(size_t i) const { return i == 0 || segment_of(i) != segment_of(i - 1); }
    // The first warp whose fetches warm simulated cluster i.
    uint64_t warm_from(size_t i) const { return starts_segment(i) ? 0 : end_warp(i - 1); }

private:
    uint64_t warps_, cluster_, clusters_, certain_ = 0, empty_ = 0, candidates_ = 0, strata_ = 0;
    uint32_t segments_ = 1;
    std::vector<SampledCluster> sim_;
};

}  // namespace rtu
