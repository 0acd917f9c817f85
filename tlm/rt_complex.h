// The RT complex: the RT units of the SMs, their L1s, the crossbar, the L2 slices and the DRAM,
// as child modules of one module, wired
//   TraceSource -> RtUnit[sm] -> L1[sm] -> Crossbar -> L2[slice] -> Dram
// (or, on a shared memory path, -> MemBridge -> the platform's memory: tlm/mem_bridge.h) and timed by its own core and memory clocks. rtsim's platform (platforms/gpu_platform.h) builds
// one; an SoC peripheral would build another around its own trace source. It has no process-wide
// side effects: it sets no global quantum, no report actions, and never stops or starts the
// simulation, so several may live in one simulation.
// AT: the children have no processes of their own; their handlers run on one event queue
// (tlm/ordered_events.h) in the order (time, rank, notification), so the kernel's order of
// same-time processes, which any other process in the simulation changes, decides nothing inside
// the complex.
// LT: one thread (lt_schedule) runs the RT units' cycles quantum by quantum, ahead of simulated
// time, then waits for the next quantum with work. Within a quantum it steps the units cycle by
// cycle (each cycle's first unit rotating: the unit of SM c mod n first in cycle c), so that the
// memory they share sees their requests nearly in time order; the quantum only sets how often the
// thread synchronises with the kernel. The quantum is sim.quantum core cycles, or a platform's
// global quantum where that is smaller. With a thread per unit, the kernel chose which unit ran
// its quantum first, and any other process in the simulation (rtsim's own monitor) changed that
// choice and LT's cycles.
#pragma once
#include <memory>
#include <vector>

#include <systemc>

#include "cache.h"
#include "clock.h"
#include "crossbar.h"
#include "dram.h"
#include "mem_bridge.h"
#include "model/fidelity.h"
#include "model/trace_source.h"
#include "ordered_events.h"
#include "payload.h"
#include "protocol_checker.h"
#include "rt_unit.h"

namespace rtu {

struct Treelets;

class RtComplex : public sc_core::sc_module {
public:
    // `treelets`: with treelet traversal, the treelets the RT units traverse by (and the image's
    // placement of them); else null. `check_protocol` (AT): a base-protocol checker on every link.
    // `shared_memory`: the L2 misses go to it through a MemBridge instead of to the complex's own
    // DRAM (null: the DRAM).
    RtComplex(sc_core::sc_module_name name, const HwConfig& cfg, const BvhImage& image, TraversalOrder order, TraceSource& source,
              Fidelity fidelity, const Treelets* treelets = nullptr, bool check_protocol = false, LineReader* shared_memory = nullptr);
    ~RtComplex() override;
    SC_HAS_PROCESS(RtComplex);

    const ClockDomain& core_clock() const { return core_; }
    const ClockDomain& memory_clock() const { return mem_; }
    const std::vector<std::unique_ptr<RtUnit>>& rt_units() const { return rt_; }
    const std::vector<std::unique_ptr<Cache>>& l1() const { return l1_; }
    const std::vector<std::unique_ptr<Cache>>& l2() const { return l2_; }
    const Dram& dram() const { return *dram_; }  // not on a shared memory path
    const MemBridge* bridge() const { return bridge_.get(); }  // on a shared memory path, else null
    const PayloadPool& pool() const { return pool_; }
    const std::vector<std::unique_ptr<ProtocolChecker>>& checkers() const { return checkers_; }
    // A job's traces are ready at the trace source (an SoC peripheral's): the RT units look for
    // work again. The first job sets the clocks' epoch to now (cycle 0 there, so that it runs as
    // rtsim's frame from time 0); later jobs find the DRAM as the last left it and the caches
    // invalidated. Call only while every RT unit is idle.
    void start_job();
    // Every RT unit idle: no trace resident, no request or response on its way (a prefetch's
    // included). start_job needs it.
    bool idle() const;
    // LT: windows of sim.quantum whatever the platform's global quantum. For a complex whose
    // memory is its own (the SoC peripheral's private path): nothing outside it sees its work
    // before the job's end, so its cycles need not depend on how often the platform synchronises.
    void use_own_quantum_only() { follow_global_quantum_ = false; }
    // Functional warming (sampled runs): the sector at `addr` into SM `sm`'s L1, and into its L2
    // slice when the L1 did not hold it (tags and LRU only).
    void warm(uint32_t sm, uint64_t addr);
    // The shader code's loads after each trace (workload.shader_reads; RtUnit::set_shader_reads),
    // each SM's into its own L1. A frame of given rays runs no shader code: its platform leaves them out.
    void set_shader_reads(const ShaderReads& reads);

private:
    void lt_schedule();  // LT

    ClockDomain core_, mem_;
    OrderedEvents events_;   // AT: every child's handlers, in an order of the complex's own
    bool started_ = false;   // start_job has set the epoch
    sc_core::sc_event work_;  // LT: a job started
    bool follow_global_quantum_ = true;
    sc_core::sc_time quantum_;  // LT: sim.quantum core cycles
    PayloadPool pool_;
    std::vector<std::unique_ptr<RtUnit>> rt_;
    std::vector<std::unique_ptr<Cache>> l1_, l2_;
    std::unique_ptr<Crossbar> xbar_;
    std::unique_ptr<Dram> dram_;
    std::unique_ptr<MemBridge> bridge_;
    std::vector<std::unique_ptr<ProtocolChecker>> checkers_;
};

}  // namespace rtu
