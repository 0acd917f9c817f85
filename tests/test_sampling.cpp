// Sampled simulation's model-level pieces: the schedule model that carries the sample's trace
// durations to the whole frame, and functional cache warming. Checked against hand-worked cases.
#include <gtest/gtest.h>

#include "model/config.h"
#include "model/sector_cache.h"
#include "sampling/estimator.h"
#include "sampling/frame_sample.h"
#include "sampling/plan.h"
#include "sampling/prepass.h"
#include "sampling/schedule_model.h"
#include "sampling/width.h"
#include "workloads/workload_driver.h"
#include "workloads/bvh_builder.h"
#include "workloads/scenes.h"
#include "workloads/rays.h"
#include "model/traversal.h"
#include "platforms/sample_segments.h"
#include "platforms/timing_run.h"
#include "workloads/input_error.h"
#include "test_util.h"
#include <fstream>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <cmath>
#include <map>
#include <random>

using namespace rtu;

// One RT unit with one slot, shading 10 cycles between a warp's traces:
//   cycle 0: warp 0 trace 0 starts (ties go to the earlier warp), leaves at 5; warp 0 ready at 15
//   cycle 5: warp 1 (ready since 0) starts, leaves at 8
//   cycle 15: warp 0 trace 1 starts, leaves at 20.
TEST(ScheduleModel, OneSlotHandWorked) {
    EXPECT_DOUBLE_EQ(schedule_cycles({{5, 5}, {3}}, {1, 1, 10}), 20.0);
    // Without shading, warp 0's second trace is ready at 5 together with the slot, but warp 1
    // has waited since 0: it goes first (5..8), then warp 0 (8..13).
    EXPECT_DOUBLE_EQ(schedule_cycles({{5, 5}, {3}}, {1, 1, 0}), 13.0);
}

// Warps go to SMs round robin (0, 2 -> SM 0; 1 -> SM 1); each SM's slots work in parallel and
// the frame ends with the slowest SM.
TEST(ScheduleModel, RoundRobinSmsAndParallelSlots) {
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}}, {2, 2, 0}), 10.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}}, {2, 1, 0}), 10.0);   // SM 0: 4 then 6
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {1}, {7}}, {2, 1, 0}), 11.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({}, {8, 4, 100}), 0.0);
    EXPECT_THROW(schedule_cycles({{1}}, {0, 4, 0}), std::invalid_argument);
}

// With resident warps, an SM holds that many shader warps; a finished warp's place goes to the
// next warp of the frame, on the SM where it finished.
//   2 SMs x 2 slots, one resident warp each: w0 (SM 0) 0..4, w1 (SM 1) 0..10; w2 takes w0's
//   place on SM 0 at 4 (4..10), w3 takes w1's on SM 1 at 10 (10..13). Without the limit w0 and
//   w2 share SM 0 and w1 and w3 share SM 1 from the start: 10.
//   One slot, shading 5: w0 runs 0..2, shades to 7, runs 7..9; only then does w1 start (9..12).
//   Without the limit w1 fills the gap (2..5): 9.
TEST(ScheduleModel, ResidentWarpsHandWorked) {
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}, {3}}, {2, 2, 0, 1}), 13.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{4}, {10}, {6}, {3}}, {2, 2, 0, 0}), 10.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{2, 2}, {3}}, {1, 1, 5, 1}), 12.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{2, 2}, {3}}, {1, 1, 5, 0}), 9.0);
    // The first warp finishing (w1 on SM 1 at 4) takes w2, wherever w2 would have gone round robin.
    EXPECT_DOUBLE_EQ(schedule_cycles({{10}, {4}, {6}}, {2, 1, 0, 1}), 10.0);
    EXPECT_DOUBLE_EQ(schedule_cycles({{10}, {4}, {6}}, {2, 1, 0, 0}), 16.0);
}

// With shader contention (ShaderTiming::contended), a warp's shader code takes 1 + contention x n
// times as long, n the other warps of its SM in shader code when it begins.
//   1 SM x 1 slot, 2 resident warps of two 10-cycle traces, shading 100, first 100, contention
//   0.5: both begin their ray generation together (n = 1): ready at 100 + 100 x 0.5 = 150. w0
//   150..160, then shades alone (w1 waits for the slot, not in shader code): ready at 260; w1
//   160..170, then shades beside w0 (n = 1): 170 + 150 = 320. w0 260..270, w1 320..330.
//   Without contention: w0 100..110, w1 110..120, w0 210..220, w1 220..230.
TEST(ScheduleModel, ShaderContentionHandWorked) {
    ScheduleShape shape{1, 1, 100, 2, 100, 100, 0.5};
    EXPECT_DOUBLE_EQ(schedule_cycles({{10, 10}, {10, 10}}, shape), 330.0);
    shape.contention = 0;
    EXPECT_DOUBLE_EQ(schedule_cycles({{10, 10}, {10, 10}}, shape), 230.0);
    // Without a limit of resident warps the model does not count warps in shader code.
    EXPECT_THROW(schedule_cycles({{10}}, {1, 1, 100, 0, 100, 100, 0.5}), std::invalid_argument);
}

// Per RT unit, the cycle its last trace leaves; the frame's end is the latest of them.
//   2 SMs x 1 slot, shading 10: SM 0 holds w0 and w2 (round robin): w0 0..5, w2 5..11, w0's
//   second trace ready at 15: 15..20. SM 1 holds w1: 0..3.
//   With one resident warp per SM (ResidentWarpsHandWorked): SM 0 ends at 10 (w0, then w2),
//   SM 1 at 13 (w1, then w3: w1 and w2 both finish at 10, and the earlier warp's place goes first).
TEST(ScheduleModel, PerSmEndsHandWorked) {
    EXPECT_EQ(schedule_sm_ends({{5, 5}, {3}, {6}}, {2, 1, 10}), (std::vector<double>{20.0, 3.0}));
    EXPECT_DOUBLE_EQ(schedule_cycles({{5, 5}, {3}, {6}}, {2, 1, 10}), 20.0);
    EXPECT_EQ(schedule_sm_ends({{4}, {10}, {6}, {3}}, {2, 2, 0, 1}), (std::vector<double>{10.0, 13.0}));
    EXPECT_EQ(schedule_sm_ends({{4}}, {3, 1, 0}), (std::vector<double>{4.0, 0.0, 0.0}));  // SMs without traces end at 0
}

// The interval's model term takes the model's error from every SM where it was measured: a
// whole-run misfit of 0 (the SM that ended last happened to match) does not make it 0.
TEST(SampleEstimateInterval, ModelErrorIsTheRootMeanSquareOverSms) {
    SampleEstimate e;
    e.schedule = true;
    e.model_sample = 1000;
    e.misfit_per_sm = {0.03, -0.03, 0.03, -0.03};
    EXPECT_DOUBLE_EQ(e.model_misfit(1000), 0.0);
    EXPECT_DOUBLE_EQ(e.model_error(1000), 0.03);
    // relative_se 0 and no extrapolation gap: the half-width is the model term alone.
    EXPECT_DOUBLE_EQ(e.relative_half_width(1000), 1.96 * std::sqrt(2.0) * 0.03);
    e.misfit_per_sm = {0.01, -0.05};
    EXPECT_DOUBLE_EQ(e.model_error(1000), std::sqrt((0.01 * 0.01 + 0.05 * 0.05) / 2));
    // Without per-SM misfits (older segment files) the whole run's misfit stands in.
    e.misfit_per_sm.clear();
    EXPECT_NEAR(e.model_error(1020), 0.02, 1e-12);
    EXPECT_NEAR(e.relative_half_width(1020), 1.96 * std::sqrt(2.0) * 0.02, 1e-12);
    // Without the schedule estimator there is no model term.
    e.schedule = false;
    e.misfit_per_sm = {0.03};
    EXPECT_DOUBLE_EQ(e.model_error(1000), 0.0);
}

// The sample design's bias bound joins the interval's terms in quadrature, as a 95 % figure
// of its own (no t or 1.96 on it): model term 1.96 x sqrt(2) x 0.03 = 0.0832, bias 0.04,
// half-width sqrt(0.0832^2 + 0.04^2) = 0.0923.
TEST(SampleEstimateInterval, DesignBiasJoinsInQuadrature) {
    SampleEstimate e;
    e.schedule = true;
    e.model_sample = 1000;
    e.misfit_per_sm = {0.03, -0.03};
    const double model = 1.96 * std::sqrt(2.0) * 0.03;
    EXPECT_DOUBLE_EQ(e.relative_half_width(1000), model);
    e.design_bias = 0.04;
    EXPECT_DOUBLE_EQ(e.relative_half_width(1000), std::sqrt(model * model + 0.04 * 0.04));
    EXPECT_NEAR(e.relative_half_width(1000), 0.0923, 1e-4);
    // Alone (a sample that fits its model exactly and has no sampling error), the bias is the interval.
    e.misfit_per_sm = {0.0};
    EXPECT_DOUBLE_EQ(e.relative_half_width(1000), 0.04);
}

// --sample-width's prediction (sampling/width.h). At the pilot's own strata it is the interval the
// pilot stated, term for term (SampleEstimate::relative_half_width computes it independently).
// Hand-worked at 40 strata of 100 candidates from a pilot of 10 with relative se 0.02 over 4
// degrees: the pairs' variance scales by (10/40) x (1 - 40/100) / (1 - 10/100) = 1/6, Student's
// t over 16 degrees is 2.1199 (tables: 2.120), so the sampling term is 2.1199 x 0.02 x 0.40825 =
// 0.017309; the floor is sqrt((1.96 sqrt2 x 0.01)^2 + (1.96 x 0.005)^2 + 0.01^2 + 0.05^2) =
// 0.058859, and the half-width sqrt(0.058859^2 + 0.017309^2) = 0.061351.
TEST(SampleWidth, PredictionCarriesThePilotsTerms) {
    PilotTerms p;
    p.relative_se = 0.02, p.degrees = 4, p.model_error = 0.01, p.extrapolation_gap = 0.005, p.first_reads_gap = 0.01, p.design_bias = 0.05;
    p.strata = 10, p.candidates = 100;
    SampleEstimate e;
    e.schedule = true;
    e.model_sample = 1000;
    e.misfit_per_sm = {0.01, -0.01};
    e.relative_se = 0.02, e.variance_degrees = 4;
    e.work_estimate = 1.005, e.work_estimate_stratified = 1.0;
    e.first_reads_rest = 1, e.first_reads_estimate = 0, e.first_read_cost = 0.01 * 1.005;  // gap: 0.01 x 1.005 x |1 - 0| / 1.005
    e.design_bias = 0.05;
    EXPECT_NEAR(p.half_width(10), e.relative_half_width(1000), 1e-12);
    EXPECT_NEAR(p.floor(), 0.058859, 1e-6);
    EXPECT_NEAR(p.half_width(40), 0.061351, 2e-6);
    // More strata narrow only the sampling term: toward the floor, never below it; the whole frame is exact.
    double last = p.half_width(10);
    for (uint64_t n = 11; n < 100; ++n) {
        EXPECT_LT(p.half_width(n), last) << n;
        EXPECT_GT(p.half_width(n), p.floor()) << n;
        last = p.half_width(n);
    }
    EXPECT_EQ(p.half_width(100), 0.0);
}

TEST(SampleWidth, FewestStrataThatReachTheWidth) {
    PilotTerms p;
    p.relative_se = 0.05, p.degrees = 5, p.model_error = 0, p.design_bias = 0.04;
    p.strata = 10, p.candidates = 200;
    // Every width between the floor and the pilot's own: the smallest n whose prediction reaches it.
    for (const double w : {0.06, 0.08, 0.1, 0.12}) {
        const std::optional<uint64_t> n = strata_for_width(p, w);
        ASSERT_TRUE(n) << w;
        EXPECT_LE(p.half_width(*n), w) << w;
        EXPECT_GT(p.half_width(*n - 1), w) << w;
    }
    // At or above the pilot's: the pilot's strata; at or below the floor: none; and none where only
    // every candidate (the whole frame) would reach it.
    EXPECT_EQ(strata_for_width(p, p.half_width(10)), 10u);
    EXPECT_EQ(strata_for_width(p, 0.5), 10u);
    EXPECT_FALSE(strata_for_width(p, 0.04));
    EXPECT_FALSE(strata_for_width(p, 0.03));
    EXPECT_FALSE(strata_for_width(p, p.half_width(199) * (1 - 1e-9)));
    EXPECT_EQ(strata_for_width(p, p.half_width(199)), 199u);
}

// The first reads' term: the frame's first reads of nodes outside the first wave against the
// sample's ratio estimate of them (per critical-path node), at their price beyond the fit. A
// frame of 4 warps of one trace each, critical paths 10, 10, 20, 20 and first reads 3, 0, 2, 0;
// warp 0 is the first wave (residence 160), warp 1 stratum 0 (weight 1, residence 100), and one
// of warps 2 and 3 stratum 1 (weight 2). Outside the first wave the frame holds 5 - 3 = 2 first
// reads and 50 critical-path nodes.
// - Warp 3 drawn (residence 200): the fit through (10, 100) and (20, 200) is a = 0, b = 10. The
//   draw holds no first read, so the price is the first wave's: 160 - 100 = 60 beyond the fit
//   for 3 first reads, 20 each. Estimate 0, work 160 + 100 + 200 + 200 = 660, gap 20 x 2 / 660.
// - Warp 2 drawn (residence 220): a = -20, b = 12, work 160 + 100 + 220 + 220 = 700. The draw
//   holds 2 x 2 = 4 first reads over 1 x 10 + 2 x 20 = 50 nodes: 0.08 a node, estimate 4. Work per
//   node r = (100 + 2 x 220) / 50 = 10.8. Off the lines per stratum: first reads x = -0.8, 0.8,
//   work y = 100 - 108 = -8, 440 - 432 = 8: the slope 10 is the price. Gap 10 x |2 - 4| / 700.
// - Warp 2 drawn with residence 180: the slope is -10, and a price below 0 is taken as 0.
TEST(SampleEstimateInterval, FirstReadsGapHandWorked) {
    struct Case {
        uint64_t drawn;
        double residence, a, b, work, cost, estimate;
        bool of_first_wave;
    };
    for (const Case& c : {Case{3, 200, 0, 10, 660, 20, 0, true}, Case{2, 220, -20, 12, 700, 10, 4, false}, Case{2, 180, 20, 8, 620, 0, 4, false}}) {
        SampleEstimator est({1, 4, 0, 0}, 4);
        PrepassResult p;
        p.trace_nodes = {{10}, {10}, {20}, {20}};
        p.first_reads_in_rounds = {3, 0, 2, 0};  // every warp resident (the shape's 0): the frame in rounds
        p.first_reads_by_warp = {9, 9, 9, 9};    // not this frame's order: never read
        p.critical_nodes_total = 60;
        est.set_prepass(std::move(p));
        std::vector<WarpRecord> rec(3);
        const uint64_t warp[3] = {0, 1, c.drawn};
        const uint32_t stratum[3] = {SampledCluster::kCertain, 0, 1};
        const double weight[3] = {1, 1, 2}, residence[3] = {160, 100, c.residence}, first[4] = {3, 0, 2, 0}, nodes[4] = {10, 10, 20, 20};
        for (int i = 0; i < 3; ++i) {
            rec[i].frame_warp = warp[i];
            rec[i].stratum = stratum[i];
            rec[i].weight = weight[i];
            rec[i].trace_nodes = {uint32_t(nodes[warp[i]])};
            rec[i].critical_nodes = nodes[warp[i]];
            rec[i].first_reads = first[warp[i]];
            est.on_trace_done(rec[i], residence[i]);
        }
        const SampleEstimate e = est.estimate(rec, 4, true);
        ASSERT_TRUE(e.schedule);
        EXPECT_NEAR(e.fit_a, c.a, 1e-9);
        EXPECT_NEAR(e.fit_b, c.b, 1e-9);
        EXPECT_NEAR(e.work_estimate, c.work, 1e-9);
        EXPECT_NEAR(e.first_read_cost, c.cost, 1e-9) << c.drawn << " " << c.residence;
        EXPECT_EQ(e.first_read_cost_of_first_wave, c.of_first_wave);
        EXPECT_DOUBLE_EQ(e.first_reads_rest, 2.0);
        EXPECT_NEAR(e.first_reads_estimate, c.estimate, 1e-12);
        EXPECT_NEAR(e.first_reads_gap(), c.cost * std::fabs(2 - c.estimate) / c.work, 1e-12);
        // It joins the interval in quadrature, taken as it is.
        SampleEstimate without = e;
        without.first_read_cost = 0;
        EXPECT_NEAR(e.relative_half_width(0) * e.relative_half_width(0),
                    without.relative_half_width(0) * without.relative_half_width(0) + e.first_reads_gap() * e.first_reads_gap(), 1e-12);
    }
    // Without first reads counted (a pre-pass without the image's size): no term.
    SampleEstimator est({1, 4, 0, 0}, 4);
    PrepassResult p;
    p.trace_nodes = {{10}, {10}};
    p.critical_nodes_total = 20;
    est.set_prepass(std::move(p));
    std::vector<WarpRecord> rec(2);
    for (int i = 0; i < 2; ++i) {
        rec[i].frame_warp = uint64_t(i);
        rec[i].stratum = i == 0 ? SampledCluster::kCertain : 0;
        rec[i].trace_nodes = {10};
        rec[i].critical_nodes = 10;
        est.on_trace_done(rec[i], 100 + 10 * i);
    }
    EXPECT_DOUBLE_EQ(est.estimate(rec, 2, true).first_reads_gap(), 0.0);
}

// --check-error's pairing of two runs of one draw (paired_work_difference). The first wave 100
// in both; four strata of weights 3, 3, 5, 5 hold fast 330, 300, 500, 550 and reference 300,
// 300, 500, 500 (residence x weight). R = 1780 / 1700 = 1.0471. Within a pair the reference's
// strata are equal, so the residuals' differences are the fast run's: 30 and -50. Collapsed
// pairs: 30^2 x (1 - 2/6) + 50^2 x (1 - 2/10) = 600 + 2000 = 2600; se = sqrt(2600) / 1700 =
// 0.02999. Satterthwaite's degrees of freedom: 2600^2 / (600^2 + 2000^2) = 1.5505, for which
// Student's 97.5 % quantile is 5.7499 (scipy.stats.t.ppf(0.975, 1.5505)): half-width 0.1725.
TEST(PairedWorkDifference, HandWorked) {
    const StrataWork fast{100, {330, 300, 500, 550}, {3, 3, 5, 5}}, ref{100, {300, 300, 500, 500}, {3, 3, 5, 5}};
    const PairedDifference p = paired_work_difference(fast, ref);
    EXPECT_DOUBLE_EQ(p.difference, 1780.0 / 1700.0 - 1.0);
    EXPECT_EQ(p.pairs, 2u);
    EXPECT_NEAR(p.degrees, 2600.0 * 2600.0 / (600.0 * 600.0 + 2000.0 * 2000.0), 1e-12);
    EXPECT_NEAR(p.half_width, 5.749944 * std::sqrt(2600.0) / 1700.0, 1e-6);
    EXPECT_NEAR(p.half_width, 0.1725, 1e-4);
    // The same draw timed alike in both: no difference and no spread.
    const PairedDifference same = paired_work_difference(ref, ref);
    EXPECT_DOUBLE_EQ(same.difference, 0.0);
    EXPECT_DOUBLE_EQ(same.half_width, 0.0);
    // Strata of one cluster each are the frame's whole (no finite-population spread).
    const PairedDifference whole = paired_work_difference({0, {330, 300}, {1, 1}}, {0, {300, 300}, {1, 1}});
    EXPECT_DOUBLE_EQ(whole.half_width, 0.0);
    // Two runs of other draws are not paired.
    EXPECT_THROW(paired_work_difference(fast, {100, {300, 300, 500}, {3, 3, 5}}), std::invalid_argument);
    EXPECT_THROW(paired_work_difference(fast, {100, {300, 300, 500, 500}, {3, 3, 4, 6}}), std::invalid_argument);
}

// The paired interval on a synthetic frame whose true ratio is known: 400 clusters with
// reference residences spread over two orders of magnitude, each timed by the fast fidelity
// 2 % slow on average with a 5 % spread of its own per cluster, and slower on heavy clusters
// (up to 4 % more: a difference that depends on the work, as a memory-bound model's would).
// With a degree of freedom per pair (no Satterthwaite) 91 % of the draws of 20 and of 40 strata
// held the ratio; with Satterthwaite's degrees 96.5, 98.1 and 96.9 % at 10, 20 and 40 strata.
// 2,000 draws of the check's design (the first cluster always, strata of equal size over the
// clusters sorted by work, one cluster drawn per stratum): the 95 % interval must hold the
// frame's ratio at least as often as its binomial range allows (0.95 - 3 sigma at 2,000 draws:
// 0.935), and it may be conservative (collapsed pairs count the spread between neighbouring
// strata as noise) but not useless: its median half-width at most three times 1.96 standard
// deviations of the draws' differences.
TEST(PairedWorkDifference, CoversAKnownFrameRatio) {
    std::mt19937_64 rng(20261201);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.05);
    const size_t clusters = 400;
    std::vector<double> ref(clusters), fast(clusters);
    double sum_ref = 0, sum_fast = 0;
    for (size_t k = 0; k < clusters; ++k) {
        ref[k] = 1000.0 * std::pow(100.0, u(rng));
        fast[k] = ref[k] * (1.02 + 0.04 * std::log(ref[k] / 1000.0) / std::log(100.0) + noise(rng));
        sum_ref += ref[k], sum_fast += fast[k];
    }
    const double truth = sum_fast / sum_ref - 1.0;
    std::vector<size_t> order(clusters - 1);
    for (size_t k = 0; k < order.size(); ++k) order[k] = k + 1;  // cluster 0 is the first wave
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ref[a] < ref[b]; });
    for (const size_t strata : {10u, 20u, 40u}) {
        const size_t draws = 2000;
        size_t held = 0;
        std::vector<double> diffs, halves;
        for (size_t d = 0; d < draws; ++d) {
            StrataWork f{fast[0], {}, {}}, r{ref[0], {}, {}};
            for (size_t h = 0; h < strata; ++h) {
                const size_t lo = h * order.size() / strata, hi = (h + 1) * order.size() / strata;
                const size_t pick = order[lo + size_t(u(rng) * double(hi - lo))];
                const double w = double(hi - lo);
                f.work.push_back(w * fast[pick]);
                r.work.push_back(w * ref[pick]);
                f.weight.push_back(w);
                r.weight.push_back(w);
            }
            const PairedDifference p = paired_work_difference(f, r);
            held += std::fabs(p.difference - truth) <= p.half_width;
            diffs.push_back(p.difference);
            halves.push_back(p.half_width);
        }
        double mean = 0, var = 0;
        for (double x : diffs) mean += x / double(draws);
        for (double x : diffs) var += (x - mean) * (x - mean) / double(draws - 1);
        std::nth_element(halves.begin(), halves.begin() + long(draws / 2), halves.end());
        const double coverage = double(held) / double(draws);
        EXPECT_GE(coverage, 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / double(draws))) << strata << " strata";
        EXPECT_LE(halves[draws / 2], 3.0 * 1.96 * std::sqrt(var)) << strata << " strata";
        EXPECT_LT(std::fabs(mean - truth), 0.2 * std::sqrt(var) + 1e-4) << strata << " strata: the ratio estimate's bias";
    }
}

// The work's sampling error (SampleEstimate::relative_se) against a synthetic frame whose total
// is known: 400 clusters (one warp each, after a first wave) of 10-1,000 critical-path nodes,
// each costing 20-40 slot-cycles a node (more for the larger ones) with 10 % noise, sorted by
// nodes into 10, 20 or 40 strata of one draw each. Without trace records there is no residence
// fit, so the estimate is the stratified ratio estimate and its half-width Student's t over the
// collapsed pairs times the standard error: over 2,000 draws it holds the frame's total at least
// as often as the binomial range of 95 % allows (3 sigma), and the estimate's mean lies within a
// fifth of its spread of the total (the ratio estimate's bias). With a degree of freedom per pair
// it held 88 %, 88 % and 93 %; with Satterthwaite's 96 %, 97 % and 98 % (on the frames of seeds 7
// and 99: 93.8-97.7 %).
TEST(SampleEstimator, TheWorksIntervalCoversAKnownFrame) {
    std::mt19937_64 rng(20261202);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.1);
    const size_t warps = 401;  // warp 0: the first wave
    std::vector<double> nodes(warps), work(warps);
    double total = 0, total_nodes = 0;
    for (size_t w = 0; w < warps; ++w) {
        nodes[w] = std::round(10.0 * std::pow(100.0, u(rng)));
        work[w] = nodes[w] * (20.0 + 20.0 * std::log10(nodes[w] / 10.0) / 2.0) * (1.0 + noise(rng));
        total += work[w], total_nodes += nodes[w];
    }
    std::vector<size_t> order(warps - 1);
    for (size_t k = 0; k < order.size(); ++k) order[k] = k + 1;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return nodes[a] < nodes[b]; });
    for (const size_t strata : {10u, 20u, 40u}) {
        const size_t draws = 2000;
        size_t held = 0;
        std::vector<double> estimates;
        for (size_t d = 0; d < draws; ++d) {
            SampleEstimator est({1, 4, 0, 0}, 4);
            PrepassResult p;
            p.trace_nodes.assign(warps, {});
            p.critical_nodes_total = total_nodes;
            est.set_prepass(std::move(p));
            std::vector<WarpRecord> rec;
            auto add = [&](size_t w, uint32_t stratum, double weight) {
                WarpRecord& r = rec.emplace_back();
                r.frame_warp = w;
                r.stratum = stratum;
                r.weight = weight;
                r.critical_nodes = nodes[w];
                est.on_trace_done(r, work[w]);
            };
            add(0, SampledCluster::kCertain, 1.0);
            for (size_t h = 0; h < strata; ++h) {
                const size_t lo = h * order.size() / strata, hi = (h + 1) * order.size() / strata;
                add(order[lo + size_t(u(rng) * double(hi - lo))], uint32_t(h), double(hi - lo));
            }
            const SampleEstimate e = est.estimate(rec, warps, true);
            ASSERT_FALSE(e.schedule);
            ASSERT_EQ(e.variance_pairs, strata / 2);
            ASSERT_DOUBLE_EQ(e.work_estimate, e.work_estimate_stratified);
            const double half = e.relative_half_width(0) * e.work_estimate;  // t x se alone: no other term here
            held += std::fabs(e.work_estimate - total) <= half;
            estimates.push_back(e.work_estimate);
        }
        double mean = 0, var = 0;
        for (double x : estimates) mean += x / double(draws);
        for (double x : estimates) var += (x - mean) * (x - mean) / double(draws - 1);
        const double coverage = double(held) / double(draws);
        EXPECT_GE(coverage, 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / double(draws))) << strata << " strata";
        EXPECT_LT(std::fabs(mean - total), 0.2 * std::sqrt(var)) << strata << " strata: the ratio estimate's bias";
    }
}

// Conservation: with one RT unit, one slot and no shading the slot never idles, so the frame
// takes exactly the sum of all durations, in any order of warps.
TEST(ScheduleModel, OneBusySlotTakesTheSumOfAllWork) {
    std::vector<std::vector<double>> t;
    double sum = 0;
    for (int w = 0; w < 50; ++w) {
        t.emplace_back();
        for (int k = 0; k <= w % 7; ++k) {
            t.back().push_back(double((w * 37 + k * 11) % 23 + 1));
            sum += t.back().back();
        }
    }
    EXPECT_DOUBLE_EQ(schedule_cycles(t, {1, 1, 0}), sum);
}

// Warming makes sectors valid without counting anything, evicts by LRU like a read, and leaves
// sectors being fetched (and sets with every way pending) alone.
TEST(SectorCacheWarm, ValidatesWithoutStatisticsAndRespectsPending) {
    SectorCache c(CacheConfig{512, 2, 128, 32, 2, 2, 0});  // 2 sets x 2 ways, 2 MSHRs
    EXPECT_FALSE(c.warm(0x000));
    EXPECT_TRUE(c.warm(0x010));  // same sector
    EXPECT_EQ(c.stats(ReqKind::Demand).accesses + c.stats(ReqKind::Prefetch).accesses, 0u);
    EXPECT_EQ(c.read(0x000, 1, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x020, 2, ReqKind::Demand), CacheOutcome::SectorMiss);  // line 0 there, sector 1 not
    EXPECT_FALSE(c.warm(0x020));  // pending: left to its fetch
    EXPECT_EQ(c.fill(0x020), (SectorCache::Tokens{2}));
    // Set 0 gets 0x100 in its free way; warming 0x200 then evicts line 0, least recently used.
    EXPECT_FALSE(c.warm(0x100));
    EXPECT_FALSE(c.warm(0x200));
    EXPECT_EQ(c.read(0x100, 3, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x200, 4, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x000, 5, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x100 (LRU)
    EXPECT_EQ(c.read(0x300, 6, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x200
    // Set 0 now has two pending lines: warming finds no way and changes nothing.
    EXPECT_FALSE(c.warm(0x100));
    EXPECT_EQ(c.fill(0x000), (SectorCache::Tokens{5}));
    EXPECT_EQ(c.read(0x100, 7, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_EQ(c.stats(ReqKind::Demand).evictions + c.stats(ReqKind::Prefetch).evictions, 3u);  // the reads' (0x100, 0x200, line 0), not the warming's
}

// The sample design (sampling/design.h) by hand: 10 clusters of 4 warps (the first wave is
// cluster 0), clusters 3 and 7 empty, a half of the frame: round(10 x 0.5) = 5
// clusters simulated, the first wave and 4 strata over the 7 other non-empty clusters sorted by
// work. Every stratum's weight is its size, the weights and the first wave and the empty
// clusters account for every cluster, no empty cluster is drawn, and each draw lies in its
// stratum's share of the work order.
// rate_for_strata names the smallest rate (in steps of 0.1 %) whose design draws the strata asked
// for: checked against SampleDesign itself over frames of 12 to 2,000 clusters, some empty.
// Hand-worked: 128 clusters, 30 strata need round(128 x rate) >= 31, so rate >= 30.5 / 128 =
// 0.2383: 0.239.
TEST(SampleDesign, RateForStrataIsTheSmallestThatDrawsThem) {
    EXPECT_EQ(rtu::rate_for_strata(128, 127, 30), 0.239);
    for (uint64_t clusters : {12u, 31u, 64u, 128u, 513u, 2000u})
        for (uint64_t empty : {0u, 3u})
            for (uint64_t want : {10u, 30u}) {
                std::vector<double> work(clusters, 1.0);
                for (uint64_t e = 0; e < empty; ++e) work[1 + e] = 0;  // clusters 1..empty read no node
                const uint64_t candidates = clusters - 1 - empty;
                const std::optional<double> rate = rtu::rate_for_strata(clusters, candidates, want);
                if (candidates < want) {
                    EXPECT_FALSE(rate) << clusters << " clusters";
                    continue;
                }
                ASSERT_TRUE(rate) << clusters << " clusters";
                EXPECT_GE(rtu::SampleDesign(clusters * 4, 4, *rate, 1, work).strata(), want) << clusters << " clusters, rate " << *rate;
                if (*rate > 0.001) {
                    EXPECT_LT(rtu::SampleDesign(clusters * 4, 4, *rate - 0.001, 1, work).strata(), want) << clusters << " clusters, rate " << *rate;
                }
            }
}

TEST(SampleDesign, FirstWaveEmptyClustersAndStrataByWork) {
    const std::vector<double> work = {5, 9, 1, 0, 7, 3, 8, 0, 2, 6};  // per cluster
    // Non-empty clusters after the first wave, by work: 2(1) 8(2) 5(3) 9(6) 4(7) 6(8) 1(9).
    const std::vector<std::vector<uint64_t>> strata_of = {{2}, {8, 5}, {9, 4}, {6, 1}};  // 7 x h / 4 .. 7 x (h + 1) / 4
    for (uint64_t seed = 1; seed <= 20; ++seed) {
        const rtu::SampleDesign d(40, 4, 0.5, seed, work);
        EXPECT_EQ(d.clusters(), 10u);
        EXPECT_EQ(d.first_wave_clusters(), 1u);
        EXPECT_EQ(d.empty_clusters(), 2u);
        EXPECT_EQ(d.strata(), 4u);
        EXPECT_FALSE(d.census());
        const auto& sim = d.simulated();
        ASSERT_EQ(sim.size(), 5u);
        EXPECT_EQ(sim[0].cluster, 0u);
        EXPECT_EQ(sim[0].stratum, rtu::SampledCluster::kCertain);
        double weights = 0;
        for (size_t i = 1; i < sim.size(); ++i) {
            EXPECT_LT(sim[i - 1].cluster, sim[i].cluster);  // frame order
            ASSERT_LT(sim[i].stratum, 4u);
            const auto& members = strata_of[sim[i].stratum];
            EXPECT_NE(std::find(members.begin(), members.end(), sim[i].cluster), members.end()) << "seed " << seed;
            EXPECT_EQ(sim[i].weight, double(members.size()));
            weights += sim[i].weight;
        }
        EXPECT_EQ(weights + 1 + 2, 10.0);
        // Warming: every warp between two simulated clusters feeds the later one.
        const auto feeds = d.feeds();
        for (size_t i = 0; i < sim.size(); ++i)
            for (uint64_t w = i ? d.end_warp(i - 1) : 0; w < d.first_warp(i); ++w) EXPECT_EQ(feeds[w], i);
    }
    // Segments: consecutive simulated clusters, sizes differing by one at most, the first wave in
    // segment 0; each segment's first cluster is warmed from the frame's first warp on (it runs
    // from cold caches), the others from the end of the cluster before them.
    for (uint32_t k = 1; k <= 5; ++k) {
        rtu::SampleDesign d(40, 4, 0.5, 3, work);
        d.split(k);
        std::vector<size_t> sizes(k, 0);
        for (size_t i = 0; i < d.simulated().size(); ++i) {
            ++sizes.at(d.segment_of(i));
            if (i > 0) {
                EXPECT_LE(d.segment_of(i - 1), d.segment_of(i));
            }
            EXPECT_EQ(d.warm_from(i), d.starts_segment(i) ? 0u : d.end_warp(i - 1)) << "k " << k << " cluster " << i;
            EXPECT_EQ(d.starts_segment(i), i == 0 || d.segment_of(i) != d.segment_of(i - 1));
        }
        EXPECT_EQ(d.segment_of(0), 0u);
        EXPECT_LE(*std::max_element(sizes.begin(), sizes.end()) - *std::min_element(sizes.begin(), sizes.end()), 1u) << "k " << k;
        EXPECT_GE(*std::min_element(sizes.begin(), sizes.end()), 1u);
    }
    rtu::SampleDesign six(40, 4, 0.5, 3, work);
    EXPECT_THROW(six.split(6), std::invalid_argument);  // 5 simulated clusters
    EXPECT_THROW(six.split(0), std::invalid_argument);
    // Everything asked for: the first wave and every non-empty cluster, a census.
    const rtu::SampleDesign all(40, 4, 0.95, 1, work);
    EXPECT_TRUE(all.census());
    EXPECT_EQ(all.simulated().size(), 8u);
}

// A frame that begins with empty clusters (sky above the scene): its first wave is the first
// cluster that reads a node, where the frame's cold start is; the empty ones before it are empty
// clusters like any other. Without the pre-pass's work, cluster 0 stays the first wave.
TEST(SampleDesign, FirstWaveIsTheFirstClusterWithWork) {
    const std::vector<double> work = {0, 0, 4, 9, 0, 7, 3, 8, 2, 6};
    for (uint64_t seed = 1; seed <= 10; ++seed) {
        const rtu::SampleDesign d(40, 4, 0.5, seed, work);
        EXPECT_EQ(d.first_wave_clusters(), 1u);
        EXPECT_EQ(d.empty_clusters(), 3u);  // 0, 1 and 4
        EXPECT_EQ(d.strata(), 4u);          // round(10 x 0.5) - 1
        const auto& sim = d.simulated();
        ASSERT_EQ(sim.size(), 5u);
        EXPECT_EQ(sim[0].cluster, 2u);
        EXPECT_EQ(sim[0].stratum, rtu::SampledCluster::kCertain);
        EXPECT_EQ(sim[0].weight, 1.0);
        double weights = 0;
        for (size_t i = 1; i < sim.size(); ++i) {
            EXPECT_NE(sim[i].cluster, 2u);
            EXPECT_GT(work[sim[i].cluster], 0.0);
            weights += sim[i].weight;
        }
        EXPECT_EQ(weights, 6.0);  // the 6 non-empty clusters beside the first wave
    }
    const rtu::SampleDesign all(40, 4, 0.95, 1, work);  // everything asked for: a census of the 7 with work
    EXPECT_TRUE(all.census());
    EXPECT_EQ(all.simulated().size(), 7u);
    const rtu::SampleDesign blind(40, 4, 0.5, 1);  // no pre-pass
    EXPECT_EQ(blind.simulated()[0].cluster, 0u);
    EXPECT_EQ(blind.simulated()[0].stratum, rtu::SampledCluster::kCertain);
    EXPECT_EQ(blind.empty_clusters(), 0u);
}

// A sample plan (--sample-plan) reads back what was written, an empty warp included (a warp whose
// rays all miss the root box has no traces; reading it once passed a null pointer to memcpy:
// found by fuzz_segment); a missing file is no plan; another identity, a file cut short, bytes
// after the last warp and a count beyond the file are bad input, each with its checksum made
// right; any flipped bit of the file is refused by the checksum. Plans of versions 1 (no first
// reads) and 2 (no checksum) are refused with a message to remove them.
TEST(SamplePlan, RoundTripsAndRefusesBadFiles) {
    rtu::test::TempDir dir;
    rtu::PrepassResult p;
    p.trace_nodes = {{3, 5, 0}, {}, {7}};
    p.first_reads_in_rounds = {4, 0, 1};
    p.first_reads_by_warp = {5, 0, 0};
    p.threads = 2;
    const std::string file = dir.file("plan.bin"), id = "scene=cornell\nframe=64x64\n";
    EXPECT_FALSE(rtu::read_plan(file, id).has_value());
    {
        std::ofstream out(file, std::ios::binary);
        out << rtu::plan_bytes(id, p);
    }
    const auto back = rtu::read_plan(file, id);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->trace_nodes, p.trace_nodes);
    EXPECT_EQ(back->threads, 2u);
    EXPECT_EQ(back->critical_nodes_total, 15.0);
    EXPECT_EQ(back->first_reads_in_rounds, p.first_reads_in_rounds);
    EXPECT_EQ(back->first_reads_by_warp, p.first_reads_by_warp);
    EXPECT_THROW(rtu::read_plan(file, "scene=wknd\n"), rtu::InputError);
    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::string body = bytes.substr(0, bytes.size() - 8);
    auto summed = [](const std::string& b) {  // the body with its checksum after it
        const uint64_t sum = rtu::fnv1a(b.data(), b.size());
        return b + std::string(reinterpret_cast<const char*>(&sum), 8);
    };
    ASSERT_EQ(summed(body), bytes);
    auto refused = [&](const std::string& content, const char* why) {
        {
            std::ofstream out(dir.file("bad.bin"), std::ios::binary);
            out << content;
        }
        try {
            (void)rtu::read_plan(dir.file("bad.bin"), id);
            ADD_FAILURE() << content.size() << " bytes accepted; expected: " << why;
        } catch (const rtu::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    for (size_t cut : {size_t(0), size_t(5), size_t(12)}) refused(bytes.substr(0, cut), "cut short");
    for (size_t cut : {size_t(20), body.size() - 1}) refused(summed(body.substr(0, cut)), "cut short");
    refused(summed(body + "x"), "bytes after");
    for (size_t bit = 0; bit < 8 * bytes.size(); bit += 37) {  // a flipped bit anywhere but the magic
        std::string flipped = bytes;
        flipped[bit / 8] = char(flipped[bit / 8] ^ (1 << (bit % 8)));
        if (bit / 8 >= 8) refused(flipped, "damaged");
    }
    for (char old : {'1', '2'}) {
        std::string v = bytes;
        v[7] = old;
        refused(v, "older rtsim");
    }
    std::string few = body;  // first reads (warp by warp) of 1 warp for 3
    few[body.size() - 3 * 4 - 8] = char(1);
    refused(summed(few), "first reads of 1 warps");
    std::string huge = body;
    huge[8 + 8 + id.size()] = char(0xff);  // the warp count's low byte: far more warps than bytes
    huge[8 + 8 + id.size() + 5] = char(0x7f);
    refused(summed(huge), "warps in");
}

// The pre-pass's first reads, against a count made here: every node the frame reads is first
// read once, by the earliest warp that reads it. Primary rays (one trace per warp) of cornell at
// 64x48, 1 spp (96 shader warps of 32 pixels): tracing the warps in frame order and counting the
// nodes not read before gives each warp's first reads; the pre-pass must give the same on 1 and
// on 3 threads, in rounds and warp by warp (one trace a warp: the same order). Path tracing: the
// nodes first read are the same in either order, so the totals agree, while the warps that read
// them first differ (in rounds a bounce of warp 0 comes after the camera rays of every warp).
struct PathWarps : FrameWarps {
    std::vector<std::vector<WorkRay>> w;  // per shader warp, its threads' first rays in path order
    explicit PathWarps(Workload& workload) {
        std::vector<WorkRay> first;
        workload.begin(first);
        std::stable_sort(first.begin(), first.end(), [](const WorkRay& a, const WorkRay& b) { return a.path < b.path; });
        for (size_t i = 0; i < first.size(); ++i) {
            if (i % 32 == 0) w.emplace_back();
            w.back().push_back(first[i]);
        }
    }
    size_t warps() const override { return w.size(); }
    uint32_t sm(size_t warp) const override { return uint32_t(warp % 2); }
    void threads(size_t warp, std::vector<uint32_t>& paths, std::vector<RayQueue>& first) const override {
        paths.resize(w[warp].size());
        first.assign(std::max(first.size(), w[warp].size()), RayQueue{});
        for (size_t i = 0; i < w[warp].size(); ++i) {
            paths[i] = w[warp][i].path;
            first[i] = RayQueue{};
            first[i].push_back(w[warp][i]);
        }
    }
};

TEST(SamplePrepass, FirstReadsCountEachNodeOnceAtItsFirstReader) {
    const Scene scene = load_scene("cornell", "");
    const BvhImage img = build_bvh_image(scene);
    WorkloadParams p;
    p.width = 64;
    p.height = 48;
    p.spp = 1;
    auto prepass = [&](WorkloadKind kind, unsigned threads) {
        SamplingOptions s;
        s.threads = threads;
        s.node_blocks = (img.size() + kBlockBytes - 1) / kBlockBytes;
        s.make_workload = [&] { return make_scene_workload(kind, scene, p); };
        s.trace = [&](const Ray& r, std::vector<StackEntry>* fetched) { return trace_ray(img, r, TraversalOrder::DFS, nullptr, fetched); };
        const std::unique_ptr<Workload> workload = s.make_workload();
        const PathWarps frame(*workload);
        PrepassWorkload shared(s.make_workload);
        return run_prepass(frame, s, shared);
    };
    // The count made here, primary rays in frame order.
    const std::unique_ptr<Workload> workload = make_scene_workload(WorkloadKind::Primary, scene, p);
    const PathWarps frame(*workload);
    ASSERT_EQ(frame.warps(), 96u);
    std::vector<bool> read((img.size() + kBlockBytes - 1) / kBlockBytes, false);
    std::vector<uint32_t> expected;
    std::vector<StackEntry> fetched;
    for (const auto& warp : frame.w) {
        expected.push_back(0);
        for (const WorkRay& r : warp) {
            fetched.clear();
            if (is_valid_ray(r.ray)) trace_ray(img, r.ray, TraversalOrder::DFS, nullptr, &fetched);
            for (const StackEntry& e : fetched)
                if (!read[e.addr / kBlockBytes]) read[e.addr / kBlockBytes] = true, ++expected.back();
        }
    }
    const double nodes_read = double(std::count(read.begin(), read.end(), true));
    EXPECT_GT(nodes_read, 10);
    for (const unsigned threads : {1u, 3u}) {
        const PrepassResult r = prepass(WorkloadKind::Primary, threads);
        EXPECT_EQ(r.first_reads_by_warp, expected) << threads << " threads";
        EXPECT_EQ(r.first_reads_in_rounds, expected) << threads << " threads";
    }
    const PrepassResult pt = prepass(WorkloadKind::PathTrace, 1), pt3 = prepass(WorkloadKind::PathTrace, 3);
    EXPECT_EQ(pt3.first_reads_in_rounds, pt.first_reads_in_rounds);
    EXPECT_EQ(pt3.first_reads_by_warp, pt.first_reads_by_warp);
    EXPECT_EQ(first_reads_total(pt.first_reads_by_warp), first_reads_total(pt.first_reads_in_rounds));
    EXPECT_GE(first_reads_total(pt.first_reads_by_warp), nodes_read);  // the bounces read the camera rays' nodes and more
    EXPECT_NE(pt.first_reads_by_warp, pt.first_reads_in_rounds);
    EXPECT_EQ(&pt.first_reads(true), &pt.first_reads_in_rounds);
    EXPECT_EQ(&pt.first_reads(false), &pt.first_reads_by_warp);
}

// The pre-pass's and the warming's threads (and a split sample's segment threads) share one
// workload instance, made once; a warp is traced by one thread at a time, others stay free.
TEST(SamplePrepass, OneSharedWorkloadHoldsEachWarpForOneThreadAtATime) {
    struct NoWork : Workload {
        void begin(std::vector<WorkRay>&) override {}
        void complete(const WorkRay&, const Hit&, std::vector<WorkRay>&) override {}
    };
    int made = 0;
    PrepassWorkload shared([&] {
        ++made;
        return std::make_unique<NoWork>();
    });
    Workload& a = shared.get(8);
    EXPECT_EQ(&shared.get(8), &a);
    EXPECT_EQ(made, 1);
    EXPECT_THROW(shared.get(9), std::logic_error);  // another frame's warps
    EXPECT_THROW(PrepassWorkload::Hold(shared, 8), std::logic_error);
    std::atomic<bool> released{false}, second_holds{false}, held_after_release{false};
    auto first = std::make_unique<PrepassWorkload::Hold>(shared, 3);
    std::thread other([&] {
        const PrepassWorkload::Hold h(shared, 3);
        held_after_release = released.load();
        second_holds = true;
    });
    { const PrepassWorkload::Hold free_warp(shared, 4); }  // another warp is not held meanwhile
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_FALSE(second_holds.load()) << "warp 3 was taken while held";
    released = true;
    first.reset();
    other.join();
    EXPECT_TRUE(second_holds.load());
    EXPECT_TRUE(held_after_release.load());
}

// The hand-driven warming tests' frame: cornell at 64x48 and 1 spp (3072 paths: 96 shader warps,
// 24 clusters of 2 SMs x 2 slots), half of it sampled with the pre-pass and functional warming.
struct WarmingFrame {
    explicit WarmingFrame(WorkloadKind kind) : scene(load_scene("cornell", "")), img(build_bvh_image(scene)) {
        p.width = 64;
        p.height = 48;
        p.spp = 1;
        s.rate = 0.5;
        s.seed = 1;
        s.capacity = 4;
        s.threads = 1;
        s.warm_window = 1u << 20;
        s.make_workload = [this, kind] { return make_scene_workload(kind, scene, p); };
        s.trace = [this](const Ray& r, std::vector<StackEntry>* fetched) { return trace_ray(img, r, TraversalOrder::DFS, nullptr, fetched); };
        workload = s.make_workload();
        sample = std::make_unique<FrameSample>(s, 2, ShaderTiming{});
        driver = std::make_unique<WorkloadDriver>(*workload, 2, 32, ShaderTiming{}, sample.get());  // 2 SMs, no shading latency, every warp resident
    }
    WarmingFrame(const WarmingFrame&) = delete;
    const Scene scene;
    const BvhImage img;
    WorkloadParams p;
    SamplingOptions s;
    std::unique_ptr<Workload> workload;
    std::unique_ptr<FrameSample> sample;
    std::unique_ptr<WorkloadDriver> driver;
};

// Functional warming follows each SM's own pace: an SM's L1 is warmed with its fetches of the
// skipped clusters when that SM takes its first trace of a simulated cluster, not when the first
// SM does. Every shader warp is ready at cycle 0, so an SM of cheap warps may reach a cluster long
// before one of costly warps; warming the lagging SM then (as before) filled its L1 while it was
// still on its earlier warps, and primary rays of a mostly empty frame (the Stanford bunny alone
// at 512x512) came out 26-56 % high (docs/sampling.md). Here SM 0 takes every one of its traces
// before SM 1 takes any: SM 0's warmings hold only SM 0's fetches, and SM 1's come with SM 1.
TEST(SampleWarming, EachSmIsWarmedWhenItStartsTheCluster) {
    WarmingFrame frame(WorkloadKind::Primary);
    WorkloadDriver& driver = *frame.driver;
    ASSERT_TRUE(frame.sample->sampled());
    uint32_t caller = 0;
    std::vector<std::map<uint32_t, size_t>> calls[2];  // per SM taking traces: each warming's fetches per SM
    frame.sample->on_warm = [&](const std::vector<WarmFetch>& fetches) {
        std::map<uint32_t, size_t> by_sm;
        for (const WarmFetch& f : fetches) ++by_sm[f.sm];
        calls[caller].push_back(by_sm);
    };
    size_t traces[2] = {0, 0};
    for (caller = 0; caller < 2; ++caller)
        while (driver.next_trace(caller, 0)) ++traces[caller];
    EXPECT_GT(traces[0], 0u);
    EXPECT_EQ(traces[0], traces[1]);
    // Each simulated cluster with skipped warps before it warms each SM once (the first has none).
    ASSERT_GT(calls[0].size(), 3u);
    EXPECT_EQ(calls[0].size(), calls[1].size());
    for (uint32_t sm = 0; sm < 2; ++sm)
        for (const auto& by_sm : calls[sm]) {
            ASSERT_EQ(by_sm.size(), 1u) << "a warming taken by SM " << sm << " holds fetches of " << by_sm.size() << " SMs";
            EXPECT_EQ(by_sm.begin()->first, sm);
            EXPECT_GT(by_sm.begin()->second, 0u);
        }
}

// With every warp ready at cycle 0 an SM takes the first traces of all its warps before any
// second trace: the frame runs in rounds. A simulated cluster's first traces therefore run where
// the other warps have run their first traces only, and warming them with the skipped warps' every
// trace put bounces' nodes in the L1 of camera rays and gave the cluster's bounces' first touches
// to the skipped warps (docs/sampling.md, "Warming"). Here the driver is run
// in rounds by hand (path tracing, each trace retired at the next cycle): the warmings taken in the
// first round hold the skipped warps' first traces only, the later ones their later traces only,
// each SM's own, one of each per cluster and SM at most.
TEST(SampleWarming, FirstTracesWarmTheFirstRoundLaterTracesTheLater) {
    WarmingFrame frame(WorkloadKind::PathTrace);
    WorkloadDriver& driver = *frame.driver;
    ASSERT_TRUE(frame.sample->sampled());
    uint64_t now = 0;
    uint32_t caller = 0;
    size_t first_warmings[2] = {0, 0}, later_warmings[2] = {0, 0};
    frame.sample->on_warm = [&](const std::vector<WarmFetch>& fetches) {
        ASSERT_FALSE(fetches.empty());
        for (const WarmFetch& f : fetches) {
            ASSERT_EQ(f.sm, caller);
            if (now == 0)
                ASSERT_EQ(f.trace, 0u) << "a warming of the first round holds a fetch of a skipped warp's trace " << f.trace;
            else
                ASSERT_GT(f.trace, 0u) << "a warming at cycle " << now << " holds a fetch of a skipped warp's first trace";
        }
        ++(now == 0 ? first_warmings : later_warmings)[caller];
    };
    size_t rounds = 0;
    for (; !driver.finished() && now < 1000; ++now) {
        bool any = false;
        for (caller = 0; caller < 2; ++caller)
            while (auto trace = driver.next_trace(caller, now)) {
                any = true;
                std::vector<RetiredRay> done;
                for (const WarpRay& w : *trace) {
                    const TraceResult r = trace_ray(frame.img, w.ray, TraversalOrder::DFS, nullptr, nullptr);
                    done.push_back({w.key, r.hit, r.nodes_visited});
                }
                driver.retire(caller, done, now + 1);
            }
        rounds += any;
    }
    ASSERT_TRUE(driver.finished());
    EXPECT_GT(rounds, 2u);  // bounces: traces after the first
    for (uint32_t sm = 0; sm < 2; ++sm) {
        EXPECT_GT(first_warmings[sm], 3u) << "SM " << sm;
        EXPECT_GT(later_warmings[sm], 0u) << "SM " << sm;
        EXPECT_LE(later_warmings[sm], first_warmings[sm]) << "SM " << sm;
    }
}

// A cluster holds the warps that run together (docs/sampling.md, "Clusters"): with a limit of
// resident warps, the SMs' resident warps (`paper`: 8 SMs x 16; `desktop`: 30 x 8), or the warp
// buffers' where those are more; with every warp resident (`mobile`), the warp buffers' (8 x 4).
// The schedule model's slots stay the warp buffers' in every case.
TEST(SampleDesign, ClustersHoldTheWarpsThatRunTogether) {
    const HwConfig mobile = Config::load("mobile").resolve(), paper = Config::load("paper").resolve(),
                   desktop = Config::load("desktop").resolve();
    EXPECT_EQ(sample_cluster_warps(mobile), 32u);
    EXPECT_EQ(sample_cluster_warps(paper), 128u);
    EXPECT_EQ(sample_cluster_warps(desktop), 240u);
    EXPECT_EQ(gpu_warp_capacity(paper), 32u);
    EXPECT_EQ(gpu_warp_capacity(desktop), 120u);
    HwConfig few = paper;
    few.resident_warps = 2;  // fewer resident than the warp buffer holds
    EXPECT_EQ(sample_cluster_warps(few), 32u);
}
