#include "design.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "workloads/rays.h"  // Rng

namespace rtu {

// The first wave: the warps that start together on the frame's cold caches, a startup the full
// frame pays once; simulated always (weight 1), it is paid once in the sample too, where a drawn
// cluster would start on warmed caches. It is the first cluster that reads a BVH node: where the
// frame begins with empty clusters (sky above a scene), they leave the RT units at once and the
// first cluster with work starts on the cold caches. (As cluster 0 whatever its work, an empty
// first wave left that cold start to the draw: cornell's primary rays at 256x256, whose first
// cluster with work holds half the frame's first reads of BVH nodes and 6.5 % of its work, came
// out 16-17 % low on the draws that missed it and 15 % high on one that took it; the clusters
// that first read the other nodes still hold ~10 % of its work, docs/sampling.md, "The first
// wave".) Empty clusters: no node read, no RT work, nothing to simulate. The other clusters,
// sorted by their critical-path node reads, fall into equal strata (neighbouring strata alike,
// as the collapsed pairs of the variance want), and one cluster per stratum is drawn.
SampleDesign::SampleDesign(uint64_t warps, uint64_t cluster, double rate, uint64_t seed, const std::vector<double>& work)
    : warps_(warps), cluster_(std::max<uint64_t>(1, cluster)), clusters_((warps + cluster_ - 1) / cluster_) {
    certain_ = std::min<uint64_t>(clusters_, 1);
    uint64_t first = 0;  // the first wave's cluster (without the pre-pass's work: cluster 0)
    while (!work.empty() && first + 1 < clusters_ && work[first] <= 0) ++first;
    std::vector<uint64_t> order;
    for (uint64_t c = 0; c < clusters_; ++c)
        if (c != first && (work.empty() || work[c] > 0)) order.push_back(c);
    empty_ = clusters_ - certain_ - order.size();
    candidates_ = order.size();
    if (!work.empty())
        std::stable_sort(order.begin(), order.end(), [&](uint64_t a, uint64_t b) { return work[a] < work[b]; });
    // round(clusters x rate) clusters simulated, the first wave among them.
    const uint64_t total = std::min<uint64_t>(clusters_, uint64_t(std::llround(double(clusters_) * rate)));
    strata_ = std::min<uint64_t>(candidates_, total > certain_ ? total - certain_ : 0);
    if (certain_) sim_.push_back({first, SampledCluster::kCertain, 1.0});
    for (uint64_t h = 0; h < strata_; ++h) {
        const uint64_t lo = h * candidates_ / strata_, hi = (h + 1) * candidates_ / strata_;
        Rng rng(seed, h, 0x5A3B1E);
        sim_.push_back({order[lo + rng.next() % (hi - lo)], uint32_t(h), double(hi - lo)});
    }
    std::sort(sim_.begin(), sim_.end(), [](const SampledCluster& a, const SampledCluster& b) { return a.cluster < b.cluster; });
}

std::optional<double> rate_for_strata(uint64_t clusters, uint64_t candidates, uint64_t strata) {
    if (clusters == 0 || candidates < strata) return std::nullopt;
    // round(clusters x rate) >= 1 + strata: clusters x rate >= strata + 0.5 (llround rounds halves up).
    return std::min(1.0, std::ceil(1000.0 * (double(strata) + 0.5) / double(clusters)) / 1000.0);
}

std::vector<uint32_t> SampleDesign::feeds() const {
    std::vector<uint32_t> feeds(warps_, ~0u);
    for (size_t i = 0; i < sim_.size(); ++i)
        for (uint64_t w = i ? end_warp(i - 1) : 0; w < first_warp(i); ++w) feeds[w] = uint32_t(i);
    return feeds;
}

void SampleDesign::split(uint32_t k) {
    if (k < 1 || k > sim_.size())
        throw std::invalid_argument(std::to_string(k) + " segments of " + std::to_string(sim_.size()) + " simulated clusters");
    segments_ = k;
}

}  // namespace rtu
