// The rtsim program as users and scripts see it: file formats, exit status, messages.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <zlib.h>
#include <unistd.h>

#include <algorithm>
#include <thread>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include <rtunit/rtu_regs.h>

#include "model/config.h"
#include "model/dram.h"
#include "model/stats.h"
#include "platforms/error_estimate.h"
#include "sampling/bias.h"
#include "platforms/timing_stats.h"
#include "dram_driver.h"
#include "test_util.h"

using rtu::test::read_text;
using rtu::test::TempDir;
using rtu::test::write_text;

namespace {

// Under the sanitizers, the segment and sample-plan tests run primary rays (a third of cornell's
// path-tracing rays): segments and plans are made, read and merged alike for every workload. So
// do most cases of RtsimConfig.EveryKeyOfEveryPresetIsRead (115 -> 51 s there) and the thread
// check of RtsimSampling.FullFrameSampleEqualsTheUnsampledRun (61 -> 7 s).
const std::string kSanitizedWorkload = rtu::test::kSanitized ? "--workload primary " : "";

struct Result {
    int status;
    std::string out, err;
};

Result rtsim(const TempDir& dir, const std::string& args) {
    const std::string out = dir.file("stdout.txt"), err = dir.file("stderr.txt");
    const std::string cmd = std::string(RTU_RTSIM) + " " + args + " > " + out + " 2> " + err + " < /dev/null";
    const int rc = std::system(cmd.c_str());
    return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, read_text(out), read_text(err)};
}

std::vector<std::string> lines(const std::string& s) {
    std::vector<std::string> v;
    std::istringstream in(s);
    std::string l;
    while (std::getline(in, l)) v.push_back(l);
    return v;
}

bool exists(const std::string& p) { return std::filesystem::exists(p); }

// A run's statistics without what measures the host rather than the model: wall-clock time, the
// simulation rate and the peak resident memory, which vary from run to run; and the provenance,
// whose command line differs between the runs compared.
void erase_host_keys(nlohmann::json& j) {
    for (const char* k : {"time_s", "simulation_rate", "memory_mb", "provenance"}) j.erase(k);
}

// The statistics of a run without what measures the machine or echoes the configuration.
nlohmann::json model_stats(const std::string& path) {
    auto j = nlohmann::json::parse(read_text(path));
    erase_host_keys(j);
    j.erase("config");
    return j;
}

}  // namespace

// Cornell box: a ray from the camera straight down -z meets the back wall z = -555 at
// t = 800 + 555 = 1355 (prims 4/5), whatever the form the numbers are written in.
TEST(Rtsim, RayFileToHitsFile) {
    TempDir dir;
    const std::string rays = write_text(dir.file("rays.txt"),
                                        "# header comment\n"
                                        "278 278 800 0 0 -1 0 inf\n"                       // 0: back wall, t 1355
                                        "\n"
                                        "0x1.16p+8\t278 800  0 0 -1e-20 0 infinity closest  # 1: tiny direction\n"
                                        "278 278 800 0 0 -1 0 1000\n"                      // 2: tfar before the wall: miss
                                        "278 278 800 0 0 -1 0 inf any\n"                   // 3: any-hit
                                        "278 278 800 0 0 1 0 inf\n"                        // 4: away from the box: miss
                                        "nan 278 800 0 0 -1 0 inf\n"                       // 5: invalid
                                        "278 278 800 0 0 0 0 inf\n"                        // 6: zero direction
                                        "278 278 800 0 0 -1 -1 inf\n"                      // 7: tnear < 0
                                        "278 278 800 0 0 -1 5 4\n"                         // 8: tnear > tfar
                                        "278 278 800 0 0 -1 0 inf sideways\n"              // 9: bad query
                                        "1 2 3\n");                                        // 10: too few fields
    const std::string hits = dir.file("hits.csv"), stats = dir.file("stats.json");
    const Result r = rtsim(dir, "--scene cornell --rays " + rays + " --hits " + hits + " --stats " + stats + " --verify");
    ASSERT_EQ(r.status, 0) << r.err;
    const auto h = lines(read_text(hits));
    ASSERT_EQ(h.size(), 12u);
    EXPECT_EQ(h[0], "ray,hit,t,geom,prim");
    auto field = [&](int ray, int col) {
        std::istringstream in(h[ray + 1]);
        std::string f;
        for (int i = 0; i <= col; ++i) std::getline(in, f, ',');
        return f;
    };
    EXPECT_EQ(field(0, 0), "0");
    EXPECT_EQ(field(0, 1), "1");
    EXPECT_EQ(field(0, 2), "1355");
    EXPECT_EQ(field(0, 3), "0");
    EXPECT_TRUE(field(0, 4) == "4" || field(0, 4) == "5") << h[1];
    EXPECT_EQ(field(1, 2), "1.355e+23");  // t in units of the given (tiny) direction
    EXPECT_EQ(h[3], "2,0,-1,-1,-1");
    EXPECT_EQ(field(3, 1), "1");
    EXPECT_EQ(h[5], "4,0,-1,-1,-1");
    for (int i = 5; i <= 10; ++i) EXPECT_EQ(h[i + 1], std::to_string(i) + ",0,-1,-1,-1");
    const auto j = nlohmann::json::parse(read_text(stats));
    EXPECT_EQ(j["rays"], 11);
    EXPECT_EQ(j["invalid_rays"], 6);
    EXPECT_EQ(j["verify"]["mismatches"], 0);
    EXPECT_GT(j["nodes_visited"].get<int>(), 0);
    EXPECT_NE(r.err.find("rays.txt:8: "), std::string::npos) << "warning names the line of the first invalid ray: " << r.err;
}

TEST(Rtsim, BadInputExitsWithStatus2AndWritesNothing) {
    TempDir dir;
    const std::string stats = dir.file("s.json"), hits = dir.file("h.csv");
    const std::string outs = " --stats " + stats + " --hits " + hits;
    const std::string obj = write_text(dir.file("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n");
    const std::string empty = write_text(dir.file("empty.obj"), "# no faces\nv 0 0 0\n");
    const std::string unknown = write_text(dir.file("mesh.abc123"), "?");
    struct Case {
        std::string args, expect;
    } cases[] = {
        {"--scene " + dir.file("missing.obj"), "missing.obj"},
        {"--scene " + obj, "bad.obj:3"},
        {"--scene " + empty, "empty scene"},
        {"--scene " + unknown, "unknown mesh format"},
        {"--scene cornell --workload xyz", "--workload 'xyz'"},
        {"--scene cornell --width 0", "--width"},
        {"--scene cornell --traversal sideways", "--traversal"},
        {"--scene cornell --fidelity xyz", "allowed are functional, at, lt"},
        {"--scene cornell --fidelity at --set l1.size_kb=0", "l1.size_kb"},
        {"--scene cornell --fidelity at --set l1.bogus=1", "unknown key 'l1.bogus'"},
        {"--scene cornell --fidelity at --config nope.json", "nope.json"},
        // Every option is checked whatever the fidelity (a functional run once took any --config).
        {"--scene cornell --config nope.json", "nope.json"},
        {"--scene cornell --vcd x.vcd", "need --fidelity at, lt or interval"},
        {"--scene cornell --fidelity interval --vcd x.vcd", "need --fidelity at or lt"},
        {"--scene cornell --fidelity interval --prefetcher park", "prefetchers none and ttp, not 'park'"},
        {"--scene cornell --fidelity interval --traversal treelet", "not treelet traversal"},
        {"--scene cornell --fidelity interval --prefetcher ttp --set prefetch.priority_after=5", "prefetch.priority_after 0"},
        {"--scene cornell --fidelity at --vcd " + dir.file("w.vcd") + " --trace-warp 99:0", "--trace-warp"},
        {"--scene cornell --fidelity at --trace-warp 0:0", "it needs --vcd"},
        {"--scene cornell --fidelity lt --quantum 0", "--quantum 0"},
        {"--scene cornell --fidelity at --quantum 100", "it needs --fidelity lt"},
        {"--scene cornell --fidelity at --sample 0.5 --threads -1", "--threads -1"},
        {"--scene cornell stray", "unexpected argument 'stray'"},
        // Paths are numbered in 32 bits: 2^32 paths is one too many (it once ran, and a larger
        // frame ended in std::bad_alloc, exit 3).
        {"--scene cornell --width 4096 --height 4096 --spp 256", "4294967296 paths: at most 4294967295"},
        // Output paths are checked before the run (a VCD into a missing folder used to end in
        // SIGFPE after the whole simulation).
        {"--scene cornell --fidelity at --vcd " + dir.file("nodir/w.vcd"), "does not exist"},
        {"--scene cornell --image " + dir.path().string(), "is a folder"},
        // Two outputs on one file: the one written last would replace the other.
        {"--scene cornell --image " + dir.file("./s.json"), "also named by --stats"},
        {"--scene cornell --fidelity at --vcd " + dir.file("h.csv") + " --dump-bvh " + dir.file("h.csv.vcd"), "also named by --vcd"},
        {"--scene cornell --fidelity at --set l2.latency=nan", "needs a finite number, got 'nan'"},
        {"--scene cornell --rays " + dir.file("no-rays.txt"), "no-rays.txt"},
        {"--scene bunny", "--assets"},
        {"--scene cornell --bogus-option", "unrecognised"},
    };
    for (const Case& c : cases) {
        const Result r = rtsim(dir, c.args + outs);
        EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_FALSE(exists(stats)) << c.args;
        EXPECT_FALSE(exists(hits)) << c.args;
    }
    // An output in a folder that does not exist: status 2, and no stray temporary files.
    const Result r = rtsim(dir, "--scene cornell --width 8 --height 8 --hits " + dir.file("nodir/h.csv"));
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("nodir/h.csv"), std::string::npos);
}

// Links in a scene folder: loops among other files are passed over; a mesh's name that loops or
// leads nowhere is exit 2 naming it (leaving it out would renumber the geometry); a looping link
// given as --scene is named as such. (A loop once ended as an internal error, exit 3.)
TEST(Rtsim, BrokenLinksInASceneAreNamed) {
    TempDir dir;
    std::filesystem::create_directory(dir.file("scene"));
    write_text(dir.file("scene/a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::filesystem::create_symlink("loop2", dir.file("scene/loop1"));
    std::filesystem::create_symlink("loop1", dir.file("scene/loop2"));
    EXPECT_EQ(rtsim(dir, "--scene " + dir.file("scene") + " --workload primary --width 8 --height 8 -q").status, 0);
    std::filesystem::create_symlink("b.obj", dir.file("scene/b.obj.tmp"));
    std::filesystem::create_symlink("c.obj", dir.file("scene/c.obj"));  // to itself
    const Result looped = rtsim(dir, "--scene " + dir.file("scene") + " --workload primary --width 8 --height 8 -q");
    EXPECT_EQ(looped.status, 2) << looped.err;
    EXPECT_NE(looped.err.find("scene/c.obj: a symbolic link that loops or leads nowhere"), std::string::npos) << looped.err;
    std::filesystem::create_symlink("self", dir.file("self"));
    const Result self = rtsim(dir, "--scene " + dir.file("self") + " -q");
    EXPECT_EQ(self.status, 2) << self.err;
    EXPECT_NE(self.err.find("a symbolic link that loops or leads nowhere"), std::string::npos) << self.err;
}

// Outputs go through a symbolic link to the file it names (the link stays) and into a FIFO or a
// device such as /dev/null (which stays what it is); a link that leads nowhere is exit 2. (They
// were replaced by regular files: as root, --stats /dev/null replaced the system's /dev/null.)
TEST(Rtsim, OutputsGoThroughLinksAndIntoSpecialFiles) {
    TempDir dir;
    write_text(dir.file("real.json"), "{}");
    std::filesystem::create_symlink(dir.file("real.json"), dir.file("link.json"));
    ASSERT_EQ(::mkfifo(dir.file("hits.fifo").c_str(), 0644), 0);
    std::string piped;
    std::thread reader([&] {
        const int fd = ::open(dir.file("hits.fifo").c_str(), O_RDONLY);
        char buf[4096];
        for (ssize_t n; fd >= 0 && (n = ::read(fd, buf, sizeof buf)) > 0;) piped.append(buf, size_t(n));
        if (fd >= 0) ::close(fd);
    });
    const Result r = rtsim(dir, "--scene cornell --width 8 --height 8 -q --stats " + dir.file("link.json") + " --hits " + dir.file("hits.fifo") +
                                    " --image /dev/null");
    if (r.status != 0) {  // the reader waits for a writer: give it one
        const int fd = ::open(dir.file("hits.fifo").c_str(), O_WRONLY);
        ::close(fd);
    }
    reader.join();
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::is_symlink(dir.file("link.json")));
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("real.json")))["scene"], "cornell");
    EXPECT_EQ(piped.substr(0, 4), "ray,") << piped.substr(0, 40);
    EXPECT_TRUE(std::filesystem::is_fifo(dir.file("hits.fifo")));
    EXPECT_TRUE(std::filesystem::is_character_file("/dev/null"));
    std::filesystem::create_symlink(dir.file("nowhere.json"), dir.file("dangling.json"));
    const Result dangling = rtsim(dir, "--scene cornell --width 8 --height 8 -q --stats " + dir.file("dangling.json"));
    EXPECT_EQ(dangling.status, 2);
    EXPECT_NE(dangling.err.find("leads nowhere"), std::string::npos) << dangling.err;
    EXPECT_TRUE(std::filesystem::is_symlink(dir.file("dangling.json")));
}

// A run whose outputs cannot all be written leaves none of them. Under a file-size limit of
// 16 KiB (ulimit -f; SIGXFSZ ignored, so a write past it fails with EFBIG): the statistics (30 KB)
// fail after the hits (2.5 KB) and the frame were written; the VCD, which SystemC cuts without a
// word, is found cut. Each is exit 2 naming the file, with no output and no temporary left.
TEST(Rtsim, AnOutputThatCannotBeWrittenLeavesNone) {
    TempDir dir;
    const std::string limited = write_text(dir.file("limited.sh"), "ulimit -f 16\ntrap '' XFSZ\nexec \"$@\"\n");
    std::filesystem::create_directory(dir.file("out"));
    auto run = [&](const std::string& args) {
        const std::string cmd = "bash " + limited + " " + RTU_RTSIM + " " + args + " > " + dir.file("o.txt") + " 2> " + dir.file("e.txt") + " < /dev/null";
        const int rc = std::system(cmd.c_str());
        return Result{WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, read_text(dir.file("o.txt")), read_text(dir.file("e.txt"))};
    };
    auto left = [&] {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(dir.file("out"))) names.push_back(e.path().filename().string());
        return names;
    };
    const std::string outs = " --hits " + dir.file("out/h.csv") + " --image " + dir.file("out/f.png") + " --stats " + dir.file("out/s.json");
    const Result stats = run("--scene cornell --workload primary --fidelity at --width 8 --height 8 -q" + outs);
    EXPECT_EQ(stats.status, 2) << stats.err;
    EXPECT_NE(stats.err.find("out/s.json"), std::string::npos) << stats.err;
    EXPECT_TRUE(left().empty()) << left().front();
    const Result vcd = run("--scene cornell --workload primary --fidelity at --width 32 --height 32 -q --vcd " + dir.file("out/w.vcd") +
                           " --hits " + dir.file("out/h.csv"));
    EXPECT_EQ(vcd.status, 2) << vcd.err;
    EXPECT_NE(vcd.err.find("out/w.vcd: cannot write: the file reached the size limit"), std::string::npos) << vcd.err;
    EXPECT_TRUE(left().empty()) << left().front();
    // A shell's plain `ulimit -f`, whose SIGXFSZ would end rtsim at the crossing write and leave
    // that output's temporary file behind: rtsim ignores the signal, so it is the same exit 2.
    const std::string plain = write_text(dir.file("plain.sh"), "ulimit -f 16\nexec \"$@\"\n");
    const std::string cmd = "bash " + plain + " " + RTU_RTSIM + " --scene cornell --workload primary --fidelity at --width 8 --height 8 -q" +
                            outs + " > /dev/null 2> " + dir.file("e.txt") + " < /dev/null";
    const int rc = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << rc << ": " << read_text(dir.file("e.txt"));
    EXPECT_TRUE(left().empty()) << left().front();  // directory_iterator lists the hidden temporaries too
    // Without the limit both write everything.
    EXPECT_EQ(rtsim(dir, "--scene cornell --workload primary --fidelity at --width 32 --height 32 -q --vcd " + dir.file("out/w.vcd") + outs).status, 0);
    EXPECT_EQ(left().size(), 4u);
}

// rtsim with no arguments runs nothing: it prints the usage and exits 2; the usage lines name
// every option of the --help table.
// A camera near the float limit makes every primary ray invalid: the run is all misses, which
// would read as an empty scene, so it says so (issue 16); one invalid ray among valid ones does not.
TEST(Rtsim, AFrameOfOnlyInvalidRaysWarns) {
    TempDir dir;
    std::filesystem::create_directory(dir.file("scene"));
    write_text(dir.file("scene/a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_text(dir.file("scene/view.camera"), "3e38 3e38 3e38\n0 0 0\n");
    const Result r = rtsim(dir, "--scene " + dir.file("scene") + " --workload primary --width 8 --height 8 --quiet");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("warning: every one of the 128 rays is invalid"), std::string::npos) << r.err;
    const Result fine = rtsim(dir, "--scene cornell --workload primary --width 8 --height 8 --quiet");
    EXPECT_EQ(fine.status, 0) << fine.err;
    EXPECT_EQ(fine.err.find("invalid"), std::string::npos) << fine.err;
}

// The SoC peripheral's inputs from a scene: the BVH image's bytes, 48-byte ray records and the
// golden hit records (rtunit/rtu_regs.h), checked against the hits file of the same run (the
// functional run loop, not the records' encoder).
TEST(Rtsim, DumpsAreThePeripheralsInputsAndHits) {
    TempDir dir;
    const std::string rays = write_text(dir.file("rays.txt"),
                                        "278 278 800 0 0 -1 0 inf\n"      // back wall
                                        "278 278 800 0.1 0.2 -1 0 inf\n"  // somewhere else
                                        "278 278 800 0 0 -1 0 1000\n"     // tfar before the wall: miss
                                        "278 278 800 0 0 -1 0 inf any\n"  // any-hit
                                        "nan 278 800 0 0 -1 0 inf\n");    // invalid
    const std::string hits = dir.file("hits.csv"), stats = dir.file("stats.json"), bvh = dir.file("c.rtubvh"),
                      rec = dir.file("c.rays"), golden = dir.file("c.hits");
    const Result r = rtsim(dir, "--scene cornell --rays " + rays + " --hits " + hits + " --stats " + stats + " --dump-bvh " + bvh +
                                    " --dump-rays " + rec + " --dump-hits " + golden);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(read_text(stats));
    const std::string image = read_text(bvh), ray_bytes = read_text(rec), hit_bytes = read_text(golden);
    EXPECT_EQ(image.size(), j["bvh"]["image_bytes"].get<size_t>());
    EXPECT_EQ(image.substr(0, 8), "RTUBVH01");
    ASSERT_EQ(ray_bytes.size(), 5 * sizeof(rtu_ray));
    ASSERT_EQ(hit_bytes.size(), 5 * sizeof(rtu_hit));
    std::vector<rtu_ray> rs(5);
    std::vector<rtu_hit> hs(5);
    std::memcpy(rs.data(), ray_bytes.data(), ray_bytes.size());
    std::memcpy(hs.data(), hit_bytes.data(), hit_bytes.size());
    EXPECT_EQ(rs[1].dir[1], 0.2f);
    EXPECT_EQ(rs[3].flags, RTU_RAY_ANY_HIT);
    EXPECT_TRUE(std::isnan(rs[4].org[0]));
    const auto h = lines(read_text(hits));
    ASSERT_EQ(h.size(), 6u);
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(rs[i].user, i);
        EXPECT_EQ(hs[i].user, i);
        std::istringstream in(h[i + 1]);
        std::string f[5];
        for (auto& x : f) std::getline(in, x, ',');
        EXPECT_EQ(hs[i].status & RTU_HIT_HIT, f[1] == "1" ? RTU_HIT_HIT : 0u) << h[i + 1];
        if (f[1] != "1") continue;
        EXPECT_EQ(hs[i].t, std::strtof(f[2].c_str(), nullptr)) << h[i + 1];  // %.9g gives the float back exactly
        EXPECT_EQ(hs[i].geom, std::stoul(f[3])) << h[i + 1];
        EXPECT_EQ(hs[i].prim, std::stoul(f[4])) << h[i + 1];
        EXPECT_GT(hs[i].nodes_visited, 0u);
    }
    EXPECT_EQ(hs[0].t, 1355.0f);
    EXPECT_EQ(hs[2].status, 0u);
    EXPECT_EQ(hs[4].status, RTU_HIT_INVALID_RAY);
    // The records' hits are the peripheral's traversal's: treelet traversal has no such hits.
    const Result t = rtsim(dir, "--scene cornell --rays " + rays + " --traversal treelet --dump-hits " + dir.file("t.hits"));
    EXPECT_EQ(t.status, 2) << t.err;
    EXPECT_FALSE(exists(dir.file("t.hits")));
    // --rays reads the dumped records back: the same rays, so the same hits file (the invalid
    // one warned about as a record). Other binary data is refused naming the file.
    const Result back = rtsim(dir, "--scene cornell --rays " + rec + " --hits " + dir.file("back.csv"));
    ASSERT_EQ(back.status, 0) << back.err;
    EXPECT_EQ(read_text(dir.file("back.csv")), read_text(hits));
    EXPECT_NE(back.err.find("c.rays:5: record 5: invalid ray"), std::string::npos) << back.err;
    const std::string garbage = write_text(dir.file("garbage.bin"), std::string("\x7f" "ELF\0\0\0\x01", 8) + std::string(42, 'x'));
    const Result bad = rtsim(dir, "--scene cornell --rays " + garbage + " --stats " + dir.file("bad.json"));
    EXPECT_EQ(bad.status, 2) << bad.err;
    EXPECT_NE(bad.err.find("garbage.bin: binary data of 50 bytes"), std::string::npos) << bad.err;
    EXPECT_FALSE(exists(dir.file("bad.json")));
}

TEST(Rtsim, NoArgumentsPrintsAUsageThatNamesEveryOption) {
    TempDir dir;
    const Result none = rtsim(dir, "");
    EXPECT_EQ(none.status, 2);
    EXPECT_TRUE(none.out.empty()) << none.out;
    EXPECT_NE(none.err.find("usage: rtsim --scene"), std::string::npos) << none.err;
    EXPECT_NE(none.err.find("rtsim --help"), std::string::npos) << none.err;
    const Result help = rtsim(dir, "--help");
    ASSERT_EQ(help.status, 0);
    const size_t table = help.out.find("\noptions");
    ASSERT_NE(table, std::string::npos);
    const std::string usage = help.out.substr(0, table), options = help.out.substr(table);
    int named = 0;
    for (const std::string& l : lines(options)) {
        // An option's line starts "  --name" or "  -h [ --help ]"; its wrapped description lines
        // start further in.
        const size_t at = l.find("--"), first = l.find_first_not_of(' ');
        if (at == std::string::npos || first != 2) continue;
        std::string opt = l.substr(at);
        opt = opt.substr(0, opt.find_first_of(" ]"));
        ++named;
        EXPECT_NE(usage.find(opt), std::string::npos) << opt << " is not in the usage lines";
    }
    EXPECT_GE(named, 25);
}

TEST(Rtsim, MainJobWritesStatsAndImage) {
    TempDir dir;
    const std::string stats = dir.file("s.json"), png = dir.file("f.png");
    const Result r = rtsim(dir, "--scene wknd --workload pt --width 32 --height 24 --spp 1 --verify --stats " + stats + " --image " + png);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(read_text(stats));
    EXPECT_EQ(j["scene"], "wknd");
    EXPECT_GE(j["rays"].get<int>(), 32 * 24);
    EXPECT_EQ(j["verify"]["mismatches"], 0);
    EXPECT_TRUE(j["verify"].contains("classes"));
    EXPECT_EQ(j["bvh"]["procedural_leaves"], 487);
    const std::string img = read_text(png);
    ASSERT_GT(img.size(), 8u);
    EXPECT_EQ(img.substr(1, 3), "PNG");
    EXPECT_NE(r.out.find("verify against Embree"), std::string::npos);
    // Nothing else is left in the folder (no temporary files).
    int files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.path().filename().string()[0] == '.';
    EXPECT_EQ(files, 0);
}

// Provenance: --version names the commit, and a statistics file holds the version, the commit,
// the command line and the resolved configuration, so that the run can be made again from the
// file alone: rerunning its command line gives the same statistics.
TEST(Rtsim, AStatisticsFileReproducesItsRun) {
    TempDir dir;
    const Result v = rtsim(dir, "--version");
    ASSERT_EQ(v.status, 0);
    // "rtsim X.Y.Z (commit C)\n", C twelve hex digits (with "-dirty") or "unknown".
    const std::string head = "rtsim ", mid = " (commit ", tail = ")\n";
    const size_t at = v.out.find(mid);
    ASSERT_TRUE(v.out.rfind(head, 0) == 0 && at != std::string::npos && v.out.size() > at + mid.size() + tail.size() &&
                v.out.compare(v.out.size() - tail.size(), tail.size(), tail) == 0) << v.out;
    const std::string version = v.out.substr(head.size(), at - head.size());
    const std::string commit = v.out.substr(at + mid.size(), v.out.size() - tail.size() - at - mid.size());
    EXPECT_EQ(std::count(version.begin(), version.end(), '.'), 2) << version;
    const std::string hex = commit.substr(0, commit.find('-'));
    EXPECT_TRUE(commit == "unknown" || (hex.size() == 12 && hex.find_first_not_of("0123456789abcdef") == std::string::npos &&
                                        (commit.size() == 12 || commit.substr(12) == "-dirty"))) << commit;
    const std::string args = "--scene cornell --width 16 --height 16 --fidelity interval --set l1.size_kb=16 --seed 3 -q --stats ";
    ASSERT_EQ(rtsim(dir, args + dir.file("a.json")).status, 0);
    auto a = nlohmann::json::parse(read_text(dir.file("a.json")));
    EXPECT_EQ(a["provenance"]["version"], version);
    EXPECT_EQ(a["provenance"]["commit"], commit);
    EXPECT_EQ(a["config"]["l1"]["size_kb"], 16);
    // The command line as given, program first; rerun with another --stats.
    const auto& cl = a["provenance"]["command_line"];
    ASSERT_GE(cl.size(), 2u);
    std::string again;
    for (size_t i = 1; i < cl.size(); ++i) {
        std::string arg = cl[i].get<std::string>();
        if (arg == dir.file("a.json")) arg = dir.file("b.json");
        again += (i > 1 ? " " : "") + arg;
    }
    EXPECT_EQ(again, args + dir.file("b.json"));
    ASSERT_EQ(rtsim(dir, again).status, 0);
    auto b = nlohmann::json::parse(read_text(dir.file("b.json")));
    EXPECT_EQ(a["provenance"]["commit"], b["provenance"]["commit"]);
    for (auto* j : {&a, &b}) erase_host_keys(*j);  // the provenance too: the command lines differ in --stats
    EXPECT_EQ(a, b);
    // A functional run records its configuration too.
    ASSERT_EQ(rtsim(dir, "--scene cornell --width 8 --height 8 --config paper -q --stats " + dir.file("f.json")).status, 0);
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("f.json")))["config"]["l1"]["size_kb"], 32);
}

TEST(Rtsim, SameSeedSameStatistics) {
    TempDir dir;
    const std::string a = dir.file("a.json"), b = dir.file("b.json");
    ASSERT_EQ(rtsim(dir, "--scene cornell --width 16 --height 16 --seed 5 --stats " + a).status, 0);
    ASSERT_EQ(rtsim(dir, "--scene cornell --width 16 --height 16 --seed 5 --stats " + b).status, 0);
    auto ja = nlohmann::json::parse(read_text(a)), jb = nlohmann::json::parse(read_text(b));
    for (auto* j : {&ja, &jb}) erase_host_keys(*j);
    EXPECT_EQ(ja, jb);
    EXPECT_EQ(rtsim(dir, "--help").status, 0);
}

// The functional pass and --verify trace on --threads threads: the statistics and the hits are
// the same for 1 and 3 threads, and so are a timing run's with --verify. 160x128 at 2 spp is
// 40,960 camera rays, three of the pass's batches of 16,384, so batch ends fall inside a wave.
TEST(Rtsim, FunctionalThreadsChangeNoResult) {
    TempDir dir;
    std::vector<nlohmann::json> stats;
    std::vector<std::string> hits;
    for (const char* threads : {"1", "3"}) {
        const Result r = rtsim(dir, std::string("--scene wknd --width 160 --height 128 --spp 2 --verify --threads ") + threads +
                                        " --stats " + dir.file("s.json") + " --hits " + dir.file("h.csv"));
        ASSERT_EQ(r.status, 0) << r.err;
        stats.push_back(nlohmann::json::parse(read_text(dir.file("s.json"))));
        erase_host_keys(stats.back());
        stats.back().erase("speed");
        hits.push_back(read_text(dir.file("h.csv")));
    }
    EXPECT_GT(stats[0]["rays"].get<uint64_t>(), 40960u);  // bounces beyond the camera rays
    EXPECT_EQ(stats[0]["verify"]["mismatches"], 0);
    EXPECT_EQ(stats[0], stats[1]);
    EXPECT_EQ(hits[0], hits[1]);
    // A timing run's --verify checks its rays on the threads too, each into its own slot.
    std::vector<nlohmann::json> timed;
    for (const char* threads : {"1", "3"}) {
        const Result r = rtsim(dir, std::string("--scene wknd --width 64 --height 64 --spp 2 --fidelity interval --verify --threads ") +
                                        threads + " --stats " + dir.file("t.json"));
        ASSERT_EQ(r.status, 0) << r.err;
        timed.push_back(nlohmann::json::parse(read_text(dir.file("t.json"))));
        erase_host_keys(timed.back());
    }
    EXPECT_GT(timed[0]["verify"]["rays"].get<uint64_t>(), 8192u);  // every ray of the frame, bounces too
    EXPECT_EQ(timed[0]["verify"]["rays"], timed[0]["rays"]);
    EXPECT_EQ(timed[0]["verify"]["mismatches"], 0);
    EXPECT_EQ(timed[0], timed[1]);
}

// A triangle of vertices at +-1e15: rays near it hit as Embree's do; a ray from 1e8 away meets
// it where the TTP authors' float Moller-Trumbore t overflows (|v2 - v0| |o - v0| |v1 - v0| =
// 2e15 x 1e8 x 2e15 > 3.4e38), a miss of the modelled hardware that --verify names as such
// (simulator_float_overflow), not as a mismatch and not under another class's excuse.
TEST(Rtsim, HugeScenesSeenFromFarMissAsTheModelledHardwareDoes) {
    TempDir dir;
    const std::string obj = write_text(dir.file("huge.obj"), "v -1e15 -1e15 0\nv 1e15 -1e15 0\nv 0 1e15 0\nf 1 2 3\n");
    const std::string rays = write_text(dir.file("r.txt"), "1 2 1 0 0 -1 0 inf\n1 2 1e8 0 0 -1 0 inf\n3 5 1e12 0.01 0.02 -1 0 inf\n");
    const Result r = rtsim(dir, "--scene " + obj + " --rays " + rays + " --verify -q --stats " + dir.file("s.json") + " --hits " + dir.file("h.csv"));
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(read_text(dir.file("s.json")));
    EXPECT_EQ(j["verify"]["classes"]["agree"], 1);
    EXPECT_EQ(j["verify"]["classes"]["simulator_float_overflow"], 2);
    EXPECT_EQ(j["verify"]["mismatches"], 0);
    const auto h = lines(read_text(dir.file("h.csv")));
    ASSERT_EQ(h.size(), 4u);
    EXPECT_EQ(h[1], "0,1,1,0,0");
    EXPECT_EQ(h[2], "1,0,-1,-1,-1");
}

// Rays lying in the Cornell box's wall planes (x = 0, x = 555, y = 0, y = 555) with +0 and -0
// direction components: they run inside box faces all the way down the BVH. Every one agrees
// with Embree up to the documented classes, and +0 and -0 give the same answer.
TEST(Rtsim, ZeroDirectionRaysInFacePlanesAgreeWithEmbree) {
    TempDir dir;
    std::string rays;
    const char* planes[4][3] = {{"0", "%s", "%s"}, {"555", "%s", "%s"}, {"%s", "0", "%s"}, {"%s", "555", "%s"}};
    const float along[] = {0.5f, 100, 277.5f, 554.5f};
    int n = 0;
    for (int p = 0; p < 4; ++p)
        for (const char* zero : {"0", "-0"})
            for (float a : along)
                for (float slope : {-0.75f, 0.0f, 0.3f}) {
                    char line[256];
                    const bool x_plane = p < 2;
                    std::snprintf(line, sizeof line, "%s %s 200 %s %s -1 0 inf\n",
                                  x_plane ? planes[p][0] : std::to_string(a).c_str(),
                                  x_plane ? std::to_string(a).c_str() : planes[p][1],
                                  x_plane ? zero : std::to_string(slope).c_str(),
                                  x_plane ? std::to_string(slope).c_str() : zero);
                    rays += line;
                    ++n;
                }
    const std::string file = write_text(dir.file("zero.txt"), rays), hits = dir.file("h.csv");
    const Result r = rtsim(dir, "--scene cornell --verify --rays " + file + " --hits " + hits);
    ASSERT_EQ(r.status, 0) << r.err << r.out;
    const auto h = lines(read_text(hits));
    ASSERT_EQ(int(h.size()), n + 1);
    int hit = 0;
    for (int p = 0; p < 4; ++p)
        for (int k = 0; k < 12; ++k) {
            const int plus = 1 + p * 24 + k, minus = plus + 12;  // same ray with +0, then -0
            EXPECT_EQ(h[plus].substr(h[plus].find(',')), h[minus].substr(h[minus].find(','))) << h[plus] << " vs " << h[minus];
            hit += h[plus].find(",1,") != std::string::npos;
        }
    EXPECT_GT(hit, 10);
}

// Same inputs and seed: bit-identical statistics from the timing model (wall-clock fields aside).
TEST(RtsimTiming, AtIsDeterministicAndWritesItsConfiguration) {
    TempDir dir;
    const std::string a = dir.file("a.json"), b = dir.file("b.json");
    const std::string args = "--scene wknd --fidelity at --width 24 --height 24 --seed 9 --set l1.size_kb=16 --stats ";
    ASSERT_EQ(rtsim(dir, args + a).status, 0);
    ASSERT_EQ(rtsim(dir, args + b).status, 0);
    auto ja = nlohmann::json::parse(read_text(a)), jb = nlohmann::json::parse(read_text(b));
    for (auto* j : {&ja, &jb}) erase_host_keys(*j);
    EXPECT_EQ(ja, jb);
    EXPECT_EQ(ja["config"]["l1"]["size_kb"], 16);
    EXPECT_EQ(ja["config"]["gpu"]["sms"], 8);
    EXPECT_GT(ja["cycles"].get<uint64_t>(), 0u);
    for (const char* k : {"accesses", "hits", "sector_misses", "line_misses", "mshr_hits", "reservation_fails"})
        EXPECT_TRUE(ja["timing"]["l1"]["demand"].contains(k)) << k;
    EXPECT_EQ(ja["timing"]["rt_unit"]["pop_streak"].size(), 5u);
    const auto& ts = ja["timing"]["rt_unit"]["thread_status"];
    const double sum = ts["waiting_to_be_scheduled"].get<double>() + ts["waiting_on_memory"].get<double>() +
                       ts["in_math"].get<double>() + ts["done_waiting_for_warp"].get<double>();
    EXPECT_NEAR(sum, 1.0, 1e-9);
}

// A run that makes no progress for sim.watchdog cycles stops with status 1 and names where it
// is stuck (a 1 MHz memory clock keeps every ray waiting far longer than the watchdog allows).
TEST(RtsimTiming, WatchdogStopsARunWithoutProgress) {
    TempDir dir;
    const std::string stats = dir.file("s.json");
    const Result r = rtsim(dir, "--scene cornell --fidelity at --width 8 --height 8 --set sim.watchdog=20000 --set gpu.memory_clock_mhz=1 --stats " + stats);
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find("no ray retired"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("rt_unit_"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("shader warp"), std::string::npos) << r.err;
    EXPECT_FALSE(exists(stats));
}

TEST(RtsimTiming, VcdHasTheDocumentedSignals) {
    TempDir dir;
    const Result r = rtsim(dir, "--scene cornell --fidelity at --width 16 --height 16 --vcd " + dir.file("w.vcd") + " --trace-warp 1:2");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string vcd = read_text(dir.file("w.vcd"));
    for (const char* s : {"warp_buffer_occupancy", "memory_access_queue_depth", "response_fifo_depth", "active_threads",
                          "mshr_occupancy", "miss_rate_window", "queue_depth", "bandwidth_utilisation_window"})
        EXPECT_NE(vcd.find(s), std::string::npos) << s;
    EXPECT_NE(vcd.find("$scope module warp2 $end"), std::string::npos);
    size_t stacks = 0;
    for (size_t at = vcd.find("stack_depth"); at != std::string::npos; at = vcd.find("stack_depth", at + 1)) ++stacks;
    EXPECT_EQ(stacks, 32u);  // one per thread of the traced warp
    EXPECT_EQ(r.err.find("Warning"), std::string::npos) << r.err;
}

// Observing never changes results: a run with waveforms (and a traced warp) gives the same
// statistics as one without, in AT and LT, with and without a prefetcher. Before, the monitor
// woke every trace window only when tracing, and its extra events reordered the kernel's
// same-time processes: wknd 128x128 under paper with TTP took 69,744 cycles traced, 70,115 not.
// rt.merge_in_flight in every timing fidelity (the RT unit's own case is hand-worked in
// RtUnitCore.AReadJoinsTheWarpsReadOfTheSameChunkInFlight): on a path-traced wknd frame each
// fidelity merges reads into its warps' chunks in flight, so it requests fewer chunks than
// unmerged, with every ray's nodes and hits unchanged, and a response for every request.
namespace {
// A small path-traced wknd frame under `paper` in `fidelity` (48x48; under the sanitizers 32x32,
// half the time, unless `side` is given), with `--set without` and with `--set with`: both runs'
// statistics.
std::pair<nlohmann::json, nlohmann::json> wknd_without_and_with(TempDir& dir, const std::string& fidelity, const std::string& without,
                                                                const std::string& with, std::string side = "") {
    if (side.empty()) side = rtu::test::kSanitized ? "32" : "48";
    const std::string args = "--scene wknd --width " + side + " --height " + side + " --config paper --fidelity " + fidelity;
    const std::string off = dir.file(fidelity + "-off.json"), on = dir.file(fidelity + "-on.json");
    EXPECT_EQ(rtsim(dir, args + " --set " + without + " --stats " + off).status, 0) << fidelity << " " << without;
    EXPECT_EQ(rtsim(dir, args + " --set " + with + " --stats " + on).status, 0) << fidelity << " " << with;
    return {nlohmann::json::parse(read_text(off)), nlohmann::json::parse(read_text(on))};
}
}  // namespace

// workload.shader_reads in every timing fidelity: the shader code's reads go through each SM's
// L1, L2 and DRAM. Counted against the frame's rays (per ray, less under one sector per SM of
// fraction); each a fresh sector, so every one misses L1 and L2, and the DRAM reads are the L2's
// misses of all three kinds (a conservation law of the read-only memory system); the rays'
// nodes and hits do not change, the frame takes longer. Given rays run no shader code: none.
// A sampled run's clusters read them after their own traces, by the same law over the rays they
// simulate (docs/sampling.md measures such samples' intervals).
TEST(RtsimTiming, ShaderReadsGoThroughL1L2AndDram) {
    TempDir dir;
    auto misses = [](const nlohmann::json& c) { return c["sector_misses"].get<uint64_t>() + c["line_misses"].get<uint64_t>(); };
    for (const std::string fidelity : {"at", "lt", "interval"}) {
        const auto [a, b] = wknd_without_and_with(dir, fidelity, "workload.shader_reads=0", "workload.shader_reads=2.5");
        const auto &t = b["timing"], &l1 = t["l1"]["shader"], &l2 = t["l2"]["shader"];
        const uint64_t reads = t["rt_unit"]["shader_reads"].get<uint64_t>(), rays = b["rays"].get<uint64_t>();
        EXPECT_EQ(a["timing"]["rt_unit"]["shader_reads"].get<uint64_t>(), 0u) << fidelity;
        EXPECT_LE(reads, rays * 5 / 2) << fidelity;
        EXPECT_GT(reads + 8, rays * 5 / 2) << fidelity;  // 8 SMs, each under one sector short
        EXPECT_EQ(l1["accesses"].get<uint64_t>() - l1["reservation_fails"].get<uint64_t>(), reads) << fidelity;
        EXPECT_EQ(misses(l1), reads) << fidelity;
        EXPECT_EQ(misses(l2), reads) << fidelity;
        uint64_t l2_misses = 0;
        for (const char* k : {"demand", "prefetch", "shader"}) l2_misses += misses(t["l2"][k]);
        EXPECT_EQ(t["dram"]["reads"].get<uint64_t>(), l2_misses) << fidelity;
        EXPECT_GT(b["cycles"].get<uint64_t>(), a["cycles"].get<uint64_t>()) << fidelity;
        for (const char* k : {"rays", "hits", "nodes_visited", "max_nodes_per_ray"}) EXPECT_EQ(a[k], b[k]) << fidelity << " " << k;
    }
    const std::string rays = write_text(dir.file("rays.txt"), "278 278 800 0 0 -1 0 inf\n278 278 800 0.1 0 -1 0 inf\n");
    const std::string given = dir.file("given.json");
    ASSERT_EQ(rtsim(dir, "--scene cornell --rays " + rays + " --fidelity at --set workload.shader_reads=4 --stats " + given).status, 0);
    EXPECT_EQ(nlohmann::json::parse(read_text(given))["timing"]["rt_unit"]["shader_reads"].get<uint64_t>(), 0u);
    // Sampled: the clusters' own rays (the statistics' `rays`) read, by the same law; and the
    // simulated share takes longer than without them.
    const std::string sampled = dir.file("sampled.json"), sampled_off = dir.file("sampled-off.json");
    const std::string sample = "--scene wknd --width 96 --height 96 --fidelity interval --sample 0.5 --sample-unchecked --stats ";
    ASSERT_EQ(rtsim(dir, sample + sampled + " --set workload.shader_reads=2").status, 0);
    ASSERT_EQ(rtsim(dir, sample + sampled_off).status, 0);
    const nlohmann::json s = nlohmann::json::parse(read_text(sampled)), s_off = nlohmann::json::parse(read_text(sampled_off));
    const auto& sampling = s["timing"]["sampling"];
    ASSERT_LT(sampling["warps_simulated"].get<uint64_t>(), sampling["warps_total"].get<uint64_t>());
    const uint64_t simulated = s["timing"]["rt_unit"]["shader_reads"].get<uint64_t>(), sampled_rays = s["rays"].get<uint64_t>();
    EXPECT_LE(simulated, sampled_rays * 2);
    EXPECT_GT(simulated + 8, sampled_rays * 2);
    EXPECT_GT(sampling["cycles_simulated"].get<uint64_t>(), s_off["timing"]["sampling"]["cycles_simulated"].get<uint64_t>());
}

// The interval fidelity sends the shader code's reads in time order with the RT units' reads, as
// AT does: on frames whose time the shaders' reads dominate (ship's primary rays at 48x48 to
// 96x96 under `paper` with 20 sectors a ray), its cycles stay within 5 % of AT's on average.
// Booked all at once at each trace's end, the reads took the L2's and DRAM's slots ahead of
// earlier RT-unit reads and the interval run came out 13.6 % slow at 64x64. One frame alone is no
// measure here: the DRAM is saturated (queue waits 400 cycles a read in AT), where the interval
// fidelity books no request queue and no FR-FCFS reordering (docs/interval.md), so its error
// moves with each frame's order of arrivals: per size (48, 56, 64, 72, 80, 96) +1.3, +7.5, +1.5,
// +7.0, +9.0, +1.0 % with rtsim 3d0f1e4, -0.5, +7.2, +4.7, +0.5, +3.4, +0.5 % since the response
// FIFO drains in arrival order. The L1 here is the one the defect was found with, so that the
// order at L2 and DRAM is what shows: the reads fill four sectors a line
// (workload.shader_lines_per_read=0.25), lines are allocated at the miss and the miss queue is
// unbounded. With the preset's streaming L1 (allocation at the fill, 16 misses queued) and
// scattered lines, the interval run is 5.8 % fast on 64x64: AT's L1 sends one miss a cycle and
// two ports' misses queue for it, which no fast fidelity books (the error grid measures what that
// costs on the preset's own frames, docs/accuracy.md).
TEST(RtsimTiming, IntervalShaderReadsKeepAtsPace) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    double error_sum = 0;
    const std::vector<std::string> sizes = {"48", "64", "80", "96"};
    for (const std::string& n : sizes) {
        const std::string base = "--scene ship --assets " + rtu::test::shared_dir() + "/scenes/ship --workload primary --width " + n +
                                 " --height " + n +
                                 " --config paper --set workload.shader_reads=20 --set workload.shader_lines_per_read=0.25 "
                                 "--set l1.allocation=miss --set l1.miss_queue=0 --set l2.miss_queue=0 --fidelity ";
        uint64_t cycles[2], reads[2];
        const char* fidelities[2] = {"at", "interval"};
        for (int i = 0; i < 2; ++i) {
            const std::string stats = dir.file(std::string(fidelities[i]) + ".json");
            ASSERT_EQ(rtsim(dir, base + fidelities[i] + " --stats " + stats).status, 0) << fidelities[i] << " " << n;
            const auto j = nlohmann::json::parse(read_text(stats));
            cycles[i] = j["cycles"].get<uint64_t>();
            reads[i] = j["timing"]["rt_unit"]["shader_reads"].get<uint64_t>();
        }
        EXPECT_EQ(reads[0], reads[1]) << n;
        EXPECT_GT(reads[0], 0u) << n;
        const double error = double(cycles[1]) / double(cycles[0]) - 1.0;
        error_sum += std::abs(error);
        std::printf("%sx%s: AT %llu cycles, interval %llu (%+.2f %%)\n", n.c_str(), n.c_str(), (unsigned long long)cycles[0],
                    (unsigned long long)cycles[1], 100 * error);
    }
    EXPECT_LT(error_sum / double(sizes.size()), 0.05);
}

// l1.miss_queue and l2.miss_queue in AT (GPGPU-Sim's miss queue): a read that would miss while the
// queue holds its size less one is refused and retried, the RT unit's (its END_REQ withheld) and
// the shaders' alike. Nothing is lost: every shader read is looked up once more per refusal
// (accesses = reads + reservation fails), and the rays' nodes and hits stay; a queue of 2 refuses
// reads that an unbounded one takes, and the frame takes longer (48x48 under the sanitizers too:
// on 32x32 the refusals' new order made that frame 0.2 % shorter).
TEST(RtsimTiming, AFullMissQueueRefusesReadsAndLosesNone) {
    TempDir dir;
    // Without the intersection loops, which spread the traces out (0.2 % shorter with the queue of 2 on 48x48).
    const std::string set = " --set workload.shader_reads=8 --set workload.intersection_latency=0";
    const auto [a, b] = wknd_without_and_with(dir, "at", "l1.miss_queue=0 --set l2.miss_queue=0" + set, "l1.miss_queue=2 --set l2.miss_queue=2" + set, "48");
    uint64_t fails[2];
    for (int i = 0; i < 2; ++i) {
        const auto& t = (i ? b : a)["timing"];
        const auto& l1 = t["l1"]["shader"];
        fails[i] = l1["reservation_fails"].get<uint64_t>() + t["l1"]["demand"]["reservation_fails"].get<uint64_t>() +
                   t["l2"]["demand"]["reservation_fails"].get<uint64_t>();
        EXPECT_EQ(l1["accesses"].get<uint64_t>(), t["rt_unit"]["shader_reads"].get<uint64_t>() + l1["reservation_fails"].get<uint64_t>());
        EXPECT_GT(t["rt_unit"]["shader_reads"].get<uint64_t>(), 8 * (i ? b : a)["rays"].get<uint64_t>() - 64);
    }
    EXPECT_EQ(a["timing"]["l1"]["shader"]["reservation_fails"].get<uint64_t>(), 0u);  // 4,096 MSHRs, ways taken at the fill
    EXPECT_GT(fails[1], fails[0] + 100);
    EXPECT_GT(b["cycles"].get<uint64_t>(), a["cycles"].get<uint64_t>());
    for (const char* k : {"rays", "hits", "nodes_visited", "max_nodes_per_ray"}) EXPECT_EQ(a[k], b[k]) << k;
}

// workload.intersection_latency in every timing fidelity: wknd's rays reach procedural leaves,
// and each trace is followed by its warp's intersection loop, so the frame takes longer with the
// same rays, hits and nodes; a triangle scene (cornell) has no candidates, and its statistics do
// not change. A sampled run cannot estimate the loops (its schedule model has none): refused.
TEST(RtsimTiming, IntersectionLoopsFollowProceduralTracesOnly) {
    TempDir dir;
    for (const std::string fidelity : {"at", "lt", "interval"}) {
        const auto [a, b] = wknd_without_and_with(dir, fidelity, "workload.intersection_latency=0", "workload.intersection_latency=3000");
        EXPECT_GT(b["cycles"].get<uint64_t>(), a["cycles"].get<uint64_t>()) << fidelity;
        for (const char* k : {"rays", "hits", "nodes_visited", "max_nodes_per_ray"}) EXPECT_EQ(a[k], b[k]) << fidelity << " " << k;
    }
    const std::string cornell = "--scene cornell --width 32 --height 32 --config paper --fidelity interval --stats ";
    ASSERT_EQ(rtsim(dir, cornell + dir.file("c0.json")).status, 0);
    ASSERT_EQ(rtsim(dir, cornell + dir.file("c1.json") + " --set workload.intersection_latency=3000").status, 0);
    EXPECT_EQ(model_stats(dir.file("c0.json")), model_stats(dir.file("c1.json")));
    const Result sampled = rtsim(dir, "--scene wknd --width 96 --height 96 --fidelity interval --sample 0.5 --sample-unchecked "
                                      "--set workload.intersection_latency=3000 --stats " + dir.file("s.json"));
    EXPECT_EQ(sampled.status, 2) << sampled.err;
    EXPECT_NE(sampled.err.find("intersection loops"), std::string::npos) << sampled.err;
    EXPECT_FALSE(exists(dir.file("s.json")));
}

// workload.shader_contention in every timing fidelity: the warps of an SM in shader code together
// slow each other, so the frame takes longer with the same rays, hits and nodes. A sample's
// schedule model counts the warps in shader code among an SM's resident warps: without a limit
// of them (mobile's 0) a sampled run is refused; with one it runs.
TEST(RtsimTiming, ShaderContentionSlowsTheWarpsOfAnSm) {
    TempDir dir;
    for (const std::string fidelity : {"at", "lt", "interval"}) {
        const auto [a, b] = wknd_without_and_with(dir, fidelity, "workload.shader_contention=0", "workload.shader_contention=0.3");
        EXPECT_GT(b["cycles"].get<uint64_t>(), a["cycles"].get<uint64_t>()) << fidelity;
        for (const char* k : {"rays", "hits", "nodes_visited", "max_nodes_per_ray"}) EXPECT_EQ(a[k], b[k]) << fidelity << " " << k;
    }
    const std::string sample = "--scene cornell --width 96 --height 96 --config mobile --fidelity interval --sample 0.5 --sample-unchecked "
                               "--set workload.shader_contention=0.3 --stats ";
    const Result refused = rtsim(dir, sample + dir.file("s.json"));
    EXPECT_EQ(refused.status, 2) << refused.err;
    EXPECT_NE(refused.err.find("resident warps"), std::string::npos) << refused.err;
    EXPECT_FALSE(exists(dir.file("s.json")));
    const Result resident = rtsim(dir, sample + dir.file("r.json") + " --set workload.resident_warps=4");
    EXPECT_EQ(resident.status, 0) << resident.err;
}

TEST(RtsimTiming, MergingReadsInFlightChangesNoHitInAnyFidelity) {
    TempDir dir;
    for (const std::string fidelity : {"at", "lt", "interval"}) {
        const auto [a, b] = wknd_without_and_with(dir, fidelity, "rt.merge_in_flight=false", "rt.merge_in_flight=true");
        const auto &ra = a["timing"]["rt_unit"], &rb = b["timing"]["rt_unit"];
        EXPECT_EQ(ra["merged_in_flight"].get<uint64_t>(), 0u) << fidelity;
        EXPECT_GT(rb["merged_in_flight"].get<uint64_t>(), 100u) << fidelity;
        EXPECT_LT(rb["chunk_requests"].get<uint64_t>(), ra["chunk_requests"].get<uint64_t>()) << fidelity;
        EXPECT_EQ(rb["chunk_requests"], rb["responses"]) << fidelity;
        for (const char* k : {"rays", "hits", "nodes_visited", "max_nodes_per_ray"}) EXPECT_EQ(a[k], b[k]) << fidelity << " " << k;
        EXPECT_EQ(ra["node_fetches"], rb["node_fetches"]) << fidelity;
    }
}

// --timeline (issue 49): one warp-buffer slot's threads as Chrome trace events. Recording changes
// no statistic (AT and LT); the file is one JSON object whose events are the slot's 32 threads'
// spans, each thread's in time order without overlap, named by status (and a fetch by where it
// was served), with TTP's prefetches as instants; the interval fidelity refuses it.
TEST(RtsimTiming, TimelineChangesNoStatistic) {
    TempDir dir;
    for (const std::string fidelity : {"at", "lt"}) {
        const std::string args = "--scene wknd --width 64 --height 64 --config paper --prefetcher ttp --fidelity " + fidelity;
        const std::string a = dir.file(fidelity + "-plain.json"), b = dir.file(fidelity + "-timed.json"), t = dir.file(fidelity + "-timeline.json");
        ASSERT_EQ(rtsim(dir, args + " --stats " + a).status, 0) << fidelity;
        const Result r = rtsim(dir, args + " --stats " + b + " --timeline " + t + " --trace-warp 1:2");
        ASSERT_EQ(r.status, 0) << fidelity << r.err;
        auto ja = nlohmann::json::parse(read_text(a)), jb = nlohmann::json::parse(read_text(b));
        erase_host_keys(ja);
        erase_host_keys(jb);
        EXPECT_EQ(ja, jb) << fidelity;
        const auto tl = nlohmann::json::parse(read_text(t));
        std::map<int, uint64_t> thread_end;
        std::map<std::string, int> names;
        for (const auto& e : tl["traceEvents"]) {
            if (e["ph"] == "M") continue;
            EXPECT_EQ(e["pid"], 1) << fidelity;
            const int tid = e["tid"].get<int>();
            EXPECT_TRUE(tid >= 0 && tid < 32) << tid;
            ++names[e["name"].get<std::string>()];
            if (e["ph"] != "X") continue;
            const uint64_t ts = e["ts"].get<uint64_t>(), dur = e["dur"].get<uint64_t>();
            EXPECT_GT(dur, 0u);
            EXPECT_GE(ts, thread_end[tid]) << fidelity << " thread " << tid << ": spans overlap";
            thread_end[tid] = ts + dur;
        }
        EXPECT_EQ(thread_end.size(), 32u) << fidelity;
        for (const auto& [name, n] : names)
            EXPECT_TRUE(name == "schedule" || name == "test" || name == "prefetch" || name.rfind("fetch: ", 0) == 0) << name;
        EXPECT_GT(names["test"], 100) << fidelity;
        EXPECT_GT(names["fetch: L1 hit"] + names["fetch: L1 miss"] + names["fetch: DRAM"], 100) << fidelity;
        EXPECT_GT(names["prefetch"], 0) << fidelity;
        uint64_t last = 0;
        for (const auto& [tid, end] : thread_end) last = std::max(last, end);
        EXPECT_LE(last, jb["cycles"].get<uint64_t>()) << fidelity;
    }
    const Result r = rtsim(dir, "--scene wknd --width 32 --height 32 --fidelity interval --timeline " + dir.file("i.json"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("--timeline"), std::string::npos) << r.err;
}

TEST(RtsimTiming, TracingChangesNoStatistic) {
    TempDir dir;
    // The first run is the frame the reordering showed on, as it was then (without the shaders'
    // reads, which `paper` has since e1301b4 and which cost CI time here); `desktop` has them, so
    // the second run traces the shader ports.
    const char* runs[] = {
        "--scene wknd --fidelity at --config paper --set workload.shader_reads=0 --prefetcher ttp --width 128 --height 128",
        "--scene cornell --fidelity at --config desktop --width 32 --height 32",
        "--scene wknd --fidelity lt --width 32 --height 32 --prefetcher ttp",
    };
    int n = 0;
    for (const char* args : runs) {
        const std::string a = dir.file("plain" + std::to_string(n) + ".json"), b = dir.file("traced" + std::to_string(n) + ".json");
        ASSERT_EQ(rtsim(dir, std::string(args) + " --stats " + a).status, 0) << args;
        const Result r = rtsim(dir, std::string(args) + " --stats " + b + " --vcd " + dir.file("t" + std::to_string(n) + ".vcd") +
                                        " --trace-warp 0:1");
        ASSERT_EQ(r.status, 0) << args << r.err;
        auto ja = nlohmann::json::parse(read_text(a)), jb = nlohmann::json::parse(read_text(b));
        for (auto* j : {&ja, &jb})
            erase_host_keys(*j);
        EXPECT_EQ(ja["cycles"], jb["cycles"]) << args;
        EXPECT_EQ(ja, jb) << args;
        // The trace ends where the frame does (its last value change), not at the kernel's time
        // at the end (the monitor's last wake-up, up to 100,000 cycles later): a viewer's zoom
        // to fit shows the frame. The last ray retires at `cycles`; a change may follow within
        // a few hundred cycles (responses still in flight), never a whole monitor period. LT's
        // values change at quantum boundaries (1,000 cycles), so its last change may come up to
        // a quantum and the last trace's few hundred cycles before.
        uint64_t last_fs = 0;
        for (const std::string& line : lines(read_text(dir.file("t" + std::to_string(n) + ".vcd"))))
            if (!line.empty() && line[0] == '#') last_fs = std::stoull(line.substr(1));
        const double period_fs = 1e9 / jb["config"]["gpu"]["core_clock_mhz"].get<double>();  // 1 MHz: 1e9 fs
        const double end_cycle = double(last_fs) / period_fs;
        EXPECT_GE(end_cycle, jb["cycles"].get<double>() - 2000.0) << args;
        EXPECT_LE(end_cycle, jb["cycles"].get<double>() + 1000.0) << args;
        ++n;
    }
}

// sim.trace_window sets how often the windowed waveforms (MSHR occupancy, miss rate, DRAM
// bandwidth) are sampled, and nothing else: a tenth of the window gives more value changes of
// those signals, and the same statistics but the key itself.
TEST(RtsimTiming, TraceWindowSetsTheWaveformSamplingOnly) {
    TempDir dir;
    const std::string args = "--scene cornell --fidelity at --width 32 --height 32 --vcd ";
    auto window_changes = [](const std::string& vcd) {  // value changes of the *_window signals
        std::set<std::string> ids;
        size_t changes = 0;
        for (const std::string& line : lines(vcd)) {
            std::istringstream ls(line);
            std::vector<std::string> t{std::istream_iterator<std::string>(ls), std::istream_iterator<std::string>()};
            if (t.size() >= 5 && t[0] == "$var" && t[4].find("_window") != std::string::npos) ids.insert(t[3]);
            else if (t.size() == 2 && (t[0][0] == 'r' || t[0][0] == 'b') && ids.count(t[1])) ++changes;
        }
        return changes;
    };
    ASSERT_EQ(rtsim(dir, args + dir.file("a.vcd") + " --stats " + dir.file("a.json")).status, 0);
    ASSERT_EQ(rtsim(dir, args + dir.file("b.vcd") + " --stats " + dir.file("b.json") + " --set sim.trace_window=100").status, 0);
    const size_t coarse = window_changes(read_text(dir.file("a.vcd"))), fine = window_changes(read_text(dir.file("b.vcd")));
    EXPECT_GT(coarse, 0u);
    EXPECT_GT(fine, 2 * coarse) << "window 100: " << fine << " changes, window 1000: " << coarse;
    auto ja = nlohmann::json::parse(read_text(dir.file("a.json"))), jb = nlohmann::json::parse(read_text(dir.file("b.json")));
    EXPECT_EQ(jb["config"]["sim"]["trace_window"], 100);
    for (auto* j : {&ja, &jb}) {
        erase_host_keys(*j);
        (*j)["config"]["sim"].erase("trace_window");
    }
    EXPECT_EQ(ja, jb);
}

// Prefetchers change timing, never answers: the hits file is the same under every prefetcher
// and both traversal orders; a TTP that prefetches nothing (all depths 0) costs exactly nothing.
TEST(RtsimPrefetch, HitsIdenticalUnderEveryPrefetcherAndNoneIsTheBaseline) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string bunny = rtu::test::shared_dir() + "/scenes/bunny";
    const std::string base = "--scene bunny --assets " + bunny + " --fidelity at --width 16 --height 16 ";
    ASSERT_EQ(rtsim(dir, base + "--hits " + dir.file("ref.csv") + " --stats " + dir.file("ref.json")).status, 0);
    const std::string ref = read_text(dir.file("ref.csv"));
    for (const std::string traversal : {"dfs", "bfs"})
        for (const std::string pf : {"none", "ttp", "park", "perfect-up", "perfect-down"}) {
            const std::string hits = dir.file(pf + traversal + ".csv");
            const Result r = rtsim(dir, base + "--traversal " + traversal + " --prefetcher " + pf + " --hits " + hits);
            ASSERT_EQ(r.status, 0) << pf << " " << traversal << ": " << r.err;
            if (traversal == "dfs") {
                EXPECT_EQ(read_text(hits), ref) << pf;
            } else {
                // BFS may pick another primitive at exact ties; hit/miss and t never differ.
                const auto a = lines(read_text(hits)), b = lines(ref);
                ASSERT_EQ(a.size(), b.size());
                for (size_t i = 0; i < a.size(); ++i) {
                    auto cut = [](const std::string& l) { return l.substr(0, l.find(',', l.find(',', l.find(',') + 1) + 1)); };
                    EXPECT_EQ(cut(a[i]), cut(b[i])) << pf << " line " << i;
                }
            }
        }
    const Result none = rtsim(dir, base + "--prefetcher none --stats " + dir.file("none.json"));
    const Result zero = rtsim(dir, base + "--prefetcher ttp --set prefetch.ttp_depth_s1=0 --set prefetch.ttp_depth_s2=0 "
                                          "--set prefetch.ttp_depth_s3=0 --stats " + dir.file("zero.json"));
    ASSERT_EQ(none.status, 0);
    ASSERT_EQ(zero.status, 0);
    const auto jr = nlohmann::json::parse(read_text(dir.file("ref.json")));
    const auto jn = nlohmann::json::parse(read_text(dir.file("none.json")));
    const auto jz = nlohmann::json::parse(read_text(dir.file("zero.json")));
    EXPECT_EQ(jn["cycles"], jr["cycles"]);
    EXPECT_EQ(jz["cycles"], jr["cycles"]);
    EXPECT_EQ(jz["timing"]["rt_unit"]["prefetch_queue"]["sent"], 0);
    EXPECT_EQ(jn["timing"]["l1"], jr["timing"]["l1"]);
}

// The Treelet prefetcher needs treelet traversal; with it, answers are still the DFS answers.
// The interval fidelity under DFS and BFS, with and without TTP: the same hits as AT's (BFS: the
// same hit/miss and t), and TTP with every depth 0 is the baseline, cycle for cycle.
TEST(RtsimPrefetch, IntervalHitsIdenticalAndZeroDepthTtpIsTheBaseline) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string base = "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --width 16 --height 16 ";
    for (const std::string traversal : {"dfs", "bfs"}) {
        const std::string ref = dir.file("at" + traversal + ".csv");
        ASSERT_EQ(rtsim(dir, base + "--fidelity at --traversal " + traversal + " --hits " + ref).status, 0);
        for (const std::string pf : {"none", "ttp"}) {
            const std::string hits = dir.file(pf + traversal + ".csv");
            const Result r = rtsim(dir, base + "--fidelity interval --traversal " + traversal + " --prefetcher " + pf + " --hits " + hits);
            ASSERT_EQ(r.status, 0) << pf << " " << traversal << ": " << r.err;
            EXPECT_EQ(read_text(hits), read_text(ref)) << pf << " " << traversal;
        }
    }
    ASSERT_EQ(rtsim(dir, base + "--fidelity interval --stats " + dir.file("none.json")).status, 0);
    ASSERT_EQ(rtsim(dir, base + "--fidelity interval --prefetcher ttp --set prefetch.ttp_depth_s1=0 --set prefetch.ttp_depth_s2=0 "
                                "--set prefetch.ttp_depth_s3=0 --stats " + dir.file("zero.json")).status, 0);
    const auto jn = nlohmann::json::parse(read_text(dir.file("none.json")));
    const auto jz = nlohmann::json::parse(read_text(dir.file("zero.json")));
    EXPECT_EQ(jz["cycles"], jn["cycles"]);
    EXPECT_EQ(jz["timing"]["rt_unit"]["prefetch_queue"]["generated"], 0);
    EXPECT_EQ(jz["timing"]["l1"]["demand"], jn["timing"]["l1"]["demand"]);
}

TEST(RtsimPrefetch, TreeletTraversalAndPrefetcher) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    // Primary rays: each independent of the others (with path tracing a tie at one bounce,
    // resolved to another duplicated face, changes the next ray).
    const std::string base = "--scene ship --assets " + rtu::test::shared_dir() + "/scenes/ship --workload primary --width 32 --height 32 ";
    ASSERT_EQ(rtsim(dir, base + "--hits " + dir.file("dfs.csv")).status, 0);
    const Result r = rtsim(dir, base + "--fidelity at --traversal treelet --prefetcher treelet --hits " + dir.file("t.csv") +
                                    " --stats " + dir.file("t.json"));
    ASSERT_EQ(r.status, 0) << r.err;
    const auto a = lines(read_text(dir.file("dfs.csv"))), b = lines(read_text(dir.file("t.csv")));
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        auto cut = [](const std::string& l) { return l.substr(0, l.find(',', l.find(',', l.find(',') + 1) + 1)); };
        EXPECT_EQ(cut(a[i]), cut(b[i])) << "line " << i;  // ray, hit, t (ties may pick another primitive)
    }
    const auto j = nlohmann::json::parse(read_text(dir.file("t.json")));
    EXPECT_GT(j["timing"]["rt_unit"]["prefetch_queue"]["sent"].get<uint64_t>(), 0u);
    const Result bad = rtsim(dir, base + "--fidelity at --prefetcher treelet");
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("--traversal treelet"), std::string::npos) << bad.err;
}

// A sample that cannot carry an interval (fewer than 10 drawn strata) is refused before anything
// runs or is written, with the smallest rate and frame that work; --sample-unchecked runs it and
// reports no interval. A draw of no stratum beside the first wave is refused even unchecked: it
// has nothing to extrapolate the rest of the frame from (the bunny mesh under its automatic
// camera, where most pixels see no geometry, 64x64, sample 10 %, seed 4, used to exit 0 with 0
// cycles).
TEST(RtsimSampling, RefusesASampleWithoutAnIntervalOrWithoutWork) {
    TempDir dir;
    // 128x128: 512 warps (a thread traces one pixel's samples, as LumiBench's), 16 clusters of 32;
    // a half is the first wave and 7 strata.
    const std::string wknd = "--scene wknd --fidelity at --width 128 --height 128 --sample 0.5 ";
    const Result few = rtsim(dir, wknd + "--stats " + dir.file("a.json") + " --image " + dir.file("a.png"));
    EXPECT_EQ(few.status, 2);
    EXPECT_NE(few.err.find("draws 7 strata"), std::string::npos) << few.err;
    EXPECT_NE(few.err.find("at least 10 strata"), std::string::npos) << few.err;
    EXPECT_NE(few.err.find("--sample 0.657"), std::string::npos) << few.err;  // 10.5 / 16 clusters
    EXPECT_NE(few.err.find("--sample-unchecked"), std::string::npos) << few.err;
    EXPECT_FALSE(exists(dir.file("a.json")));
    EXPECT_FALSE(exists(dir.file("a.png")));
    const Result unchecked = rtsim(dir, wknd + "--sample-unchecked --stats " + dir.file("b.json"));
    ASSERT_EQ(unchecked.status, 0) << unchecked.err;
    EXPECT_NE(unchecked.out.find("no interval"), std::string::npos) << unchecked.out;
    const auto j = nlohmann::json::parse(read_text(dir.file("b.json")));
    EXPECT_TRUE(j["timing"]["sampling"]["cycles_ci95"].is_null());
    EXPECT_EQ(j["timing"]["sampling"]["strata"], 7);
    EXPECT_GT(j["cycles"].get<uint64_t>(), j["timing"]["sampling"]["cycles_simulated"].get<uint64_t>());
    EXPECT_EQ(rtsim(dir, "--scene wknd --fidelity at --sample-unchecked").status, 2);  // needs --sample
    // 64x32: two clusters, the first wave and one more; a half draws none beside the first wave.
    const Result none = rtsim(dir, "--scene wknd --fidelity at --width 64 --height 32 --sample 0.5 --sample-unchecked");
    EXPECT_EQ(none.status, 2);
    EXPECT_NE(none.err.find("draws no cluster beside the first wave"), std::string::npos) << none.err;

    RTU_NEED_SHARED_SCENES();
    const std::string mesh = "--scene " + rtu::test::shared_dir() + "/scenes/bunny/stanford-bunny.obj --fidelity at --width 64 "
                             "--height 64 --sample 0.1 --sample-seed 4 --sample-unchecked --stats " + dir.file("c.json");
    const Result empty = rtsim(dir, mesh);
    EXPECT_EQ(empty.status, 2);
    EXPECT_NE(empty.err.find("draws no cluster"), std::string::npos) << empty.err;
    EXPECT_FALSE(exists(dir.file("c.json")));
}

// Sampled simulation: selecting the whole frame is the unsampled run, bit for bit; a half-frame
// sample reports its estimate with an interval and simulates about half the rays, whatever the
// number of pre-pass threads.
TEST(RtsimSampling, FullFrameSampleEqualsTheUnsampledRun) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string base = "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --fidelity at --width 64 --height 32 --spp 1 ";
    ASSERT_EQ(rtsim(dir, base + "--stats " + dir.file("full.json")).status, 0);
    ASSERT_EQ(rtsim(dir, base + "--sample 1 --stats " + dir.file("one.json")).status, 0);
    // 64x32 at 1 spp is 64 warps (a warp is 32 pixels), two clusters of 32: no rate gives 10
    // strata; the message names the smallest frame that does at this rate, 10.5 / 0.5 clusters.
    const Result refused = rtsim(dir, base + "--sample 0.5 --stats " + dir.file("refused.json"));
    EXPECT_EQ(refused.status, 2);
    EXPECT_NE(refused.err.find("at least 10 strata"), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("a frame of at least 672 shader warps"), std::string::npos) << refused.err;
    EXPECT_FALSE(exists(dir.file("refused.json")));
    auto full = nlohmann::json::parse(read_text(dir.file("full.json")));
    auto one = nlohmann::json::parse(read_text(dir.file("one.json")));
    EXPECT_FALSE(full["time_s"].contains("prepass"));  // no sample, no pre-pass
    for (auto* j : {&full, &one}) erase_host_keys(*j);
    EXPECT_EQ(full, one);
    EXPECT_FALSE(full["timing"].contains("sampling"));
    // The pre-pass's threads change nothing (128x256 at 1 spp: 1024 warps, 32 clusters; a half is
    // the first wave and 15 strata; primary rays under the sanitizers, whose clusters, empty or
    // not, are path tracing's: a path starts with its camera ray). The interval holds the
    // estimate and is not below the cycles simulated.
    std::vector<nlohmann::json> by_threads;
    for (const char* threads : {"1", "3"}) {
        const Result r = rtsim(dir, "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --fidelity at --width 128 "
                                    "--height 256 --spp 1 --sample 0.5 " + kSanitizedWorkload + "--threads " + threads + " --stats " + dir.file("t.json"));
        ASSERT_EQ(r.status, 0) << r.err;
        by_threads.push_back(nlohmann::json::parse(read_text(dir.file("t.json"))));
        const auto& t = by_threads.back();
        const auto& s = t["timing"]["sampling"];
        EXPECT_EQ(s["prepass_threads"].get<int>(), std::stoi(threads));
        EXPECT_EQ(s["warps_total"], 1024);
        EXPECT_EQ(s["cluster_warps"], 32);
        EXPECT_EQ(s["first_wave_clusters"], 1);
        EXPECT_EQ(s["strata"], 15);
        EXPECT_EQ(s["warps_simulated"].get<int>(), 32 * (1 + s["strata"].get<int>()));
        EXPECT_EQ(s["rate_simulated"].get<double>(), 0.5);  // 16 of 32 clusters
        EXPECT_GT(s["first_reads"]["frame_beyond_first_wave"].get<double>(), 0.0);  // counted, and the same on 1 and 3 threads
        const auto& ci = s["cycles_ci95"];
        ASSERT_TRUE(ci.is_array());
        EXPECT_GE(ci[0].get<double>(), s["cycles_simulated"].get<double>());
        EXPECT_LE(ci[0].get<double>(), t["cycles"].get<double>());
        EXPECT_GE(ci[1].get<double>(), t["cycles"].get<double>());
        // The pre-pass's wall time is part of the run's.
        EXPECT_GT(t["time_s"]["prepass"].get<double>(), 0.0);
        EXPECT_LE(t["time_s"]["prepass"].get<double>(), t["time_s"]["run"].get<double>());
        erase_host_keys(by_threads.back());
        by_threads.back()["timing"]["sampling"].erase("prepass_threads");
    }
    EXPECT_EQ(by_threads[0], by_threads[1]);
    EXPECT_EQ(rtsim(dir, base + "--sample 0").status, 2);
    EXPECT_EQ(rtsim(dir, base + "--sample 1.5").status, 2);
}

// Sampling on the interval fidelity, as on AT: the whole frame selected is the unsampled run,
// bit for bit. Half of the frame (cornell and the bunny, two draws each) simulates the same
// warps as AT's sample of the same draw, its estimate is within 3 % of AT's (the interval
// fidelity's accuracy; without the caches' warming cornell's is 14 % off), and its 95 % interval
// covers the full interval run's cycles.
TEST(RtsimSampling, IntervalFidelitySampledAsAt) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    // Under the sanitizers the bunny, the slower of the two scenes, is left to the Release suite.
    std::vector<std::string> scenes = {"cornell"};
    if (!rtu::test::kSanitized) scenes.push_back("bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny");
    for (const std::string& scene : scenes) {
        const std::string base = "--scene " + scene + " --workload pt --width 128 --height 256 --spp 1 --fidelity ";
        auto stats = [&](const std::string& args) {
            const Result r = rtsim(dir, base + args + " --stats " + dir.file("s.json"));
            EXPECT_EQ(r.status, 0) << r.err;
            auto j = nlohmann::json::parse(read_text(dir.file("s.json")));
            erase_host_keys(j);
            return j;
        };
        const auto full = stats("interval");
        EXPECT_EQ(stats("interval --sample 1"), full);
        const double truth = full["cycles"].get<double>();
        for (int seed = 1; seed <= 2; ++seed) {
            const std::string sample = " --sample 0.5 --sample-seed " + std::to_string(seed);
            const auto j = stats("interval" + sample);
            const auto at = stats("at" + sample);
            const auto& s = j["timing"]["sampling"];
            const double est = j["cycles"].get<double>(), lo = s["cycles_ci95"][0].get<double>(), hi = s["cycles_ci95"][1].get<double>();
            SCOPED_TRACE(scene + ", sample seed " + std::to_string(seed) + ": estimate " + std::to_string(est) + " [" +
                         std::to_string(lo) + ", " + std::to_string(hi) + "], AT's " + at["cycles"].dump() +
                         ", full interval run " + std::to_string(truth));
            EXPECT_EQ(s["estimator"], "schedule (functional pre-pass)");
            EXPECT_EQ(s["warps_simulated"].get<int>(), 32 * (1 + s["strata"].get<int>()));
            EXPECT_EQ(s["warps_simulated"], at["timing"]["sampling"]["warps_simulated"]);
            EXPECT_EQ(j["rays"], at["rays"]);
            EXPECT_EQ(j["hits"], at["hits"]);
            EXPECT_LT(std::fabs(est / at["cycles"].get<double>() - 1.0), 0.03);
            EXPECT_LE(lo, truth);
            EXPECT_GE(hi, truth);
        }
    }
}

// A sample split into segments (docs/sampling.md, "Segments"): the segments run as separate
// processes (as array tasks on a cluster would) and merged in any order give the same statistics,
// bit for bit, as rtsim --sample-segments alone, with its segments one at a time or three at once
// (AT: child processes; the interval fidelity: threads of the one process, which share its scene,
// BVH image and pre-pass); the segments together simulate the warps of
// the continuous sample, each once, and their cycles add up to the merged run's simulated
// cycles; the merged interval covers the full run. A sample plan (the pre-pass kept in a file)
// changes no statistic, and a plan of another frame is refused. Merging refuses a missing
// segment, a duplicate and a segment of another draw; a split of fewer than 16 clusters per
// segment is refused, or runs without an interval when unchecked.
TEST(RtsimSampling, SegmentsMergedEqualTheSingleProcessRun) {
    TempDir dir;
    // Under the sanitizers, the interval fidelity alone: the segments' code is the same for both,
    // and AT's sampled runs are checked there by other tests (FullFrameSampleEqualsTheUnsampledRun).
    const std::vector<std::string> fidelities = rtu::test::kSanitized ? std::vector<std::string>{"interval"}
                                                                      : std::vector<std::string>{"at", "interval"};
    for (const std::string& fidelity : fidelities) {
        SCOPED_TRACE(fidelity);
        // 512x256 at 1 spp: 128 clusters, 64 simulated, 21-22 per segment (16 needed).
        const std::string base = "--scene cornell --width 512 --height 256 --spp 1 --sample 0.5 --threads 1 " + kSanitizedWorkload +
                                 "--fidelity " + fidelity;
        const std::string split = base + " --sample-segments 3";
        auto load = [&](const std::string& f) {
            auto j = nlohmann::json::parse(read_text(dir.file(f)));
            erase_host_keys(j);
            return j;
        };
        const Result single = rtsim(dir, split + " --stats " + dir.file("single.json"));
        ASSERT_EQ(single.status, 0) << single.err;
        // The merge's pre-pass: the frame's, made before the segments (threads), or read from the
        // plan the first child wrote; part of the run's time.
        const auto timed = nlohmann::json::parse(read_text(dir.file("single.json")))["time_s"];
        EXPECT_GT(timed["prepass"].get<double>(), 0.0);
        EXPECT_LE(timed["prepass"].get<double>(), timed["run"].get<double>());
        uint64_t cycles = 0, rays = 0, warps = 0;
        std::set<uint64_t> simulated;
        for (int i = 0; i < 3; ++i) {
            const std::string f = "seg" + std::to_string(i) + ".json";
            const Result r = rtsim(dir, split + " --segment " + std::to_string(i) + " --stats " + dir.file(f));
            ASSERT_EQ(r.status, 0) << r.err;
            const auto j = load(f);
            EXPECT_FALSE(j["timing"].contains("sampling"));  // one segment is no estimate of the frame
            EXPECT_EQ(j["error_estimate"]["kind"], "none");
            EXPECT_EQ(j["cycles"], j["segment"]["cycles_simulated"]);
            cycles += j["segment"]["cycles_simulated"].get<uint64_t>();
            rays += j["rays"].get<uint64_t>();
            for (const auto& w : j["segment"]["warps"]) EXPECT_TRUE(simulated.insert(w[0].get<uint64_t>()).second) << "warp " << w[0];
            warps += j["segment"]["warps"].size();
        }
        const Result merged = rtsim(dir, split + " --merge-segments " + dir.file("seg2.json") + " " + dir.file("seg0.json") + " " +
                                             dir.file("seg1.json") + " --stats " + dir.file("merged.json"));
        ASSERT_EQ(merged.status, 0) << merged.err;
        const auto m = load("merged.json");
        EXPECT_EQ(m, load("single.json"));
        // The three segments at once (--threads 3; AT's children start when the first has written
        // the frame's plan, on its 3 threads; the interval fidelity's threads after the frame's
        // pre-pass on all 3): the same statistics, but for the record of the pre-pass's threads.
        {
            std::string split3 = split;
            split3.replace(split3.find("--threads 1"), 11, "--threads 3");
            const Result concurrent = rtsim(dir, split3 + " --stats " + dir.file("concurrent.json"));
            ASSERT_EQ(concurrent.status, 0) << concurrent.err;
            auto together = load("concurrent.json"), one = m;
            EXPECT_EQ(together["timing"]["sampling"]["prepass_threads"], 3);
            together["timing"]["sampling"].erase("prepass_threads");
            one["timing"]["sampling"].erase("prepass_threads");
            EXPECT_EQ(together, one);
        }
        // The same through a sample plan: the first segment writes the pre-pass, the others and
        // the merge read it; the statistics do not change.
        std::filesystem::remove(dir.file("plan.bin"));
        const std::string plan = " --sample-plan " + dir.file("plan.bin");
        for (int i = 0; i < 3; ++i)
            ASSERT_EQ(rtsim(dir, split + plan + " --segment " + std::to_string(i) + " --stats " + dir.file("p" + std::to_string(i) + ".json")).status, 0);
        EXPECT_TRUE(exists(dir.file("plan.bin")));
        for (int i = 0; i < 3; ++i) EXPECT_EQ(load("p" + std::to_string(i) + ".json"), load("seg" + std::to_string(i) + ".json")) << i;
        ASSERT_EQ(rtsim(dir, split + plan + " --merge-segments " + dir.file("p0.json") + " " + dir.file("p1.json") + " " + dir.file("p2.json") +
                                 " --stats " + dir.file("mp.json")).status, 0);
        EXPECT_EQ(load("mp.json"), m);
        // A plan of another frame, or not a plan, is refused.
        const Result foreign = rtsim(dir, split + plan + " --seed 9 --segment 0 --stats " + dir.file("f.json"));
        EXPECT_EQ(foreign.status, 2);
        EXPECT_NE(foreign.err.find("a sample plan of another frame or configuration"), std::string::npos) << foreign.err;
        write_text(dir.file("junk.bin"), "RTUPLAN3\x05");
        const Result junk = rtsim(dir, split + " --sample-plan " + dir.file("junk.bin") + " --segment 0 --stats " + dir.file("f.json"));
        EXPECT_EQ(junk.status, 2);
        EXPECT_NE(junk.err.find("cut short"), std::string::npos) << junk.err;
        EXPECT_FALSE(exists(dir.file("f.json")));
        const auto& s = m["timing"]["sampling"];
        // The schedule model's misfit per SM (mobile: 8) comes through the segment files.
        EXPECT_EQ(s["schedule_model_misfit_per_sm"].size(), 8u);
        // A segment file is sealed with a checksum of its contents (docs/sampling.md, "Segments"):
        // one changed digit, or no checksum, is refused, naming the file; nothing is written.
        {
            std::string text = read_text(dir.file("seg1.json"));
            const size_t at = text.find("\"l1_miss_nodes\": ") + 17;
            text[at] = text[at] == '1' ? '2' : '1';
            write_text(dir.file("flipped.json"), text);
            const Result flipped = rtsim(dir, split + " --merge-segments " + dir.file("seg0.json") + " " + dir.file("flipped.json") + " " +
                                                  dir.file("seg2.json") + " --stats " + dir.file("s.json"));
            EXPECT_EQ(flipped.status, 2);
            EXPECT_NE(flipped.err.find(dir.file("flipped.json") + ": a damaged segment file"), std::string::npos) << flipped.err;
            auto j = nlohmann::ordered_json::parse(read_text(dir.file("seg1.json")));
            j["segment"].erase("checksum");
            write_text(dir.file("unsealed.json"), j.dump());
            const Result unsealed = rtsim(dir, split + " --merge-segments " + dir.file("seg0.json") + " " + dir.file("unsealed.json") + " " +
                                                   dir.file("seg2.json") + " --stats " + dir.file("s.json"));
            EXPECT_EQ(unsealed.status, 2);
            EXPECT_NE(unsealed.err.find("without a checksum"), std::string::npos) << unsealed.err;
        }
        // Files without each warp's SM and last cycle (as rtsim wrote them before it kept them),
        // sealed again as the statistics reference says (FNV-1a of the compact JSON with the
        // checksum empty and without the host's keys, computed here), merge to the same estimate with the whole run's misfit
        // as the model's error.
        for (int i = 0; i < 3; ++i) {
            auto j = nlohmann::ordered_json::parse(read_text(dir.file("seg" + std::to_string(i) + ".json")));
            for (auto& w : j["segment"]["warps"]) w.erase(6), w.erase(5);
            j["segment"]["checksum"] = "";
            nlohmann::ordered_json model = j;
            for (const char* k : {"time_s", "simulation_rate", "memory_mb", "provenance"}) model.erase(k);
            uint64_t h = 14695981039346656037ull;
            for (const unsigned char c : model.dump()) h = (h ^ c) * 1099511628211ull;
            char hex[17];
            std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
            j["segment"]["checksum"] = hex;
            write_text(dir.file("old" + std::to_string(i) + ".json"), j.dump());
        }
        ASSERT_EQ(rtsim(dir, split + " --merge-segments " + dir.file("old0.json") + " " + dir.file("old1.json") + " " +
                                 dir.file("old2.json") + " --stats " + dir.file("mold.json")).status, 0);
        const auto old = load("mold.json");
        EXPECT_EQ(old["cycles"], m["cycles"]);
        EXPECT_TRUE(old["timing"]["sampling"]["schedule_model_misfit_per_sm"].empty());
        EXPECT_EQ(old["timing"]["sampling"]["schedule_model_error"], old["timing"]["sampling"]["schedule_model_misfit"]);
        EXPECT_EQ(s["cycles_simulated"].get<uint64_t>(), cycles);
        EXPECT_EQ(m["rays"].get<uint64_t>(), rays);
        EXPECT_EQ(s["warps_simulated"].get<uint64_t>(), warps);
        ASSERT_EQ(rtsim(dir, base + " --stats " + dir.file("continuous.json")).status, 0);
        const auto c = load("continuous.json");
        EXPECT_EQ(c["timing"]["sampling"]["warps_simulated"].get<uint64_t>(), warps);
        EXPECT_EQ(c["rays"], m["rays"]);
        ASSERT_EQ(rtsim(dir, "--scene cornell --width 512 --height 256 --spp 1 " + kSanitizedWorkload + "--fidelity " + fidelity + " --stats " +
                                 dir.file("full.json")).status, 0);
        const double truth = load("full.json")["cycles"].get<double>();
        EXPECT_LE(s["cycles_ci95"][0].get<double>(), truth) << m["cycles"];
        EXPECT_GE(s["cycles_ci95"][1].get<double>(), truth) << m["cycles"];
        // Refused: a segment missing, one twice, one of another draw of the sample.
        const Result missing = rtsim(dir, split + " --merge-segments " + dir.file("seg0.json") + " " + dir.file("seg1.json"));
        EXPECT_EQ(missing.status, 2);
        EXPECT_NE(missing.err.find("give each segment's statistics once"), std::string::npos) << missing.err;
        const Result twice = rtsim(dir, split + " --merge-segments " + dir.file("seg0.json") + " " + dir.file("seg1.json") + " " + dir.file("seg1.json"));
        EXPECT_EQ(twice.status, 2);
        EXPECT_NE(twice.err.find("segment 2 is missing"), std::string::npos) << twice.err;
        ASSERT_EQ(rtsim(dir, split + " --sample-seed 7 --segment 1 --stats " + dir.file("other.json")).status, 0);
        const Result other = rtsim(dir, split + " --merge-segments " + dir.file("seg0.json") + " " + dir.file("other.json") + " " + dir.file("seg2.json"));
        EXPECT_EQ(other.status, 2);
        EXPECT_NE(other.err.find("segment 1 is of another run: its sample is '0.5 seed 7'"), std::string::npos) << other.err;
        EXPECT_FALSE(exists(dir.file("s.json")));
    }
    // Options that cannot work: exit 2 before anything runs.
    const std::string wknd = "--scene wknd --fidelity at --width 128 --height 256 --spp 1 --sample 0.5 ";
    for (const std::string& bad : {std::string("--sample-segments 0"), std::string("--sample-segments -1"), std::string("--segment 0"),
                                   std::string("--sample-segments 2 --segment 2"), std::string("--sample-segments 2 --hits h.csv"),
                                   std::string("--sample-segments 17 --segment 0"), std::string("--sample-segments 2")}) {
        const Result r = rtsim(dir, wknd + bad + " --stats " + dir.file("bad.json"));
        EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
        EXPECT_FALSE(exists(dir.file("bad.json"))) << bad;
    }
    EXPECT_EQ(rtsim(dir, "--scene wknd --fidelity at --sample-segments 2").status, 2);  // needs --sample
    // 128x256 at 1 spp, at a half: 16 simulated clusters, 8 per segment of 2: refused (too few to
    // split); unchecked, it runs and reports no interval. 512x256 at a half: 64 clusters, at most 4
    // segments.
    const Result few = rtsim(dir, wknd + "--sample-segments 2 --segment 0");
    EXPECT_NE(few.err.find("8 per segment; a segment needs 16"), std::string::npos) << few.err;
    EXPECT_NE(few.err.find("too few to split"), std::string::npos) << few.err;
    const Result five = rtsim(dir, "--scene wknd --fidelity at --width 512 --height 256 --spp 1 --sample 0.5 --sample-segments 5 --segment 0");
    EXPECT_EQ(five.status, 2);
    EXPECT_NE(five.err.find("use --sample-segments 4 or fewer"), std::string::npos) << five.err;
    const Result unchecked = rtsim(dir, wknd + "--sample-segments 2 --sample-unchecked --stats " + dir.file("u.json"));
    ASSERT_EQ(unchecked.status, 0) << unchecked.err;
    EXPECT_TRUE(nlohmann::json::parse(read_text(dir.file("u.json")))["timing"]["sampling"]["cycles_ci95"].is_null());
}

// A sample plan holds the functional pre-pass, which depends on the frame and the traversal, not
// on the hardware: written by one run, it serves runs of the same frame in other fidelities,
// presets, SM counts, prefetchers and samples, whose statistics are then bit for bit those they
// have without it; a run that would trace the frame otherwise (another warp size, traversal,
// next-node register, flattening) refuses it.
TEST(RtsimSampling, APlanServesEveryRunOfTheFrameAndNoOther) {
    TempDir dir;
    // Under the sanitizers, 256x128 (32 clusters: 16 simulated, the first wave and 15 strata):
    // a plan is read alike whatever the frame's size, and the runs take a third of 512x256's time.
    const std::string size = rtu::test::kSanitized ? "--width 256 --height 128 " : "--width 512 --height 256 ";
    const std::string frame = "--scene cornell " + size + "--spp 1 --sample 0.5 --threads 1 " + kSanitizedWorkload;
    const std::string plan = " --sample-plan " + dir.file("plan.bin");
    auto load = [&](const std::string& f) {
        auto j = nlohmann::json::parse(read_text(dir.file(f)));
        erase_host_keys(j);
        return j;
    };
    ASSERT_EQ(rtsim(dir, frame + "--fidelity interval" + plan).status, 0);
    ASSERT_TRUE(exists(dir.file("plan.bin")));
    int i = 0;
    // Under the sanitizers, the two interval cases alone: the plan is read alike in every fidelity.
    // `paper` on 2 SMs: its clusters hold the SMs' 16 resident warps each, 32 clusters here as above.
    std::vector<std::string> others = {"--fidelity interval --config paper --set l1.size_kb=64 --set gpu.sms=2", "--fidelity interval --sample 0.75"};
    if (!rtu::test::kSanitized) others.insert(others.begin(), {"--fidelity lt --prefetcher ttp", "--fidelity at --set gpu.sms=4 --sample-seed 3"});
    std::map<std::string, std::string> without_plan;  // case -> its statistics without the plan
    for (const std::string& other : others) {
        SCOPED_TRACE(other);
        const std::string args = (other.find("--sample 0.75") != std::string::npos ? "--scene cornell " + size + "--spp 1 --threads 1 " + kSanitizedWorkload : frame) + other;
        const std::string without = "n" + std::to_string(i) + ".json", with = "y" + std::to_string(i) + ".json";
        without_plan[other] = without;
        ++i;
        const Result a = rtsim(dir, args + " --stats " + dir.file(without));
        ASSERT_EQ(a.status, 0) << a.err;
        const Result b = rtsim(dir, args + plan + " --stats " + dir.file(with));
        ASSERT_EQ(b.status, 0) << b.err;
        EXPECT_EQ(load(with), load(without));
    }
    for (const std::string other : {"--set rt.warp_size=16", "--traversal bfs", "--set rt.next_node_register=true", "--flatten"}) {
        const Result r = rtsim(dir, frame + "--fidelity interval " + other + plan + " --stats " + dir.file("refused.json"));
        EXPECT_EQ(r.status, 2) << other;
        EXPECT_NE(r.err.find("a sample plan of another frame or configuration"), std::string::npos) << other << ": " << r.err;
        EXPECT_FALSE(exists(dir.file("refused.json"))) << other;
    }
    // The BVH is part of the frame: the same mesh file rewritten with other geometry (or a
    // LumiBench scene's name with other assets) is another frame.
    write_text(dir.file("m.obj"), "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n");
    const std::string mesh = "--scene " + dir.file("m.obj") + " --workload primary " + size + "--spp 1 --sample 0.5 --threads 1 --fidelity interval";
    const std::string mplan = " --sample-plan " + dir.file("mesh-plan.bin");
    const Result m1 = rtsim(dir, mesh + mplan);
    ASSERT_EQ(m1.status, 0) << m1.err;
    write_text(dir.file("m.obj"), "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 0 0.5\nf 1 2 3\nf 1 3 4\nf 1 2 5\n");
    const Result m2 = rtsim(dir, mesh + mplan);
    EXPECT_EQ(m2.status, 2);
    EXPECT_NE(m2.err.find("a sample plan of another frame or configuration"), std::string::npos) << m2.err;
    // A ray file likewise: rewritten under its name with other rays (as many), another frame.
    auto ray_file = [&](float spread) {
        std::string text;
        for (int y = 0; y < 256; ++y)
            for (int x = 0; x < 256; ++x)
                text += "278 278 800 " + std::to_string(spread * (x - 128) / 128.0f) + " " + std::to_string(spread * (y - 128) / 128.0f) + " -1 0 inf\n";
        write_text(dir.file("rays.txt"), text);
    };
    const std::string rays = "--scene cornell --rays " + dir.file("rays.txt") + " --sample 0.5 --threads 1";
    const std::string rplan = " --sample-plan " + dir.file("rays-plan.bin");
    ray_file(0.4f);
    const Result r1 = rtsim(dir, rays + rplan + " --fidelity interval");
    ASSERT_EQ(r1.status, 0) << r1.err;
    ASSERT_EQ(rtsim(dir, rays + rplan + " --fidelity lt").status, 0);  // the same rays: read
    ray_file(0.3f);
    const Result r2 = rtsim(dir, rays + rplan + " --fidelity interval");
    EXPECT_EQ(r2.status, 2);
    EXPECT_NE(r2.err.find("a sample plan of another frame or configuration"), std::string::npos) << r2.err;
    // Given a folder, each frame keeps a plan of its own in it: a sweep over frames and
    // configurations shares one --sample-plan. Two frames, two plans; a rerun of the first under
    // another configuration reads its plan (no third file) and equals the run without one.
    std::filesystem::create_directory(dir.file("plans"));
    const std::string folder = " --sample-plan " + dir.file("plans");
    const std::string wknd = "--scene wknd " + size + "--spp 1 --sample 0.5 --threads 1 --fidelity interval " + kSanitizedWorkload;
    ASSERT_EQ(rtsim(dir, frame + "--fidelity interval" + folder).status, 0);
    ASSERT_EQ(rtsim(dir, wknd + folder).status, 0);
    auto files = [&] {
        size_t n = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir.file("plans"))) n += e.path().filename().string().rfind("plan-", 0) == 0;
        return n;
    };
    EXPECT_EQ(files(), 2u);
    const std::string another = others.front();  // LT with TTP; under the sanitizers `paper` with 64 KB L1s
    ASSERT_EQ(rtsim(dir, frame + another + folder + " --stats " + dir.file("f.json")).status, 0);
    EXPECT_EQ(files(), 2u);
    EXPECT_EQ(load("f.json"), load(without_plan.at(another)));
}

// The sampled estimate against the truth, known from simulating the whole frame: on two scenes
// (the built-in cornell box and the bunny, 128x256, 1 spp, half of the frame: the first wave and
// 15 strata) and eight draws of the sample each, the 95 % interval covers the full run's cycles
// in at least 6 of the 8 (a 95 % interval misses 3 or more of 8 with probability 0.6 %; cornell
// covered 18 of 20 draws, seeds 1-20, when measured), every estimate is within 10 % of them and
// every interval is not vacuous (narrower than +-25 %). On the bunny the node fetches' L1 and
// DRAM miss shares are within 15 % of the full run's.
// The sparse bunny mesh under its automatic camera (most clusters empty) is covered as well.
// Before the strata were sorted by the pre-pass's work, such runs covered the truth 78 % of the
// time (issue 14).
TEST(RtsimSampling, IntervalCoversTheFullRun) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    for (const std::string& scene : {std::string("cornell"), "bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny"}) {
        const std::string base = "--scene " + scene + " --fidelity at --workload pt --width 128 --height 256 --spp 1 ";
        const Result full = rtsim(dir, base + "--stats " + dir.file("full.json"));
        ASSERT_EQ(full.status, 0) << full.err;
        const auto f = nlohmann::json::parse(read_text(dir.file("full.json")));
        const double truth = f["cycles"].get<double>();
        int covered = 0;
        for (int seed = 1; seed <= 8; ++seed) {
            const Result r = rtsim(dir, base + "--sample 0.5 --sample-seed " + std::to_string(seed) + " --stats " + dir.file("s.json"));
            ASSERT_EQ(r.status, 0) << r.err;
            const auto j = nlohmann::json::parse(read_text(dir.file("s.json")));
            const auto& s = j["timing"]["sampling"];
            const double est = j["cycles"].get<double>(), lo = s["cycles_ci95"][0].get<double>(), hi = s["cycles_ci95"][1].get<double>();
            SCOPED_TRACE(scene + ", sample seed " + std::to_string(seed) + ": estimate " + std::to_string(est) + " [" +
                         std::to_string(lo) + ", " + std::to_string(hi) + "], full run " + std::to_string(truth));
            EXPECT_EQ(s["estimator"], "schedule (functional pre-pass)");
            covered += lo <= truth && truth <= hi;
            EXPECT_LT(std::fabs(est / truth - 1.0), 0.10);
            EXPECT_LT((hi - lo) / 2.0, 0.25 * est);
            EXPECT_EQ(s["strata"], 15);  // 32 clusters of 32 warps: the first wave and 15 strata
            // The share of node fetches missing L1 / going to DRAM: within 15 % of the frame's.
            // The warmed sample sees fewer misses (seed 3: the DRAM share 12.8 % low, the L1
            // share's interval [0.155, 0.165] for the frame's 0.170), and their intervals count
            // the sampling error only (docs/sampling.md), so they are not checked for coverage. Not on cornell, whose misses all come from the frame's
            // cold start.
            if (scene == "cornell") continue;
            for (const char* k : {"node_fetch_l1_miss_share", "node_fetch_dram_share"}) {
                const double share = f["timing"]["rt_unit"][k].get<double>();
                EXPECT_LT(std::fabs(s[k]["estimate"].get<double>() / share - 1.0), 0.15) << k;
                EXPECT_LE(s[k]["ci95"][0].get<double>(), s[k]["estimate"].get<double>()) << k;
                EXPECT_GE(s[k]["ci95"][1].get<double>(), s[k]["estimate"].get<double>()) << k;
            }
        }
        EXPECT_GE(covered, 6) << scene << ": the interval covered the full run in " << covered << " of 8 draws";
        // The full run's shares are the pop-streak table's misses over its node fetches.
        const auto& rt = f["timing"]["rt_unit"];
        double l1 = 0, dram = 0, fetches = 0;
        for (const auto& c : f["timing"]["rt_unit"]["pop_streak"]) {
            l1 += c["l1_misses"].get<double>();
            dram += c["dram_misses"].get<double>();
            fetches += c["node_fetches"].get<double>();
        }
        EXPECT_DOUBLE_EQ(fetches, rt["node_fetches"].get<double>());
        EXPECT_DOUBLE_EQ(rt["node_fetch_l1_miss_share"].get<double>(), l1 / fetches);
        EXPECT_DOUBLE_EQ(rt["node_fetch_dram_share"].get<double>(), dram / fetches);
    }
    // The sparse mesh: most clusters read no node; they are never drawn, and every draw covers.
    const std::string mesh = "--scene " + rtu::test::shared_dir() + "/scenes/bunny/stanford-bunny.obj --fidelity at --width 128 --height 256 --spp 1 ";
    ASSERT_EQ(rtsim(dir, mesh + "--stats " + dir.file("full.json")).status, 0);
    const double truth = nlohmann::json::parse(read_text(dir.file("full.json")))["cycles"].get<double>();
    for (int seed = 1; seed <= 4; ++seed) {
        const Result r = rtsim(dir, mesh + "--sample 0.5 --sample-seed " + std::to_string(seed) + " --stats " + dir.file("s.json"));
        ASSERT_EQ(r.status, 0) << r.err;
        const auto j = nlohmann::json::parse(read_text(dir.file("s.json")));
        const auto& s = j["timing"]["sampling"];
        SCOPED_TRACE("bunny mesh, sample seed " + std::to_string(seed) + ": estimate " + j["cycles"].dump() + " " +
                     s["cycles_ci95"].dump() + ", full run " + std::to_string(truth));
        EXPECT_GT(s["empty_clusters"].get<int>(), 0);
        EXPECT_LE(s["cycles_ci95"][0].get<double>(), truth);
        EXPECT_GE(s["cycles_ci95"][1].get<double>(), truth);
    }
    EXPECT_EQ(rtsim(dir, "--scene cornell --fidelity at --sample-seed 3").status, 2);  // needs --sample
    EXPECT_EQ(rtsim(dir, "--scene cornell --fidelity at --sample 0.5 --threads 0").status, 2);
}

// Primary rays of a mostly empty frame (the Stanford bunny alone, automatic camera): the SMs go
// through their warps at very different paces, and while the first SM to reach a simulated
// cluster warmed every SM's L1, the sample came out 26-33 % high at 512x512 and a quarter of the
// frame, its intervals (+-5-12 %) missing the full run. Each SM is now warmed when it reaches the
// cluster itself (SampleWarming.EachSmIsWarmedWhenItStartsTheCluster): -1.6 to -2.5 %, covered.
TEST(RtsimSampling, PrimaryRaysOfASparseFrame) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string base = "--scene " + rtu::test::shared_dir() +
                             "/scenes/bunny/stanford-bunny.obj --workload primary --fidelity interval --width 512 --height 512 ";
    ASSERT_EQ(rtsim(dir, base + "--stats " + dir.file("full.json")).status, 0);
    const double truth = nlohmann::json::parse(read_text(dir.file("full.json")))["cycles"].get<double>();
    for (int seed = 1; seed <= (rtu::test::kSanitized ? 1 : 2); ++seed) {  // the second draw: Release only
        const Result r = rtsim(dir, base + "--sample 0.25 --sample-seed " + std::to_string(seed) + " --stats " + dir.file("s.json"));
        ASSERT_EQ(r.status, 0) << r.err;
        const auto j = nlohmann::json::parse(read_text(dir.file("s.json")));
        const auto& ci = j["timing"]["sampling"]["cycles_ci95"];
        SCOPED_TRACE("sample seed " + std::to_string(seed) + ": estimate " + j["cycles"].dump() + " " + ci.dump() + ", full run " +
                     std::to_string(truth));
        EXPECT_LT(std::fabs(j["cycles"].get<double>() / truth - 1.0), 0.10);
        ASSERT_TRUE(ci.is_array());
        EXPECT_LE(ci[0].get<double>(), truth);
        EXPECT_GE(ci[1].get<double>(), truth);
    }
}

// Modelling only what a scene needs: --flatten builds one single-level BVH when every mesh is
// placed as it is (no instance leaves, same answers). (A scene that needs its transforms is left
// as it was: BvhImage.FlattenLeavesAPlacedMeshTwoLevel.)
TEST(RtsimFlatten, SameAnswersWithoutInstanceLeaves) {
    TempDir dir;
    write_text(dir.file("a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n");
    write_text(dir.file("b.obj"), "v 0 0 -2\nv 3 0 -2\nv 0 3 -2\nf 1 2 3\n");
    write_text(dir.file("c.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n-1 -1 -1\n2 -1 -1\n-1 2 -1\n3 0 1 2\n");
    const std::string folder = dir.path().string();
    const std::string args = " --workload primary --width 24 --height 24 --verify --hits ";
    ASSERT_EQ(rtsim(dir, "--scene " + folder + args + dir.file("two.csv") + " --stats " + dir.file("two.json")).status, 0);
    const Result r = rtsim(dir, "--scene " + folder + " --flatten" + args + dir.file("one.csv") + " --stats " + dir.file("one.json"));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(read_text(dir.file("one.csv")), read_text(dir.file("two.csv")));
    const auto one = nlohmann::json::parse(read_text(dir.file("one.json")));
    const auto two = nlohmann::json::parse(read_text(dir.file("two.json")));
    EXPECT_EQ(one["bvh"]["instance_leaves"], 0);
    EXPECT_EQ(two["bvh"]["instance_leaves"], 3);
    EXPECT_FALSE(one["bvh"]["two_level"].get<bool>());
    EXPECT_TRUE(two["bvh"]["two_level"].get<bool>());
    EXPECT_LT(one["bvh"]["image_bytes"].get<uint64_t>(), two["bvh"]["image_bytes"].get<uint64_t>());
}

// LT at the smallest quantum against AT. Stated bound: within 3 % in total cycles and one point
// of L1 miss rate (measured: -0.5 % and < 0.1 points on bunny 32x32). The remaining gap is
// structural (no FR-FCFS reordering in LT's DRAM, tag and row state in call order), not temporal.
TEST(RtsimTiming, LtAtTheSmallestQuantumIsWithinTheStatedBoundOfAt) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string base = "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --width 32 --height 32 --stats ";
    ASSERT_EQ(rtsim(dir, base + dir.file("at.json") + " --fidelity at").status, 0);
    ASSERT_EQ(rtsim(dir, base + dir.file("lt.json") + " --fidelity lt --quantum 1").status, 0);
    const auto at = nlohmann::json::parse(read_text(dir.file("at.json")));
    const auto lt = nlohmann::json::parse(read_text(dir.file("lt.json")));
    const double ca = at["cycles"].get<double>(), cl = lt["cycles"].get<double>();
    EXPECT_LE(std::fabs(cl - ca) / ca, 0.03) << "AT " << ca << " LT " << cl;
    EXPECT_LE(std::fabs(lt["timing"]["l1"]["demand"]["miss_rate"].get<double>() - at["timing"]["l1"]["demand"]["miss_rate"].get<double>()), 0.01);
}

// LT steps its RT units cycle by cycle within each quantum (tlm/rt_complex.cpp), so the quantum
// only sets how often LT's thread meets the SystemC kernel: neither it nor the other `sim` keys
// (the watchdog's period, the trace window) may change a statistic. Before, each unit ran its
// whole quantum in turn, and the quantum moved LT's cycles by several per cent (desktop, sprng
// primary rays 128x128: -4.6 % at 500, +5.1 % at 700, -10.4 % at 1,000 against AT). Eight SMs
// (mobile) sharing the L2 and DRAM, path tracing, so that the units' requests interleave.
TEST(RtsimTiming, LtStatisticsDoNotDependOnTheQuantum) {
    TempDir dir;
    auto run = [&](const std::string& name, const std::string& args) {
        const Result r = rtsim(dir, "--scene cornell --width 48 --height 48 --fidelity lt --stats " + dir.file(name) + " " + args);
        EXPECT_EQ(r.status, 0) << args << r.err;
        auto j = nlohmann::json::parse(read_text(dir.file(name)));
        EXPECT_EQ(j["config"]["gpu"]["sms"].get<int>(), 8);
        erase_host_keys(j);
        j.erase("config");
        return j;
    };
    const auto stock = run("q.json", "--vcd " + dir.file("q.vcd"));
    EXPECT_GT(stock["timing"]["l2"]["demand"]["accesses"].get<uint64_t>(), 0u);
    // The quantum is read: it is how far LT runs ahead of the kernel, so the monitor that writes
    // the waveforms samples the units at other points of their work.
    run("q100.json", "--quantum 100 --vcd " + dir.file("q100.vcd"));
    auto body = [](const std::string& vcd) { return vcd.substr(vcd.find("$enddefinitions")); };  // past $date
    EXPECT_NE(body(read_text(dir.file("q.vcd"))), body(read_text(dir.file("q100.vcd"))));
    for (const std::string args : {"--quantum 1", "--quantum 37", "--quantum 100", "--quantum 100000", "--set sim.watchdog=5000",
                                   "--set sim.trace_window=10"}) {
        const auto other = run("o.json", args);
        EXPECT_EQ(other["cycles"], stock["cycles"]) << args;
        EXPECT_EQ(other, stock) << args;
    }
}

// The interval fidelity against AT (docs/interval.md). Stated bound on these 32x32 frames:
// within 5 % in total cycles and 8 % in TTP's speed-up over the baseline, with TTP a speed-up
// in both (measured with the interval fidelity's warp scheduler: ship -0.6 % and 1.584x against
// 1.530x; docs/interval.md). Same inputs, same statistics.
TEST(RtsimTiming, IntervalIsWithinTheStatedBoundOfAt) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    for (const std::string scene : {"bunny", "ship"}) {
        const std::string base = "--scene " + scene + " --assets " + rtu::test::shared_dir() + "/scenes/" + scene +
                                 " --width 32 --height 32 --stats ";
        auto run = [&](const std::string& name, const std::string& args) {
            EXPECT_EQ(rtsim(dir, base + dir.file(name) + " " + args).status, 0) << args;
            auto j = nlohmann::json::parse(read_text(dir.file(name)));
            erase_host_keys(j);
            return j;
        };
        const auto at = run("at.json", "--fidelity at"), at_ttp = run("at_ttp.json", "--fidelity at --prefetcher ttp");
        const auto iv = run("iv.json", "--fidelity interval"), iv_ttp = run("iv_ttp.json", "--fidelity interval --prefetcher ttp");
        const double ca = at["cycles"].get<double>(), ci = iv["cycles"].get<double>();
        EXPECT_LE(std::fabs(ci - ca) / ca, 0.05) << scene << ": AT " << ca << " interval " << ci;
        const double sa = ca / at_ttp["cycles"].get<double>(), si = ci / iv_ttp["cycles"].get<double>();
        EXPECT_GT(si, 1.0) << scene;
        EXPECT_LE(std::fabs(si / sa - 1.0), 0.08) << scene << ": TTP speed-up AT " << sa << " interval " << si;
        EXPECT_EQ(iv["nodes_visited"], at["nodes_visited"]);
        EXPECT_EQ(iv["hits"], at["hits"]);
        // Every prefetch chunk generated is sent, dropped as a duplicate or taken out by a demand
        // read of its chunk (the queue has no bound here); every one sent reads L1 once, and once
        // more after a reservation fail.
        const auto& pf = iv_ttp["timing"]["rt_unit"]["prefetch_queue"];
        const auto& l1 = iv_ttp["timing"]["l1"];
        EXPECT_EQ(pf["full_dropped"].get<uint64_t>(), 0u);
        EXPECT_GT(pf["removed_by_demand"].get<uint64_t>(), 0u);
        EXPECT_EQ(pf["sent"].get<uint64_t>() + pf["duplicates_dropped"].get<uint64_t>() + pf["removed_by_demand"].get<uint64_t>(),
                  pf["generated"].get<uint64_t>());
        EXPECT_EQ(l1["prefetch"]["accesses"].get<uint64_t>(), pf["sent"].get<uint64_t>() + l1["prefetch"]["reservation_fails"].get<uint64_t>());
        EXPECT_GT(l1["prefetched"]["useful"].get<uint64_t>(), 0u) << scene;
        EXPECT_EQ(run("iv2.json", "--fidelity interval"), iv) << scene;
    }
}

// LT and AT count the same events where the hardware has them: demand reads that find a TTP
// prefetch still on its way (late prefetches) and node fetches served by DRAM, including those
// that waited for a miss already on its way (model/cache_bookings.h). Stated bound, bunny 32x32:
// late prefetches within 25 % of AT's and the DRAM share within 2 points (measured: 1,180
// against 1,165 and 17.5 % against 18.0 %). Before the shared cache timing, LT counted no late
// prefetch and a DRAM share of 9.7 %.
TEST(RtsimTiming, LtCountsLatePrefetchesAndDramFetchesAsAtDoes) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const std::string base = "--scene bunny --assets " + rtu::test::shared_dir() +
                             "/scenes/bunny --width 32 --height 32 --prefetcher ttp --stats ";
    ASSERT_EQ(rtsim(dir, base + dir.file("at.json") + " --fidelity at").status, 0);
    ASSERT_EQ(rtsim(dir, base + dir.file("lt.json") + " --fidelity lt").status, 0);
    const auto at = nlohmann::json::parse(read_text(dir.file("at.json")))["timing"];
    const auto lt = nlohmann::json::parse(read_text(dir.file("lt.json")))["timing"];
    const double late_at = at["l1"]["prefetched"]["late"].get<double>(), late_lt = lt["l1"]["prefetched"]["late"].get<double>();
    ASSERT_GT(late_at, 0);
    EXPECT_LE(std::fabs(late_lt / late_at - 1.0), 0.25) << "AT " << late_at << " LT " << late_lt;
    const double dram_at = at["rt_unit"]["node_fetch_dram_share"].get<double>(), dram_lt = lt["rt_unit"]["node_fetch_dram_share"].get<double>();
    EXPECT_LE(std::fabs(dram_lt - dram_at), 0.02) << "AT " << dram_at << " LT " << dram_lt;
}

namespace {
// The keys of a stats file as the schema writes them: dotted, list items of objects as "[]".
void flatten_keys(const nlohmann::json& j, const std::string& path, std::set<std::string>& out) {
    if (!path.empty()) out.insert(path);
    if (j.is_object()) {
        for (auto it = j.begin(); it != j.end(); ++it) flatten_keys(it.value(), path.empty() ? it.key() : path + "." + it.key(), out);
    } else if (j.is_array()) {
        for (const auto& item : j)
            if (item.is_object())
                for (auto it = item.begin(); it != item.end(); ++it) flatten_keys(it.value(), path + "[]." + it.key(), out);
    }
}
}  // namespace

// `rtsim --stats-schema` lists every key a stats file can hold, once, with a unit column and a
// description, and nothing that no run writes: a functional run with --verify, a sampled AT run
// with TTP and --verify, an interval run with --check-error, one segment of a split sample and a
// sample of a given width together write every key of the schema.
TEST(RtsimStats, SchemaListsEveryKeyWrittenAndNothingElse) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    const Result schema = rtsim(dir, "--stats-schema");
    ASSERT_EQ(schema.status, 0);
    std::set<std::string> declared;
    const auto rows = lines(schema.out);
    ASSERT_FALSE(rows.empty());
    EXPECT_EQ(rows[0], "key\tunit\tdescription");
    for (size_t i = 1; i < rows.size(); ++i) {
        const auto tab = rows[i].find('\t'), tab2 = rows[i].find('\t', tab + 1);
        ASSERT_NE(tab2, std::string::npos) << rows[i];
        EXPECT_TRUE(declared.insert(rows[i].substr(0, tab)).second) << "declared twice: " << rows[i];
        EXPECT_GT(rows[i].size(), tab2 + 1) << "no description: " << rows[i];
    }
    std::set<std::string> written;
    const std::string bunny = "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --spp 1 ";
    const std::string scene = bunny + "--width 64 --height 32 ";  // 64 warps
    for (const std::string& args : {scene + "--verify", scene + "--fidelity at --prefetcher ttp --sample 0.75 --verify",
                                   // 1,024 warps, 32 clusters (a check of 4 drawn needs 25)
                                   bunny + "--width 256 --height 128 --fidelity interval --check-error 4 --check-error-any-cost",
                                   scene + "--fidelity at --sample 0.75 --sample-unchecked --sample-segments 2 --segment 1",
                                   // 2,048 warps, 64 clusters: a pilot of 16.5 %
                                   std::string("--scene cornell --width 256 --height 256 --spp 1 --fidelity interval --sample-width 60")}) {
        ASSERT_EQ(rtsim(dir, args + " --stats " + dir.file("s.json")).status, 0) << args;
        std::set<std::string> keys;
        flatten_keys(nlohmann::json::parse(read_text(dir.file("s.json"))), "", keys);
        for (const std::string& k : keys) EXPECT_TRUE(declared.count(k)) << args << ": '" << k << "' is not in the schema";
        written.insert(keys.begin(), keys.end());
    }
    for (const std::string& k : declared) EXPECT_TRUE(written.count(k)) << "'" << k << "' is declared but no run wrote it";
}

namespace {
// Two bumpy 40x40 heightfields side by side, one OBJ file each: a folder scene of two meshes,
// so a TLAS over two BLASes (instance leaves and transforms), 6,400 triangles whose BVH image
// (about 0.5 MB) misses in L1 and partly in L2.
std::string two_heightfields(const TempDir& dir) {
    std::filesystem::create_directories(dir.file("fields"));
    for (int m = 0; m < 2; ++m) {
        std::ostringstream obj;
        const int n = 40;
        for (int y = 0; y <= n; ++y)
            for (int x = 0; x <= n; ++x)
                obj << "v " << x + m * (n + 5) << " " << y << " " << 2.0 * std::sin(0.7 * x) * std::cos(0.5 * y + m) << "\n";
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const int a = y * (n + 1) + x + 1, b = a + 1, c = a + n + 1, d = c + 1;
                obj << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
            }
        write_text(dir.file("fields/field" + std::to_string(m) + ".obj"), obj.str());
    }
    return dir.file("fields");
}

}  // namespace

// Every preset: TTP speeds a small AT path-tracing run of the bunny up (its direction, not its
// digits: 32x32 measured 1.33x mobile, 1.47x paper, 1.55x desktop), with the same rays and hits.
TEST(RtsimPresets, TtpSpeedsUpPathTracingOnEveryPreset) {
    RTU_NEED_SHARED_SCENES();
    TempDir dir;
    for (const std::string preset : {"mobile", "paper", "desktop"}) {
        const std::string base = "--scene bunny --assets " + rtu::test::shared_dir() + "/scenes/bunny --fidelity at --width 32 --height 32 --config " +
                                 preset + " --stats ";
        ASSERT_EQ(rtsim(dir, base + dir.file("base.json")).status, 0) << preset;
        ASSERT_EQ(rtsim(dir, base + dir.file("ttp.json") + " --prefetcher ttp").status, 0) << preset;
        const auto a = nlohmann::json::parse(read_text(dir.file("base.json"))), b = nlohmann::json::parse(read_text(dir.file("ttp.json")));
        EXPECT_GT(a["cycles"].get<double>() / b["cycles"].get<double>(), 1.0) << preset;
        EXPECT_EQ(a["hits"], b["hits"]) << preset;
        EXPECT_EQ(a["nodes_visited"], b["nodes_visited"]) << preset;
    }
}

// docs/paper-preset.md gives the source of every key of the presets that follow the TTP
// authors' setup: every configuration key has a row, and its paper, desktop and mobile columns
// are the presets' values (so the table cannot drift from the JSON). Every key of paper.json and
// desktop.json is written out (nothing silently inherited from mobile).
TEST(RtsimConfig, PaperPresetTableMatchesTheJson) {
    using namespace rtu;
    const std::string doc = read_text(std::string(RTU_SOURCE_DIR) + "/docs/paper-preset.md");
    ASSERT_FALSE(doc.empty());
    std::map<std::string, std::vector<std::string>> rows;  // key -> cells after the key
    for (const std::string& line : lines(doc)) {
        if (line.rfind("| ", 0) != 0) continue;
        std::vector<std::string> cells;
        std::string cell;
        for (size_t i = 1; i < line.size(); ++i) {
            if (line[i] == '|') {
                const size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
                cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
                cell.clear();
            } else {
                cell += line[i];
            }
        }
        if (cells.size() == 5) rows[cells[0]] = {cells[1], cells[2], cells[3], cells[4]};
    }
    auto flat = [](const nlohmann::ordered_json& j) {
        std::map<std::string, nlohmann::json> out;
        std::function<void(const nlohmann::ordered_json&, const std::string&)> walk = [&](const nlohmann::ordered_json& o, const std::string& p) {
            for (auto it = o.begin(); it != o.end(); ++it) {
                if (!it.key().empty() && it.key()[0] == '_') continue;
                const std::string k = p.empty() ? it.key() : p + "." + it.key();
                if (it.value().is_object()) walk(it.value(), k);
                else out[k] = it.value();
            }
        };
        walk(j, "");
        return out;
    };
    const std::vector<std::string> presets = {"paper", "desktop", "mobile"};
    std::vector<std::map<std::string, nlohmann::json>> values;
    for (const std::string& p : presets) values.push_back(flat(Config::load(p).to_json()));
    for (const char* p : {"paper", "desktop"}) {
        const auto file = flat(nlohmann::ordered_json::parse(read_text(std::string(RTU_SOURCE_DIR) + "/platforms/configs/" + p + ".json")));
        for (const Config::KeyInfo& k : Config::keys()) EXPECT_TRUE(file.count(k.name)) << p << ".json does not write '" << k.name << "'";
    }
    for (const Config::KeyInfo& k : Config::keys()) {
        auto row = rows.find(k.name);
        if (row == rows.end()) {
            ADD_FAILURE() << "docs/paper-preset.md has no row for '" << k.name << "'";
            continue;
        }
        EXPECT_FALSE(row->second[3].empty()) << k.name << ": no source";
        for (size_t i = 0; i < presets.size(); ++i) {
            const nlohmann::json& v = values[i].at(k.name);
            const std::string& cell = row->second[i];
            if (v.is_number()) {
                EXPECT_DOUBLE_EQ(std::stod(cell), v.get<double>()) << k.name << " (" << presets[i] << ")";
            } else if (v.is_boolean()) {
                EXPECT_EQ(cell, v.get<bool>() ? "true" : "false") << k.name << " (" << presets[i] << ")";
            } else {
                EXPECT_EQ(cell, v.get<std::string>()) << k.name << " (" << presets[i] << ")";
            }
        }
    }
}

// Every configuration key of every preset is read. Changed alone (or with the keys it must agree
// with), each changes the statistics of a small AT run (16x16; 32x32 for the keys that show
// only under that frame's load), or (the watchdog) its exit status. The
// DRAM's write timing and write energy change no run, because the modelled RT unit only reads:
// they are shown read by the DRAM model and the energy figures directly.
TEST(RtsimConfig, EveryKeyOfEveryPresetIsRead) {
    using namespace rtu;
    TempDir dir;
    const std::string scene = two_heightfields(dir);
    struct Case {
        std::vector<std::string> sets;  // the change
        std::string extra = "";         // arguments of both runs
        bool exit_status = false;       // the change shows in the exit status
    };
    const std::string ttp = "--prefetcher ttp", treelet = "--traversal treelet --prefetcher treelet";
    // Path tracing where the sanitizers' runs take primary rays (below) and a key shows only there.
    const std::string pt = " --workload pt";
    // The runs are 16x16; a key that shows only under a 32x32 frame's load of the memory system says so.
    const std::string big = "--width 32 --height 32 ";
    const std::vector<Case> cases = {
        {{"gpu.sms=2"}}, {{"gpu.core_clock_mhz=700"}}, {{"gpu.memory_clock_mhz=1000"}}, {{"rt.warp_size=8"}},
        {{"rt.warp_buffer=1"}, "--set gpu.sms=2"}, {{"rt.l1_hit_latency=30"}}, {{"rt.response_fifo=1"}}, {{"rt.next_node_register=flip"}}, {{"rt.leaf_descriptor_read=flip"}}, {{"rt.merge_in_flight=flip"}, big}, {{"rt.warp_scheduler=round_robin|oldest_first"}, "--set gpu.sms=2"},
        {{"rt.latency.structure=40"}}, {{"rt.latency.ray_box=40"}}, {{"rt.latency.transform=40"}},
        {{"rt.latency.leaf_descriptor=40"}}, {{"rt.latency.ray_triangle=40"}}, {{"rt.latency.triangle_hit=40"}},
        {{"rt.latency.procedural=40"}, "--scene wknd"}, {{"workload.shade_latency=5000"}}, {{"workload.intersection_latency=2000"}, "--scene wknd" + pt}, {{"workload.launch_latency=3000"}}, {{"workload.shader_reads=3"}}, {{"workload.shader_lines_per_read=0.25"}, "--set workload.shader_reads=3"}, {{"workload.resident_warps=1"}, "--set gpu.sms=2"}, {{"workload.shader_contention=0.5"}, "--set gpu.sms=2"},
        {{"l1.size_kb=2"}}, {{"l1.assoc=4"}}, {{"l1.replacement=fifo"}, "--set l1.size_kb=2"}, {{"l2.replacement=fifo"}, big + "--set l2.slice_kb=4 --set l2.assoc=4 --set l2.set_index=linear"}, {{"l1.line=64", "l2.line=64", "l2.set_index=linear"}}, {{"l1.sector=64", "l2.sector=64"}},
        {{"l1.mshrs=2", "l1.mshr_merge=2"}}, {{"l1.mshr_merge=1"}, big}, {{"l1.miss_queue=2"}, big + "--scene wknd --set workload.shader_reads=8 --set l2.mshrs=2 --set l2.mshr_merge=2"}, {{"l2.miss_queue=2"}, big},
        {{"l1.allocation=miss|fill"}, "--set l1.size_kb=2"}, {{"l2.allocation=miss|fill"}, "--set l2.slice_kb=4 --set l2.assoc=4 --set l2.set_index=linear"},
        {{"l2.slices=1", "dram.address_map=line"}}, {{"l2.slice_kb=4", "l2.set_index=linear"}}, {{"l2.assoc=1"}, "--set l2.slice_kb=4 --set l2.set_index=linear"}, {{"l2.mshrs=2", "l2.mshr_merge=2"}}, {{"l2.mshr_merge=1"}},
        {{"l2.latency=20"}}, {{"l2.set_index=ipoly", "l2.slice_kb=16", "l2.assoc=2"}}, {{"xbar.latency=30"}},
        {{"dram.channels=1", "dram.address_map=line"}}, {{"dram.banks=2", "dram.address_map=line"}}, {{"dram.bus_bytes=1"}}, {{"dram.burst=32"}}, {{"dram.queue=1"}}, {{"dram.frontend_latency=50"}}, {{"dram.beats_per_cycle=8"}},
        {{"dram.address_map=dramid@9;00000000.00000000.00000000.00000000.0000RRRR.RRRRRRRR.RBBBCCCC.BCCSSSSS", "l2.slices=4", "dram.channels=4"}},
        {{"dram.row_bytes=256", "dram.address_map=line"}}, {{"dram.scheduler=fcfs"}}, {{"dram.tCL=40"}}, {{"dram.tRCD=40"}}, {{"dram.tRP=40"}},
        {{"dram.tRAS=60"}}, {{"dram.tRC=200"}}, {{"dram.tRRD=40"}}, {{"dram.tCCD=16"}},
        {{"prefetch.kind=ttp"}}, {{"prefetch.treelet_budget=4096"}, treelet}, {{"prefetch.treelet_threshold=0.25"}, treelet + " --set prefetch.treelet_heuristic=popularity"},
        {{"prefetch.treelet_heuristic=always|popularity"}, treelet}, {{"prefetch.treelet_layout=bvh|contiguous"}, treelet},
        {{"prefetch.treelet_stride=1024"}, treelet + " --set prefetch.treelet_layout=contiguous"},
        {{"prefetch.treelet_queue_limit=2"}, treelet}, {{"prefetch.treelet_vote_period=64"}, treelet},
        {{"prefetch.treelet_order=treelets|root-then-dfs"}, treelet + " --set prefetch.treelet_budget=512"},
        {{"prefetch.ttp_depth_s1=4"}, ttp}, {{"prefetch.ttp_depth_s2=8"}, ttp + pt}, {{"prefetch.ttp_depth_s3=2"}, ttp + pt},
        {{"prefetch.bfs_n=4"}, ttp + " --traversal bfs"}, {{"prefetch.bfs_policy=fixed|trend"}, ttp + " --traversal bfs"}, {{"prefetch.priority_after=5"}, ttp}, {{"prefetch.queue=1"}, ttp}, {{"prefetch.thread_window=2"}, big + ttp},
        {{"energy.l1_access_pj=40"}}, {{"energy.l2_access_pj=160"}}, {{"energy.dram_read_pj=1000"}},
        {{"energy.dram_activate_pj=2000"}}, {{"energy.static_w=10"}},
        {{"sim.watchdog=1000"}, "--set workload.shade_latency=200000", true},
    };
    // Read by the DRAM model's write path and the energy figures, which no run reaches.
    const std::set<std::string> write_path = {"dram.tWL", "dram.tWR", "energy.dram_write_pj"};
    // Change only the waveforms: RtsimTiming.TraceWindowSetsTheWaveformSamplingOnly and
    // RtsimTiming.LtStatisticsDoNotDependOnTheQuantum (LT's run-ahead seen in its trace) show them read.
    const std::set<std::string> waveforms_only = {"sim.trace_window", "sim.quantum"};
    {
        DramConfig d = Config::load("mobile").resolve().dram;
        auto write_done = [&](const DramConfig& c) {
            DramRequest w;
            w.write = true;
            w.token = 1;
            DramRequest conflict;  // same bank, another row: its precharge waits for the write's recovery
            conflict.at.row = 1;
            conflict.token = 2;
            return test::drive_channel(c, {w, conflict}).at(2);
        };
        const uint64_t base = write_done(d);
        DramConfig wl = d, wr = d;
        wl.tWL += 20;
        wr.tWR += 200;
        EXPECT_NE(write_done(wl), base) << "dram.tWL";
        EXPECT_NE(write_done(wr), base) << "dram.tWR";
        HwConfig hw = Config::load("mobile").resolve();
        HierarchyCounts h;
        h.dram.push_back(DramStats{});
        h.dram[0].writes = 1;
        auto dram_j = [&](const HwConfig& c) {
            nlohmann::ordered_json j;
            StatsOut out(j);
            write_hierarchy(out, c, h, {}, 1.0);
            return j["energy"]["dram_j"].get<double>();
        };
        const double e = dram_j(hw);
        hw.energy.dram_write_pj *= 2;
        EXPECT_NE(dram_j(hw), e) << "energy.dram_write_pj";
    }
    // Every key of the schema has a case.
    std::set<std::string> covered = write_path;
    covered.insert(waveforms_only.begin(), waveforms_only.end());
    for (const Case& c : cases)
        for (const std::string& s : c.sets) covered.insert(s.substr(0, s.find('=')));
    for (const Config::KeyInfo& k : Config::keys()) EXPECT_TRUE(covered.count(k.name)) << "no case shows that '" << k.name << "' is read";
    // Under the sanitizers, `paper` alone (the preset with the most of the model switched on).
    const std::vector<std::string> presets = rtu::test::kSanitized ? std::vector<std::string>{"paper"}
                                                                   : std::vector<std::string>{"mobile", "paper", "desktop"};
    for (const std::string& preset : presets) {
        const nlohmann::ordered_json values = Config::load(preset).to_json();
        std::map<std::string, std::pair<int, nlohmann::json>> baselines;  // by `extra`
        int n = 0;
        for (const Case& c : cases) {
            // The heightfields in AT, unless the case names another scene or fidelity.
            // Under the sanitizers, primary rays (kSanitizedWorkload), unless the case names a workload.
            const bool own_scene = c.extra.find("--scene") != std::string::npos, own_fidelity = c.extra.find("--fidelity") != std::string::npos;
            const bool own_workload = c.extra.find("--workload") != std::string::npos, own_size = c.extra.find("--width") != std::string::npos;
            const std::string base = (own_scene ? "" : "--scene " + scene) + (own_fidelity ? "" : " --fidelity at") +
                                     (own_size ? "" : " --width 16 --height 16") + " --spp 1 --config " + preset + " " + (own_workload ? "" : kSanitizedWorkload) + c.extra;
            auto run = [&](const std::string& args) {
                const std::string stats = dir.file("s" + std::to_string(n++) + ".json");
                const Result r = rtsim(dir, base + " " + args + " --stats " + stats);
                return std::make_pair(r.status, exists(stats) ? model_stats(stats) : nlohmann::json());
            };
            if (!baselines.count(c.extra)) baselines[c.extra] = run("");
            std::string sets;
            for (std::string s : c.sets) {
                const std::string key = s.substr(0, s.find('='));
                const std::string value = s.substr(key.size() + 1);
                std::string pointer = "/" + key;
                std::replace(pointer.begin(), pointer.end(), '.', '/');
                const nlohmann::json preset_value = values.at(nlohmann::json::json_pointer(pointer));
                if (value == "flip") {  // a boolean: the preset's opposite
                    s = key + "=" + (preset_value.get<bool>() ? "false" : "true");
                } else if (value.find('|') != std::string::npos) {  // alternatives: the first that is not the preset's
                    const std::string a = value.substr(0, value.find('|')), b = value.substr(value.find('|') + 1);
                    s = key + "=" + (preset_value.get<std::string>() == a ? b : a);
                }
                sets += " --set '" + s + "'";
            }
            const auto changed = run(sets);
            const auto& reference = baselines[c.extra];
            ASSERT_EQ(reference.first, 0) << preset << " " << c.extra;
            if (c.exit_status) {
                EXPECT_NE(changed.first, reference.first) << preset << ":" << sets;
            } else {
                ASSERT_EQ(changed.first, 0) << preset << ":" << sets;
                EXPECT_TRUE(changed.second != reference.second) << preset << ":" << sets << " changed nothing";
            }
        }
    }
}

// Every timing run states its error against AT (platforms/error_estimate.h): AT is the
// reference; LT and interval inside the error grid's regime carry the grid's worst error for their
// workload (platforms/configs/error_bounds.json, read here independently); outside it (another
// quantum, a ray file) no value and the reason; a sampled AT run its interval's upper half-width.
TEST(RtsimError, EveryTimingRunStatesItsError) {
    TempDir dir;
    const auto bounds = nlohmann::json::parse(read_text(std::string(RTU_SOURCE_DIR) + "/platforms/configs/error_bounds.json"));
    auto run = [&](const std::string& args) {
        const Result r = rtsim(dir, "--scene cornell " + args + " --stats " + dir.file("s.json"));
        EXPECT_EQ(r.status, 0) << args << r.err;
        EXPECT_NE(r.out.find("error estimate: "), std::string::npos) << args << r.out;
        return nlohmann::json::parse(read_text(dir.file("s.json")))["error_estimate"];
    };
    auto at = run("--fidelity at --width 32 --height 32");
    EXPECT_EQ(at["kind"], "reference");
    EXPECT_EQ(at["value"].get<double>(), 0.0);
    EXPECT_TRUE(at["check"].is_null());
    for (const std::string fid : {"lt", "interval"}) {
        // Path tracing, 2 spp, mobile: in the grid. A frame of the grid's takes that size's
        // bound, one between two sizes the worse of the two.
        const auto& by_size = bounds["bounds"][fid]["pt"]["by_size"];
        auto e = run("--fidelity " + fid + " --width 64 --height 64");
        EXPECT_EQ(e["kind"], "validated bound") << fid << e.dump();
        EXPECT_EQ(e["value"].get<double>(), by_size["64"]["worst"].get<double>()) << fid;
        EXPECT_NE(e["basis"].get<std::string>().find("error grid"), std::string::npos);
        e = run("--fidelity " + fid + " --width 96 --height 96");
        EXPECT_EQ(e["value"].get<double>(), std::max(by_size["64"]["worst"].get<double>(), by_size["128"]["worst"].get<double>())) << fid;
    }
    // The quantum changes no statistic (RtsimTiming.LtStatisticsDoNotDependOnTheQuantum): any
    // quantum stays in the regime; a hardware key does not.
    auto q = run("--fidelity lt --quantum 100 --width 64 --height 64");
    EXPECT_EQ(q["kind"], "validated bound") << q.dump();
    q = run("--fidelity lt --set l2.latency=161 --width 64 --height 64");
    EXPECT_EQ(q["kind"], "none");
    EXPECT_TRUE(q["value"].is_null());
    EXPECT_NE(q["basis"].get<std::string>().find("configuration other than the grid's"), std::string::npos) << q.dump();
    write_text(dir.file("rays.txt"), "278 278 800 0 0 -1 0 inf\n");
    const Result rays = rtsim(dir, "--scene cornell --fidelity interval --rays " + dir.file("rays.txt") + " --stats " + dir.file("r.json"));
    ASSERT_EQ(rays.status, 0) << rays.err;
    EXPECT_NE(rays.out.find("error estimate: none (outside the validated regime: a ray file"), std::string::npos) << rays.out;
    const Result sampled = rtsim(dir, "--scene cornell --fidelity at --width 512 --height 256 --spp 1 --sample 0.5 --stats " + dir.file("p.json"));
    ASSERT_EQ(sampled.status, 0) << sampled.err;
    const auto p = nlohmann::json::parse(read_text(dir.file("p.json")));
    EXPECT_EQ(p["error_estimate"]["kind"], "interval");
    const double c = p["cycles"].get<double>(), hi = p["timing"]["sampling"]["cycles_ci95"][1].get<double>();
    EXPECT_NEAR(p["error_estimate"]["value"].get<double>(), (hi - c) / c, 1e-9);
    EXPECT_EQ(p["timing"]["sampling"]["strata"], 63);  // 128 clusters at 50 %, the first wave among them
    EXPECT_EQ(p["error_estimate"]["basis"].get<std::string>().find("fewer than 30"), std::string::npos) << p["error_estimate"].dump();
    // Below 30 strata the estimate says so and names the rate that draws 30: round(128 x rate) >=
    // 31 clusters simulated, rate >= 0.2383.
    const Result few = rtsim(dir, "--scene cornell --fidelity interval --width 512 --height 256 --spp 1 --sample 0.1 --stats " + dir.file("f.json"));
    ASSERT_EQ(few.status, 0) << few.err;
    const auto f = nlohmann::json::parse(read_text(dir.file("f.json")));
    EXPECT_EQ(f["timing"]["sampling"]["strata"], 12);
    EXPECT_NE(f["error_estimate"]["basis"].get<std::string>().find("12 drawn strata, fewer than 30"), std::string::npos) << f["error_estimate"].dump();
    EXPECT_NE(few.out.find("--sample 0.239 draws 30"), std::string::npos) << few.out;
    EXPECT_EQ(few.out.find("--sample-width"), std::string::npos) << few.out;  // a --sample run: no width planned it
    const Result thirty = rtsim(dir, "--scene cornell --fidelity interval --width 512 --height 256 --spp 1 --sample 0.239 --stats " + dir.file("t.json"));
    ASSERT_EQ(thirty.status, 0) << thirty.err;
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("t.json")))["timing"]["sampling"]["strata"], 30);
}

// A fidelity whose whole grid was run again after a change to it alone (scripts/bench_error_grid.py,
// REPLACE) names its own commit; the others the file's.
TEST(ErrorBounds, AReplacedFidelityNamesItsCommit) {
    const auto b = rtu::ErrorBounds::parse(R"({"measured_on": "base", "grid": {"scenes": ["a"],
        "configs": ["mobile"], "primary_sizes": [], "pt_sizes": [64]}, "bounds": {
        "lt": {"pt": {"runs": 1, "worst": 0.01, "by_size": {"64": {"runs": 1, "worst": 0.01}}}},
        "interval": {"measured_on": "new", "pt": {"runs": 1, "worst": 0.02, "by_size": {"64": {"runs": 1, "worst": 0.02}}}}}})");
    EXPECT_EQ(b.measured_on_for("interval"), "new");
    EXPECT_EQ(b.measured_on_for("lt"), "base");
    const auto i = b.bound("interval", "pt", 64);
    ASSERT_TRUE(i);
    EXPECT_EQ(i->worst, 0.02);
}

// Frame sizes added to the error grid later (scripts/bench_error_grid.py, EXTEND) carry their own
// scenes and commit, and a bound that takes one of them names them in its basis.
TEST(ErrorBounds, AddedSizesNameTheirScenesAndCommit) {
    const auto b = rtu::ErrorBounds::parse(R"({"measured_on": "base", "grid": {"scenes": ["a", "b", "c"], "configs": ["mobile"],
        "primary_sizes": [], "pt_sizes": [64, 128, 512]}, "bounds": {"interval": {"pt": {"runs": 6, "worst": 0.05, "by_size": {
        "64": {"runs": 3, "worst": 0.05}, "128": {"runs": 1, "worst": 0.01},
        "512": {"runs": 2, "worst": 0.02, "scenes": ["a", "b"], "measured_on": "later"}}}}}})");
    const auto at64 = b.bound("interval", "pt", 64);
    ASSERT_TRUE(at64);
    EXPECT_EQ(at64->runs, 3u);
    EXPECT_TRUE(at64->added.empty());
    EXPECT_TRUE(at64->nearest);
    const auto at512 = b.bound("interval", "pt", 512);
    ASSERT_TRUE(at512);
    EXPECT_EQ(at512->runs, 2u);
    EXPECT_EQ(at512->worst, 0.02);
    EXPECT_EQ(at512->added, std::vector<std::string>{"512x512 added later: 2 scenes (a, b), rtsim later"});
    const auto at256 = b.bound("interval", "pt", 256);  // between 128 and 512: both, the worse of the two
    ASSERT_TRUE(at256);
    EXPECT_EQ(at256->runs, 3u);
    EXPECT_EQ(at256->worst, 0.02);
    EXPECT_EQ(at256->added.size(), 1u);
    const auto whole = b.bound("interval", "pt");  // the whole grid's, added sizes among them
    ASSERT_TRUE(whole);
    EXPECT_EQ(whole->added, at512->added);
    // A scene of the grid that the added size left out takes the whole grid's bound there; a
    // scene of the size, or one the grid never had, that size's.
    const auto c512 = b.bound("interval", "pt", 512, "c");
    ASSERT_TRUE(c512);
    EXPECT_EQ(c512->runs, 6u);
    EXPECT_EQ(c512->worst, 0.05);
    EXPECT_EQ(c512->added.back(), "512x512 was added later without c: the whole grid's bound");
    EXPECT_FALSE(c512->nearest);  // the basis then says "at every frame size"
    EXPECT_EQ(b.bound("interval", "pt", 512, "a")->worst, 0.02);
    EXPECT_EQ(b.bound("interval", "pt", 512, "mine.obj")->worst, 0.02);
    EXPECT_EQ(b.bound("interval", "pt", 128, "c")->worst, 0.01);  // a size of the whole grid
}

// The sample design's bias bound: per workload kind, and the larger of the two for what the grids
// did not measure; the basis says where it was measured and, for those, that it was not.
TEST(SamplingBias, KindsAndWhatWasNotMeasured) {
    const auto b = rtu::SamplingBias::parse(R"({"measured_on": "abc", "bias": {
        "primary": {"value": 0.07, "cell": "wknd primary 256 mobile interval 0.1", "cells": 32, "runs": 96},
        "other": {"value": 0.03, "cell": null, "cells": 60, "runs": 300}}})");
    EXPECT_EQ(b.value("primary"), 0.07);
    EXPECT_EQ(b.value("pt"), 0.03);
    EXPECT_EQ(b.value("ao"), 0.07);
    EXPECT_EQ(b.value(""), 0.07);  // a ray file
    EXPECT_NE(b.basis("primary").find("wknd primary 256"), std::string::npos) << b.basis("primary");
    EXPECT_EQ(b.basis("primary").find("not measured"), std::string::npos) << b.basis("primary");
    EXPECT_NE(b.basis("pt").find("no cell biased"), std::string::npos) << b.basis("pt");
    EXPECT_NE(b.basis("sh").find("taken for sh (not measured)"), std::string::npos) << b.basis("sh");
    // The built-in bound is measured: a bias on both kinds, from cells of the grids.
    const auto& in = rtu::SamplingBias::built_in();
    EXPECT_GT(in.primary.value, 0.0);
    EXPECT_GT(in.other.value, 0.0);
    EXPECT_GE(in.other.cells, 10u);
}

// A sampled run's interval carries the design's bias bound for its workload: reported, named in
// the error estimate's basis, and never narrower than it.
TEST(RtsimSampling, IntervalCarriesTheDesignBias) {
    TempDir dir;
    for (const std::string wl : {"pt", "primary"}) {
        const std::string stats = dir.file(wl + ".json");
        const Result r = rtsim(dir, "--scene cornell --fidelity interval --width 512 --height 256 --spp 1 --workload " + wl +
                                        " --sample 0.25 --stats " + stats);
        ASSERT_EQ(r.status, 0) << r.err;
        const auto j = nlohmann::json::parse(read_text(stats));
        const auto& s = j["timing"]["sampling"];
        const double bias = rtu::SamplingBias::built_in().value(wl);
        EXPECT_EQ(s["design_bias"].get<double>(), bias) << wl;
        const double c = j["cycles"].get<double>();
        EXPECT_GE(s["cycles_ci95"][1].get<double>() - c, bias * c * (1 - 1e-12)) << wl;
        EXPECT_NE(j["error_estimate"]["basis"].get<std::string>().find("the sample design's bias bound"), std::string::npos)
            << j["error_estimate"].dump();
        EXPECT_EQ(j["error_estimate"]["basis"].get<std::string>().find("not on this configuration"), std::string::npos)
            << j["error_estimate"].dump();
    }
    // The grids measured the bound on the presets: a sampled AT run (whose estimate is the
    // sample's interval alone; the other fidelities outside the error grid's configurations have
    // none) with a key the presets do not set says so, whatever its prefetcher; a preset with TTP
    // does not.
    for (const std::string extra : {"--set rt.merge_in_flight=true", "--set l2.latency=180 --prefetcher ttp"}) {
        const std::string stats = dir.file("keyed.json");
        const Result r = rtsim(dir, "--scene cornell --fidelity at --width 512 --height 256 --spp 1 --workload pt --sample 0.25 " +
                                        extra + " --stats " + stats);
        ASSERT_EQ(r.status, 0) << r.err;
        const auto j = nlohmann::json::parse(read_text(stats));
        EXPECT_NE(j["error_estimate"]["basis"].get<std::string>().find("the bias bound was measured on the presets"), std::string::npos)
            << extra << ": " << j["error_estimate"].dump();
    }
    const Result ttp = rtsim(dir, "--scene cornell --fidelity at --width 512 --height 256 --spp 1 --workload pt --sample 0.25 "
                                  "--prefetcher ttp --stats " + dir.file("ttp.json"));
    ASSERT_EQ(ttp.status, 0) << ttp.err;
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("ttp.json")))["error_estimate"]["basis"].get<std::string>().find("not on this configuration"),
              std::string::npos);
}

// --sample-width W (docs/sampling.md, "A sample of a given width"): refused before anything runs
// where the design's bias bound alone is W or more, and where its pilot's floor reaches W; where
// the pilot reaches W it is the run (the same clusters and cycles as --sample at its rate); else
// the run samples more strata, and states about the width that was predicted for it.
namespace {
std::string exact_text(double v) {  // as rtsim reads it back exactly
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}
}  // namespace

// How far the width a larger sample delivers may lie from the one its pilot predicted: on the
// grid of docs/sampling.md ("A sample of a given width", path tracing and primary rays at
// 512x512), 0.84-1.33 times it, and once 4.2 (cornell's primary rays, whose draws may miss the
// clusters that first read most of its BVH).
constexpr double kWidthPrediction = 0.5;

TEST(RtsimSampling, SampleWidthPlansItsRateFromAPilot) {
    TempDir dir;
    const std::string cornell = "--scene cornell --width 256 --height 256 --spp 1 --workload pt ";
    // Options: the rate is the width's to choose.
    for (const std::string bad : {"--fidelity interval --sample-width 20 --sample 0.5", "--fidelity interval --sample-width 20 --sample-unchecked",
                                  "--sample-width 20", "--fidelity interval --sample-width 0", "--fidelity interval --sample-width 100"}) {
        const Result r = rtsim(dir, cornell + bad);
        EXPECT_EQ(r.status, 2) << bad;
        EXPECT_NE(r.err.find("--sample-width"), std::string::npos) << bad << ": " << r.err;
    }
    // Below the bias bound: refused before the pilot, nothing written.
    const double bias = rtu::SamplingBias::built_in().value("pt");
    const Result low = rtsim(dir, cornell + "--fidelity interval --sample-width " + std::to_string(100 * bias - 0.5) + " --stats " + dir.file("low.json"));
    EXPECT_EQ(low.status, 2);
    EXPECT_NE(low.err.find("no rate narrows"), std::string::npos) << low.err;
    EXPECT_EQ(low.err.find("pilot"), std::string::npos) << low.err;
    EXPECT_FALSE(exists(dir.file("low.json")));
    // A frame whose pilot alone would sample more than half of it (128x128: 16 clusters): refused before it.
    const Result small = rtsim(dir, "--scene cornell --width 128 --height 128 --spp 1 --fidelity interval --sample-width 30");
    EXPECT_EQ(small.status, 2);
    EXPECT_NE(small.err.find("more than 50 %"), std::string::npos) << small.err;
    EXPECT_EQ(small.err.find("pilot sample ("), std::string::npos) << small.err;

    int larger = 0, few_plans = 0;
    for (int seed = 1; seed <= 6; ++seed) {
        const std::string stats = dir.file("w" + std::to_string(seed) + ".json");
        const Result r = rtsim(dir, cornell + "--fidelity interval --sample-width 20 --sample-seed " + std::to_string(seed) + " --stats " + stats);
        ASSERT_EQ(r.status, 0) << r.err;
        const auto j = nlohmann::json::parse(read_text(stats));
        const auto& s = j["timing"]["sampling"];
        const auto& w = s["width"];
        const double rate = s["rate"].get<double>(), pilot = w["pilot_rate"].get<double>(), c = j["cycles"].get<double>();
        // The interval the run states is the one its width block reports.
        EXPECT_NEAR(w["delivered"].get<double>(), s["cycles_ci95"][1].get<double>() / c - 1, 1e-9) << seed;
        EXPECT_EQ(w["reached"].get<bool>(), w["delivered"].get<double>() <= 0.2) << seed;
        EXPECT_EQ(w["pilots"], 1) << seed;
        EXPECT_GE(w["pilot_strata"].get<int>(), 10) << seed;
        EXPECT_LT(w["floor"].get<double>(), 0.2) << seed;
        EXPECT_LE(w["predicted"].get<double>(), 0.2) << seed;
        // A plan of fewer than 30 strata says the width chose them, and how to draw more.
        const std::string basis = j["error_estimate"]["basis"].get<std::string>();
        const bool few = basis.find("drawn strata, fewer than 30") != std::string::npos;
        few_plans += few;
        EXPECT_EQ(few, basis.find("--sample-width planned the fewest strata predicted to reach +-20 %; a narrower width draws more") != std::string::npos)
            << seed << ": " << basis;
        if (rate == pilot) {
            // The pilot reached W and is the run: exactly the sample --sample draws at its rate.
            EXPECT_EQ(w["predicted"].get<double>(), w["delivered"].get<double>()) << seed;
            EXPECT_LE(w["pilot_half_width"].get<double>(), 0.2) << seed;
            const std::string plain = dir.file("p" + std::to_string(seed) + ".json");
            ASSERT_EQ(rtsim(dir, cornell + "--fidelity interval --sample " + exact_text(pilot) + " --sample-seed " + std::to_string(seed) + " --stats " + plain).status, 0);
            EXPECT_EQ(nlohmann::json::parse(read_text(plain))["cycles"], j["cycles"]) << seed;
        } else {
            // A larger sample: the pilot's prediction against what it delivers.
            ++larger;
            EXPECT_GT(rate, pilot) << seed;
            EXPECT_GT(w["pilot_half_width"].get<double>(), 0.2) << seed;
            EXPECT_GT(s["strata"].get<int>(), w["pilot_strata"].get<int>()) << seed;
            EXPECT_NEAR(w["delivered"].get<double>() / w["predicted"].get<double>(), 1.0, kWidthPrediction) << seed << ": " << w.dump();
        }
    }
    EXPECT_GE(larger, 1);  // seeds 1, 4 and 5 draw pilots wider than 20 % at this commit
    EXPECT_GE(few_plans, 1);

    // LT: the pilot a child run (SystemC elaborates once per process), its plan this run's; where
    // it reaches W the run simulates its clusters again.
    const std::string lt = "--scene wknd --width 256 --height 256 --spp 1 --workload pt --fidelity lt ";
    const Result r = rtsim(dir, lt + "--sample-width 60 --stats " + dir.file("lt.json"));
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(read_text(dir.file("lt.json")));
    const auto& w = j["timing"]["sampling"]["width"];
    EXPECT_GT(w["pilot_s"].get<double>(), 0);
    EXPECT_EQ(j["timing"]["sampling"]["rate"], w["pilot_rate"]);
    ASSERT_EQ(rtsim(dir, lt + "--sample " + exact_text(w["pilot_rate"].get<double>()) + " --stats " + dir.file("lt-plain.json")).status, 0);
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("lt-plain.json")))["cycles"], j["cycles"]);
    EXPECT_EQ(w["predicted"], w["delivered"]);
}

// --check-error N is refused before the run where N is below 4 (its interval pairs strata two by
// two), where N + 1 clusters are more than a fifth of the frame (its check would cost about as
// much as AT's run), and in AT; and after the run where its sample took half the run's time or
// more: cornell's primary rays at 256x256 in the interval fidelity, whose sample traces the whole
// frame in its pre-pass as the run does, and more (warming), and took 1.1 times the run's time.
// The run stands, without a check, and says why; --check-error-any-cost runs the check anyway.
TEST(RtsimError, CheckErrorRefusesWhatCostsAsMuchAsAt) {
    TempDir dir;
    const std::string small = "--scene cornell --width 64 --height 32 --spp 1 --stats ";  // 64 warps: 2 clusters of 32 (mobile)
    Result r = rtsim(dir, small + dir.file("x.json") + " --fidelity interval --check-error 5");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("the frame is too small for a check"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.json")));
    const std::string big = "--scene cornell --width 128 --height 256 --spp 1 --stats ";  // 1,024 warps: 32 clusters
    r = rtsim(dir, big + dir.file("x.json") + " --fidelity lt --check-error 6");  // 7 clusters of 32: beyond a fifth
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("give N at most 5"), std::string::npos) << r.err;
    r = rtsim(dir, big + dir.file("x.json") + " --fidelity lt --check-error 3");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("N of at least 4"), std::string::npos) << r.err;
    EXPECT_EQ(rtsim(dir, big + dir.file("x.json") + " --fidelity at --check-error 4").status, 2);
    EXPECT_EQ(rtsim(dir, big + dir.file("x.json") + " --fidelity lt --check-error-any-cost").status, 2);
    // A frame no sample can estimate (wknd's spheres under `paper`: docs/sampling.md, "Refusals").
    r = rtsim(dir, "--scene wknd --config paper --width 64 --height 32 --spp 1 --fidelity interval --check-error 4 --stats " + dir.file("x.json"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("--check-error: its check simulates a sample of the frame, and this scene has"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.json")));

    const std::string primary = "--scene cornell --workload primary --width 256 --height 256 --fidelity interval --check-error 10 --stats ";
    r = rtsim(dir, primary + dir.file("p.json"));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("warning: --check-error refused: its sample took"), std::string::npos) << r.err;
    const auto p = nlohmann::json::parse(read_text(dir.file("p.json")));
    EXPECT_TRUE(p["error_estimate"]["check"].is_null());
    EXPECT_NE(p["error_estimate"]["basis"].get<std::string>().find("--check-error refused: its sample took"), std::string::npos);
    ASSERT_EQ(rtsim(dir, primary + dir.file("q.json") + " --check-error-any-cost").status, 0);
    EXPECT_EQ(nlohmann::json::parse(read_text(dir.file("q.json")))["error_estimate"]["check"]["clusters"], 11);
}

// --check-error N simulates N drawn clusters and the first wave in the run's fidelity and in AT:
// the samples that runs at the rate (N + 1) / clusters with the same seed simulate (one pre-pass,
// through a plan). It states the frame's RT-unit residence in the fidelity against AT, a ratio
// estimate paired by stratum, with its 95 % interval (paired_work_difference), and that holds
// the full runs' difference in cycles here: wknd's path tracing at 256x256 (1 spp) in LT,
// 4 clusters drawn of 64.
TEST(RtsimError, CheckErrorPairsTheSameClustersInAt) {
    TempDir dir;
    const std::string frame = "--scene wknd --width 256 --height 256 --spp 1 --stats ";
    ASSERT_EQ(rtsim(dir, frame + dir.file("lt.json") + " --fidelity lt --check-error 4 --check-error-any-cost").status, 0);
    for (const std::string fid : {"lt", "at"})
        ASSERT_EQ(rtsim(dir, frame + dir.file(fid + "s.json") + " --fidelity " + fid + " --sample 0.078125 --sample-unchecked").status, 0);
    ASSERT_EQ(rtsim(dir, frame + dir.file("at.json") + " --fidelity at").status, 0);
    const auto lt = nlohmann::json::parse(read_text(dir.file("lt.json")));
    const auto& c = lt["error_estimate"]["check"];
    EXPECT_EQ(c["clusters"], 5);
    EXPECT_EQ(c["share"].get<double>(), 5.0 / 64.0);
    const auto lts = nlohmann::json::parse(read_text(dir.file("lts.json")))["timing"]["sampling"];
    const auto ats = nlohmann::json::parse(read_text(dir.file("ats.json")))["timing"]["sampling"];
    EXPECT_EQ(c["fidelity_cycles"], lts["cycles_simulated"]);
    EXPECT_EQ(c["at_cycles"], ats["cycles_simulated"]);
    auto strata = [](const nlohmann::json& s) {
        return rtu::StrataWork{s["strata_work"]["first_wave_residence_cycles"].get<double>(), s["strata_work"]["residence_cycles"].get<std::vector<double>>(),
                          s["strata_work"]["weights"].get<std::vector<double>>()};
    };
    const rtu::PairedDifference paired = rtu::paired_work_difference(strata(lts), strata(ats));
    EXPECT_EQ(c["difference"].get<double>(), paired.difference);
    EXPECT_EQ(c["difference_half_width"].get<double>(), paired.half_width);
    EXPECT_EQ(c["variance_pairs"], 2);
    const double truth = lt["cycles"].get<double>() / nlohmann::json::parse(read_text(dir.file("at.json")))["cycles"].get<double>() - 1.0;
    EXPECT_LE(std::fabs(truth - paired.difference), paired.half_width) << "the full runs differ by " << truth;
    // 256x256 at 1 spp (181x181 at the grid's 2 spp), path tracing on mobile: in the error grid,
    // whose bound (5.6 %) is wider than the check's.
    EXPECT_EQ(lt["error_estimate"]["kind"], "validated bound") << lt["error_estimate"].dump();
}

namespace {

// rtsim started in the background with stderr to a file; `signal` is sent once `marker` shows on
// its stderr (its progress line: the phase the signal should reach), then its exit status.
struct Stopped {
    int status = -1;  // exit status; -1: ended by a signal, -2: finished before the marker showed
    std::string err;
};

// Starts rtsim with `args` in the background, its stderr to `err`, stdout and stdin /dev/null.
pid_t spawn_rtsim(const std::string& err, std::vector<std::string> args) {
    args.insert(args.begin(), RTU_RTSIM);
    std::vector<char*> argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    const pid_t pid = fork();
    if (pid == 0) {
        const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int null = ::open("/dev/null", O_RDWR);
        dup2(fd, 2);
        dup2(null, 1);
        dup2(null, 0);
        execv(argv[0], argv.data());
        _exit(127);
    }
    return pid;
}

// AT and LT show progress and stop at the monitor's wake-ups, every min(sim.watchdog / 4,
// 100,000) cycles (docs/usage.md). These arguments make it every 10,000, so that the first
// progress line shows and a stop lands within a second or two under the sanitizers too (the
// default took 15 s and 10 s there).
const std::vector<std::string> kPromptMonitor = {"--set", "sim.watchdog=40000"};

// Sends `signal` `times` times (20 ms apart) once `marker` shows in rtsim's messages.
Stopped stop_rtsim(const TempDir& dir, std::vector<std::string> args, const std::string& marker, int signal, int times = 1) {
    const std::string err = dir.file("stderr.txt");
    const pid_t pid = spawn_rtsim(err, std::move(args));
    int status = 0;
    bool sent = false;
    for (int i = 0; i < 1200 && !sent; ++i) {  // up to 120 s for the marker
        if (waitpid(pid, &status, WNOHANG) == pid) return {-2, read_text(err)};
        if (read_text(err).find(marker) != std::string::npos) {
            for (int k = 0; k < times; ++k) {
                if (k) usleep(20000);
                kill(pid, signal);
            }
            sent = true;
        } else {
            usleep(100000);
        }
    }
    if (!sent) kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_text(err)};
}

}  // namespace

// SIGINT and SIGTERM stop a long run at a clean point: the statistics of what was simulated so far
// with "interrupted": true, the VCD closed, no frame, exit 130 / 143 (issue 16). Each run would
// take 10 s or more (interval 11 s, functional 15 s, AT about a minute on the project's machine);
// the signal goes when its progress line shows (after 2 s).
TEST(Rtsim, SignalsStopTheRunAndKeepWhatItSimulated) {
    struct Case {
        std::string fidelity, marker;
        int signal, status;
        std::vector<std::string> size;
    };
    // Under the sanitizers a quarter of the frame still outlasts the progress line many times.
    const std::string side = rtu::test::kSanitized ? "512" : "1024";
    const std::vector<Case> cases = {
        {"at", "cycle ", SIGINT, 130, {"--width", side, "--height", side}},
        {"interval", "cycle ", SIGTERM, 143, {"--width", side, "--height", side}},
        {"functional", "traced ", SIGINT, 130, {"--width", side, "--height", side}},
        {"lt", "cycle ", SIGHUP, 129, {"--width", side, "--height", side}},  // a dropped SSH session
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.fidelity);
        TempDir dir;
        const std::string stats = dir.file("s.json"), png = dir.file("f.png"), vcd = dir.file("w.vcd");
        std::vector<std::string> args = {"--scene", "wknd", "--fidelity", c.fidelity, "--stats", stats, "--image", png};
        args.insert(args.end(), c.size.begin(), c.size.end());
        if (c.fidelity == "at") args.insert(args.end(), {"--vcd", vcd});
        if (c.fidelity == "at" || c.fidelity == "lt") args.insert(args.end(), kPromptMonitor.begin(), kPromptMonitor.end());
        const Stopped r = stop_rtsim(dir, args, c.marker, c.signal);
        ASSERT_NE(r.status, -2) << "the run finished before its progress line showed: make the frame larger\n" << r.err;
        ASSERT_EQ(r.status, c.status) << r.err;
        EXPECT_NE(r.err.find(std::string("interrupted by ") + (c.signal == SIGINT ? "SIGINT" : c.signal == SIGTERM ? "SIGTERM" : "SIGHUP")), std::string::npos) << r.err;
        EXPECT_FALSE(exists(png)) << "a partial frame was written";
        const nlohmann::json j = nlohmann::json::parse(read_text(stats));
        EXPECT_TRUE(j["interrupted"].get<bool>());
        const uint64_t frame_rays = uint64_t(j["params"]["width"].get<int>()) * j["params"]["height"].get<int>() * j["params"]["spp"].get<int>();
        EXPECT_GT(j["rays"].get<uint64_t>(), 0u);
        // Path tracing makes at least one ray per pixel sample and, on wknd, far more: a stop
        // after 2 s of a minute's run has not traced them all.
        EXPECT_LT(j["rays"].get<uint64_t>(), 3 * frame_rays);
        if (c.fidelity != "functional") {
            EXPECT_GT(j["cycles"].get<uint64_t>(), 0u);
            EXPECT_EQ(j["error_estimate"]["kind"], "none");
            EXPECT_TRUE(j["error_estimate"]["value"].is_null());
            // The counters are those of the cycles simulated: every node visited was fetched.
            EXPECT_GT(j["timing"]["l1"]["demand"]["accesses"].get<uint64_t>(), 0u);
        }
        if (c.fidelity == "at") {
            const std::string w = read_text(vcd);
            EXPECT_NE(w.find("$enddefinitions"), std::string::npos);
            EXPECT_EQ(w.back(), '\n') << "the VCD was not closed";
        }
    }
}

// SIGUSR1 writes the statistics so far ("snapshot": true, "interrupted": true) into the --stats
// file and the run goes on; its end replaces them with the final statistics, the same as a run
// that was never asked (observing changes nothing). The interval fidelity, wknd 640x640: about
// 5 s, the signal when its progress line shows (after 2 s).
TEST(Rtsim, Sigusr1WritesTheStatisticsSoFarAndTheRunGoesOn) {
    TempDir dir;
    const std::string stats = dir.file("s.json"), err = dir.file("stderr.txt");
    // The run must outlast its first progress line (2 s): 448x448 takes about 9 s in Release, and
    // 192x192 about 12 s under the sanitizers. There the run that is not signalled is left out:
    // that observing changes no statistic is checked in Release (as scripts/test_sanitizers.sh
    // leaves RtsimTiming.TracingChangesNoStatistic to it).
    const std::string side = rtu::test::kSanitized ? "192" : "448";
    const pid_t pid = spawn_rtsim(err, {"--scene", "wknd", "--fidelity", "interval", "--width", side, "--height", side, "--stats", stats});
    int status = 0;
    bool sent = false, snapshot_seen = false, exited = false;
    nlohmann::json snapshot;
    for (int i = 0; i < 1200 && !(exited = waitpid(pid, &status, WNOHANG) == pid); ++i) {  // watched for up to 120 s
        const std::string e = read_text(err);
        if (!sent && e.find("cycle ") != std::string::npos) {
            kill(pid, SIGUSR1);
            sent = true;
        }
        if (sent && !snapshot_seen && e.find("SIGUSR1: ") != std::string::npos) {
            snapshot = nlohmann::json::parse(read_text(stats));  // written whole (renamed) before the line
            snapshot_seen = true;
        }
        usleep(50000);
    }
    // A slow build (a sanitizer's, on a loaded machine) may still be running: its end is awaited,
    // not taken for exit status 0.
    if (!exited) waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << read_text(err);
    ASSERT_EQ(WEXITSTATUS(status), 0) << read_text(err);
    ASSERT_TRUE(sent) << "the run finished before its progress line showed: make the frame larger";
    ASSERT_TRUE(snapshot_seen) << read_text(err);
    EXPECT_NE(read_text(err).find("the run goes on"), std::string::npos);
    EXPECT_TRUE(snapshot["snapshot"].get<bool>());
    EXPECT_TRUE(snapshot["interrupted"].get<bool>());
    auto final_stats = nlohmann::json::parse(read_text(stats));
    EXPECT_FALSE(final_stats["snapshot"].get<bool>());
    EXPECT_GT(snapshot["rays"].get<uint64_t>(), 0u);
    EXPECT_LT(snapshot["rays"].get<uint64_t>(), final_stats["rays"].get<uint64_t>());
    EXPECT_LT(snapshot["cycles"].get<uint64_t>(), final_stats["cycles"].get<uint64_t>());
    EXPECT_LE(snapshot["timing"]["l1"]["demand"]["accesses"].get<uint64_t>(), final_stats["timing"]["l1"]["demand"]["accesses"].get<uint64_t>());
    if (rtu::test::kSanitized) return;
    const Result plain = rtsim(dir, "--scene wknd --fidelity interval --width " + side + " --height " + side + " -q --stats " + dir.file("plain.json"));
    ASSERT_EQ(plain.status, 0) << plain.err;
    auto unobserved = nlohmann::json::parse(read_text(dir.file("plain.json")));
    for (auto* j : {&final_stats, &unobserved}) erase_host_keys(*j);
    EXPECT_EQ(final_stats, unobserved);
}

// A second SIGINT ends rtsim at once, by the signal, and leaves no cut VCD behind (neither under
// its name nor under the temporary one it was written to).
TEST(Rtsim, ASecondSignalEndsAtOnceAndLeavesNoCutVcd) {
    TempDir dir;
    std::filesystem::create_directory(dir.file("out"));
    std::vector<std::string> args = {"--scene", "wknd", "--fidelity", "at", "--width", "1024", "--height", "1024", "--vcd", dir.file("out/w.vcd"),
                                     "--stats", dir.file("out/s.json")};
    args.insert(args.end(), kPromptMonitor.begin(), kPromptMonitor.end());
    const Stopped r = stop_rtsim(dir, args, "cycle ", SIGINT, 2);
    ASSERT_NE(r.status, -2) << "the run finished before its progress line showed\n" << r.err;
    EXPECT_EQ(r.status, -1) << "not ended by the signal\n" << r.err;
    EXPECT_TRUE(std::filesystem::is_empty(dir.file("out")));
}

// A stop before anything is simulated (here in the sampling pre-pass) writes nothing.
TEST(Rtsim, SignalBeforeTheSimulationWritesNothing) {
    TempDir dir;
    const std::string stats = dir.file("s.json");
    const Stopped r = stop_rtsim(dir,
                                 {"--scene", "wknd", "--fidelity", "interval", "--width", "1024", "--height", "1024", "--sample", "0.1",
                                  "--threads", "1", "--stats", stats},
                                 "sampling pre-pass", SIGINT);
    ASSERT_NE(r.status, -2) << r.err;
    EXPECT_EQ(r.status, 130) << r.err;
    EXPECT_NE(r.err.find("before the simulation started; nothing written"), std::string::npos) << r.err;
    EXPECT_FALSE(exists(stats));
}

// A legal configuration of maximal sizes asks for terabytes of cache tags: refused before the
// model is elaborated, naming the keys that make it large and the limit it passes (issue 16).
TEST(Rtsim, ConfigurationsTooLargeForTheMachineAreRefusedBeforeElaboration) {
    TempDir dir;
    const std::string stats = dir.file("s.json");
    const Result r = rtsim(dir, "--scene cornell --workload primary --width 8 --height 8 --fidelity at --set gpu.sms=1024 "
                                "--set l1.size_kb=1048576 --set l1.line=16 --set l1.sector=16 --set l2.slices=256 --set l2.slice_kb=4194304 "
                                "--set l2.line=16 --set l2.sector=16 --stats " + stats);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("l1.size_kb"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("l2.slice_kb"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("TiB"), std::string::npos) << r.err;  // no machine has that much
    EXPECT_FALSE(exists(stats));
    // Under an address-space limit (ulimit -v), a configuration that fits the machine but not the
    // limit: 64 slices of 16 MiB need about 0.4 GiB of tags (measured: 0.3 GiB resident at start).
    // AddressSanitizer reserves terabytes of address space for its shadow: it cannot start there.
#if defined(__SANITIZE_ADDRESS__)
    return;
#endif
    const std::string cmd = "ulimit -v 300000; " + std::string(RTU_RTSIM) +
                            " --scene cornell --workload primary --width 8 --height 8 --fidelity interval --set l2.slices=64 "
                            "--set l2.slice_kb=16384 --stats " + stats + " > /dev/null 2> " + dir.file("e.txt");
    const int rc = std::system(("bash -c '" + cmd + "'").c_str());
    EXPECT_EQ(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, 2) << read_text(dir.file("e.txt"));
    EXPECT_NE(read_text(dir.file("e.txt")).find("ulimit -v"), std::string::npos) << read_text(dir.file("e.txt"));
    EXPECT_FALSE(exists(stats));
    // A functional frame too large for the machine is refused by its estimate, before the
    // workload takes any of it: under 2 GB of address space, not as an allocation failure. (It
    // once ran 57 s and took 3.2 GB before failing.)
    const std::string big = "ulimit -v 2000000; " + std::string(RTU_RTSIM) + " --scene cornell --width 16384 --height 16384 -q --stats " + stats +
                            " > /dev/null 2> " + dir.file("e.txt");
    const int big_rc = std::system(("bash -c '" + big + "'").c_str());
    EXPECT_EQ(WIFEXITED(big_rc) ? WEXITSTATUS(big_rc) : -1, 2) << read_text(dir.file("e.txt"));
    EXPECT_NE(read_text(dir.file("e.txt")).find("the frame's traced rays, at least one a path"), std::string::npos) << read_text(dir.file("e.txt"));
    EXPECT_FALSE(exists(stats));
}

// The estimate against the memory actually taken: the growth of peak resident memory from a small
// configuration to large ones (many SMs; large L2 slices; many threads in flight) is within 20 % of
// the estimate's growth. Resident memory is the independent measure (getrusage); sanitizers
// inflate it, so it is not compared under them.
TEST(Rtsim, MemoryEstimateMatchesTheMemoryTaken) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "built with AddressSanitizer: resident memory includes its shadow and redzones";
#endif
    TempDir dir;
    const auto run = [&](const std::string& args) {
        const std::string stats = dir.file("m.json");
        const Result r = rtsim(dir, "--scene cornell --workload primary -q --stats " + stats + " " + args);
        EXPECT_EQ(r.status, 0) << r.err;
        const nlohmann::json j = nlohmann::json::parse(read_text(stats));
        return std::pair<double, double>{j["memory_mb"]["model_estimate"].get<double>(), j["memory_mb"]["peak_resident"].get<double>()};
    };
    for (const std::string fidelity : {"at", "interval"}) {
        const auto base = run("--width 8 --height 8 --fidelity " + fidelity);
        for (const std::string big : {"--width 8 --height 8 --set gpu.sms=1024", "--width 8 --height 8 --set l2.slices=32 --set l2.slice_kb=16384",
                                      "--width 512 --height 512 --spp 1 --set gpu.sms=128 --set rt.warp_buffer=64"}) {
            SCOPED_TRACE(fidelity + " " + big);
            const auto m = run(big + " --fidelity " + fidelity);
            const double estimated = m.first - base.first, measured = m.second - base.second;
            EXPECT_GT(estimated, 30.0);  // MiB: large against the measure's noise (a few MiB)
            EXPECT_NEAR(measured / estimated, 1.0, 0.2) << "estimated +" << estimated << " MiB, measured +" << measured << " MiB";
        }
    }
}

// Bounded work for bounded input (issue 16): hostile files of up to 1 MB, each of a class that
// once took gigabytes or minutes, end in at most 2 GB of resident memory (rtsim and the mesh
// importer's process) and 30 s, with exit 0 or 2. Measured per run with wait4 (the child's and its
// own children's peak); sanitizers inflate memory, so they skip it.
TEST(Rtsim, HostileInputsOfUpTo1MBStayWithin2GBAnd30s) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "built with AddressSanitizer: resident memory includes its shadow and redzones";
#endif
    TempDir dir;
    const size_t mb = 1 << 20;
    std::vector<std::pair<std::string, std::vector<std::string>>> cases;  // what, rtsim's arguments
    const auto scene_case = [&](const std::string& name, const std::string& bytes) {
        ASSERT_LE(bytes.size(), mb) << name;
        cases.push_back({name, {"--scene", write_text(dir.file(name), bytes), "--workload", "primary", "--width", "8", "--height", "8"}});
    };
    {  // a gzip bomb: one member of 16 MiB of spaces (16 KiB compressed) repeated to 1 MB: 1 GiB inflated
        const std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        const std::string member_path = dir.file("member.gz");
        gzFile g = gzopen(member_path.c_str(), "wb9");
        const std::string spaces(1 << 20, ' ');
        for (int i = 0; i < 16; ++i) gzwrite(g, spaces.data(), unsigned(spaces.size()));
        gzclose(g);
        const std::string member = read_text(member_path);
        gzFile h = gzopen(dir.file("head.gz").c_str(), "wb9");
        gzwrite(h, ply.data(), unsigned(ply.size()));
        gzclose(h);
        std::string bomb = read_text(dir.file("head.gz"));
        while (bomb.size() + member.size() <= mb) bomb += member;
        scene_case("bomb.ply.gz", bomb);
    }
    {  // a PLY whose header claims 2^31 vertices and faces, then 1 MB of numbers
        std::string ply = "ply\nformat ascii 1.0\nelement vertex 2147483647\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 2147483647\nproperty list uchar int vertex_indices\nend_header\n";
        while (ply.size() < mb - 16) ply += "0 0 0\n";
        scene_case("claims.ply", ply);
        std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 2147483647\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 2147483647\nproperty list uint int vertex_indices\nend_header\n";
        bin.resize(mb, '\xff');  // face lists of 4 billion entries
        scene_case("claims-binary.ply", bin);
    }
    {  // OBJ: 1 MB of faces with far-away and negative indices; 1 MB of vertices, no face
        std::string faces, verts;
        for (int i = 0; faces.size() < mb - 64; ++i) faces += "f " + std::to_string(2000000000 - i) + " -1 -2147483647\n";
        for (int i = 0; verts.size() < mb - 64; ++i) verts += "v 1e30 -1e30 " + std::to_string(i) + "\n";
        scene_case("faces.obj", faces);
        scene_case("verts.obj", verts);
    }
    {  // OFF counts of 2^31 with a 1 MB body
        std::string off = "OFF\n2147483647 2147483647 0\n";
        while (off.size() < mb - 16) off += "0 0 0\n";
        scene_case("claims.off", off);
    }
    {  // a GLB whose chunk claims 4 GiB, padded to 1 MB
        const std::string json = R"({"asset":{"version":"2.0"}}   )";
        std::string glb = "glTF";
        const auto u32 = [&glb](uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
        u32(2);
        u32(uint32_t(mb));
        u32(0xFFFFFF00u);
        glb += "JSON" + json;
        glb.resize(mb, ' ');
        scene_case("bomb.glb", glb);
    }
    {  // a configuration nested 500 k levels deep; 1 MB of rays (all to be traced, at AT)
        cases.push_back({"nested.json", {"--scene", "cornell", "--fidelity", "at", "--config",
                                         write_text(dir.file("nested.json"), std::string(mb / 2, '[') + std::string(mb / 2, ']'))}});
        std::string rays;
        while (rays.size() < mb - 64) rays += "278 278 800 0 0 -1 0 inf\n";
        cases.push_back({"rays.txt", {"--scene", "cornell", "--fidelity", "at", "--rays", write_text(dir.file("rays.txt"), rays)}});
    }
    for (auto& [what, args] : cases) {
        SCOPED_TRACE(what);
        args.insert(args.begin(), RTU_RTSIM);
        args.push_back("-q");
        std::vector<char*> argv;
        for (std::string& s : args) argv.push_back(s.data());
        argv.push_back(nullptr);
        const auto t0 = std::chrono::steady_clock::now();
        const pid_t pid = fork();
        if (pid == 0) {
            const int null = ::open("/dev/null", O_RDWR);
            dup2(null, 0);
            dup2(null, 1);
            dup2(null, 2);
            alarm(120);  // a hang ends as a failure, not a stuck suite
            execv(argv[0], argv.data());
            _exit(127);
        }
        int status = 0;
        rusage ru{};
        ASSERT_EQ(wait4(pid, &status, 0, &ru), pid);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
        EXPECT_TRUE(WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 2) << "exit " << WEXITSTATUS(status);
        EXPECT_LE(ru.ru_maxrss, 2L << 20) << "KiB";
        EXPECT_LE(seconds, 30.0);
        std::printf("  %-18s exit %d, %6.1f MiB, %5.2f s\n", what.c_str(), WEXITSTATUS(status), double(ru.ru_maxrss) / 1024.0, seconds);
    }
}
