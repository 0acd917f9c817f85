// The RT unit as an SoC peripheral: the RT complex of the timing model (RT units, L1s, crossbar,
// L2 slices, DRAM) behind a register block, a system-memory master and a level interrupt, as
// accelerators are integrated in virtual platforms (docs/peripheral.md).
//
//   regs  target socket, 32-bit registers in a 4 KiB aperture (rtunit/rtu_regs.h); b_transport
//         and transport_dbg, LT; errors as TLM response statuses
//   mem   initiator socket: reads the BVH image, the ray records and the job descriptors, writes
//         the hit and completion records, at the addresses software programmed (b_transport, and
//         DMI where granted)
//   irq   level interrupt, OR(INT_STATUS & INT_ENABLE), written by one process; may stay unbound
//
// Software writes a job (BVH image, rays, hit buffer) into the JOB registers or a chain of
// descriptors, then CTRL.START. The unit reads the image and the rays, traces them with the
// configured fidelity, writes one hit record per ray and raises JOB_DONE. Functional, interval, LT and AT
// fidelities; the memory path is private by default (the RT complex's own caches and DRAM, so its
// cycles do not depend on the SoC) or shared (its L2 misses read on `mem`). No process-wide side effects: no global quantum, no report actions, no
// sc_stop; any number of instances per simulation.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

#include "export.h"

namespace rtu {

struct RTUNIT_API PeripheralConfig {
    std::string config = "mobile";  // a preset (mobile, desktop, paper) or a JSON file, as rtsim --config
    std::vector<std::string> sets;  // key=value overrides of the configuration, as rtsim --set
    std::string fidelity = "lt";    // functional, interval, lt or at
    std::string traversal = "dfs";  // dfs or bfs
    // private: the RT complex's own L2 and DRAM (cycles independent of the SoC, equal to rtsim
    // --rays); shared: its L2 misses become reads on `mem` at the BVH's system address, so the
    // SoC's memory times them (lt and at only).
    std::string memory = "private";
    sc_core::sc_time reg_latency = sc_core::sc_time(10, sc_core::SC_NS);  // added to every register access
    // The core clock's period (RT units, L1s, crossbar, L2), as the platform's clock tree gives it:
    // kept in whole ticks of SystemC's time resolution, as is. Zero: the configuration's
    // gpu.core_clock_mhz (which must not be set as well). From 10 ps to 1 us. The DRAM keeps the
    // configuration's gpu.memory_clock_mhz.
    sc_core::sc_time core_clock_period = sc_core::SC_ZERO_TIME;
    // Direct memory access on `mem` where the target grants it: ray and hit records copied, the BVH
    // image used in place. Host speed only: hits and traversal cycles are the same without.
    bool use_dmi = true;
    // Every job checks its BVH image as if its flags had RTU_JOB_CHECK_BVH (a checking mode: on
    // the private path one extra read per node the job read; on the shared path each sector read
    // is compared).
    bool check_bvh = false;
    // By name, for platforms that configure modules from strings (QBox, VCML, Lua):
    // fidelity=, traversal=, memory=, config=, reg_latency_ns=, core_clock_period_ps=, use_dmi=, check_bvh=; any other key=value is a configuration key
    // (l1.size_kb=64, prefetch.kind=ttp, ...). Checked when the peripheral is built.
    void set(const std::string& key_value);
};

class RTUNIT_API RtUnitPeripheral : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<RtUnitPeripheral, 32> regs;
    tlm_utils::simple_initiator_socket<RtUnitPeripheral, 32> mem;
    sc_core::sc_port<sc_core::sc_signal_inout_if<bool>, 1, sc_core::SC_ZERO_OR_MORE_BOUND> irq;
    // Optional active-high reset (may stay unbound): at its rising edge a running job ends as by
    // ABORT (no hit or completion record written after it), then every register and counter
    // returns to its reset value and the interrupt goes low; while it is high START is ignored;
    // register accesses are answered as usual.
    sc_core::sc_port<sc_core::sc_signal_in_if<bool>, 1, sc_core::SC_ZERO_OR_MORE_BOUND> rst;

    // Throws std::invalid_argument for a bad configuration (naming the key or value).
    RtUnitPeripheral(sc_core::sc_module_name name, const PeripheralConfig& cfg = {});
    ~RtUnitPeripheral() override;
    SC_HAS_PROCESS(RtUnitPeripheral);

    struct Impl;  // defined in tlm/peripheral.cpp

private:
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& delay);
    unsigned int transport_dbg(tlm::tlm_generic_payload& t);
    void invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end);
    void run_jobs();   // SC_THREAD: one job or chain per START
    void drive_irq();  // SC_METHOD: the interrupt line's only writer
    void on_reset();   // on every change of rst (spawned when it is bound)
    void end_of_elaboration() override;

    std::unique_ptr<Impl> impl_;
};

}  // namespace rtu
