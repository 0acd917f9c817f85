#include "bias.h"

#include <sstream>

#include <nlohmann/json.hpp>

#include "sampling_bias.h"

namespace rtu {

std::string percent_text(double v) {
    std::ostringstream s;
    s.precision(v < 0.1 ? 2 : 3);
    s << 100.0 * v << " %";
    return s.str();
}

SamplingBias SamplingBias::parse(const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text);
    SamplingBias b;
    b.measured_on = j.at("measured_on").get<std::string>();
    auto kind = [&](const char* name) {
        const nlohmann::json& k = j.at("bias").at(name);
        return Kind{k.at("value").get<double>(), k.at("cell").is_null() ? std::string("no cell biased") : k.at("cell").get<std::string>(),
                    k.at("cells").get<uint64_t>(), k.at("runs").get<uint64_t>()};
    };
    b.primary = kind("primary");
    b.other = kind("other");
    return b;
}

const SamplingBias& SamplingBias::built_in() {
    static const SamplingBias b = parse(kSamplingBiasJson);
    return b;
}

const SamplingBias::Kind& SamplingBias::of(const std::string& workload) const {
    if (workload == "primary") return primary;
    if (workload == "pt") return other;
    return primary.value >= other.value ? primary : other;  // not measured: the larger
}

std::string SamplingBias::basis(const std::string& workload) const {
    const Kind& k = of(workload);
    const bool p = &k == &primary;
    std::string s = "the sample design's bias bound " + percent_text(k.value) + ", the largest bias beyond the draws' noise among " +
                    std::to_string(k.cells) + " cells of the sampling grids (" + std::to_string(k.runs) + " runs of " +
                    (p ? "primary rays" : "path tracing") + ", rtsim " + measured_on + "; " + k.cell + ")";
    if (workload != "primary" && workload != "pt") s += ", taken for " + (workload.empty() ? std::string("a ray file") : workload) + " (not measured)";
    return s;
}

}  // namespace rtu
