// A sample that plans its own width (--sample-width W, docs/sampling.md "A sample of a given
// width"): from a pilot sample of the frame, the 95 % half-width a larger sample of the same
// frame would state, and the fewest strata that should reach W. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <optional>

namespace rtu {

// What a pilot sample measured (its statistics, timing.sampling): the terms of its interval
// (SampleEstimate::relative_half_width), its strata and the frame's candidate clusters.
struct PilotTerms {
    double relative_se = 0;   // the work's standard error, relative
    double degrees = 0;       // Student's t's degrees of freedom for it (Satterthwaite's)
    double model_error = 0;   // the schedule model's error (root mean square of the per-SM misfits)
    double extrapolation_gap = 0, first_reads_gap = 0, design_bias = 0;
    uint64_t strata = 0;      // drawn by the pilot
    uint64_t clusters = 0;    // the frame's clusters
    uint64_t candidates = 0;  // of them, those that can be drawn (neither the first wave nor empty)

    // clusters and candidates from the sample's design: the frame's shader warps, its clusters'
    // warps, and its first-wave and empty clusters.
    void set_frame(uint64_t warps_total, uint64_t cluster_warps, uint64_t first_wave_clusters, uint64_t empty_clusters);

    // The parts of the half-width no rate narrows: the model's error, the gaps and the bias bound,
    // in quadrature as the interval takes them (interval_half_width, sampling/estimator.h).
    // Measured on the ten grids of docs/sampling.md ("Where the width, the error and the time
    // come from"): from the lowest rate to the highest the median cell's model term is 0.90 times
    // what it was (it grew in 15 of 38 cells), so the pilot's is taken as the frame's at any rate.
    double floor() const;
    // The half-width a sample of n strata (pilot.strata <= n < candidates) of this frame should
    // state: the floor and the sampling term carried from the pilot's. Collapsed pairs of equal
    // strata, one cluster each, give a relative variance of (1/n) x (1 - n/K) x the mean pair's
    // spread; the spread is taken as the pilot's (strata by work narrow as n grows, so it can only
    // fall: the prediction errs wide), and Satterthwaite's degrees grow with the pairs.
    // With `model_falls`, the schedule model's error is taken to fall as 1 / sqrt(n) as well (the
    // per-SM misfits as noise of the sample's size): the narrowest the frame could give. On the
    // grid of docs/sampling.md ("A sample of a given width") it fell from 10 to 80 strata by 0.5x
    // on some frames and not at all on others.
    double half_width(uint64_t n, bool model_falls = false) const;
};

struct SampleEstimate;  // sampling/estimator.h

// A pilot's terms from its estimate (its design_bias set) and the cycles it simulated.
PilotTerms pilot_terms(const SampleEstimate& e, double cycles_simulated);

// The largest share of the frame --sample-width samples, pilots included: beyond it the full run is
// the better buy. Measured on the grids of docs/sampling.md ("A sample of a given width"): samples
// of 80-90 % of a 384x384 frame took 0.87-0.99 times the full run's time, of 42-52 % 1.2-1.5
// times less (their pre-pass, warming and pilot beside the simulation), and an interval at that
// rate is no narrower than the model's term.
constexpr double kWidthMaxRate = 0.5;

// What --sample-width planned, for the statistics (timing.sampling.width); what it delivered is the
// run's own interval.
struct SampleWidth {
    double asked = 0;             // the relative half-width asked
    double pilot_rate = 0;        // the pilot's --sample
    uint64_t pilot_strata = 0;    // its drawn strata
    double pilot_half_width = 0;  // the relative half-width it stated
    double pilot_s = 0;           // its wall time (a child run: the scene loaded, the frame traced for the plan, the sample)
    double floor = 0;             // PilotTerms::floor
    double predicted = 0;         // PilotTerms::half_width at the strata chosen
    uint32_t pilots = 0;          // 1, or 2 where the first's floor reached W but its model term might fall
};

// The fewest strata (from the pilot's up, below every candidate: n = candidates is the whole
// frame) whose predicted half-width (PilotTerms::half_width) is at most `width`; nullopt where
// none is.
std::optional<uint64_t> strata_for_width(const PilotTerms& pilot, double width, bool model_falls = false);

}  // namespace rtu
