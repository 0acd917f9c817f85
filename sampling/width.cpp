#include "width.h"

#include <algorithm>
#include <cmath>

#include "estimator.h"  // t95

namespace rtu {

double PilotTerms::floor() const {
    // As SampleEstimate::relative_half_width: the model's error on both sides (1.96 x sqrt(2)),
    // the extrapolation gap (1.96 x it), the first reads' gap and the bias bound as they are.
    const double model = 1.96 * std::sqrt(2.0) * model_error, gap = 1.96 * extrapolation_gap;
    return std::sqrt(model * model + gap * gap + first_reads_gap * first_reads_gap + design_bias * design_bias);
}

double PilotTerms::half_width(uint64_t n, bool model_falls) const {
    if (n >= candidates) return 0.0;  // the whole frame
    PilotTerms at = *this;
    if (strata == 0 || n == 0) return floor();
    const double K = double(candidates), n0 = double(strata), m = double(n);
    if (model_falls) at.model_error = model_error * std::sqrt(n0 / m);
    const double f = at.floor();
    // The variance per stratum pair scales as (1/n)(1 - n/K): its ratio to the pilot's.
    const double fpc0 = 1.0 - n0 / K, fpc = 1.0 - m / K;
    const double scale = fpc0 > 0 ? std::sqrt((n0 / m) * (fpc / fpc0)) : 0.0;
    const double se = t95(degrees * m / n0) * relative_se * scale;
    return std::sqrt(f * f + se * se);
}

PilotTerms pilot_terms(const SampleEstimate& e, double cycles_simulated) {
    PilotTerms p;
    p.relative_se = e.relative_se;
    p.degrees = e.variance_degrees;
    p.model_error = e.model_error(cycles_simulated);
    p.extrapolation_gap = e.extrapolation_gap();
    p.first_reads_gap = e.first_reads_gap();
    p.design_bias = e.design_bias;
    p.strata = e.design.strata;
    const uint64_t cw = std::max<uint64_t>(1, e.design.cluster_warps), clusters = (e.warps_total + cw - 1) / cw;
    p.candidates = clusters - std::min(clusters, e.design.first_wave_clusters + e.design.empty_clusters);
    return p;
}

std::optional<uint64_t> strata_for_width(const PilotTerms& pilot, double width, bool model_falls) {
    // half_width falls with n (t, the variance and with model_falls the model's term all shrink):
    // bisect on [pilot, candidates).
    uint64_t lo = std::max<uint64_t>(1, pilot.strata), hi = pilot.candidates;  // hi: the whole frame (not a sample)
    if (lo >= hi) return std::nullopt;
    if (pilot.half_width(lo, model_falls) <= width) return lo;
    if (pilot.half_width(hi - 1, model_falls) > width) return std::nullopt;
    while (hi - lo > 1) {  // half_width(lo) > width >= half_width(hi)
        const uint64_t mid = lo + (hi - lo) / 2;
        (pilot.half_width(mid, model_falls) <= width ? hi : lo) = mid;
    }
    return hi;
}

}  // namespace rtu
