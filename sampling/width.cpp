#include "width.h"

#include <algorithm>
#include <cmath>

#include "estimator.h"  // t95, interval_half_width

namespace rtu {

double PilotTerms::floor() const { return interval_half_width(0.0, model_error, extrapolation_gap, first_reads_gap, design_bias); }

double PilotTerms::half_width(uint64_t n, bool model_falls) const {
    if (n >= candidates) return 0.0;  // the whole frame
    if (strata == 0 || n == 0) return floor();
    const double K = double(candidates), n0 = double(strata), m = double(n);
    // The variance per stratum pair scales as (1/n)(1 - n/K): its ratio to the pilot's.
    const double fpc0 = 1.0 - n0 / K, fpc = 1.0 - m / K;
    const double scale = fpc0 > 0 ? std::sqrt((n0 / m) * (fpc / fpc0)) : 0.0;
    const double model = model_falls ? model_error * std::sqrt(n0 / m) : model_error;
    return interval_half_width(t95(degrees * m / n0) * relative_se * scale, model, extrapolation_gap, first_reads_gap, design_bias);
}

void PilotTerms::set_frame(uint64_t warps_total, uint64_t cluster_warps, uint64_t first_wave_clusters, uint64_t empty_clusters) {
    const FrameClusters f(warps_total, cluster_warps, first_wave_clusters, empty_clusters);
    clusters = f.clusters;
    candidates = f.candidates;
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
    p.set_frame(e.warps_total, e.design.cluster_warps, e.design.first_wave_clusters, e.design.empty_clusters);
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
