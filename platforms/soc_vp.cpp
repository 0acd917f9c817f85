// rtu-soc-vp: a minimal SoC virtual platform around the RT-unit peripheral, and the check that
// it works as firmware would use it (docs/peripheral.md).
//
//   cpu (scripted bus master) --+-- router -- 0x1000_0000 + 4 KiB : rtu.regs
//   rtu.mem --------------------+          -- 0x8000_0000 + 64 MiB: ram
//   rtu.irq -> sc_signal "rtu_irq" -> cpu.irq
//
// The script loads a BVH image at a deliberately odd 64-byte-aligned address, runs a job in
// register mode and a chain of two descriptors, waits for the interrupt each time, checks every
// hit record bit for bit against the functional reference (and against golden hits when given),
// checks an error path, and prints "N passed, M failed" (exit status 1 if any failed).
//
// usage: rtu-soc-vp [--fidelity functional|interval|lt|at] [--memory private|shared] [--data PREFIX] [--quantum NS]
//                   [--ram-syncs]
//   --memory shared  the unit's L2 misses are reads on this platform's RAM (lt and at only)
//   --quantum NS     the platform's global quantum (TLM-2.0; default 0, none)
//   --ram-syncs      the RAM waits an initiator's time offset out inside b_transport once it
//                    reaches the global quantum, as a quantum keeper would
//   --data PREFIX  PREFIX.rtubvh, PREFIX.rays and PREFIX.hits, as rtsim --dump-bvh, --dump-rays and
//                  --dump-hits write them (default: cornell's, 16x16 camera rays, made at build
//                  time or installed with the package). The platform adds an any-hit copy of
//                  every fifth ray and an invalid ray, which only the functional reference covers.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <systemc>

#include <rtunit/job.h>
#include <rtunit/peripheral.h>
#include <rtunit/rtu_regs.h>

#include "soc_vp.h"

#ifndef RTU_SOC_VP_DATA
#error "RTU_SOC_VP_DATA: the default inputs' path prefix (the build defines it)"
#endif

namespace {

using namespace sc_core;
using namespace rtu;

constexpr uint64_t kRegs = 0x10000000, kRam = 0x80000000, kRamBytes = 64ull << 20;
constexpr uint64_t kBvh = 0x81234040;  // 64 B aligned, no power of two: the image is relocatable
constexpr uint64_t kDesc = 0x80010000, kHits2 = 0x83000000, kBadDesc = 0x80020000, kBadHits = 0x83800000;

struct Data {
    std::vector<uint8_t> bvh;
    std::vector<rtu_ray> rays;
    std::vector<rtu_hit> golden;  // of the rays as loaded (before add_edge_rays)
};

std::vector<uint8_t> read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(path + ": cannot read");
    return {std::istreambuf_iterator<char>(in), {}};
}

template <class T>
std::vector<T> read_records(const std::string& path) {
    const std::vector<uint8_t> b = read_bytes(path);
    if (b.size() % sizeof(T)) throw std::runtime_error(path + ": " + std::to_string(b.size()) + " bytes is not a whole number of " + std::to_string(sizeof(T)) + "-byte records");
    std::vector<T> v(b.size() / sizeof(T));
    std::memcpy(v.data(), b.data(), b.size());
    return v;
}

// The any-hit and invalid rays appended to the loaded ones.
void add_edge_rays(Data& d) {
    const size_t n = d.rays.size();
    for (size_t i = 4; i < n; i += 5) {
        rtu_ray r = d.rays[i];
        r.flags = RTU_RAY_ANY_HIT;
        r.user = uint32_t(d.rays.size());
        d.rays.push_back(r);
    }
    rtu_ray bad = d.rays[0];
    bad.org[1] = std::nanf("");  // answered as a miss with INVALID_RAY
    bad.user = uint32_t(d.rays.size());
    d.rays.push_back(bad);
}

struct Checks {
    int passed = 0, failed = 0;
    void operator()(bool ok, const std::string& what) {
        ++(ok ? passed : failed);
        std::cout << (ok ? "pass: " : "FAIL: ") << what << "\n";
    }
};

size_t differing(const uint8_t* got, const std::vector<rtu_hit>& want) {
    size_t n = 0;
    for (size_t i = 0; i < want.size(); ++i) n += std::memcmp(got + i * sizeof(rtu_hit), &want[i], sizeof(rtu_hit)) != 0;
    return n;
}

}  // namespace

int sc_main(int argc, char** argv) {
    std::string fidelity = "lt", memory = "private", data = RTU_SOC_VP_DATA;
    double quantum_ns = 0.0;
    bool ram_syncs = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if ((a == "--fidelity" || a == "--memory" || a == "--data") && i + 1 < argc) {
            (a == "--fidelity" ? fidelity : a == "--memory" ? memory : data) = argv[++i];
        } else if (a == "--ram-syncs") {
            ram_syncs = true;
        } else if (a == "--quantum" && i + 1 < argc) {
            char* end = nullptr;
            quantum_ns = std::strtod(argv[++i], &end);
            if (!end || *end || !(quantum_ns >= 0.0 && quantum_ns <= 1e9)) {
                std::cerr << "error: --quantum " << argv[i] << ": a number of nanoseconds from 0 to 1e9 is allowed\n";
                return 2;
            }
        } else {
            std::cerr << "usage: rtu-soc-vp [--fidelity functional|interval|lt|at] [--memory private|shared] [--data PREFIX] [--quantum NS] "
                         "[--ram-syncs]\n";
            return 2;
        }
    }
    // The RT complex's clocks are exact to 1 fs at this resolution (docs/peripheral.md).
    sc_set_time_resolution(1, SC_FS);
    // The platform's global quantum (--quantum; 0: SystemC's default, none): an LT initiator syncs
    // at least that often.
    tlm::tlm_global_quantum::instance().set(sc_time(quantum_ns, SC_NS));
    Data d;
    try {
        d = Data{read_bytes(data + ".rtubvh"), read_records<rtu_ray>(data + ".rays"), read_records<rtu_hit>(data + ".hits")};
        if (d.golden.size() != d.rays.size() || d.rays.empty()) throw std::runtime_error(data + ".hits: not one record per ray of " + data + ".rays");
        add_edge_rays(d);
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 2;
    }
    const uint64_t rays_at = (kBvh + d.bvh.size() + 255) / 256 * 256, hits_at = (rays_at + d.rays.size() * sizeof(rtu_ray) + 4095) / 4096 * 4096;
    if (hits_at + d.rays.size() * sizeof(rtu_hit) > kHits2) {
        std::cerr << "error: the inputs need more than the platform's RAM holds\n";
        return 2;
    }

    PeripheralConfig cfg;
    std::unique_ptr<RtUnitPeripheral> rtu_ptr;
    try {
        cfg.set("fidelity=" + fidelity);
        cfg.set("memory=" + memory);
        rtu_ptr = std::make_unique<RtUnitPeripheral>("rtu", cfg);
    } catch (const std::invalid_argument& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 2;
    }
    RtUnitPeripheral& rtu = *rtu_ptr;
    vp::Cpu cpu("cpu");
    vp::Router bus("bus");
    vp::Ram ram("ram", kRam, kRamBytes);
    ram.sync_at_quantum = ram_syncs;
    sc_signal<bool> irq("rtu_irq");
    cpu.bus.bind(bus.in);
    rtu.mem.bind(bus.in);
    bus.map(kRegs, RTU_APERTURE_BYTES);
    bus.out.bind(rtu.regs);
    bus.map(kRam, kRamBytes);
    bus.out.bind(ram.in);
    rtu.irq.bind(irq);
    cpu.irq.bind(irq);
    cpu.reg_base = kRegs;

    // The golden hits of the functional reference, which refuses an image the peripheral would
    // refuse too (its BAD_BVH error): bad input, said as such, not an exception out of sc_main.
    std::vector<rtu_hit> want;
    try {
        want = reference_hits(d.bvh.data(), d.bvh.size(), reinterpret_cast<const uint8_t*>(d.rays.data()), uint32_t(d.rays.size()));
    } catch (const std::exception& e) {
        std::cerr << "error: " << data << ".rtubvh: " << e.what() << "\n";
        return 2;
    }
    const size_t n = d.rays.size(), half = n / 2;
    Checks check;
    cpu.script = [&] {
        // 1. The loader: image, rays, hit buffers filled with 0xA5, in zero time.
        cpu.load(kBvh, d.bvh.data(), d.bvh.size());
        cpu.load(rays_at, d.rays.data(), n * sizeof(rtu_ray));
        const std::vector<uint8_t> fill(n * sizeof(rtu_hit), 0xA5);
        for (uint64_t at : {hits_at, kHits2, kBadHits}) cpu.load(at, fill.data(), fill.size());
        // 2. Identify the unit; enable every interrupt.
        check(cpu.rd(RTU_ID) == RTU_ID_VALUE && cpu.rd(RTU_VERSION) == RTU_VERSION_VALUE, "ID and VERSION");
        cpu.wr(RTU_INT_ENABLE, RTU_INT_ALL);
        // 3. Register mode.
        cpu.wr64(RTU_BVH_BASE_LO, kBvh);
        cpu.wr64(RTU_BVH_SIZE_LO, d.bvh.size());
        cpu.wr64(RTU_RAY_BASE_LO, rays_at);
        cpu.wr(RTU_RAY_COUNT, uint32_t(n));
        cpu.wr64(RTU_HIT_BASE_LO, hits_at);
        cpu.wr(RTU_CTRL, RTU_CTRL_START);
        const sc_time t0 = sc_time_stamp();
        // 4. The interrupt, not polling; write-1-to-clear drops the line.
        check(cpu.wait_irq(), "register-mode job raises the interrupt");
        const sc_time t_irq = sc_time_stamp();
        const uint32_t st = cpu.rd(RTU_INT_STATUS);
        check(st == RTU_INT_JOB_DONE, "INT_STATUS is JOB_DONE");
        cpu.wr(RTU_INT_STATUS, st);
        wait(SC_ZERO_TIME);
        check(!irq.read(), "the line is low after write-1-to-clear");
        const uint64_t cycles = cpu.rd64(RTU_PERF_JOB_CYCLES);
        std::cout << "register-mode job: " << cycles << " cycles, " << cpu.rd64(RTU_PERF_TRAVERSAL_CYCLES) << " traversal cycles\n";
        const double period = 1e-6 / 1365.0;  // the presets' core clock, 1365 MHz
        check(std::fabs((t_irq - t0).to_seconds() - double(cycles) * period) <= period, "the interrupt comes after PERF_JOB_CYCLES core cycles");
        // 5. Every hit record, bit for bit.
        std::vector<uint8_t> got(n * sizeof(rtu_hit));
        cpu.fetch(hits_at, got.data(), got.size());
        check(differing(got.data(), want) == 0, std::to_string(n) + " hit records equal the functional reference");
        check(differing(got.data(), d.golden) == 0, "the first " + std::to_string(d.golden.size()) + " hit records equal the golden hits file");
        check(cpu.rd64(RTU_PERF_RAYS) == n, "PERF_RAYS counts every ray");
        // 6. Two descriptors chained; the second asks for JOB_DONE.
        rtu_job_desc d0{}, d1{};
        d0.magic = d1.magic = RTU_DESC_MAGIC;
        d0.bvh_base = d1.bvh_base = kBvh;
        d0.bvh_size = d1.bvh_size = d.bvh.size();
        d0.ray_base = rays_at;
        d0.ray_count = uint32_t(half);
        d0.hit_base = kHits2;
        d0.job_id = 1;
        d0.next = kDesc + 128;
        d1.ray_base = rays_at + half * sizeof(rtu_ray);
        d1.ray_count = uint32_t(n - half);
        d1.hit_base = kHits2 + half * sizeof(rtu_hit);
        d1.flags = RTU_JOB_IRQ_ON_DONE;
        d1.job_id = 2;
        cpu.load(kDesc, &d0, sizeof d0);
        cpu.load(kDesc + 128, &d1, sizeof d1);
        cpu.wr64(RTU_DESC_ADDR_LO, kDesc);
        cpu.wr(RTU_CTRL, RTU_CTRL_MODE_CHAIN | RTU_CTRL_START);
        check(cpu.wait_irq(), "descriptor chain raises the interrupt");
        std::cout << "descriptor chain's last job: " << cpu.rd64(RTU_PERF_JOB_CYCLES) << " cycles\n";
        const uint32_t cst = cpu.rd(RTU_INT_STATUS);
        check(cst == (RTU_INT_JOB_DONE | RTU_INT_CHAIN_DONE), "INT_STATUS is JOB_DONE | CHAIN_DONE");
        cpu.wr(RTU_INT_STATUS, cst);
        rtu_job_desc r0, r1;
        cpu.fetch(kDesc, &r0, sizeof r0);
        cpu.fetch(kDesc + 128, &r1, sizeof r1);
        check(r0.status == RTU_DESC_STATUS_DONE && r1.status == RTU_DESC_STATUS_DONE, "both completion records say DONE");
        check(r0.rays == half && r1.rays == n - half && r0.start_ps < r1.start_ps, "completion records: rays, in order");
        cpu.fetch(kHits2, got.data(), got.size());
        check(differing(got.data(), want) == 0, "the chain's hit records equal the functional reference");
        // 7. A descriptor with a wrong magic: ERROR, its code and address, no hit written.
        rtu_job_desc bad = d0;
        bad.magic = 0x4B4F4F42;
        bad.hit_base = kBadHits;
        bad.next = 0;
        cpu.load(kBadDesc, &bad, sizeof bad);
        cpu.wr64(RTU_DESC_ADDR_LO, kBadDesc);
        cpu.wr(RTU_CTRL, RTU_CTRL_MODE_CHAIN | RTU_CTRL_START);
        check(cpu.wait_irq(), "a bad descriptor raises the interrupt");
        check(cpu.rd(RTU_INT_STATUS) == RTU_INT_ERROR, "INT_STATUS is ERROR");
        check(cpu.rd(RTU_ERR_CODE) == RTU_ERR_BAD_DESC_MAGIC && cpu.rd64(RTU_ERR_ADDR_LO) == kBadDesc, "ERR_CODE BAD_DESC_MAGIC at the descriptor");
        cpu.fetch(kBadHits, got.data(), got.size());
        check(std::equal(got.begin(), got.end(), fill.begin()), "no hit written for the bad descriptor");
        cpu.wr(RTU_INT_STATUS, RTU_INT_ALL);
        check(cpu.ok, "every register access answered OK");
    };
    sc_start();
    check(cpu.finished, "the script ran to its end and sc_start() returned");
    std::cout << check.passed << " passed, " << check.failed << " failed\n";
    return check.failed ? 1 : 0;
}
