// The timing model (AT and LT). SystemC elaborates once per process: every test case here
// builds one platform and runs it once (ctest runs each case in its own process).
#include <gtest/gtest.h>

#include <cstring>

#include <systemc>

#include "platforms/functional_run.h"
#include <map>

#include "platforms/gpu_platform.h"
#include "platforms/fidelity_run.h"
#include "platforms/interval_run.h"
#include "model/interval_gpu.h"
#include "test_util.h"
#include "tlm/fifo_peq.h"
#include "tlm/payload.h"
#include "tlm/protocol_checker.h"
#include "tlm/rt_complex.h"
#include <nlohmann/json.hpp>
#include "workloads/workload_driver.h"

#include <glm/common.hpp>
#include <tlm_utils/peq_with_get.h>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>
#include "workloads/bvh_builder.h"
#include "workloads/scenes.h"

using namespace rtu;

namespace {

struct FsResolution {
    FsResolution() { sc_core::sc_set_time_resolution(1, sc_core::SC_FS); }
};

Scene scene_named(const std::string& name) {
    if (name == "wknd" || name == "cornell") return load_scene(name, "");
    return load_scene(name, rtu::test::shared_dir() + "/scenes/" + name);
}

enum class Model { AT, LT, Interval };

// Every ray a timing run retired (keyed by path and order within its path) got exactly the hit
// the functional model finds on the same workload, and no ray is missing or extra.
void expect_functional_hits(const Scene& scene, const BvhImage& image, WorkloadKind kind, const WorkloadParams& p,
                            const std::vector<TracedRay>& rays, const std::string& what = "") {
    auto fw = make_scene_workload(kind, scene, p);
    const FunctionalResult f = run_functional(scene, image, *fw, FunctionalOptions{}, nullptr);
    std::map<std::pair<uint32_t, uint32_t>, Hit> expected;
    for (size_t i = 0; i < f.rays.size(); ++i) expected[{f.path[i], f.seq[i]}] = f.hits[i];
    ASSERT_EQ(rays.size(), f.rays.size()) << what;
    for (const TracedRay& t : rays) {
        const auto it = expected.find({t.path, t.seq});
        ASSERT_NE(it, expected.end()) << what << " ray " << t.path << "/" << t.seq << " not in the functional run";
        EXPECT_EQ(t.hit.hit, it->second.hit) << what;
        EXPECT_EQ(t.hit.t, it->second.t) << what;
        EXPECT_EQ(t.hit.geom, it->second.geom) << what;
        EXPECT_EQ(t.hit.prim, it->second.prim) << what;
    }
}

// Runs the functional model and the timing model on the same workload and checks that every ray
// (keyed by path and order within its path) got exactly the same hit.
void timing_equals_functional(const std::string& name, Model model, WorkloadKind kind, uint32_t response_fifo = 0) {
    FsResolution resolution;
    const Scene scene = scene_named(name);
    const BvhImage image = build_bvh_image(scene);
    WorkloadParams p;
    p.width = p.height = 24;
    p.seed = 3;
    auto tw = make_scene_workload(kind, scene, p);
    TimingOptions opt;
    opt.fidelity = model == Model::LT ? Fidelity::LT : Fidelity::AT;
    opt.check_protocol = true;
    HwConfig hw = Config::load("mobile").resolve();
    hw.response_fifo = response_fifo;
    TimingResult r;
    if (model == Model::Interval) {
        r = run_interval(hw, image, *tw, opt);
    } else {
        GpuPlatform platform(hw, image, *tw, opt);
        r = platform.run();
    }
    ASSERT_FALSE(r.stuck) << r.stuck_report;
    EXPECT_TRUE(r.invariant_failures.empty()) << r.invariant_failures.front();
    expect_functional_hits(scene, image, kind, p, r.rays);
    EXPECT_GT(r.cycles, 0u);
    if (model == Model::AT) {
        EXPECT_GT(r.protocol_transactions, r.rays.size());
        EXPECT_TRUE(r.protocol_violations.empty()) << r.protocol_violations.front();
    }
    // Cache accounting: L1 sees every chunk request (plus retries), L2 every L1 miss.
    EXPECT_GE(total(r.counts.l1).demand.accesses, total(r.counts.rt).chunk_requests);
    if (response_fifo) {
        EXPECT_EQ(total(r.counts.rt).max_response_fifo, response_fifo);
    }
}

}  // namespace

TEST(TimingAT, BunnyPathTracingHitsEqualFunctional) { RTU_NEED_SHARED_SCENES(); timing_equals_functional("bunny", Model::AT, WorkloadKind::PathTrace); }
TEST(TimingAT, WkndAmbientOcclusionHitsEqualFunctional) { timing_equals_functional("wknd", Model::AT, WorkloadKind::AmbientOcclusion); }
TEST(TimingAT, ShipShadowHitsEqualFunctional) { RTU_NEED_SHARED_SCENES(); timing_equals_functional("ship", Model::AT, WorkloadKind::Shadow); }
// A one-entry response FIFO: a response that finds it full waits in the L1 (BEGIN_RESP accepted,
// END_RESP when the FIFO has drained), within the base protocol, and the answers do not change.
TEST(TimingAT, OneEntryResponseFifoHoldsResponsesBackWithinTheProtocol) {
    timing_equals_functional("cornell", Model::AT, WorkloadKind::PathTrace, 1);
}
TEST(TimingLT, OneEntryResponseFifo) { timing_equals_functional("cornell", Model::LT, WorkloadKind::PathTrace, 1); }
TEST(TimingLT, BunnyPathTracingHitsEqualFunctional) { RTU_NEED_SHARED_SCENES(); timing_equals_functional("bunny", Model::LT, WorkloadKind::PathTrace); }
TEST(TimingLT, CornellPrimaryHitsEqualFunctional) { timing_equals_functional("cornell", Model::LT, WorkloadKind::Primary); }
TEST(TimingInterval, BunnyPathTracingHitsEqualFunctional) { RTU_NEED_SHARED_SCENES(); timing_equals_functional("bunny", Model::Interval, WorkloadKind::PathTrace); }
TEST(TimingInterval, ShipShadowHitsEqualFunctional) { RTU_NEED_SHARED_SCENES(); timing_equals_functional("ship", Model::Interval, WorkloadKind::Shadow); }

namespace {
// One triangle at z = 0, flattened: header [0,64), root internal node [64,128), triangle leaf
// [128,192). The ray reads the header first (its 64 B, then structure latency), then the nodes.
BvhImage one_triangle_image() {
    Scene s;
    s.name = "one-triangle";
    s.materials.push_back(Material{});
    Mesh m;
    m.vertices = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    m.material = {0};
    s.meshes.push_back(m);
    add_identity_instances(s);
    s.flatten = true;  // single-level: no TLAS, no instance leaf, no BLAS header
    BvhImage image = build_bvh_image(s);
    EXPECT_TRUE(image.header().has_headers);
    EXPECT_EQ(image.header().root, 64u);
    EXPECT_EQ(image.size(), 192u);
    return image;
}

// The hand-worked tests' one ray: from z = -5 straight up +z through the triangle's interior.
Ray ray_through_the_triangle() {
    Ray r;
    r.org = {0, 0, -5};
    r.dir = {0, 0, 1};
    return r;
}
// As a ray file; make_ray_file_workload keeps a reference to it, so it must outlive the workload.
std::vector<RayFileEntry> one_ray_file() {
    std::vector<RayFileEntry> rays(1);
    rays[0].ray = ray_through_the_triangle();
    rays[0].valid = true;
    return rays;
}
// The one ray through the AT platform, with the protocol checker on.
TimingResult run_one_ray_at(const HwConfig& hw, const BvhImage& image) {
    const std::vector<RayFileEntry> rays = one_ray_file();
    auto w = make_ray_file_workload(rays);
    TimingOptions opt;
    opt.check_protocol = true;
    GpuPlatform platform(hw, image, *w, opt);
    return platform.run();
}
WarpRay one_warp_ray() {
    WarpRay r;
    r.ray = ray_through_the_triangle();
    r.scale = scale_direction(r.ray);
    return r;
}
}  // namespace

// One ray, one triangle, cold caches, memory clock = core clock (so no rounding between clock
// domains). The image is: header [0,64), root internal node [64,128), triangle leaf [128,192).
// Worked by hand from the mobile preset's latencies:
//   cycle 0    the warp is accepted; the scheduler puts the header's two chunks (0, 32) in the queue
//   cycle 1    chunk 0 leaves: L1 line miss -> L2 slice 0 (line 0) line miss, +160 -> DRAM 161
//              channel 0 bank 0 closed: ACT 161, column 181 (+tRCD), data 201..209 (+tCL, 8 cycles)
//   cycle 2    chunk 32 leaves: L1 and L2 sector misses -> DRAM 162, scheduler waits until the
//              column bus allows (next column 189 - tRCD = 169): row hit, column 189, data 209..217
//   217        the header is drained: structure latency 4 -> 221; the root box is hit
//   221        the root's chunks (64, 96) are queued; they leave at 222 and 223: L1 and L2 sector
//              misses of line 0 -> DRAM 382, row 0 still open: column 382, data 402..410; DRAM
//              383, column 390 (tCCD later), data 410..418
//   418        the root is complete: ray-box 8 -> 426
//   426        the leaf's chunks (128, 160) are queued; they leave at 427 and 428
//   427        line 1: L2 slice 1, DRAM channel 1 at 587: ACT 587, column 607, data 627..635
//   428        DRAM 588, decision at 615 - 20 = 595, row hit, column 615, data 635..643
//   643        leaf complete: descriptor 4 + ray-triangle 8 + hit 8 = 20 -> ray retires at 663
TEST(TimingAT, SingleRayLatencyIsTheHandWorkedSum) {
    FsResolution resolution;
    const BvhImage image = one_triangle_image();
    Config c = Config::load("mobile");
    c.set("gpu.memory_clock_mhz=1365");
    const HwConfig hw = c.resolve();
    const uint64_t L2 = hw.l2.latency, rcd = hw.dram.tRCD, cl = hw.dram.tCL, xfer = 32 / (2 * hw.dram.bus_bytes);
    const uint64_t ccd = std::max<uint64_t>(hw.dram.tCCD, xfer);
    const uint64_t header_a = 1 + L2 + rcd + cl + xfer;                     // 209
    const uint64_t col_a = 1 + L2 + rcd;                                     // 181
    const uint64_t header_b = col_a + ccd + cl + xfer;                       // 217
    const uint64_t header_done = std::max(header_a, header_b) + hw.lat.structure;  // 221
    const uint64_t root_col = header_done + 1 + L2;                          // 382, a row hit
    const uint64_t root_done = root_col + ccd + cl + xfer + hw.lat.ray_box;  // 426
    const uint64_t leaf_a = root_done + 1 + L2 + rcd + cl + xfer;            // 635
    const uint64_t leaf_b = leaf_a + xfer;                                   // 643 (column tCCD/xfer later)
    const uint64_t expected = leaf_b + hw.lat.leaf_descriptor + hw.lat.ray_triangle + hw.lat.triangle_hit;  // 663
    ASSERT_EQ(expected, 663u);

    const TimingResult r = run_one_ray_at(hw, image);
    ASSERT_EQ(r.rays.size(), 1u);
    EXPECT_TRUE(r.rays[0].hit.hit);
    EXPECT_EQ(r.cycles, expected);
    const DramStats dram = total(r.counts.dram);
    EXPECT_EQ(dram.reads, 6u);
    EXPECT_EQ(dram.row_misses, 2u);
    EXPECT_EQ(dram.row_hits, 4u);
    EXPECT_EQ(total(r.counts.l1).demand.line_misses, 2u);
    EXPECT_EQ(total(r.counts.l1).demand.sector_misses, 4u);
    const RtUnitStats rt = total(r.counts.rt);
    EXPECT_EQ(rt.node_fetches, 2u);
    EXPECT_EQ(rt.header_fetches, 1u);
    EXPECT_TRUE(r.protocol_violations.empty()) << r.protocol_violations.front();
}

// The interval fidelity on the same ray (model/interval_gpu.h). Cold, it takes AT's hand-worked
// 663 cycles above: the same request port, drain, L2 and DRAM timing. The same ray again on the
// same SM finds every chunk in its L1: per read (header, root, leaf), the chunks leave one per
// cycle from the cycle after the thread was scheduled, each drains in the cycle after it left,
// then the math runs: (2 + 1 + 4) + (2 + 1 + 8) + (2 + 1 + 20). On another SM (cold L1, warm L2)
// each read's second chunk is back 2 + L2 latency after scheduling. Two threads with the same ray
// share each fetch (coalescing).
TEST(TimingInterval, SingleRayLatenciesAreTheHandWorkedSums) {
    const BvhImage image = one_triangle_image();
    Config c = Config::load("mobile");
    c.set("gpu.memory_clock_mhz=1365");
    const HwConfig hw = c.resolve();
    IntervalGpu gpu(hw, image, TraversalOrder::DFS);
    std::vector<RetiredRay> out;
    // One trace alone, run to its end: the cycle it finishes.
    auto time_trace = [&](uint32_t sm, const std::vector<WarpRay>& rays, uint64_t start) {
        std::vector<IntervalGpu::Finished> done;
        gpu.start_trace(sm, rays, start, done);
        while (done.empty() && gpu.next_event() != ~0ull) gpu.run_next(done);
        EXPECT_EQ(done.size(), 1u);
        EXPECT_EQ(gpu.next_event(), ~0ull);
        if (done.empty()) return uint64_t(0);
        out.insert(out.end(), done[0].rays.begin(), done[0].rays.end());
        return done[0].end;
    };
    const WarpRay r = one_warp_ray();
    const uint64_t header = hw.lat.structure, internal = hw.lat.ray_box, leaf = hw.lat.leaf_descriptor + hw.lat.ray_triangle + hw.lat.triangle_hit;
    EXPECT_EQ(time_trace(0, {r}, 0), 663u);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_TRUE(out[0].hit.hit);
    EXPECT_EQ(out[0].nodes_visited, 2u);  // the header is read, not visited
    EXPECT_EQ(out[0].dram_nodes, 2u);
    const DramStats d = total(gpu.dram_stats());
    EXPECT_EQ(d.reads, 6u);
    EXPECT_EQ(d.row_misses, 2u);
    EXPECT_EQ(d.row_hits, 4u);
    EXPECT_EQ(gpu.l1()[0].tags().stats(ReqKind::Demand).line_misses, 2u);
    EXPECT_EQ(gpu.l1()[0].tags().stats(ReqKind::Demand).sector_misses, 4u);

    EXPECT_EQ(time_trace(0, {r}, 1000), 1000 + (2 + 1 + header) + (2 + 1 + internal) + (2 + 1 + leaf));  // 1041
    EXPECT_EQ(gpu.l1()[0].tags().stats(ReqKind::Demand).hits, 6u);
    EXPECT_EQ(time_trace(1, {r}, 2000), 2000 + (2 + hw.l2.latency + header) + (2 + hw.l2.latency + internal) + (2 + hw.l2.latency + leaf));  // 2518
    EXPECT_EQ(gpu.l2()[0].tags().stats(ReqKind::Demand).hits + gpu.l2()[1].tags().stats(ReqKind::Demand).hits, 6u);
    EXPECT_EQ(time_trace(0, {r, r}, 3000), 3041u);
    EXPECT_EQ(total(gpu.rt_stats()).coalesced_fetches, 3u);
    EXPECT_EQ(total(gpu.dram_stats()).reads, 6u);
    EXPECT_EQ(out.size(), 5u);
}

// The checker itself catches broken sequences (a checker that never fires proves nothing).
TEST(ProtocolChecker, DetectsViolations) {
    FsResolution resolution;
    ProtocolChecker chk("chk");
    PayloadPool pool;
    unsigned char data[32] = {};
    tlm::tlm_generic_payload* a = pool.acquire(0, 32, data);
    tlm::tlm_generic_payload* b = pool.acquire(32, 32, data);
    chk.on_fw(*a, tlm::BEGIN_REQ, tlm::BEGIN_REQ, tlm::TLM_ACCEPTED);
    EXPECT_TRUE(chk.violations().empty());
    chk.on_fw(*b, tlm::BEGIN_REQ, tlm::BEGIN_REQ, tlm::TLM_ACCEPTED);  // request exclusion broken
    ASSERT_EQ(chk.violations().size(), 1u);
    EXPECT_NE(chk.violations()[0].find("request exclusion"), std::string::npos);
    chk.on_bw(*a, tlm::BEGIN_RESP, tlm::BEGIN_RESP, tlm::TLM_ACCEPTED);  // status still incomplete
    EXPECT_NE(chk.violations().back().find("TLM_INCOMPLETE_RESPONSE"), std::string::npos);
    b->set_response_status(tlm::TLM_OK_RESPONSE);
    chk.on_bw(*b, tlm::BEGIN_RESP, tlm::BEGIN_RESP, tlm::TLM_ACCEPTED);  // response exclusion broken
    EXPECT_NE(chk.violations().back().find("response exclusion"), std::string::npos);
    chk.on_fw(*a, tlm::END_REQ, tlm::END_REQ, tlm::TLM_ACCEPTED);        // wrong path for END_REQ
    bool found = false;
    for (const std::string& v : chk.violations()) found |= v.find("forward path carries END_REQ") != std::string::npos;
    EXPECT_TRUE(found);
    a->release();
    b->release();
    EXPECT_EQ(pool.outstanding(), 0u);
}

// The checker's rules of blocking transport, debug transport and DMI, each broken once: by an
// initiator calling from a method process, handing over a status already set and no data; by a
// target leaving the status incomplete and changing the data length; by a DMI grant beside the
// address. A well-behaved exchange through the checker adds nothing.
namespace {
struct BlockingTarget : sc_core::sc_module {
    tlm_utils::simple_target_socket<BlockingTarget> in{"in"};
    unsigned char mem[64] = {};
    explicit BlockingTarget(sc_core::sc_module_name n) : sc_module(n) {
        in.register_b_transport(this, &BlockingTarget::b_transport);
        in.register_transport_dbg(this, &BlockingTarget::transport_dbg);
    }
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& d) {
        std::memcpy(t.get_data_ptr(), mem, t.get_data_length());
        d += sc_core::sc_time(10, sc_core::SC_NS);
        t.set_response_status(tlm::TLM_OK_RESPONSE);
    }
    unsigned transport_dbg(tlm::tlm_generic_payload& t) { return t.get_data_length(); }
};
struct BlockingInitiator : sc_core::sc_module {
    tlm_utils::simple_initiator_socket<BlockingInitiator> out{"out"};
    bool from_method = false;
    SC_HAS_PROCESS(BlockingInitiator);
    explicit BlockingInitiator(sc_core::sc_module_name n) : sc_module(n) {
        SC_THREAD(thread);
        SC_METHOD(method);
    }
    void read(uint64_t addr) {
        unsigned char data[4];
        tlm::tlm_generic_payload t;
        t.set_read();
        t.set_address(addr);
        t.set_data_ptr(data);
        t.set_data_length(4);
        t.set_streaming_width(4);
        t.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
        sc_core::sc_time d = sc_core::SC_ZERO_TIME;
        out->b_transport(t, d);
        EXPECT_TRUE(t.is_response_ok());
        EXPECT_EQ(out->transport_dbg(t), 4u);
    }
    void thread() { read(0); }
    void method() {
        if (from_method) read(4);
    }
};
}  // namespace

TEST(ProtocolChecker, DetectsBlockingTransportViolations) {
    FsResolution resolution;
    BlockingInitiator clean("clean"), wrong("wrong");
    wrong.from_method = true;
    BlockingTarget target_a("target_a"), target_b("target_b");
    ProtocolChecker chk_clean("chk_clean"), chk_wrong("chk_wrong");
    clean.out.bind(chk_clean.in);
    chk_clean.out.bind(target_a.in);
    wrong.out.bind(chk_wrong.in);
    chk_wrong.out.bind(target_b.in);
    sc_core::sc_start();
    EXPECT_EQ(chk_clean.transactions(), 1u);
    EXPECT_TRUE(chk_clean.violations().empty()) << chk_clean.violations().front();
    ASSERT_EQ(chk_wrong.violations().size(), 1u);
    EXPECT_NE(chk_wrong.violations()[0].find("method process"), std::string::npos) << chk_wrong.violations()[0];

    // By hand: an initiator's payload with its status already set and no data pointer; then a
    // target that leaves the status incomplete and shortens the data.
    ProtocolChecker& chk = chk_clean;
    const size_t before = chk.violations().size();
    tlm::tlm_generic_payload t;
    t.set_write();
    t.set_data_length(8);
    t.set_streaming_width(8);
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    const ProtocolChecker::Request r = chk.check_b_request(t);
    ASSERT_EQ(chk.violations().size(), before + 2);
    EXPECT_NE(chk.violations()[before].find("without a data pointer"), std::string::npos);
    EXPECT_NE(chk.violations()[before + 1].find("must be TLM_INCOMPLETE_RESPONSE"), std::string::npos);
    t.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    t.set_data_length(4);
    chk.check_b_response(t, r);
    ASSERT_EQ(chk.violations().size(), before + 4);
    EXPECT_NE(chk.violations()[before + 2].find("returned TLM_INCOMPLETE_RESPONSE"), std::string::npos);
    EXPECT_NE(chk.violations()[before + 3].find("changed the command, data pointer, data length"), std::string::npos);
    // A DMI grant of [0x100, 0x1FF] for a transaction at 0x80.
    unsigned char mem[256];
    tlm::tlm_dmi d;
    d.set_start_address(0x100);
    d.set_end_address(0x1FF);
    d.set_dmi_ptr(mem);
    d.allow_read();
    t.set_address(0x80);
    chk.check_dmi_grant(t, d);
    ASSERT_EQ(chk.violations().size(), before + 5);
    EXPECT_NE(chk.violations()[before + 4].find("does not cover"), std::string::npos);
    t.set_address(0x180);
    chk.check_dmi_grant(t, d);
    EXPECT_EQ(chk.violations().size(), before + 5);
}

// The RT unit tracks its chunks in flight in a ring indexed by chunk id. A response held back
// while more chunks than the ring's 8192 slots leave after it (LT at a quantum of 10,000 did
// this) must neither collide nor be lost: here the very first chunk is answered only after
// 10,000 others, and every ray still gets the hit that functional traversal gives it.
TEST(RtUnitCore, ResponseHeldBackPastTheTrackingRing) {
    RTU_NEED_SHARED_SCENES();
    const Scene s = scene_named("bunny");
    const BvhImage img = build_bvh_image(s);
    const HwConfig hw = Config::load("mobile").resolve();
    RtUnitCore core(hw, img, TraversalOrder::DFS);
    std::vector<Ray> rays;
    for (int i = 0; i < 4096; ++i) {
        Ray r;
        r.org = {278, 278, 800};
        r.dir = glm::vec3(-0.3f + 0.6f * float(i % 64) / 64.0f, -0.3f + 0.6f * float(i / 64) / 64.0f, -1.0f);
        rays.push_back(r);
    }
    size_t next = 0;
    std::map<uint64_t, Hit> got;
    std::multimap<uint64_t, uint64_t> answers;  // cycle -> chunk id
    uint64_t held = 0, sent = 0;
    bool released = false;
    for (uint64_t c = 0; c < 5000000 && (next < rays.size() || !core.idle()); ++c) {
        while (next < rays.size() && core.has_free_slot()) {
            std::vector<WarpRay> warp;
            for (int t = 0; t < 32 && next < rays.size(); ++t, ++next) {
                WarpRay w;
                w.ray = rays[next];
                w.scale = scale_direction(w.ray);
                w.key = next;
                warp.push_back(w);
            }
            core.accept_warp(warp, c);
        }
        for (auto it = answers.begin(); it != answers.end() && it->first <= c; it = answers.erase(it))
            core.on_response(it->second, true, true, c);
        if (held && sent >= 10000 && !released) {  // once, even if no request leaves for some cycles
            answers.insert({c + 1, held});
            released = true;
        }
        if (core.has_request(c)) {
            const ChunkRequest r = core.front_request(c);
            core.pop_request(c);
            ++sent;
            if (!held) held = r.id;
            else answers.insert({c + 20, r.id});
        }
        core.cycle(c);
        for (const RetiredRay& r : core.take_retired()) got[r.key] = r.hit;  // t in the rescaled ray's units
    }
    ASSERT_GT(sent, 10000u);
    ASSERT_TRUE(core.idle());
    ASSERT_EQ(got.size(), rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        Ray scaled = rays[i];
        scale_direction(scaled);
        const TraceResult f = trace_ray(img, scaled, TraversalOrder::DFS);
        ASSERT_EQ(got[i].hit, f.hit.hit) << "ray " << i;
        if (f.hit.hit) {
            EXPECT_EQ(got[i].geom, f.hit.geom) << "ray " << i;
            EXPECT_EQ(got[i].prim, f.hit.prim) << "ray " << i;
            EXPECT_EQ(got[i].t, f.hit.t) << "ray " << i;
        }
    }
}

// rt.merge_in_flight, hand-worked. Two triangles: X, large, at z = 0; Y, small, at z = -1 with its
// box over (0..1, 0..1). Ray A, through Y and ending before z = 0, reads the root then Y. Ray B,
// through Y's box where Y's triangle is not, reads the root, X (its hit: the traversal takes X's
// child first), then Y (entered nearer than the hit, so not culled), while A's read of Y is still
// in flight (its responses are held back here). Merged, B's read of Y joins A's: Y's two chunks
// are requested once, both threads take the one response, and each ray gets the functional
// traversal's hit; without the merge B requests them again (the test's other half, so that it
// can fail).
TEST(RtUnitCore, AReadJoinsTheWarpsReadOfTheSameChunkInFlight) {
    Scene s;
    s.name = "two-triangles";
    s.materials.push_back(Material{});
    Mesh m;
    m.vertices = {{-10, -10, 0}, {20, -10, 0}, {-10, 20, 0}, {0, 0, -1}, {1, 0, -1}, {0, 1, -1}};
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    m.material = {0, 0};
    s.meshes.push_back(m);
    add_identity_instances(s);
    s.flatten = true;
    const BvhImage img = build_bvh_image(s);
    Ray a, b;
    a.org = {0.2f, 0.2f, -5};
    a.tfar = 4.5f;  // short of X
    b.org = {0.9f, 0.9f, -5};
    a.dir = b.dir = {0, 0, 1};
    std::vector<StackEntry> path_a, path_b;
    const TraceResult fa = trace_ray(img, a, TraversalOrder::DFS, nullptr, &path_a);
    const TraceResult fb = trace_ray(img, b, TraversalOrder::DFS, nullptr, &path_b);
    ASSERT_EQ(path_a.size(), 3u);  // header, root, Y
    ASSERT_EQ(path_b.size(), 4u);  // header, root, X, Y
    const uint64_t y = path_a[2].addr;  // Y's leaf: the read both make
    ASSERT_EQ(path_b[3].addr, y);
    ASSERT_NE(path_b[2].addr, y);
    ASSERT_TRUE(fa.hit.hit && fb.hit.hit);
    ASSERT_EQ(fa.hit.prim, 1u);
    ASSERT_EQ(fb.hit.prim, 0u);
    for (const bool merge : {true, false}) {
        Config c = Config::load("mobile");
        c.set(std::string("rt.merge_in_flight=") + (merge ? "true" : "false"));
        const HwConfig hw = c.resolve();
        ASSERT_EQ(chunks_of(NodeType::Triangle), 2u);
        RtUnitCore core(hw, img, TraversalOrder::DFS);
        std::vector<WarpRay> warp(2);
        warp[0].ray = a;
        warp[1].ray = b;
        warp[1].key = 1;
        for (WarpRay& w : warp) w.scale = scale_direction(w.ray);
        core.accept_warp(warp, 0);
        std::multimap<uint64_t, uint64_t> answers;  // cycle -> chunk id
        std::vector<uint64_t> held;
        uint32_t y_requests = 0;
        std::map<uint64_t, Hit> got;
        for (uint64_t cyc = 0; cyc < 10000 && !core.idle(); ++cyc) {
            if (cyc == 500)
                for (uint64_t id : held) answers.insert({cyc, id});
            for (auto it = answers.begin(); it != answers.end() && it->first <= cyc; it = answers.erase(it))
                core.on_response(it->second, true, false, cyc);
            if (core.has_request(cyc)) {
                const ChunkRequest r = core.front_request(cyc);
                core.pop_request(cyc);
                const bool of_y = r.image_addr >= y && r.image_addr < y + 64;
                y_requests += of_y;
                if (of_y && held.size() < 2) held.push_back(r.id);  // A's read of Y waits until cycle 500
                else answers.insert({cyc + 5, r.id});
            }
            core.cycle(cyc);
            for (const RetiredRay& r : core.take_retired()) got[r.key] = r.hit;
        }
        ASSERT_TRUE(core.idle()) << "merge " << merge;
        EXPECT_EQ(y_requests, merge ? 2u : 4u) << "merge " << merge;
        EXPECT_EQ(core.stats().merged_in_flight, merge ? 2u : 0u);
        EXPECT_EQ(core.stats().chunk_requests, merge ? 2u + 2u + 2u + 2u : 2u + 2u + 2u + 4u);  // header, root, X, Y (Y twice unmerged)
        ASSERT_EQ(got.size(), 2u);
        EXPECT_EQ(got[0].prim, fa.hit.prim);
        EXPECT_EQ(got[1].prim, fb.hit.prim);
        EXPECT_TRUE(got[0].hit && got[1].hit);
    }
}

// FifoPeq (tlm/fifo_peq.h) against tlm_utils::peq_with_get, the queue it replaces in the caches
// and the crossbar: two FIFOs sharing an event and a sequence, each with its own fixed latency
// (here hits after 30 ns, fills after 10 ns), must hand out the same payloads at the same times,
// in the same order, as one peq_with_get fed the same schedule. Payloads of the two FIFOs due at
// the same time leave in the order they were queued. A delivery due before the last one queued
// in its FIFO is refused.
namespace {
struct PeqBench : sc_core::sc_module {
    OrderedEvents events{"events"};
    OrderedEvent shared{events, [this] { drain(); }};
    uint64_t seq = 0;
    FifoPeq<int> hits{shared, seq}, fills{shared, seq};
    tlm_utils::peq_with_get<int> ref{"ref"};
    std::vector<std::pair<double, int>> got, want;
    int items[11];
    bool refused = false;
    SC_HAS_PROCESS(PeqBench);
    explicit PeqBench(sc_core::sc_module_name n) : sc_module(n) {
        for (int i = 0; i < 11; ++i) items[i] = i;
        SC_THREAD(feed);
        SC_METHOD(drain_ref);
        sensitive << ref.get_event();
        dont_initialize();
    }
    void both(int i, bool hit) {
        const sc_core::sc_time d(hit ? 30 : 10, sc_core::SC_NS);
        (hit ? hits : fills).notify(items[i], d);
        ref.notify(items[i], d);
    }
    void feed() {
        using sc_core::SC_NS;
        both(0, true);   // due 30
        both(1, false);  // due 10
        sc_core::wait(5, SC_NS);
        both(2, true);   // due 35
        sc_core::wait(15, SC_NS);
        both(3, false);  // due 30: ties with item 0, queued after it
        sc_core::wait(5, SC_NS);
        both(4, false);  // due 35: ties with item 2
        sc_core::wait(5, SC_NS);
        both(5, true);   // due 60
        both(6, false);  // due 40
        sc_core::wait(20, SC_NS);
        both(7, false);  // due 60: ties with item 5
        sc_core::wait(50, SC_NS);
        try {
            hits.notify(items[8], sc_core::sc_time(30, SC_NS));  // due 130
            hits.notify(items[9], sc_core::sc_time(10, SC_NS));  // due 110, before item 8: refused
        } catch (const std::logic_error&) {
            refused = true;
        }
    }
    void drain() {
        while (int* p = FifoPeq<int>::merge_next(hits, fills)) got.push_back({sc_core::sc_time_stamp().to_seconds() * 1e9, *p});
    }
    void drain_ref() {
        while (int* p = ref.get_next_transaction()) want.push_back({sc_core::sc_time_stamp().to_seconds() * 1e9, *p});
    }
};
}  // namespace

TEST(FifoPeq, SameDeliveriesAsPeqWithGet) {
    FsResolution resolution;
    PeqBench bench("bench");
    sc_core::sc_start(sc_core::sc_time(1, sc_core::SC_US));
    // The reference, worked by hand: 10: 1; 30: 0, 3; 35: 2, 4; 40: 6; 60: 5, 7.
    const std::vector<std::pair<double, int>> expected{{10, 1}, {30, 0}, {30, 3}, {35, 2}, {35, 4}, {40, 6}, {60, 5}, {60, 7}};
    ASSERT_EQ(bench.want.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_NEAR(bench.want[i].first, expected[i].first, 1e-6);
        EXPECT_EQ(bench.want[i].second, expected[i].second);
    }
    // The FIFOs also delivered item 8, which the reference never saw.
    ASSERT_EQ(bench.got.size(), expected.size() + 1);
    EXPECT_EQ(bench.got.back().second, 8);
    bench.got.pop_back();
    EXPECT_EQ(bench.got, bench.want);
    EXPECT_TRUE(bench.refused);
}

// OrderedEvents (tlm/ordered_events.h): handlers due at one time run by rank, then in the order
// they were notified; one notified for the current time runs after those of its rank or below
// already due, before those of a higher rank; a pending notification keeps the earlier of two
// times; and a process of the kernel's woken at the same times changes none of it. Worked by hand.
namespace {
struct OrderBench : sc_core::sc_module {
    OrderedEvents events{"events"};
    std::vector<std::string> log;
    std::vector<double> at;
    OrderedEvent a{events, [this] { note("a"); }}, b{events, [this] { note("b"); }, [](uint64_t) { return 2u; }},
        c{events, [this] { note("c"); }, [](uint64_t) { return 1u; }},
        d{events, [this] {
              note("d");
              e.notify(sc_core::SC_ZERO_TIME);  // rank 0, now: before c (rank 1) and b (rank 2)
              a.notify(sc_core::sc_time(5, sc_core::SC_NS));
          }},
        e{events, [this] { note("e"); }}, f{events, [this] { note("f"); }}, g{events, [this] { note("g"); }};
    int ticks = 0;
    SC_HAS_PROCESS(OrderBench);
    explicit OrderBench(sc_core::sc_module_name n) : sc_module(n) {
        SC_THREAD(feed);
        SC_METHOD(foreign);  // the kernel's own timed events at the same times
    }
    void note(const char* what) {
        log.push_back(what);
        at.push_back(sc_core::sc_time_stamp().to_seconds() * 1e9);
    }
    void foreign() {
        if (++ticks < 40) next_trigger(sc_core::sc_time(1, sc_core::SC_NS));
    }
    void feed() {
        using sc_core::SC_NS;
        b.notify(sc_core::sc_time(10, SC_NS));
        c.notify(sc_core::sc_time(10, SC_NS));
        a.notify(sc_core::sc_time(10, SC_NS));
        c.notify(sc_core::sc_time(20, SC_NS));  // later than pending: dropped
        d.notify(sc_core::sc_time(12, SC_NS));
        d.notify(sc_core::sc_time(10, SC_NS));  // earlier: replaces 12
        f.notify(sc_core::sc_time(30, SC_NS));
        g.notify(sc_core::sc_time(25, SC_NS));  // a time between two already due: runs in time order
    }
};
}  // namespace

TEST(OrderedEvents, SameTimeHandlersRunByRankThenNotification) {
    FsResolution resolution;
    OrderBench bench("bench");
    sc_core::sc_start();
    // At 10: rank 0 in notification order (a, d), d's zero-delay e (rank 0) before c (rank 1) and
    // b (rank 2); at 15: a again; g at 25 and f at 30, in time order though notified the other
    // way. Nothing at 12 or 20.
    const std::vector<std::string> want{"a", "d", "e", "c", "b", "a", "g", "f"};
    EXPECT_EQ(bench.log, want);
    const std::vector<double> want_at{10, 10, 10, 10, 10, 15, 25, 30};
    ASSERT_EQ(bench.at.size(), want_at.size());
    for (size_t i = 0; i < want_at.size(); ++i) EXPECT_NEAR(bench.at[i], want_at[i], 1e-6) << i;
    EXPECT_TRUE(bench.events.empty());
}

namespace {
// The ray of the hand-worked test above with rt.leaf_descriptor_read: the leaf is read in two
// dependent steps. Worked by hand (mobile latencies, memory clock = core clock):
//   426        the root is done (as above); the leaf's descriptor chunk (128) is queued
//   427        it leaves: L1 and L2 line misses -> DRAM channel 1 at 587: ACT, column 607, data 627..635
//   635        the descriptor is drained; decoding it takes leaf_descriptor = 4 -> 639
//   639        the leaf's two chunks are queued; 128 leaves at 640 (an L1 hit now), 160 at 641:
//              L1 and L2 sector misses -> DRAM 801, a row hit: column 801, data 821..829
//   829        the leaf is whole: ray-triangle 8 + hit 8 = 16 -> the ray retires at 845
constexpr uint64_t kTwoStepLeafCycles = 845;
HwConfig two_step_config() {
    Config c = Config::load("mobile");
    c.set("gpu.memory_clock_mhz=1365");
    c.set("rt.leaf_descriptor_read=true");
    return c.resolve();
}
}  // namespace

TEST(TimingAT, TwoStepLeafReadIsTheHandWorkedSum) {
    FsResolution resolution;
    const BvhImage image = one_triangle_image();
    const HwConfig hw = two_step_config();
    const uint64_t L2 = hw.l2.latency, rcd = hw.dram.tRCD, cl = hw.dram.tCL, xfer = 32 / (2 * hw.dram.bus_bytes);
    const uint64_t descriptor = 426 + 1 + L2 + rcd + cl + xfer;                    // 635
    const uint64_t leaf = descriptor + hw.lat.leaf_descriptor + 2 + L2 + cl + xfer;  // 829 (row hit)
    ASSERT_EQ(leaf + hw.lat.ray_triangle + hw.lat.triangle_hit, kTwoStepLeafCycles);
    const TimingResult r = run_one_ray_at(hw, image);
    ASSERT_EQ(r.rays.size(), 1u);
    EXPECT_TRUE(r.rays[0].hit.hit);
    EXPECT_EQ(r.cycles, kTwoStepLeafCycles);
    const RtUnitStats rt = total(r.counts.rt);
    EXPECT_EQ(rt.node_fetches, 2u);    // two node reads: the root and the leaf
    EXPECT_EQ(rt.header_fetches, 1u);
    EXPECT_EQ(rt.chunk_requests, 7u);  // header 2 + root 2 + descriptor 1 + leaf 2
    EXPECT_EQ(total(r.counts.l1).demand.hits, 1u);  // the leaf's first chunk: the descriptor's sector
    EXPECT_EQ(total(r.counts.dram).reads, 6u);
    EXPECT_TRUE(r.protocol_violations.empty()) << r.protocol_violations.front();
}

TEST(TimingInterval, TwoStepLeafReadIsTheHandWorkedSum) {
    const BvhImage image = one_triangle_image();
    IntervalGpu gpu(two_step_config(), image, TraversalOrder::DFS);
    std::vector<IntervalGpu::Finished> done;
    gpu.start_trace(0, {one_warp_ray()}, 0, done);
    while (done.empty() && gpu.next_event() != ~0ull) gpu.run_next(done);
    ASSERT_EQ(done.size(), 1u);
    EXPECT_EQ(done[0].end, kTwoStepLeafCycles);
    EXPECT_EQ(total(gpu.rt_stats()).node_fetches, 2u);
    EXPECT_EQ(total(gpu.rt_stats()).chunk_requests, 7u);
}

// The paper's Figure 3 walk (section 3.2): a BVH with nodes A..P laid out by hand and one ray
// that the paper's traversal sends A -> D -> I -> J -> M -> P -> O -> N, then up N -> L -> K -> H
// -> B (and, our addition to finish the tree, B's leaves F and E). The ray hits O's triangle and
// then E's, nearer; P, N, L, K, H and F are leaves whose boxes it enters but whose triangles it
// misses; the boxes of C and G (internal nodes) it misses. TTP (depths 1, 2, 16) with every
// node read a pop: popping P prefetches O (S1); popping O prefetches N and L (S2); popping N
// prefetches K, H and B (S3, the entries not yet prefetched since the last push). The same
// sequence of pushes, pops, states and prefetched nodes comes out of AT, LT and the interval
// fidelity, with the paper preset's two-step leaf reads (the second read is no pop).
namespace figure3 {

struct Node {
    char name;
    bool internal;
    std::vector<char> children;  // internal: in child order
    Aabb box;
    TriangleLeaf tri{};
};

// Miss: the bounding box in x, y contains the ray's line (x = y = 0), the triangle does not
// (its long edge passes below the origin). Hit: a triangle around the origin. Off: far aside.
TriangleLeaf tri(float z, bool hit) {
    if (hit) return {{-1, -1, z}, {1, -1, z}, {0, 1, z}, 0, 0};
    return {{-1, -1, z}, {1, -1, z}, {1, 0.5f, z}, 0, 0};
}
Aabb leaf_box(const TriangleLeaf& t) {
    Aabb b;
    b.lo = glm::min(glm::min(t.v0, t.v1), t.v2) - glm::vec3(0, 0, 0.1f);
    b.hi = glm::max(glm::max(t.v0, t.v1), t.v2) + glm::vec3(0, 0, 0.1f);
    return b;
}

struct Walk {
    BvhImage image;
    std::map<uint64_t, char> name_of;
};

Walk build() {
    std::map<char, Node> n;
    auto leaf = [&](char c, float z, bool hit) {
        Node x{c, false, {}, {}, tri(z, hit)};
        x.box = leaf_box(x.tri);
        n[c] = x;
    };
    auto off = [&](char c) {
        Node x{c, false, {}, {}, {{5, 5, 0}, {6, 5, 0}, {5, 6, 0}, 0, 0}};
        x.box = leaf_box(x.tri);
        n[c] = x;
    };
    // Leaves: the ray starts at z = -10 going +z, so t = z + 10.
    leaf('E', 0, true);   // t = 10: the closest hit, found last
    leaf('F', -1, false);
    leaf('H', 1, false);
    leaf('K', 2, false);
    leaf('L', 3, false);
    leaf('N', 4, false);
    leaf('O', 5, true);   // t = 15: hit first
    leaf('P', 6, false);
    off('c');             // under C
    off('g');             // under G
    auto inner = [&](char c, std::vector<char> kids) {
        Node x{c, true, kids, {}, {}};
        for (char k : kids) {
            x.box.lo = glm::min(x.box.lo, n[k].box.lo);
            x.box.hi = glm::max(x.box.hi, n[k].box.hi);
        }
        n[c] = x;
    };
    inner('M', {'N', 'O', 'P'});
    inner('J', {'L', 'M'});
    inner('I', {'K', 'J'});
    inner('D', {'H', 'I'});
    inner('C', {'c'});
    inner('G', {'g'});
    inner('B', {'E', 'F', 'G'});
    inner('A', {'B', 'C', 'D'});
    // Layout: the header, then A, then each internal node's children side by side, breadth first.
    std::map<char, uint64_t> addr;
    std::vector<char> order = {'A'};
    addr['A'] = kBlockBytes;
    uint64_t next = 2 * kBlockBytes;
    for (size_t i = 0; i < order.size(); ++i)
        for (char k : n[order[i]].children) {
            addr[k] = next;
            next += kBlockBytes;
            order.push_back(k);
        }
    std::vector<uint8_t> bytes(next, 0);
    ImageHeader h;
    h.root_box = n['A'].box;
    h.root = addr['A'];
    h.leaves = 10;
    encode_header(h, bytes.data());
    Walk w;
    for (const auto& [c, x] : n) {
        w.name_of[addr[c]] = c;
        if (!x.internal) {
            encode_triangle(x.tri, bytes.data() + addr[c]);
            continue;
        }
        std::vector<NodeType> types;
        std::vector<Aabb> boxes;
        for (char k : x.children) {
            types.push_back(n[k].internal ? NodeType::Internal : NodeType::Triangle);
            boxes.push_back(n[k].box);
        }
        encode_internal(x.box, int(x.children.size()), types.data(), boxes.data(), addr[x.children[0]], bytes.data() + addr[c]);
    }
    w.image = BvhImage(std::move(bytes));
    return w;
}

struct Recorder : PrefetchObserver {
    const std::map<uint64_t, char>* name_of = nullptr;
    std::vector<std::string> log;
    void on_pop(uint64_t popped, int state, const std::vector<uint64_t>& prefetched) override {
        std::string s = std::string("pop ") + name_of->at(popped) + " S" + std::to_string(state);
        if (!prefetched.empty()) s += " prefetch";
        for (uint64_t p : prefetched) s += std::string(" ") + name_of->at(p);
        log.push_back(s);
    }
    void on_push(size_t size) override { log.push_back("push " + std::to_string(size)); }
};

const std::vector<std::string> kExpected = {
    "pop A S1", "push 2",  // B, D
    "pop D S1 prefetch B", "push 3",  // B, H, I
    "pop I S1 prefetch H", "push 4",  // B, H, K, J
    "pop J S1 prefetch K", "push 5",  // B, H, K, L, M
    "pop M S1 prefetch L", "push 7",  // B, H, K, L, N, O, P
    "pop P S1 prefetch O",            // the paper: O prefetched when P is popped (S1)
    "pop O S2 prefetch N L",          // the paper: N and L prefetched when O is popped (S2)
    "pop N S3 prefetch K H B",        // the rest of the stack, once
    "pop L S3", "pop K S3", "pop H S3", "pop B S3", "push 2",  // E, F
    "pop F S1 prefetch E", "pop E S2",
};

// Runs the walk in `fidelity` and checks the log, the hit and the reads.
void check(Fidelity fidelity, bool interval) {
    FsResolution resolution;
    const Walk w = build();
    std::vector<RayFileEntry> rays(1);
    rays[0].ray.org = {0, 0, -10};
    rays[0].ray.dir = {0, 0, 1};
    rays[0].valid = true;
    auto work = make_ray_file_workload(rays);
    Config c = Config::load("paper");
    c.set("prefetch.kind=ttp");
    HwConfig hw = c.resolve();
    auto rec = std::make_shared<Recorder>();
    rec->name_of = &w.name_of;
    hw.prefetch.observer = rec;
    TimingOptions opt;
    opt.fidelity = fidelity;
    TimingResult r;
    if (interval) {
        r = run_interval(hw, w.image, *work, opt);
    } else {
        GpuPlatform platform(hw, w.image, *work, opt);
        r = platform.run();
    }
    EXPECT_EQ(rec->log, kExpected);
    ASSERT_EQ(r.rays.size(), 1u);
    EXPECT_TRUE(r.rays[0].hit.hit);
    EXPECT_NEAR(r.rays[0].hit.t, 10.0f, 1e-4f);  // E
    EXPECT_EQ(r.rays[0].nodes_visited, 14u);      // A D I J M P O N L K H B F E
    const RtUnitStats rt = total(r.counts.rt);
    EXPECT_EQ(rt.node_fetches, 14u);
    // TTP picks 11 nodes (B, H, K and L twice: the pointer resets on a push); the paper preset's
    // thread window (the authors' last 16 prefetches) drops the second picks of B, H, K and L,
    // so 7 nodes of 64 B reach the queue as 2 chunks each.
    EXPECT_EQ(rt.prefetch_queue.window_dropped, 4u);
    EXPECT_EQ(rt.prefetch_queue.generated, 14u);
}

}  // namespace figure3

TEST(PaperFigure3, DfsWithTtpWalkInAt) { figure3::check(Fidelity::AT, false); }
TEST(PaperFigure3, DfsWithTtpWalkInLt) { figure3::check(Fidelity::LT, false); }
TEST(PaperFigure3, DfsWithTtpWalkInInterval) { figure3::check(Fidelity::AT, true); }

// The RT complex as a library module (tlm/rt_complex.h): three in one simulation (cornell and
// wknd in LT, wknd in AT), each fed by its own workload driver, retire every ray with the hits the
// functional model finds; the modules are children named in the hierarchy; building and running
// them touches no process-wide state (the global quantum stays unset, nobody calls sc_stop); and
// each takes exactly the cycles rtsim takes on its workload alone, so they share nothing. AT too:
// beside them runs a process woken on every core clock edge, whose timed events share the kernel's
// queue with the complexes' at the same times; until 2026-11-26 the kernel's order of such
// same-time processes decided AT's cycles (tlm/ordered_events.h).
namespace {
struct EdgeTicker : sc_core::sc_module {
    SC_HAS_PROCESS(EdgeTicker);
    EdgeTicker(sc_core::sc_module_name n, sc_core::sc_time period, uint64_t edges) : sc_module(n), period_(period), left_(edges) {
        SC_METHOD(tick);
    }
    void tick() {
        if (left_-- > 0) next_trigger(period_);
    }
    sc_core::sc_time period_;
    uint64_t left_;
};
}  // namespace

// After a trace, a shader warp runs its intersection loop before its next trace: one iteration
// (workload.intersection_latency cycles) per procedural candidate of the trace's ray with the
// most, the others masked off as SIMT threads are, then its shader code (workload.shade_latency).
// Hand-worked on a cornell path-tracing warp on one SM: shade 100, 7 cycles an iteration; the
// first trace is ready at 100 (no launch latency); its 32 rays retire at cycle 150 with 0..4
// candidates (the ray number modulo 5), so the warp's bounces (of the rays that hit the box) are
// ready at 150 + 4 x 7 + 100 = 278; without the loop (0 cycles an iteration) at 250.
TEST(ShaderTiming, AWarpsNextTraceWaitsForItsIntersectionLoop) {
    const Scene scene = make_cornell();
    const BvhImage img = build_bvh_image(scene);
    WorkloadParams p;
    p.width = 8;
    p.height = 4;  // 32 pixels: one warp
    p.spp = 1;
    for (const uint32_t iteration : {7u, 0u}) {
        const std::unique_ptr<Workload> workload = make_scene_workload(WorkloadKind::PathTrace, scene, p);
        ShaderTiming timing;
        timing.shade = 100;
        timing.intersection = iteration;
        WorkloadDriver driver(*workload, 1, 32, timing);
        EXPECT_EQ(driver.earliest_ready(0), 100u);
        EXPECT_FALSE(driver.next_trace(0, 99));
        const auto trace = driver.next_trace(0, 100);
        ASSERT_TRUE(trace);
        ASSERT_EQ(trace->size(), 32u);
        std::vector<RetiredRay> done;
        uint32_t i = 0;
        for (const WarpRay& w : *trace) {
            const TraceResult r = trace_ray(img, w.ray, TraversalOrder::DFS);
            RetiredRay rr{w.key, r.hit, r.nodes_visited};
            rr.candidates = i++ % 5;
            done.push_back(rr);
        }
        driver.retire(0, done, 150);
        EXPECT_EQ(driver.earliest_ready(0), 150u + 4u * iteration + 100u) << iteration << " cycles an iteration";
    }
}

// With contention (workload.shader_contention) a warp's shader code takes 1 + contention x n times
// as long, n the other warps of its SM in shader code when it begins. Hand-worked on cornell path
// tracing, 4 warps, shade 100, contention 0.25, no launch latency:
// - on 1 SM the 4 begin their ray generation together (n = 3): ready at 100 x 1.75 = 175; on
//   2 SMs, 2 each (n = 1): 125;
// - on 1 SM, the 4 traces taken at 175; warp 0's retires at 200 while the others are in the RT
//   unit (n = 0): ready at 300; warp 1's at 250, beside warp 0's code (n = 1): 375; warp 2's at
//   320, when warp 0's code has ended and warp 1's has not (n = 1): 445.
TEST(ShaderTiming, AWarpsShaderCodeSlowsBesideItsSmsOthers) {
    const Scene scene = make_cornell();
    const BvhImage img = build_bvh_image(scene);
    WorkloadParams p;
    p.width = 16;
    p.height = 8;  // 128 pixels: 4 warps
    p.spp = 1;
    ShaderTiming timing;
    timing.shade = 100;
    timing.contention = 0.25;
    {
        const std::unique_ptr<Workload> workload = make_scene_workload(WorkloadKind::PathTrace, scene, p);
        WorkloadDriver driver(*workload, 2, 32, timing);
        EXPECT_EQ(driver.earliest_ready(0), 125u);
        EXPECT_EQ(driver.earliest_ready(1), 125u);
    }
    const std::unique_ptr<Workload> workload = make_scene_workload(WorkloadKind::PathTrace, scene, p);
    WorkloadDriver driver(*workload, 1, 32, timing);
    EXPECT_EQ(driver.earliest_ready(0), 175u);
    EXPECT_FALSE(driver.next_trace(0, 174));
    std::vector<std::vector<WarpRay>> traces;
    for (int w = 0; w < 4; ++w) {
        auto t = driver.next_trace(0, 175);
        ASSERT_TRUE(t);
        traces.push_back(*t);
    }
    auto retire = [&](const std::vector<WarpRay>& trace, uint64_t now) {
        std::vector<RetiredRay> done;
        for (const WarpRay& w : trace) {
            const TraceResult r = trace_ray(img, w.ray, TraversalOrder::DFS);
            done.push_back(RetiredRay{w.key, r.hit, r.nodes_visited});
        }
        driver.retire(0, done, now);
    };
    retire(traces[0], 200);
    EXPECT_EQ(driver.earliest_ready(0), 300u);
    retire(traces[1], 250);
    ASSERT_TRUE(driver.next_trace(0, 300));  // warp 0's second trace: warp 1's is next
    EXPECT_EQ(driver.earliest_ready(0), 375u);
    retire(traces[2], 320);
    ASSERT_TRUE(driver.next_trace(0, 375));  // warp 1's second trace: warp 2's is next
    EXPECT_EQ(driver.earliest_ready(0), 445u);
}

TEST(RtComplex, SeveralInOneSimulationShareNothing) {
    FsResolution resolution;
    struct Unit {
        std::string scene;
        Fidelity fidelity;
        const char* fidelity_name;
    };
    const Unit units[] = {{"cornell", Fidelity::LT, "lt"}, {"wknd", Fidelity::LT, "lt"}, {"wknd", Fidelity::AT, "at"}, {"cornell", Fidelity::AT, "at"}};
    const size_t n = std::size(units);
    const HwConfig hw = Config::load("mobile").resolve();
    WorkloadParams p;
    p.width = p.height = 24;
    p.seed = 3;
    std::vector<Scene> scenes;
    std::vector<BvhImage> images;
    std::vector<std::unique_ptr<Workload>> workloads;
    std::vector<std::unique_ptr<WorkloadDriver>> drivers;
    std::vector<std::unique_ptr<RtComplex>> gpus;
    for (const Unit& u : units) {
        scenes.push_back(load_scene(u.scene, ""));
        images.push_back(build_bvh_image(scenes.back()));
    }
    for (size_t i = 0; i < n; ++i) {
        workloads.push_back(make_scene_workload(WorkloadKind::Primary, scenes[i], p));
        drivers.emplace_back(new WorkloadDriver(*workloads[i], hw.sms, hw.warp_size, shader_timing(hw, *workloads[i])));
        gpus.emplace_back(new RtComplex(("gpu_" + std::to_string(i)).c_str(), hw, images[i], TraversalOrder::DFS, *drivers[i], units[i].fidelity));
    }
    EXPECT_EQ(std::string(gpus[1]->rt_units()[3]->name()), "gpu_1.rt_unit_3");
    EXPECT_EQ(std::string(gpus[0]->dram().name()), "gpu_0.dram");
    EdgeTicker ticker("ticker", gpus[0]->core_clock().period(), 20000);
    sc_core::sc_start();
    EXPECT_FALSE(sc_core::sc_end_of_simulation_invoked()) << "something called sc_stop";
    EXPECT_EQ(tlm::tlm_global_quantum::instance().get(), sc_core::SC_ZERO_TIME);
    rtu::test::TempDir dir;
    for (size_t i = 0; i < n; ++i) {
        const std::string what = units[i].scene + " " + units[i].fidelity_name;
        ASSERT_TRUE(drivers[i]->finished()) << what;
        EXPECT_EQ(gpus[i]->pool().outstanding(), 0u) << what;
        expect_functional_hits(scenes[i], images[i], WorkloadKind::Primary, p, drivers[i]->results(), what);
        const std::string stats = dir.file(std::to_string(i) + ".json");
        const std::string cmd = std::string(RTU_RTSIM) + " --scene " + units[i].scene +
                                " --workload primary --width 24 --height 24 --seed 3 --config mobile --fidelity " +
                                units[i].fidelity_name + " --quiet --stats " + stats;
        ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
        const auto j = nlohmann::json::parse(rtu::test::read_text(stats));
        EXPECT_EQ(drivers[i]->last_progress(), j["cycles"].get<uint64_t>()) << what;
    }
}

namespace {
// A hand-built two-level scene: mesh A, one triangle around (0, 0, 0), and mesh B, one around
// (10, 0, 0), both in the plane z = 0, each under an identity instance of its own (a BLAS each
// under the TLAS). The ray from (10, 0, -5) along +z meets B alone. Worked by hand, it reads
// (DFS, every node read a pop):
//   1. the image's (TLAS's) 64 B header at 0: the root box is hit, the TLAS root is pushed
//   2. the TLAS root: two instance leaves; A's box (x in [-1, 1]) is missed, B's is hit
//   3. B's instance leaf (128 B): its BLAS header follows in the same pop
//   4. B's BLAS header (64 B, the block before its root): the BLAS root is pushed
//   5. the BLAS root: one child, the triangle leaf
//   6. the triangle leaf: the hit
// Two header reads, four node visits, 2 + 2 + 4 + 2 + 2 + 2 = 14 chunks of 32 B.
struct TwoLevel {
    Scene scene;
    BvhImage image;
    Ray ray;
};
TwoLevel two_level_scene() {
    TwoLevel t;
    t.scene.name = "two-level";
    t.scene.materials.push_back(Material{});
    for (float x : {0.0f, 10.0f}) {
        Mesh m;
        m.vertices = {{x - 1, -1, 0}, {x + 1, -1, 0}, {x, 1, 0}};
        m.triangles = {{0, 1, 2}};
        m.material = {0};
        t.scene.meshes.push_back(m);
    }
    add_identity_instances(t.scene);
    t.image = build_bvh_image(t.scene);
    t.ray.org = {10, 0, -5};
    t.ray.dir = {0, 0, 1};
    return t;
}
// The one ray as a timing run of `fidelity` (mobile, memory clock = core clock).
TimingResult run_two_level(Fidelity fidelity) {
    const TwoLevel t = two_level_scene();
    std::vector<RayFileEntry> rays(1);
    rays[0].ray = t.ray;
    rays[0].valid = true;
    auto w = make_ray_file_workload(rays);
    Config c = Config::load("mobile");
    c.set("gpu.memory_clock_mhz=1365");
    TimingOptions opt;
    opt.fidelity = fidelity;
    opt.keep_rays = true;
    return run_timing(c.resolve(), t.image, *w, opt);
}
void expect_two_level_records(const TimingResult& r) {
    ASSERT_EQ(r.rays.size(), 1u);
    EXPECT_TRUE(r.rays[0].hit.hit);
    EXPECT_EQ(r.rays[0].hit.geom, 1u);  // mesh B
    EXPECT_EQ(r.rays[0].nodes_visited, 4u);
    const RtUnitStats rt = total(r.counts.rt);
    EXPECT_EQ(rt.header_fetches, 2u);
    EXPECT_EQ(rt.node_fetches, 4u);
    EXPECT_EQ(rt.chunk_requests, 14u);
}
}  // namespace

TEST(TwoLevelRecords, TraversalReadsTheHandWorkedList) {
    const TwoLevel t = two_level_scene();
    const ImageHeader& h = t.image.header();
    ASSERT_TRUE(h.has_instances && h.has_headers);
    const InternalNode root = decode_internal(t.image.at(h.root, kBlockBytes));
    ASSERT_EQ(root.count, 2);
    ASSERT_EQ(root.type[0], NodeType::Instance);
    ASSERT_EQ(root.type[1], NodeType::Instance);
    // B's instance leaf: the one whose BLAS holds mesh 1.
    uint64_t inst_b = 0, blas_b = 0;
    for (int i = 0; i < 2; ++i) {
        const InstanceLeaf il = decode_instance(t.image.at(root.addr[i], 2 * kBlockBytes));
        if (il.geom == 1) inst_b = root.addr[i], blas_b = il.blas_root;
    }
    ASSERT_NE(inst_b, 0u);
    const InternalNode blas_root = decode_internal(t.image.at(blas_b, kBlockBytes));
    ASSERT_EQ(blas_root.count, 1);
    ASSERT_EQ(blas_root.type[0], NodeType::Triangle);
    const std::vector<std::pair<uint64_t, NodeType>> expected = {
        {0, NodeType::Header},           {h.root, NodeType::Internal}, {inst_b, NodeType::Instance},
        {blas_b - kBlockBytes, NodeType::Header}, {blas_b, NodeType::Internal}, {blas_root.addr[0], NodeType::Triangle}};
    Ray r = t.ray;
    scale_direction(r);
    TraversalThread th;
    th.start(r, h, TraversalOrder::DFS);
    std::vector<std::pair<uint64_t, NodeType>> read;
    while (!th.done()) {
        read.push_back({th.peek().addr, th.peek().type});
        th.step(t.image);
    }
    EXPECT_EQ(read, expected);
    EXPECT_TRUE(th.hit().hit);
    EXPECT_EQ(th.hit().geom, 1u);
    EXPECT_EQ(th.nodes_visited(), 4u);
}
TEST(TwoLevelRecords, AtFetchesThem) {
    FsResolution resolution;
    expect_two_level_records(run_two_level(Fidelity::AT));
}
TEST(TwoLevelRecords, LtFetchesThem) {
    FsResolution resolution;
    expect_two_level_records(run_two_level(Fidelity::LT));
}
TEST(TwoLevelRecords, IntervalFetchesThem) { expect_two_level_records(run_two_level(Fidelity::Interval)); }
