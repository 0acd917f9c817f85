#include "error_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "error_bounds.h"
#include "sampling/bias.h"
#include "sampling/estimator.h"
#include "simulation.h"
#include "timing_run.h"

namespace rtu {
namespace {

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

// A configuration's hardware: all but its `sim` keys (the LT quantum, the watchdog, the trace
// window), which change no statistic of a run (test RtsimTiming.LtStatisticsDoNotDependOnTheQuantum).
nlohmann::ordered_json hardware(nlohmann::ordered_json config) {
    config.erase("sim");
    return config;
}

// The hardware of the configuration `name` (NAME or NAME+PREFETCHER) of the grid, as a run would hold it.
nlohmann::ordered_json grid_config(const std::string& name) {
    const size_t plus = name.find('+');
    Config c = Config::load(name.substr(0, plus));
    if (plus != std::string::npos) c.set("prefetch.kind=" + name.substr(plus + 1));
    return hardware(c.to_json());
}

// Whether the hardware `run` is that of one of the configurations `names` (grid_config's names).
bool one_of(const nlohmann::ordered_json& run, const std::vector<std::string>& names) {
    for (const std::string& name : names)
        if (grid_config(name) == run) return true;
    return false;
}

// Whether the run's hardware is a preset's, with the run's prefetcher. The sampling grids that
// measured the design's bias bound ran the presets (platforms/configs/sampling_bias.json,
// "grids"): a run on other hardware (a key set, a file) carries a bound measured elsewhere.
bool preset_hardware(const Config& config) {
    const nlohmann::ordered_json run = hardware(config.to_json());
    const std::string kind = run.at("prefetch").at("kind").get<std::string>();
    std::vector<std::string> names;
    for (const std::string& name : Config::presets()) names.push_back(name + "+" + kind);
    return one_of(run, names);
}

// A sample of fewer than kAimStrata drawn strata (and not every cluster): its interval rests on
// few strata, and the rate that draws kAimStrata, where the frame has that many clusters to draw.
// `width`: the run's --sample-width (0: none), which chose the fewest strata predicted to reach
// it; the rate that draws kAimStrata is then the other way to more strata.
std::string few_strata(const SampleEstimate& e, double width) {
    const SampleEstimate::Design& d = e.design;
    if (d.cluster_warps == 0 || d.strata >= kAimStrata) return "";
    const auto [clusters, candidates] = FrameClusters(e.warps_total, d.cluster_warps, d.first_wave_clusters, d.empty_clusters);
    if (d.strata >= candidates) return "";  // every cluster simulated: no sampling error
    std::string s = "; " + std::to_string(d.strata) + " drawn strata, fewer than " + std::to_string(kAimStrata) +
                    ": intervals of so few strata missed more often in the project's grids (docs/sampling.md, \"How many strata\"); ";
    if (width > 0) s += "--sample-width planned the fewest strata predicted to reach +-" + percent_text(width) + "; ";
    const std::optional<double> rate = rate_for_strata(clusters, candidates, kAimStrata);
    if (rate && *rate < 1.0) {
        char r[16];
        std::snprintf(r, sizeof r, "%.3g", *rate);
        s += (width > 0 ? "a narrower width draws more, and --sample " : "--sample ") + std::string(r) + " draws " + std::to_string(kAimStrata);
    } else {
        s += "this frame has " + std::to_string(candidates) + " clusters to draw from: a larger frame draws more";
    }
    return s;
}

// A frame size added to the grid later (scripts/bench_error_grid.py, EXTEND): its own scenes and commit.
std::string added_later(const std::string& side, const nlohmann::json& size_entry) {
    const auto scenes = size_entry["scenes"].get<std::vector<std::string>>();
    return side + "x" + side + " added later: " + std::to_string(scenes.size()) + " scenes (" + join(scenes) + "), rtsim " +
           size_entry.value("measured_on", std::string("?"));
}

}  // namespace

std::optional<ErrorBounds::Bound> ErrorBounds::bound(const std::string& fidelity, const std::string& workload) const {
    if (!bounds.contains(fidelity) || !bounds[fidelity].contains(workload)) return std::nullopt;
    const nlohmann::json& b = bounds[fidelity][workload];
    if (b.value("runs", 0) == 0) return std::nullopt;
    Bound all{b["runs"].get<uint64_t>(), b["worst"].get<double>(), {}};
    if (b.contains("by_size"))
        for (const auto& [side, s] : b["by_size"].items())
            if (s.contains("scenes")) all.added.push_back(added_later(side, s));
    return all;
}

double ErrorBounds::side(const RunSpec& spec) const {
    return std::sqrt(double(spec.params.width) * double(spec.params.height) * double(spec.params.spp) / spp);
}

std::optional<ErrorBounds::Bound> ErrorBounds::bound(const std::string& fidelity, const std::string& workload, double side,
                                                     const std::string& scene) const {
    const std::optional<Bound> all = bound(fidelity, workload);
    if (!all || !bounds[fidelity][workload].contains("by_size")) return all;
    const std::vector<int>& sizes = this->sizes(workload);
    Bound b;
    b.nearest = true;
    for (size_t i = 0; i < sizes.size(); ++i) {
        // The sizes bracketing `side`: the largest at or below it and the smallest at or above it.
        const bool below = sizes[i] <= side && (i + 1 == sizes.size() || sizes[i + 1] > side);
        const bool above = sizes[i] >= side && (i == 0 || sizes[i - 1] < side);
        if (!below && !above) continue;
        const nlohmann::json& s = bounds[fidelity][workload]["by_size"][std::to_string(sizes[i])];
        if (s.value("runs", 0) == 0) return all;  // a size without runs: the whole grid's bound
        const auto listed = [&](const std::vector<std::string>& names) { return std::find(names.begin(), names.end(), scene) != names.end(); };
        if (s.contains("scenes") && listed(scenes) && !listed(s["scenes"].get<std::vector<std::string>>())) {
            // A size added later without this scene of the grid: not measured where the grid
            // knows the scene (party's path tracing was the interval fidelity's worst at 384x384).
            Bound w = *all;
            w.added.push_back(std::to_string(sizes[i]) + "x" + std::to_string(sizes[i]) + " was added later without " + scene +
                              ": the whole grid's bound");
            return w;
        }
        b.runs += s["runs"].get<uint64_t>();
        b.worst = std::max(b.worst, s["worst"].get<double>());
        if (s.contains("scenes")) b.added.push_back(added_later(std::to_string(sizes[i]), s));
    }
    if (b.runs == 0) return all;
    return b;
}

std::string ErrorBounds::measured_on_for(const std::string& fidelity) const {
    if (bounds.contains(fidelity) && bounds[fidelity].contains("measured_on")) return bounds[fidelity]["measured_on"].get<std::string>();
    return measured_on;
}

ErrorBounds ErrorBounds::parse(const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text);
    ErrorBounds b;
    b.measured_on = j.at("measured_on").get<std::string>();
    const nlohmann::json& g = j.at("grid");
    b.scenes = g.at("scenes").get<std::vector<std::string>>();
    b.configs = g.at("configs").get<std::vector<std::string>>();
    b.primary_sizes = g.at("primary_sizes").get<std::vector<int>>();
    b.pt_sizes = g.at("pt_sizes").get<std::vector<int>>();
    b.spp = g.value("spp", 2);
    b.bounds = j.at("bounds");
    return b;
}

const ErrorBounds& ErrorBounds::built_in() {
    static const ErrorBounds b = parse(kErrorBoundsJson);
    return b;
}

std::optional<std::string> outside_regime(const RunSpec& spec, const ErrorBounds& bounds) {
    const std::string fid = fidelity_name(spec.run.fidelity);
    if (!spec.rays.empty()) return "a ray file (the grid measured scene workloads)";
    if (!bounds.bound(fid, spec.workload)) return "no " + fid + " runs of the " + spec.workload + " workload in the grid";
    if (spec.run.order != TraversalOrder::DFS) return "traversal other than dfs";
    const auto& sizes = bounds.sizes(spec.workload);
    // The frame's size as its number of pixel samples, within the grid's smallest and largest.
    const auto [lo, hi] = std::minmax_element(sizes.begin(), sizes.end());
    const double side = bounds.side(spec);
    if (side < *lo || side > *hi)
        return "a frame of " + std::to_string(spec.params.width) + "x" + std::to_string(spec.params.height) + " at " +
               std::to_string(spec.params.spp) + " spp (the grid: " + std::to_string(*lo) + "^2 to " + std::to_string(*hi) + "^2 pixels at " +
               std::to_string(bounds.spp) + " spp)";
    if (spec.workload == "pt" && spec.params.bounces != WorkloadParams{}.bounces) return "a bounce limit other than the default";
    if (one_of(hardware(spec.config.to_json()), bounds.configs)) return std::nullopt;
    return "a configuration other than the grid's (" + join(bounds.configs) + ", each at its preset's values)";
}

namespace {

ErrorEstimate estimate_of(const RunSpec& spec, const TimingResult& t, const std::optional<ErrorCheck>& check, const ErrorBounds& bounds) {
    ErrorEstimate e;
    e.check = check;
    // A sampled run first carries its sampling interval (relative half-width around the estimate).
    double sampling = 0;
    std::string sampled_basis;
    if (t.sampled) {
        if (!t.estimate.design.has_interval) {
            e.kind = "none";
            e.basis = "a sample too small for an interval (fewer than 10 strata, or segments of fewer than 16 clusters; --sample-unchecked) has none";
            return e;
        }
        sampling = t.estimate.relative_half_width(double(t.cycles_simulated));
        const std::string model = !t.estimate.schedule ? ""
                                  : std::string(", with the schedule model's error") + (t.estimate.misfit_per_sm.empty() ? "" : " over every SM") +
                                        ", the extrapolation term" + (t.estimate.first_reads_gap() > 0 ? ", the first reads' term" : "");
        sampled_basis = "95 % sampling interval over " + std::to_string(t.estimate.design.strata) + " drawn strata" + model +
                        (t.estimate.design_bias > 0 ? " and " + SamplingBias::built_in().basis(spec.rays.empty() ? spec.workload : "") : "") +
                        " (docs/sampling.md)";
        if (t.estimate.design_bias > 0 && !preset_hardware(spec.config))
            sampled_basis += "; the bias bound was measured on the presets (" + join(Config::presets()) +
                             "), not on this configuration";
        sampled_basis += few_strata(t.estimate, spec.sample_width);
    }
    const std::string fid = fidelity_name(spec.run.fidelity);
    if (spec.run.fidelity == Fidelity::AT) {
        e.value = sampling;
        e.kind = t.sampled ? "interval" : "reference";
        e.basis = t.sampled ? sampled_basis : "AT is the reference timing model (docs/accuracy.md)";
        return e;
    }
    const std::string plus = t.sampled ? "interval + " : "";
    const auto add_sampling = [&](const std::string& basis) { return t.sampled ? sampled_basis + "; plus " + basis : basis; };
    const std::optional<std::string> outside = outside_regime(spec, bounds);
    std::string measured;
    if (check)
        measured = "measured against AT on " + std::to_string(check->clusters) + " clusters (" + percent_text(check->share) +
                   " of the frame's warps): the frame's RT-unit residence " + (check->difference() >= 0 ? "+" : "") +
                   percent_text(check->difference()) + " +- " + percent_text(check->residence.half_width) + " (95 %, " +
                   std::to_string(check->residence.pairs) + " stratum pairs)";
    if (!outside) {
        const ErrorBounds::Bound b = *bounds.bound(fid, spec.workload, bounds.side(spec), spec.scene);
        const std::string bound_basis = "worst |cycles error| against AT in the " + std::to_string(b.runs) + " runs of " + fid + " on " +
                                        spec.workload + (b.nearest ? " at the nearest frame sizes" : " at every frame size") + " of the error grid (" +
                                        std::to_string(bounds.scenes.size()) + " scenes, configurations " + join(bounds.configs) +
                                        "; rtsim " + bounds.measured_on_for(fid) + (b.added.empty() ? "" : "; " + join(b.added)) +
                                        "; docs/accuracy.md)";
        // A check whose interval reaches beyond the bound may show the bound does not hold here:
        // the larger stands.
        if (check && check->bound() > b.worst) {
            e.value = sampling + check->bound();
            e.kind = plus + "measured";
            e.basis = add_sampling(measured + ", reaching beyond the " + percent_text(b.worst) + " " + bound_basis);
        } else {
            e.value = sampling + b.worst;
            e.kind = plus + "validated bound";
            e.basis = add_sampling(bound_basis);
        }
        return e;
    }
    if (check) {
        e.value = sampling + check->bound();
        e.kind = plus + "measured";
        e.basis = add_sampling(measured + "; outside the validated regime: " + *outside);
        return e;
    }
    e.kind = "none";
    e.basis = "outside the validated regime: " + *outside + "; --check-error N measures this run's error against AT";
    return e;
}

}  // namespace

ErrorEstimate estimate_error(const RunSpec& spec, const TimingResult& t, const std::optional<ErrorCheck>& check, const ErrorBounds& bounds,
                             const std::string& check_refused) {
    ErrorEstimate e = estimate_of(spec, t, check, bounds);
    if (!check_refused.empty()) e.basis += "; --check-error refused: " + check_refused;
    return e;
}

std::string error_line(const nlohmann::ordered_json& s) {
    std::string line = "error estimate: ";
    if (s["value"].is_null())
        line += "none (" + s["basis"].get<std::string>() + ")";
    else
        line += "+-" + percent_text(s["value"].get<double>()) + " (" + s["kind"].get<std::string>() + ": " + s["basis"].get<std::string>() + ")";
    if (s.contains("check") && !s["check"].is_null()) {
        const auto& c = s["check"];
        line += "\nchecked against AT on " + std::to_string(c["clusters"].get<uint64_t>()) + " clusters (" +
                percent_text(c["share"].get<double>()) + " of the frame): RT-unit residence " +
                (c["difference"].get<double>() >= 0 ? "+" : "") + percent_text(c["difference"].get<double>()) + " +- " +
                percent_text(c["difference_half_width"].get<double>()) + " (95 %, paired by stratum)";
        char took[96];
        std::snprintf(took, sizeof took, "; the check took %.1f s (AT %.1f s, this fidelity %.1f s)", c["wall_s"].get<double>(),
                      c["at_s"].get<double>(), c["fidelity_s"].get<double>());
        line += took;
    }
    return line;
}

}  // namespace rtu
