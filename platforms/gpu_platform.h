// The GPU platform of the timing model: the only place where modules are wired together.
//   WorkloadDriver -> RtUnit[sm] -> L1[sm] -> Crossbar -> L2[slice] -> Dram
// Built from a HwConfig, elaborated once per process, run with sc_start().
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/bvh_image.h"
#include "model/config.h"
#include "tlm/cache.h"
#include "tlm/clock.h"
#include "tlm/crossbar.h"
#include "tlm/dram.h"
#include "tlm/driver.h"
#include "tlm/payload.h"
#include "tlm/protocol_checker.h"
#include "tlm/rt_unit.h"

namespace rtu {

struct TimingOptions {
    Fidelity fidelity = Fidelity::AT;
    TraversalOrder order = TraversalOrder::DFS;
    bool progress = false;
    std::string vcd;                  // VCD file (without the .vcd suffix SystemC adds)
    int trace_sm = -1, trace_warp = -1;  // one warp-buffer slot whose threads' stack depths are traced
    uint32_t trace_window = 1000;     // cycles per sample of windowed waveforms (miss rate, bandwidth)
    bool check_protocol = false;      // AT: a base-protocol checker on every socket
    double sample_rate = 1.0;         // < 1: sampled simulation of this share of the frame's warps
    uint64_t sample_seed = 1;
    // Sampled runs: makes fresh instances of the workload for the functional pre-pass
    // (docs/sampling.md), one per thread; empty: the plain stratified estimate.
    std::function<std::unique_ptr<Workload>()> sample_workload;
    unsigned sample_threads = 1;
    // Keep every ray with its hit for TimingResult::rays (hits files, verification); without,
    // memory holds only the rays in flight.
    bool keep_rays = true;
};

struct TimingResult {
    std::vector<TracedRay> rays;    // with TimingOptions::keep_rays
    WorkloadDriver::RaySummary summary;  // always
    uint64_t cycles = 0;            // the frame's cycles (extrapolated when sampled)
    uint64_t cycles_simulated = 0;  // cycles of what was actually simulated
    bool stuck = false;
    std::string stuck_report;
    std::vector<std::string> invariant_failures;
    std::vector<std::string> protocol_violations;  // with check_protocol
    uint64_t protocol_transactions = 0;
    nlohmann::ordered_json stats;  // hierarchy statistics (no wall time)
};

// The workload driver's sampling options for a timing run (docs/sampling.md): clusters of as
// many warps as the GPU holds, the functional pre-pass on `image`, warming enough to refill
// every cache twice. `treelets` as for the run's traversal (may be null).
SamplingOptions sampling_options(const HwConfig& cfg, const BvhImage& image, const TimingOptions& opt, const Treelets* treelets);

class GpuPlatform {
public:
    GpuPlatform(const HwConfig& cfg, const BvhImage& image, Workload& workload, const TimingOptions& opt);
    ~GpuPlatform();
    // Runs the simulation to the end (call once per process: SystemC elaborates once).
    TimingResult run();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtu
