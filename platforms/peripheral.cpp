// rtu::RtUnitPeripheral (include/rtunit/peripheral.h): the register block (tlm/rtu_registers.h),
// the job engine (one SC_THREAD: descriptors, DMA over `mem`, the RT complex through the job
// feeder), and the interrupt line (one SC_METHOD, its only writer).
#include <rtunit/peripheral.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <stdexcept>
#include <utility>

#include "fidelity_run.h"
#include "job_feeder.h"
#include "model/interval_gpu.h"
#include "model/config.h"
#include "model/job_records.h"
#include "model/node_format.h"
#include "model/prefetcher.h"
#include "tlm/rt_complex.h"
#include "tlm/rtu_registers.h"
#include "workloads/rays.h"

namespace rtu {

using namespace sc_core;

namespace {
// The number `v` of option `k`, within [lo, hi]; otherwise std::invalid_argument saying `allowed`.
double number_in(const std::string& k, const std::string& v, double lo, double hi, const char* allowed) {
    size_t used = 0;
    double x = std::nan("");
    try {
        x = std::stod(v, &used);
    } catch (const std::exception&) {
    }
    if (used != v.size() || !(x >= lo && x <= hi)) throw std::invalid_argument("peripheral option " + k + "='" + v + "': " + allowed);
    return x;
}
}  // namespace

void PeripheralConfig::set(const std::string& kv) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw std::invalid_argument("peripheral option '" + kv + "': expected key=value");
    const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
    if (k == "fidelity") fidelity = v;
    else if (k == "traversal") traversal = v;
    else if (k == "config") config = v;
    else if (k == "memory") memory = v;
    else if (k == "use_dmi" || k == "check_bvh") {
        if (v != "0" && v != "1" && v != "true" && v != "false") throw std::invalid_argument("peripheral option " + k + "='" + v + "': 0, 1, true or false");
        (k == "use_dmi" ? use_dmi : check_bvh) = v == "1" || v == "true";
    }
    else if (k == "reg_latency_ns") reg_latency = sc_time(number_in(k, v, 0, 1e9, "a number of ns in [0, 1e9)"), SC_NS);
    else if (k == "core_clock_period_ps") core_clock_period = sc_time(number_in(k, v, 10, 1e6, "a number of ps in [10, 1e6]"), SC_PS);
    else sets.push_back(kv);
}

namespace {

using Job = JobSpec;  // as software gave it (model/job_records.h)

// What ends a job early: an error code and the system address it concerns.
struct JobError {
    uint32_t code;
    uint64_t addr;
};


// What one job did, for the completion record and the counters.
struct JobResult {
    uint64_t rays = 0, hits = 0, invalid = 0, nodes_visited = 0;
    uint64_t traversal_cycles = 0;
    uint64_t node_fetches = 0, l1_accesses = 0, l1_misses = 0, l2_accesses = 0, l2_misses = 0, dram_reads = 0;
    uint64_t prefetches_sent = 0, prefetches_useful = 0;
};

// The counters that add up over jobs, and what each counts.
constexpr std::pair<uint32_t, uint64_t JobResult::*> kCounted[] = {
    {RTU_PERF_RAYS, &JobResult::rays},
    {RTU_PERF_HITS, &JobResult::hits},
    {RTU_PERF_INVALID_RAYS, &JobResult::invalid},
    {RTU_PERF_NODES_VISITED, &JobResult::nodes_visited},
    {RTU_PERF_NODE_FETCHES, &JobResult::node_fetches},
    {RTU_PERF_L1_ACCESSES, &JobResult::l1_accesses},
    {RTU_PERF_L1_MISSES, &JobResult::l1_misses},
    {RTU_PERF_L2_ACCESSES, &JobResult::l2_accesses},
    {RTU_PERF_L2_MISSES, &JobResult::l2_misses},
    {RTU_PERF_DRAM_READS, &JobResult::dram_reads},
    {RTU_PERF_PREFETCHES_SENT, &JobResult::prefetches_sent},
    {RTU_PERF_PREFETCHES_USEFUL, &JobResult::prefetches_useful},
};

// The counters of a timing model's RT units, L1s, L2 slices and DRAM channels, summed.
JobResult totals(const std::vector<RtUnitStats>& rt, const std::vector<CacheCounts>& l1, const std::vector<CacheCounts>& l2,
                 const std::vector<DramStats>& dram) {
    JobResult r;
    for (const RtUnitStats& u : rt) {
        r.node_fetches += u.node_fetches;
        r.prefetches_sent += u.prefetch_queue.sent;
    }
    auto caches = [](const std::vector<CacheCounts>& cs, uint64_t& acc, uint64_t& miss, uint64_t* useful) {
        for (const CacheCounts& k : cs) {
            acc += k.demand.accesses + k.prefetch.accesses;
            miss += k.demand.sector_misses + k.demand.line_misses + k.prefetch.sector_misses + k.prefetch.line_misses;
            if (useful) *useful += k.prefetched.useful;
        }
    };
    caches(l1, r.l1_accesses, r.l1_misses, &r.prefetches_useful);
    caches(l2, r.l2_accesses, r.l2_misses, nullptr);
    for (const DramStats& d : dram) r.dram_reads += d.reads;
    return r;
}

// The RT complex's counters so far (they add up over jobs: a job's are a difference).
JobResult complex_totals(const RtComplex& gpu) {
    std::vector<RtUnitStats> rt;
    std::vector<CacheCounts> l1, l2;
    for (const auto& u : gpu.rt_units()) rt.push_back(u->core().stats());
    for (const auto& c : gpu.l1()) l1.push_back(c->tags().counts());
    for (const auto& c : gpu.l2()) l2.push_back(c->tags().counts());
    if (const MemBridge* b = gpu.bridge()) {  // the shared path: its reads on `mem` are the DRAM's
        JobResult r = totals(rt, l1, l2, {});
        r.dram_reads = b->reads();
        return r;
    }
    return totals(rt, l1, l2, gpu.dram().stats());
}

// The timing model's part of a job's counters: differences of the RT complex's, or the interval
// run's own.
constexpr uint64_t JobResult::*kModelCounters[] = {&JobResult::node_fetches, &JobResult::l1_accesses, &JobResult::l1_misses,
                                                   &JobResult::l2_accesses, &JobResult::l2_misses, &JobResult::dram_reads,
                                                   &JobResult::prefetches_sent, &JobResult::prefetches_useful};

HwConfig resolve_config(const PeripheralConfig& pc, TraversalOrder order) {
    try {
        Config c = Config::load(pc.config);
        for (const std::string& s : pc.sets) c.set(s);
        if (pc.core_clock_period != SC_ZERO_TIME) {
            // The platform's period, as the clock's MHz: ClockDomain rounds 1e9 / MHz fs to the
            // resolution's ticks, which gives the period's own ticks back (the quotient's relative
            // rounding error, about 1e-16, is far below half a tick in 1e6 ps).
            const double ps = pc.core_clock_period / sc_time(1, SC_PS);
            for (const std::string& s : pc.sets)
                if (s.rfind("gpu.core_clock_mhz=", 0) == 0)
                    throw std::invalid_argument("peripheral core_clock_period and " + s + ": give the core clock once");
            if (!(ps >= 10 && ps <= 1e6))
                throw std::invalid_argument("peripheral core_clock_period " + pc.core_clock_period.to_string() + ": allowed is 10 ps to 1 us");
            char mhz[64];
            std::snprintf(mhz, sizeof mhz, "gpu.core_clock_mhz=%.17g", 1e6 / ps);
            c.set(mhz);
        }
        HwConfig hw = c.resolve();
        check_prefetcher(hw.prefetch, order);
        return hw;
    } catch (const ConfigError& e) {
        throw std::invalid_argument(e.what());
    }
}

TraversalOrder parse_order(const std::string& t) {
    if (t == "dfs") return TraversalOrder::DFS;
    if (t == "bfs") return TraversalOrder::BFS;
    throw std::invalid_argument("peripheral traversal '" + t + "': allowed are dfs, bfs (treelet traversal needs the image's treelets)");
}

// Whether the memory path is shared (L2 misses on `mem`); checked against the fidelity.
bool parse_memory_path(const std::string& m, Fidelity f) {
    if (m != "private" && m != "shared") throw std::invalid_argument("peripheral memory '" + m + "': allowed are private, shared");
    if (m == "shared" && f != Fidelity::LT && f != Fidelity::AT)
        throw std::invalid_argument(std::string("peripheral memory=shared needs fidelity lt or at: ") +
                                    (f == Fidelity::Functional ? "the functional fidelity has no memory system"
                                                               : "the interval fidelity runs a job without the SystemC kernel, so its misses cannot wait for the SoC's memory"));
    return m == "shared";
}

uint32_t fidelity_code(Fidelity f) {
    switch (f) {
        case Fidelity::Functional: return RTU_FIDELITY_FUNCTIONAL;
        case Fidelity::Interval: return RTU_FIDELITY_INTERVAL;
        case Fidelity::LT: return RTU_FIDELITY_LT;
        case Fidelity::AT: return RTU_FIDELITY_AT;
    }
    return 0;
}

}  // namespace

// The shared memory path's reads (tlm/mem_bridge.h): an L2 miss at image offset `offset` becomes
// a read on `mem` at the job's BVH base plus the offset, clipped to the image (a line may run past
// its end; those bytes are not the job's to read). A non-OK response or, with CHECK_BVH, bytes
// that differ from the image the job traverses are the job's error, reported when its rays are
// traced. Called from the RT complex's processes: the LT thread, or the bridge's thread in AT.
class SharedMemory : public LineReader {
public:
    SharedMemory(tlm_utils::simple_initiator_socket<RtUnitPeripheral, 32>& socket, RtuRegisters& regs) : socket_(socket), regs_(regs) {}
    // The job whose image the RT complex traverses from now on; its first error is cleared.
    void begin_job(uint64_t bvh_base, const BvhImage& image, bool check_bvh) {
        base_ = bvh_base;
        image_ = &image;
        check_ = check_bvh;
        error_code_ = 0;
        error_addr_ = 0;
    }
    uint32_t error_code() const { return error_code_; }
    uint64_t error_addr() const { return error_addr_; }

    uint32_t read_line(uint64_t offset, uint32_t bytes, sc_time& delay) override {
        if (!image_ || offset >= image_->size()) return 0;  // nothing of the image there: no read
        const uint32_t n = uint32_t(std::min<uint64_t>(bytes, image_->size() - offset));
        buf_.resize(n);
        tlm::tlm_generic_payload t;
        t.set_command(tlm::TLM_READ_COMMAND);
        t.set_address(base_ + offset);
        t.set_data_ptr(buf_.data());
        t.set_data_length(n);
        t.set_streaming_width(n);
        t.set_byte_enable_ptr(nullptr);
        t.set_dmi_allowed(false);
        t.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
        socket_->b_transport(t, delay);
        regs_.count(RTU_PERF_MEM_BYTES_RD, n);
        if (error_code_) return n;  // the job's first error stands
        if (!t.is_response_ok()) {
            error_code_ = RTU_ERR_MEM_FAULT;
            error_addr_ = base_ + offset;
        } else if (check_) {
            for (uint32_t i = 0; i < n; ++i)
                if (buf_[i] != image_->data()[offset + i]) {  // the 64 B block of the first changed byte: a node's address
                    error_code_ = RTU_ERR_BVH_CHANGED;
                    error_addr_ = base_ + ((offset + i) & ~uint64_t(63));
                    break;
                }
        }
        return n;
    }

private:
    tlm_utils::simple_initiator_socket<RtUnitPeripheral, 32>& socket_;
    RtuRegisters& regs_;
    uint64_t base_ = 0;
    const BvhImage* image_ = nullptr;
    bool check_ = false;
    uint32_t error_code_ = 0;
    uint64_t error_addr_ = 0;
    std::vector<uint8_t> buf_;
};

struct RtUnitPeripheral::Impl {
    PeripheralConfig pc;
    TraversalOrder order;
    HwConfig hw;
    Fidelity fidelity;
    RtuRegisters regs;
    BvhImage image;  // the current job's snapshot; the RT complex reads it by reference
    JobFeeder feeder;
    std::unique_ptr<SharedMemory> shared_memory;  // the shared path's reads on `mem` (null: the private path)
    std::unique_ptr<RtComplex> gpu;  // LT, AT
    ClockDomain core;                // functional: the clock the counters count in
    sc_event start, irq_update, abort;
    bool chain = false;  // the accepted START's mode
    bool abort_requested = false;
    bool in_reset = false;       // rst is high: START is ignored
    bool reset_pending = false;  // rst rose during a job: the job engine resets the registers when it ends (a short pulse too)
    std::vector<tlm::tlm_dmi> dmi;  // regions granted on `mem`
    uint64_t desc_addr = 0;
    Job latched;

    // ABORT, and a reset during a job: the job engine ends the job at its next step.
    void request_abort(const sc_time& delay) {
        abort_requested = true;
        feeder.abort();
        abort.notify(delay);
    }

    Impl(const PeripheralConfig& c, TraversalOrder o, const HwConfig& h, Fidelity f, bool sh)
        : pc(c), order(o), hw(h), fidelity(f),
          regs(std::min<uint32_t>(h.sms, 255) | std::min<uint32_t>(h.warp_size, 255) << 8 | std::min<uint32_t>(h.warp_buffer, 255) << 16 |
                   fidelity_code(f) << 24 | (sh ? RTU_MEMORY_SHARED : RTU_MEMORY_PRIVATE) << 28,
               uint32_t(o == TraversalOrder::BFS) | uint32_t(h.prefetch.kind) << 4 | uint32_t(h.core_mhz) << 8),
          core(h.core_mhz) {}
};

RtUnitPeripheral::RtUnitPeripheral(sc_module_name name, const PeripheralConfig& cfg)
    : sc_module(name), regs("regs"), mem("mem"), irq("irq"), rst("rst") {
    const TraversalOrder order = parse_order(cfg.traversal);
    const Fidelity fidelity = parse_fidelity(cfg.fidelity, "peripheral fidelity");
    const bool shared = parse_memory_path(cfg.memory, fidelity);
    impl_.reset(new Impl(cfg, order, resolve_config(cfg, order), fidelity, shared));
    Impl& m = *impl_;
    // The fidelity's engine (platforms/fidelity_run.h): the interval fidelity runs each job on its
    // own, without the kernel; AT and LT on an RT complex elaborated here, inside the platform.
    const Engine engine = engine_of(fidelity);
    if (engine == Engine::Interval) IntervalGpu(m.hw, m.image, order);  // throws for what the fidelity does not model
    if (engine == Engine::SystemC) {
        if (shared) m.shared_memory.reset(new SharedMemory(mem, m.regs));
        m.gpu.reset(new RtComplex("rt_complex", m.hw, m.image, order, m.feeder, fidelity, nullptr, false, m.shared_memory.get()));
        // The private path: nothing outside sees the complex's work before the job's end, so its
        // cycles need not depend on the platform's quantum. The shared path's reads are seen.
        if (!shared) m.gpu->use_own_quantum_only();
        m.feeder.set_clock(m.gpu->core_clock());
    }
    mem.register_invalidate_direct_mem_ptr(this, &RtUnitPeripheral::invalidate_direct_mem_ptr);
    regs.register_b_transport(this, &RtUnitPeripheral::b_transport);
    regs.register_transport_dbg(this, &RtUnitPeripheral::transport_dbg);
    SC_THREAD(run_jobs);
    SC_METHOD(drive_irq);
    sensitive << m.irq_update;
    dont_initialize();
}

RtUnitPeripheral::~RtUnitPeripheral() = default;

void RtUnitPeripheral::end_of_elaboration() {
    if (irq.size()) irq->write(false);  // reset value (no process runs yet: this is the only other write)
    if (rst.size()) {  // an unbound port has no event to be sensitive to
        sc_spawn_options o;
        o.spawn_method();
        o.set_sensitivity(&rst->value_changed_event());
        o.dont_initialize();
        sc_spawn([this] { on_reset(); }, sc_gen_unique_name("on_reset"), &o);
    }
}

void RtUnitPeripheral::on_reset() {
    Impl& m = *impl_;
    m.in_reset = rst->read();
    if (!m.in_reset) return;
    if (m.regs.state.busy) {  // ended like ABORT; the job engine then resets the registers
        m.reset_pending = true;
        m.request_abort(SC_ZERO_TIME);
    } else {
        m.regs.reset();
    }
    m.irq_update.notify(SC_ZERO_TIME);
}

void RtUnitPeripheral::drive_irq() {
    if (irq.size()) irq->write(impl_->regs.irq_level());
}

void RtUnitPeripheral::b_transport(tlm::tlm_generic_payload& t, sc_time& delay) {
    Impl& m = *impl_;
    RtuRegisters::Commands c = m.regs.access(t, uint32_t(t.get_address() & (RTU_APERTURE_BYTES - 1)), false);
    delay += m.pc.reg_latency;  // the register target never waits; its effects come at now + delay
    RtuRegisters::State& s = m.regs.state;
    if (c.soft_reset && !s.busy) {
        m.regs.reset();
        m.irq_update.notify(delay);
    }
    if (c.start && m.in_reset) c.start = false;  // held in reset
    if (c.start) {
        if (s.busy) {
            s.start_ignored = true;
        } else {
            // START latches the job (or the chain's head) and sets BUSY at once, so that a second
            // START before the job begins is ignored too.
            s = RtuRegisters::State{};
            s.busy = true;
            m.abort_requested = false;
            m.chain = m.regs.word(RTU_CTRL) & RTU_CTRL_MODE_CHAIN;
            m.desc_addr = m.regs.pair(RTU_DESC_ADDR_LO);
            Job& j = m.latched;
            j.bvh_base = m.regs.pair(RTU_BVH_BASE_LO);
            j.bvh_size = m.regs.pair(RTU_BVH_SIZE_LO);
            j.ray_base = m.regs.pair(RTU_RAY_BASE_LO);
            j.hit_base = m.regs.pair(RTU_HIT_BASE_LO);
            j.ray_count = m.regs.word(RTU_RAY_COUNT);
            j.ray_stride = job_stride(m.regs.word(RTU_STRIDES) & 0xFFFFu, sizeof(rtu_ray));
            j.hit_stride = job_stride(m.regs.word(RTU_STRIDES) >> 16, sizeof(rtu_hit));
            j.flags = m.regs.word(RTU_JOB_FLAGS);
            j.job_id = m.regs.word(RTU_JOB_ID);
            j.next = 0;
            m.start.notify(delay);
        }
    }
    if (c.abort && s.busy) m.request_abort(delay);  // the job engine ends the job, then sets ABORTED
    if (c.irq_changed) m.irq_update.notify(delay);
}

void RtUnitPeripheral::invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end) {
    auto& d = impl_->dmi;
    d.erase(std::remove_if(d.begin(), d.end(), [&](const tlm::tlm_dmi& r) { return r.get_start_address() <= end && start <= r.get_end_address(); }),
            d.end());
}

unsigned int RtUnitPeripheral::transport_dbg(tlm::tlm_generic_payload& t) {
    impl_->regs.access(t, uint32_t(t.get_address() & (RTU_APERTURE_BYTES - 1)), true);
    return t.is_response_ok() ? t.get_data_length() : 0;
}

namespace {

// The job engine's use of the memory socket: blocking transport from the job thread, each
// access's annotated delay waited out before the next (the thread is the unit's only initiator),
// at most 4 KiB per access. With DMI allowed, a region the target grants (after a transaction
// that says DMI is allowed) is used for the chunks it covers: a copy and the region's latency
// instead of a transaction. Regions are dropped on invalidate_direct_mem_ptr.
class Dma {
public:
    Dma(tlm_utils::simple_initiator_socket<RtUnitPeripheral, 32>& s, RtuRegisters& regs, std::vector<tlm::tlm_dmi>* dmi)
        : socket_(s), regs_(regs), dmi_(dmi) {}
    void read(uint64_t addr, uint8_t* out, uint64_t bytes) { transfer(tlm::TLM_READ_COMMAND, addr, out, bytes); }
    void write(uint64_t addr, const uint8_t* in, uint64_t bytes) { transfer(tlm::TLM_WRITE_COMMAND, addr, const_cast<uint8_t*>(in), bytes); }
    // [addr, addr + bytes) in place, where one granted DMI region covers it for reading (asked for
    // if none is known yet), its latency waited once per 4 KiB as the reads would take; else null.
    const uint8_t* direct_read(uint64_t addr, uint64_t bytes) {
        if (!dmi_) return nullptr;
        if (!region(tlm::TLM_READ_COMMAND, addr, bytes)) request(addr);
        const tlm::tlm_dmi* r = region(tlm::TLM_READ_COMMAND, addr, bytes);
        if (!r) return nullptr;
        for (uint64_t done = 0; done < bytes; done += kChunk) wait(r->get_read_latency());
        regs_.count(RTU_PERF_MEM_BYTES_RD, bytes);
        return r->get_dmi_ptr() + (addr - r->get_start_address());
    }

private:
    static constexpr uint64_t kChunk = 4096;
    const tlm::tlm_dmi* region(tlm::tlm_command cmd, uint64_t addr, uint64_t n) const {
        if (!dmi_) return nullptr;
        for (const tlm::tlm_dmi& r : *dmi_)
            if (addr >= r.get_start_address() && n > 0 && addr + n - 1 <= r.get_end_address() && addr + n - 1 >= addr &&
                (cmd == tlm::TLM_READ_COMMAND ? r.is_read_allowed() : r.is_write_allowed()))
                return &r;
        return nullptr;
    }
    void request(uint64_t addr) {
        tlm::tlm_generic_payload t;
        t.set_command(tlm::TLM_READ_COMMAND);
        t.set_address(addr);
        tlm::tlm_dmi d;
        if (socket_->get_direct_mem_ptr(t, d) && d.get_dmi_ptr()) dmi_->push_back(d);
    }
    void transfer(tlm::tlm_command cmd, uint64_t addr, uint8_t* data, uint64_t bytes) {
        for (uint64_t done = 0; done < bytes;) {
            const uint32_t n = uint32_t(std::min(kChunk, bytes - done));
            if (const tlm::tlm_dmi* r = region(cmd, addr + done, n)) {
                uint8_t* mem = r->get_dmi_ptr() + (addr + done - r->get_start_address());
                if (cmd == tlm::TLM_READ_COMMAND) std::memcpy(data + done, mem, n);
                else std::memcpy(mem, data + done, n);
                wait(cmd == tlm::TLM_READ_COMMAND ? r->get_read_latency() : r->get_write_latency());
            } else {
                tlm::tlm_generic_payload t;
                t.set_command(cmd);
                t.set_address(addr + done);
                t.set_data_ptr(data + done);
                t.set_data_length(n);
                t.set_streaming_width(n);
                t.set_byte_enable_ptr(nullptr);
                t.set_dmi_allowed(false);
                t.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
                sc_time d = SC_ZERO_TIME;
                socket_->b_transport(t, d);
                if (!t.is_response_ok()) throw JobError{RTU_ERR_MEM_FAULT, addr + done};
                wait(d);
                if (dmi_ && t.is_dmi_allowed()) request(addr + done);
            }
            regs_.count(cmd == tlm::TLM_READ_COMMAND ? RTU_PERF_MEM_BYTES_RD : RTU_PERF_MEM_BYTES_WR, n);
            done += n;
        }
    }
    tlm_utils::simple_initiator_socket<RtUnitPeripheral, 32>& socket_;
    RtuRegisters& regs_;
    std::vector<tlm::tlm_dmi>* dmi_;  // granted regions; null: DMI not used
};

// One job: the image and the rays read, checked and traced, the hits written.
class JobRun {
public:
    JobRun(RtUnitPeripheral::Impl& m, Dma& dma) : m_(m), dma_(dma) {}
    JobResult run(const Job& j);

private:
    RtUnitPeripheral::Impl& m_;
    Dma& dma_;
};

}  // namespace

namespace {

void check_job(const Job& j) {
    if (const JobFieldError e = check_job_fields(j); e.code) throw JobError{e.code, e.addr};
}

}  // namespace

JobResult JobRun::run(const Job& j) {
    check_job(j);
    JobResult r;
    const bool check_bvh = (j.flags & RTU_JOB_CHECK_BVH) || m_.pc.check_bvh;
    // The image in place where DMI grants it (software must not change it during the job, the
    // contract of a GPU's acceleration structure), else a copy. CHECK_BVH compares memory with
    // what the job traced, so it always takes a copy.
    try {
        if (const uint8_t* in_place = check_bvh ? nullptr : dma_.direct_read(j.bvh_base, j.bvh_size)) {
            m_.image = BvhImage::view(in_place, j.bvh_size);
        } else {
            std::vector<uint8_t> bytes(j.bvh_size);
            dma_.read(j.bvh_base, bytes.data(), bytes.size());
            m_.image = BvhImage(std::move(bytes));
        }
    } catch (const std::runtime_error&) {
        throw JobError{RTU_ERR_BAD_BVH, j.bvh_base};
    }
    std::vector<rtu_ray> rays(j.ray_count);
    if (j.ray_stride == sizeof(rtu_ray)) {
        dma_.read(j.ray_base, reinterpret_cast<uint8_t*>(rays.data()), uint64_t(j.ray_count) * sizeof(rtu_ray));
    } else {
        for (uint32_t i = 0; i < j.ray_count; ++i) dma_.read(j.ray_base + uint64_t(i) * j.ray_stride, reinterpret_cast<uint8_t*>(&rays[i]), sizeof(rtu_ray));
    }
    // The functional model answers every ray first: it finds a broken image (a node outside it,
    // a cycle) before the timing model runs into it, and its hits are the ones the timing model
    // must reproduce.
    std::vector<rtu_hit> hits(j.ray_count);
    std::map<uint64_t, uint32_t> read_nodes;  // CHECK_BVH, private path: every node the job reads (image offset, bytes)
    std::vector<StackEntry> fetched;
    try {
        for (uint32_t i = 0; i < j.ray_count; ++i) {
            fetched.clear();
            hits[i] = trace_record(m_.image, rays[i], m_.order, check_bvh && !m_.shared_memory ? &fetched : nullptr);
            for (const StackEntry& e : fetched) read_nodes.emplace(e.addr, node_bytes(e.type));
        }
    } catch (const std::out_of_range&) {
        throw JobError{RTU_ERR_BVH_OUT_OF_RANGE, j.bvh_base};
    } catch (const std::exception&) {
        throw JobError{RTU_ERR_BAD_BVH, j.bvh_base};
    }
    for (const rtu_hit& h : hits) {
        r.rays += 1;
        r.hits += (h.status & RTU_HIT_HIT) != 0;
        r.invalid += (h.status & RTU_HIT_INVALID_RAY) != 0;
        r.nodes_visited += h.nodes_visited;
    }
    if (m_.abort_requested) return r;  // ABORT while the inputs were read
    // The timing model: the rays as rtsim reads a ray file, through the same driver.
    std::vector<RayFileEntry> entries(m_.fidelity == Fidelity::Functional ? 0 : j.ray_count);
    for (size_t i = 0; i < entries.size(); ++i) entries[i].ray = ray_of_record(rays[i], entries[i].valid);
    const std::unique_ptr<Workload> workload = make_ray_file_workload(entries);
    std::vector<TracedRay> traced;
    if (engine_of(m_.fidelity) == Engine::Interval) {
        // The whole job at once, without the kernel (a fresh interval GPU: cold caches and DRAM),
        // then the job's simulated time waited out; ABORT ends the wait and the job.
        TimingOptions to;
        to.fidelity = m_.fidelity;
        to.order = m_.order;
        to.keep_rays = true;
        TimingResult t = run_timing(m_.hw, m_.image, *workload, to);
        if (!t.invariant_failures.empty()) throw std::logic_error("interval fidelity: " + t.invariant_failures.front());
        r.traversal_cycles = t.cycles;
        const JobResult model = totals(t.counts.rt, t.counts.l1, t.counts.l2, t.counts.dram);
        for (uint64_t JobResult::*f : kModelCounters) r.*f = model.*f;
        wait(m_.core.period() * double(t.cycles), m_.abort);
        if (m_.abort_requested) return r;
        traced = std::move(t.rays);
    }
    if (m_.gpu) {
        // A job's rays are in memory already: no kernel launch before its first warps.
        ShaderTiming timing = shader_timing(m_.hw, *workload);
        timing.launch = 0;
        auto driver = std::make_unique<WorkloadDriver>(*workload, m_.hw.sms, m_.hw.warp_size, timing);
        driver->keep_rays(true);
        // The last job's prefetches may still be on their way after its last ray retired: this
        // job starts when they are in.
        while (!m_.gpu->idle()) wait(m_.gpu->core_clock().period() * 16.0);
        const JobResult before = complex_totals(*m_.gpu);
        if (m_.shared_memory) m_.shared_memory->begin_job(j.bvh_base, m_.image, check_bvh);
        m_.feeder.start(std::move(driver));
        m_.gpu->start_job();
        const uint64_t first = m_.gpu->core_clock().cycle_at_or_after(sc_time_stamp());
        wait(m_.feeder.done);
        const WorkloadDriver& d = *m_.feeder.driver();
        r.traversal_cycles = d.rays_retired() ? d.last_progress() - first : 0;
        traced = d.results();
        const JobResult after = complex_totals(*m_.gpu);
        for (uint64_t JobResult::*f : kModelCounters) r.*f = after.*f - before.*f;
        if (m_.feeder.aborted()) return r;
        if (m_.shared_memory && m_.shared_memory->error_code())
            throw JobError{m_.shared_memory->error_code(), m_.shared_memory->error_addr()};
    }
    // The timing models traverse with the same code as the functional one: their answers must
    // be the same, bit for bit.
    for (const TracedRay& t : traced) {
        const rtu_hit h = hit_record(t.hit, t.nodes_visited, !t.valid, rays[t.path].user);
        if (std::memcmp(&h, &hits[t.path], sizeof h) != 0)
            throw std::logic_error("ray " + std::to_string(t.path) + ": the timing model's hit differs from the functional model's");
    }
    if (m_.abort_requested) return r;
    // CHECK_BVH: every node the job read, read again through `mem` once the rays are traced and
    // compared with the copy they were traced on. A difference means software changed the image
    // during the job; the job ends with BVH_CHANGED at the node's address and writes no hit. A
    // change is caught whether it came before the node was traversed or after; a node no ray read
    // is not checked. One extra read per node: a checking mode, not a model of hardware. (On the
    // shared path every line the L2 read from `mem` was compared as it came, SharedMemory above:
    // a change is caught where a line is read after it, and no node is read twice.)
    std::vector<uint8_t> now;
    for (const auto& [offset, bytes] : read_nodes) {
        if (m_.abort_requested) return r;
        now.resize(bytes);
        dma_.read(j.bvh_base + offset, now.data(), bytes);
        if (std::memcmp(now.data(), m_.image.data() + offset, bytes) != 0) throw JobError{RTU_ERR_BVH_CHANGED, j.bvh_base + offset};
    }
    if (j.hit_stride == sizeof(rtu_hit)) {
        dma_.write(j.hit_base, reinterpret_cast<const uint8_t*>(hits.data()), uint64_t(j.ray_count) * sizeof(rtu_hit));
    } else {
        for (uint32_t i = 0; i < j.ray_count; ++i) dma_.write(j.hit_base + uint64_t(i) * j.hit_stride, reinterpret_cast<const uint8_t*>(&hits[i]), sizeof(rtu_hit));
    }
    return r;
}

void RtUnitPeripheral::run_jobs() {
    Impl& m = *impl_;
    Dma dma(mem, m.regs, m.pc.use_dmi ? &m.dmi : nullptr);
    JobRun job_run(m, dma);
    for (;;) {
        wait(m.start);
        RtuRegisters::State& s = m.regs.state;
        const sc_time busy_from = sc_time_stamp();
        uint32_t raise = 0;
        uint64_t next = m.chain ? m.desc_addr : 0;
        uint32_t descs = 0;
        try {
            do {
                Job j = m.latched;
                const sc_time job_from = sc_time_stamp();
                uint64_t desc = 0;
                if (m.chain) {
                    if (descs >= m.regs.word(RTU_MAX_CHAIN)) throw JobError{RTU_ERR_CHAIN_LOOP, next};
                    desc = next;
                    if (desc % 64) throw JobError{RTU_ERR_BAD_ALIGN, desc};
                    rtu_job_desc d;
                    dma.read(desc, reinterpret_cast<uint8_t*>(&d), 64);
                    if (d.magic != RTU_DESC_MAGIC) throw JobError{RTU_ERR_BAD_DESC_MAGIC, desc};
                    j = job_of_descriptor(d);
                }
                JobError error{0, 0};
                JobResult r;
                try {
                    r = job_run.run(j);
                } catch (const JobError& e) {
                    if (!m.chain) throw;
                    error = e;
                }
                const uint64_t job_cycles = m.core.cycle_at_or_after(sc_time_stamp() - job_from);
                if (m.reset_pending) break;  // reset: no memory access after the edge, not even the completion record
                if (m.chain) {  // the completion half, then its status word last
                    rtu_job_desc c{};
                    c.rays = uint32_t(std::min<uint64_t>(r.rays, UINT32_MAX));
                    c.job_cycles = job_cycles;
                    c.traversal_cycles = r.traversal_cycles;
                    c.hits = uint32_t(std::min<uint64_t>(r.hits, UINT32_MAX));
                    c.invalid_rays = uint32_t(std::min<uint64_t>(r.invalid, UINT32_MAX));
                    c.nodes_visited = r.nodes_visited;
                    c.node_fetches = r.node_fetches;
                    c.l1_misses = uint32_t(std::min<uint64_t>(r.l1_misses, UINT32_MAX));
                    c.l2_misses = uint32_t(std::min<uint64_t>(r.l2_misses, UINT32_MAX));
                    c.start_ps = uint64_t(job_from.to_seconds() * 1e12 + 0.5);
                    const uint8_t* p = reinterpret_cast<const uint8_t*>(&c);
                    dma.write(desc + 0x44, p + 0x44, 128 - 0x44);
                    c.status = error.code ? RTU_DESC_STATUS_ERROR | error.code : m.abort_requested ? RTU_DESC_STATUS_ABORTED : RTU_DESC_STATUS_DONE;
                    dma.write(desc + 0x40, p + 0x40, 4);
                    if (error.code) throw error;
                }
                m.regs.set_counter(RTU_PERF_JOB_CYCLES, job_cycles);
                m.regs.set_counter(RTU_PERF_TRAVERSAL_CYCLES, r.traversal_cycles);
                for (const auto& [offset, field] : kCounted) m.regs.count(offset, r.*field);
                if (m.abort_requested) break;
                ++descs;
                s.descs_done = descs;
                if (!m.chain || (j.flags & RTU_JOB_IRQ_ON_DONE)) raise |= RTU_INT_JOB_DONE;
                next = j.next;
            } while (m.chain && next != 0);
            if (m.abort_requested) raise |= RTU_INT_ABORTED;
            else if (m.chain) raise |= RTU_INT_CHAIN_DONE;
        } catch (const JobError& e) {
            s.error = true;
            s.err_code = e.code;
            s.err_addr = e.addr;
            raise |= RTU_INT_ERROR;
            // A warning, not SC_REPORT_ERROR: an error's default action throws out of sc_start,
            // and a bad job must not take the platform down (the registers say what went wrong).
            char addr[24];
            std::snprintf(addr, sizeof addr, "0x%llx", static_cast<unsigned long long>(e.addr));
            SC_REPORT_WARNING(name(), ("job failed: error code " + std::to_string(e.code) + " (rtunit/rtu_regs.h RTU_ERR_*) at " + addr).c_str());
        }
        m.regs.count(RTU_PERF_BUSY_CYCLES, m.core.cycle_at_or_after(sc_time_stamp() - busy_from));
        if (m.reset_pending) {  // rst rose during the job: it ends with every register at its reset value
            m.reset_pending = false;
            m.regs.reset();
            m.irq_update.notify(SC_ZERO_TIME);
            continue;
        }
        // Every write of the job has returned: DONE and the interrupt come now, never earlier.
        s.busy = false;
        s.aborted = m.abort_requested && !s.error;
        s.done = !s.error && !s.aborted;
        m.regs.raise(raise);
        m.irq_update.notify(SC_ZERO_TIME);
    }
}

}  // namespace rtu
