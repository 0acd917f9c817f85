#include "rt_complex.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <tlm>

namespace rtu {

using namespace sc_core;

RtComplex::RtComplex(sc_module_name name, const HwConfig& cfg, const BvhImage& image, TraversalOrder order, TraceSource& source,
                     Fidelity fidelity, const Treelets* treelets, bool check_protocol, LineReader* shared_memory)
    : sc_module(name), core_(cfg.core_mhz), mem_(cfg.memory_mhz), events_("events"), quantum_(core_.period() * double(cfg.quantum)) {
    // Binds initiator to target, through a protocol checker when asked for (AT only: LT's
    // blocking transport has no phases to check).
    const bool check = check_protocol && fidelity == Fidelity::AT;
    auto link = [&](auto& initiator, auto& target, const std::string& link_name) {
        if (!check) {
            initiator.bind(target);
            return;
        }
        checkers_.emplace_back(new ProtocolChecker(("check_" + link_name).c_str()));
        initiator.bind(checkers_.back()->in);
        checkers_.back()->out.bind(target);
    };
    // The children are made in this order (RT unit and L1 per SM, the crossbar, the DRAM, then
    // the L2 slices); the RT units' first handlers (time 0) run in it.
    for (uint32_t s = 0; s < cfg.sms; ++s) {
        const std::string id = std::to_string(s);
        rt_.emplace_back(new RtUnit(("rt_unit_" + id).c_str(), s, cfg, image, order, source, pool_, core_, fidelity, events_, treelets));
        l1_.emplace_back(new Cache(("l1_" + id).c_str(), CacheRole::L1, cfg.l1, cfg.l1_hit_latency, pool_, core_, fidelity, events_));
        link(rt_[s]->socket, l1_[s]->in, "rt_unit_" + id + "_l1_" + id);
    }
    xbar_.reset(new Crossbar("crossbar", cfg.address_map(), cfg.l2_slices, cfg.xbar_latency, core_, fidelity, events_));
    for (uint32_t s = 0; s < cfg.sms; ++s) link(l1_[s]->out, xbar_->in, "l1_" + std::to_string(s) + "_crossbar");
    if (shared_memory) bridge_.reset(new MemBridge("mem_bridge", *shared_memory, mem_, fidelity, events_));
    else dram_.reset(new Dram("dram", cfg.dram, cfg.address_map(), mem_, core_.period(), fidelity, events_));
    for (uint32_t s = 0; s < cfg.l2_slices; ++s) {
        const std::string id = std::to_string(s);
        l2_.emplace_back(new Cache(("l2_" + id).c_str(), CacheRole::L2, cfg.l2, cfg.l2.latency, pool_, core_, fidelity, events_));
        link(xbar_->out, l2_[s]->in, "crossbar_l2_" + id);
        if (bridge_) link(l2_[s]->out, bridge_->in, "l2_" + id + "_mem_bridge");
        else link(l2_[s]->out, dram_->in, "l2_" + id + "_dram");
    }
    if (fidelity == Fidelity::LT) SC_THREAD(lt_schedule);
}

RtComplex::~RtComplex() = default;

void RtComplex::lt_schedule() {
    for (;;) {
        uint64_t first = ~0ull;
        for (const auto& u : rt_) first = std::min(first, u->lt_next());
        if (first == ~0ull) {  // no unit has work, and none will get any until a job starts
            wait(work_);
            continue;
        }
        const sc_time t = core_.time_of(first);
        if (t > sc_time_stamp()) wait(t - sc_time_stamp());
        // The quantum holding `first`: windows on multiples of the quantum from the clocks'
        // epoch (from time 0 in rtsim, as tlm_global_quantum places sync points).
        sc_time q = quantum_;
        const sc_time& global = tlm::tlm_global_quantum::instance().get();
        if (follow_global_quantum_ && global != SC_ZERO_TIME && global < q) q = global;
        const uint64_t end = std::max(first + 1, q == SC_ZERO_TIME ? first + 1 : core_.cycle_at_or_after(t - sc_time::from_value((t - core_.epoch()).value() % q.value()) + q));
        // The units run the window cycle by cycle, all of them through cycle c before any runs
        // c + 1 (the first of each cycle rotating with it, as no RT unit of a GPU has precedence),
        // so the L2 slices and the DRAM, which several units share, are called nearly in time
        // order, as in AT. The window only sets how often the thread synchronises with the
        // kernel: in rtsim LT's statistics do not depend on sim.quantum. Before (until
        // 2026-11-25), each unit ran its whole window in turn, so shared memory saw one unit's
        // requests up to a quantum ahead of another's: with 30 SMs (desktop, sprng primary rays
        // 128x128) L2 misses waited 15 % less than in AT (median 331 cycles against 453), DRAM
        // row hits came out 18 % above AT's, and LT ran 8.7 % fast (now -1.8 % on that frame; over
        // five L2 latencies the bias went from -10.0 % to -7.7 %, docs/accuracy.md). The cost:
        // 20-40 % more wall time (the units are stepped once per busy cycle, not once per window).
        const size_t n = rt_.size();
        for (;;) {
            uint64_t c = ~0ull;
            for (const auto& u : rt_) c = std::min(c, u->lt_next());
            if (c >= end) break;
            const size_t first_unit = size_t(c % n);
            for (size_t i = 0; i < n; ++i) rt_[(first_unit + i) % n]->lt_run(c + 1);
        }
    }
}

bool RtComplex::idle() const {
    for (const auto& u : rt_)
        if (!u->core().idle()) return false;
    return true;
}

void RtComplex::start_job() {
    if (!idle()) throw std::logic_error(std::string(name()) + ": a job started while the RT units were busy");
    const bool new_epoch = !started_;
    if (!started_) {
        // The clocks start here: the first job runs as rtsim's frame runs from time 0.
        core_.set_epoch(sc_time_stamp());
        mem_.set_epoch(sc_time_stamp());
        started_ = true;
    } else {
        // The caches' tags are image offsets: another image at the same offsets must not hit
        // on the last job's lines.
        for (const auto& c : l1_) c->invalidate();
        for (const auto& c : l2_) c->invalidate();
    }
    for (const auto& u : rt_) u->wake(new_epoch);
    work_.notify(SC_ZERO_TIME);
}

void RtComplex::set_shader_reads(const ShaderReads& reads) {
    for (size_t s = 0; s < rt_.size(); ++s)
        rt_[s]->set_shader_reads(reads, [l1 = l1_[s].get()](uint64_t addr, uint64_t cycle) { return l1->shader_read(addr, cycle); });
}

void RtComplex::warm(uint32_t sm, uint64_t addr) {
    if (!l1_[sm]->warm(addr)) l2_[xbar_->slice_of(addr)]->warm(addr);
}

}  // namespace rtu
