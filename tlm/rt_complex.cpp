#include "rt_complex.h"

#include <string>

namespace rtu {

using namespace sc_core;

RtComplex::RtComplex(sc_module_name name, const HwConfig& cfg, const BvhImage& image, TraversalOrder order, TraceSource& source,
                     Fidelity fidelity, const Treelets* treelets, bool check_protocol)
    : sc_module(name), core_(cfg.core_mhz), mem_(cfg.memory_mhz) {
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
    // the L2 slices): the kernel runs same-time processes in the order they were made, and the
    // statistics are bit-identical to those of the platform this module was factored out of.
    for (uint32_t s = 0; s < cfg.sms; ++s) {
        const std::string id = std::to_string(s);
        rt_.emplace_back(new RtUnit(("rt_unit_" + id).c_str(), s, cfg, image, order, source, pool_, core_, fidelity, treelets));
        l1_.emplace_back(new Cache(("l1_" + id).c_str(), CacheRole::L1, cfg.l1, cfg.l1_hit_latency, pool_, core_, fidelity));
        link(rt_[s]->socket, l1_[s]->in, "rt_unit_" + id + "_l1_" + id);
    }
    xbar_.reset(new Crossbar("crossbar", cfg.address_map(), cfg.l2_slices, cfg.xbar_latency, core_, fidelity));
    for (uint32_t s = 0; s < cfg.sms; ++s) link(l1_[s]->out, xbar_->in, "l1_" + std::to_string(s) + "_crossbar");
    dram_.reset(new Dram("dram", cfg.dram, cfg.address_map(), mem_, core_.period(), fidelity));
    for (uint32_t s = 0; s < cfg.l2_slices; ++s) {
        const std::string id = std::to_string(s);
        l2_.emplace_back(new Cache(("l2_" + id).c_str(), CacheRole::L2, cfg.l2, cfg.l2.latency, pool_, core_, fidelity));
        link(xbar_->out, l2_[s]->in, "crossbar_l2_" + id);
        link(l2_[s]->out, dram_->in, "l2_" + id + "_dram");
    }
}

RtComplex::~RtComplex() = default;

void RtComplex::warm(uint32_t sm, uint64_t addr) {
    if (!l1_[sm]->warm(addr)) l2_[xbar_->slice_of(addr)]->warm(addr);
}

}  // namespace rtu
