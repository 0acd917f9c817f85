// Cache tags/LRU/MSHR logic and DRAM timing, checked against hand-worked sequences.
#include <map>

#include <gtest/gtest.h>

#include "dram_driver.h"
#include "test_util.h"

#include <random>
#include <set>
#include <vector>

#include "model/cache_bookings.h"
#include "model/calendar.h"
#include "model/config.h"
#include "model/dram.h"
#include "model/event_wheel.h"
#include "model/sector_cache.h"

using namespace rtu;

namespace {
CacheConfig tiny_cache() {
    // 4 lines of 128 B in 2 sets of 2 ways, 32 B sectors, 2 MSHRs merging 2 requests each.
    return CacheConfig{512, 2, 128, 32, 2, 2, 0};
}
}  // namespace

// Set index = (addr / 128) % 2. Lines 0x000, 0x100, 0x200 fall into set 0; 0x080 into set 1.
TEST(SectorCache, HandWorkedSequence) {
    SectorCache c(tiny_cache());
    EXPECT_EQ(c.read(0x000, 1, ReqKind::Demand), CacheOutcome::LineMiss);     // A: line 0, sector 0
    EXPECT_EQ(c.read(0x010, 2, ReqKind::Demand), CacheOutcome::MshrHit);      // same sector: merged
    EXPECT_EQ(c.read(0x008, 3, ReqKind::Demand), CacheOutcome::ReservationFail);  // merge limit 2
    EXPECT_EQ(c.read(0x020, 4, ReqKind::Prefetch), CacheOutcome::SectorMiss);  // line 0, sector 1
    EXPECT_EQ(c.read(0x100, 5, ReqKind::Demand), CacheOutcome::ReservationFail);  // both MSHRs busy
    EXPECT_EQ(c.mshrs_in_use(), 2u);
    EXPECT_EQ(c.fill(0x000), (SectorCache::Tokens{1, 2}));
    EXPECT_EQ(c.read(0x01F, 6, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x100, 7, ReqKind::Demand), CacheOutcome::LineMiss);     // set 0, second way
    // Set 0 now holds line 0 (sector 1 pending) and line 0x100 (pending): no victim.
    EXPECT_EQ(c.read(0x200, 8, ReqKind::Demand), CacheOutcome::ReservationFail);
    EXPECT_EQ(c.fill(0x020), (SectorCache::Tokens{4}));
    EXPECT_EQ(c.fill(0x100), (SectorCache::Tokens{7}));
    // Touch line 0 so that 0x100 is least recently used, then 0x200 evicts 0x100.
    EXPECT_EQ(c.read(0x030, 9, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x200, 10, ReqKind::Demand), CacheOutcome::LineMiss);
    c.fill(0x200);
    EXPECT_EQ(c.read(0x000, 11, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x100, 12, ReqKind::Demand), CacheOutcome::LineMiss);    // was evicted: evicts 0x200 (LRU)
    c.fill(0x100);
    EXPECT_EQ(c.read(0x200, 13, ReqKind::Demand), CacheOutcome::LineMiss);    // evicts line 0 (LRU)
    EXPECT_EQ(c.read(0x080, 14, ReqKind::Demand), CacheOutcome::LineMiss);    // set 1 unaffected

    const CacheAccessCounts d = c.stats(ReqKind::Demand), p = c.stats(ReqKind::Prefetch);
    EXPECT_EQ(d.accesses, 13u);  // tokens 1-3 and 5-14
    EXPECT_EQ(p.accesses, 1u);
    EXPECT_EQ(p.sector_misses, 1u);
    EXPECT_EQ(d.hits, 3u);
    EXPECT_EQ(d.mshr_hits, 1u);
    EXPECT_EQ(d.reservation_fails, 3u);
    EXPECT_EQ(d.line_misses, 6u);  // tokens 1, 7, 10, 12, 13, 14
    // Conservation: every access has exactly one outcome.
    for (const CacheAccessCounts& s : {d, p})
        EXPECT_EQ(s.accesses, s.hits + s.mshr_hits + s.sector_misses + s.line_misses + s.reservation_fails);
    EXPECT_EQ(d.evictions + p.evictions, 3u);
}

TEST(SectorCache, FullyAssociativeLru) {
    SectorCache c(CacheConfig{4 * 128, 0, 128, 32, 8, 8, 0});
    for (uint64_t l = 0; l < 4; ++l) {
        ASSERT_EQ(c.read(l * 128, l, ReqKind::Demand), CacheOutcome::LineMiss);
        c.fill(l * 128);
    }
    EXPECT_EQ(c.read(0, 9, ReqKind::Demand), CacheOutcome::Hit);         // line 0 most recent
    EXPECT_EQ(c.read(7 * 128, 9, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts line 1
    c.fill(7 * 128);
    EXPECT_EQ(c.read(1 * 128, 9, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_EQ(c.read(0, 9, ReqKind::Demand), CacheOutcome::Hit);
}

// Allocation at the fill (l1.allocation fill, GPGPU-Sim's streaming L1), hand-worked on set 0 of
// tiny_cache (lines 0x000, 0x100, 0x200, 0x300). Nothing is reserved at a miss: set 0 takes a
// third and fourth line miss while two are on their way, where allocation at the miss refuses
// the third (HandWorkedSequence); the victim is chosen when the data arrives, by the LRU order
// then; and a read of a sector on its way joins its MSHR whether or not its line is there.
TEST(SectorCache, AllocationAtTheFillChoosesTheVictimWhenTheDataArrives) {
    CacheConfig cfg = tiny_cache();
    cfg.allocate_on_fill = true;
    cfg.mshrs = 4;
    SectorCache c(cfg);
    for (uint64_t line : {0x000, 0x100}) {
        ASSERT_EQ(c.read(line, 1, ReqKind::Demand), CacheOutcome::LineMiss);
        c.fill(line);
    }
    // Both ways valid, 0x000 least recently used. Two line misses leave with no way taken.
    EXPECT_TRUE(c.would_miss(0x200));
    EXPECT_EQ(c.read(0x200, 2, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_TRUE(c.would_miss(0x200));  // on its way, not in its line: a miss that joins the MSHR
    EXPECT_EQ(c.read(0x210, 3, ReqKind::Demand), CacheOutcome::MshrHit);
    EXPECT_EQ(c.read(0x300, 4, ReqKind::Shader), CacheOutcome::LineMiss);
    EXPECT_EQ(c.read(0x000, 5, ReqKind::Demand), CacheOutcome::Hit);  // now 0x100 is the LRU line
    EXPECT_EQ(c.fill(0x200), (SectorCache::Tokens{2, 3}));                 // evicts 0x100, not 0x000
    EXPECT_EQ(c.read(0x000, 6, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x100, 7, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_EQ(c.fill(0x300), (SectorCache::Tokens{4}));  // evicts 0x200 (0x000 used since it came)
    EXPECT_EQ(c.read(0x200, 8, ReqKind::Demand), CacheOutcome::LineMiss);
    EXPECT_EQ(c.read(0x300, 9, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_FALSE(c.would_miss(0x300));
    const CacheAccessCounts d = c.stats(ReqKind::Demand), s = c.stats(ReqKind::Shader);
    EXPECT_EQ(d.reservation_fails + s.reservation_fails, 0u);
    EXPECT_EQ(d.evictions, 1u);  // 0x200's fill evicted 0x100
    EXPECT_EQ(s.evictions, 1u);  // the shader read's fill evicted 0x200
    EXPECT_EQ(c.mshrs_in_use(), 2u);  // 0x100 and 0x200 on their way

    // Allocated at the miss, the same reads find set 0 without a free way at the second miss.
    CacheConfig at_miss = tiny_cache();
    at_miss.mshrs = 4;
    SectorCache m(at_miss);
    for (uint64_t line : {0x000, 0x100}) {
        ASSERT_EQ(m.read(line, 1, ReqKind::Demand), CacheOutcome::LineMiss);
        m.fill(line);
    }
    EXPECT_EQ(m.read(0x200, 2, ReqKind::Demand), CacheOutcome::LineMiss);   // evicts 0x000 now
    EXPECT_FALSE(m.would_miss(0x210));                                      // reserved: merges
    EXPECT_EQ(m.read(0x300, 4, ReqKind::Shader), CacheOutcome::LineMiss);   // evicts 0x100
    EXPECT_EQ(m.read(0x000, 5, ReqKind::Demand), CacheOutcome::ReservationFail);  // both ways pending
}

// FIFO (l1.replacement fifo, GPGPU-Sim's F): set 0 of tiny_cache takes lines 0x000 then 0x100;
// line 0 is read again, which LRU counts and FIFO does not, so 0x200 evicts line 0 (the first in)
// where LRU evicts 0x100.
TEST(SectorCache, FifoEvictsTheFirstLineInWhateverItsUse) {
    CacheConfig cfg = tiny_cache();
    cfg.replacement = "fifo";
    SectorCache c(cfg);
    for (uint64_t line : {0x000, 0x100}) {
        ASSERT_EQ(c.read(line, 1, ReqKind::Demand), CacheOutcome::LineMiss);
        c.fill(line);
    }
    ASSERT_EQ(c.read(0x000, 2, ReqKind::Demand), CacheOutcome::Hit);
    ASSERT_EQ(c.read(0x200, 3, ReqKind::Demand), CacheOutcome::LineMiss);
    c.fill(0x200);
    EXPECT_EQ(c.read(0x100, 4, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x000, 5, ReqKind::Demand), CacheOutcome::LineMiss);  // evicts 0x100, in before 0x200
    c.fill(0x000);
    EXPECT_EQ(c.read(0x200, 6, ReqKind::Demand), CacheOutcome::Hit);
    EXPECT_EQ(c.read(0x100, 7, ReqKind::Demand), CacheOutcome::LineMiss);
}

// A transfer moves whole bursts: 2 B x 8 beats = 16 B per burst, two beats per memory cycle.
TEST(Dram, TransfersAreWholeBursts) {
    DramConfig c{};
    c.bus_bytes = 2;
    c.burst = 8;
    c.beats_per_cycle = 2;
    EXPECT_EQ(dram_transfer_cycles(c, 32), 8u);  // 2 bursts, 16 beats
    EXPECT_EQ(dram_transfer_cycles(c, 16), 4u);  // 1 burst
    EXPECT_EQ(dram_transfer_cycles(c, 8), 4u);   // still a whole burst
    c.burst = 32;                                // 64 B bursts
    EXPECT_EQ(dram_transfer_cycles(c, 32), 16u);
    c.burst = 1;                                 // 2 B per beat: 16 beats
    EXPECT_EQ(dram_transfer_cycles(c, 32), 8u);
    c.bus_bytes = 4;
    EXPECT_EQ(dram_transfer_cycles(c, 2), 1u);   // one beat, half a cycle, rounds up
    // The TTP authors' desktop (RTVR_RTX2060): 2 B x 16 beats = 32 B, 4 beats per command cycle.
    c.bus_bytes = 2;
    c.burst = 16;
    c.beats_per_cycle = 4;
    EXPECT_EQ(dram_transfer_cycles(c, 32), 4u);
    EXPECT_EQ(dram_transfer_cycles(c, 64), 8u);
}

namespace {
DramConfig dram() {
    DramConfig d{};
    d.channels = 1;
    d.banks = 4;
    d.bus_bytes = 2;
    d.burst = 8;
    d.beats_per_cycle = 2;
    d.queue = 8;
    d.row_bytes = 2048;
    d.set_scheduler("frfcfs_channel");  // the scheduler these tests work by hand
    d.tCL = 20, d.tRCD = 20, d.tRP = 20, d.tRAS = 50, d.tRC = 62, d.tRRD = 10, d.tCCD = 4, d.tWL = 8, d.tWR = 20;
    return d;
}
}  // namespace

// From the timing parameters: a 32 B read moves 32 / (2 B x 2) = 8 data cycles. Closed bank:
// tRCD + tCL + 8 = 48. Row hit: tCL + 8 = 28 after its column slot. Row conflict: precharge no
// earlier than ACT + tRAS, then tRP + tRCD + tCL + 8.
TEST(Dram, RowHitRowMissAndConflictLatencies) {
    const DramConfig cfg = dram();
    AddressMap map("line", cfg.channels, cfg.banks, cfg.row_bytes, cfg.channels, 128);
    DramChannel ch(cfg);
    auto issue = [&](uint64_t addr, uint64_t now) {
        DramRequest r;
        r.addr = addr;
        r.at = map.dram(addr);
        r.arrival = now;
        ch.enqueue(r);
        DramRequest out;
        uint64_t done = 0;
        EXPECT_TRUE(ch.schedule(now, &out, &done));
        return done;
    };
    EXPECT_EQ(issue(0, 0), 48u);            // closed bank: ACT 0, COL 20, data 40..48
    EXPECT_EQ(issue(128, 100), 100u + 28u); // same row (lines 0..15 share a row): hit
    // Row 1 of bank 0 is 16 lines x 4 banks further on: a conflict. ACT was at 0, so precharge
    // at 200 (>= tRAS), ACT 220, COL 240, data 260..268.
    const uint64_t conflict = 16ull * 128 * 4;
    EXPECT_EQ(map.dram(conflict).bank, 0u);
    EXPECT_EQ(map.dram(conflict).row, 1u);
    EXPECT_EQ(issue(conflict, 200), 200u + 20 + 20 + 20 + 8);
    const DramStats& s = ch.stats();
    EXPECT_EQ(s.row_misses, 1u);
    EXPECT_EQ(s.row_hits, 1u);
    EXPECT_EQ(s.row_conflicts, 1u);
    EXPECT_EQ(s.data_cycles, 24u);
}

TEST(Dram, FrFcfsPrefersRowHitsAndTrcHolds) {
    const DramConfig cfg = dram();
    AddressMap map("line", cfg.channels, cfg.banks, cfg.row_bytes, cfg.channels, 128);
    DramChannel ch(cfg);
    auto push = [&](uint64_t addr) {
        DramRequest r;
        r.addr = addr;
        r.token = addr;
        r.at = map.dram(addr);
        ch.enqueue(r);
    };
    DramRequest out;
    uint64_t done;
    push(0);
    ASSERT_TRUE(ch.schedule(0, &out, &done));  // opens row 0 of bank 0
    const uint64_t conflict = 16ull * 128 * 4;
    push(conflict);  // older, but a conflict
    push(256);       // younger row hit
    ASSERT_TRUE(ch.schedule(1, &out, &done));
    EXPECT_EQ(out.addr, 256u);
    ASSERT_TRUE(ch.schedule(2, &out, &done));
    EXPECT_EQ(out.addr, conflict);
    // ACT at 0; the next ACT of the same bank waits for tRC = 62 and tRAS + tRP = 70.
    EXPECT_EQ(done, 70u + 20 + 20 + 8);
}

namespace {
// test::drive_channel over (arrival, address) pairs, each request's token its address.
std::map<uint64_t, uint64_t> run_channel(const DramConfig& cfg, const AddressMap& map, std::vector<std::pair<uint64_t, uint64_t>> arrivals,
                                         bool every_cycle) {
    std::vector<DramRequest> requests;
    for (auto [arrival, addr] : arrivals) {
        DramRequest r;
        r.addr = addr;
        r.token = addr;
        r.arrival = arrival;
        r.at = map.dram(addr);
        requests.push_back(r);
    }
    return test::drive_channel(cfg, requests, every_cycle);
}
}  // namespace

// dram.scheduler frfcfs_banks (GPGPU-Sim's per-bank DRAM), worked by hand from dram.cc's rules
// with the timings of dram() (tRCD 20, tCL 20, tRP 20, tRAS 50, tRC 62, tRRD 10, tCCD 4); a 32 B
// read is two column commands of 16 B (2 B x burst 8), each with 4 data cycles, tCL after it.
//   0: bank 0 takes A (row 0) and ACTs; 1: bank 1 takes B; 10 (tRRD): bank 1 ACTs;
//   20, 24: A's columns, data ends 24 + 20 + 4 = 48; 30, 34: B's, ends 34 + 24 = 58.
//   100: bank 0 takes C (row 1, a conflict) and precharges (tRAS since its ACT at 0 has passed);
//   105: bank 1 takes D (row 0 of bank 1, a hit) and issues its columns at 105 and 109: ends 133;
//   120 (tRP): bank 0 ACTs row 1; 140, 144: C's columns, ends 168.
// The channel scheduler (frfcfs) gives C the same 168, but D waits for C's ACT: it picks D at
// 128 (tRCD before the column bus frees at 148), column 148, data 168..176.
TEST(Dram, PerBankSchedulerLetsOtherBanksPassAConflict) {
    DramConfig cfg = dram();
    cfg.set_scheduler("frfcfs_banks");
    AddressMap map("line", cfg.channels, cfg.banks, cfg.row_bytes, cfg.channels, 128);
    const uint64_t a = 0, b = 16 * 128, c = 16ull * 128 * 4, d = 16 * 128 + 256;
    ASSERT_EQ(map.dram(b).bank, 1u);
    ASSERT_EQ(map.dram(c).bank, 0u);
    ASSERT_EQ(map.dram(c).row, 1u);
    ASSERT_EQ(map.dram(d).row, map.dram(b).row);
    const std::vector<std::pair<uint64_t, uint64_t>> arrivals{{0, a}, {0, b}, {100, c}, {105, d}};
    for (bool every_cycle : {false, true}) {
        const auto done = run_channel(cfg, map, arrivals, every_cycle);
        EXPECT_EQ(done.at(a), 48u);
        EXPECT_EQ(done.at(b), 58u);
        EXPECT_EQ(done.at(c), 168u);
        EXPECT_EQ(done.at(d), 133u);
    }
    cfg.set_scheduler("frfcfs_channel");
    const auto channel = run_channel(cfg, map, arrivals, false);
    EXPECT_EQ(channel.at(c), 168u);
    EXPECT_EQ(channel.at(d), 176u);
}

// frfcfs_banks keeps the activation spacing: bank 0's second ACT tRC (62) after its first, and
// across banks tRRD (10). Reads to rows 0, 1 and 2 of bank 0 and row 0 of banks 1 and 2, all at 0.
//   0: bank 0 takes row 0, ACT; 1: bank 1 takes its read; 2: bank 2; 10: bank 1 ACTs, 20: bank 2.
//   Columns: bank 0 at 20, 24 (ends 48); bank 1 at 30, 34 (ends 58); bank 2 at 40, 44 (ends 68).
//   25: bank 0, its read done, takes row 1 (the oldest left); precharge at 50 (tRAS), ACT at 70
//   (tRP; tRC would allow 62), columns 90, 94: ends 118. 95: takes row 2; precharge at 120 (tRAS
//   after the ACT at 70), ACT 140, columns 160, 164: ends 188.
TEST(Dram, PerBankSchedulerKeepsActivationSpacing) {
    DramConfig cfg = dram();
    cfg.set_scheduler("frfcfs_banks");
    AddressMap map("line", cfg.channels, cfg.banks, cfg.row_bytes, cfg.channels, 128);
    const uint64_t row = 16ull * 128 * 4;
    const uint64_t b1 = 16 * 128, b2 = 2 * 16 * 128;
    const std::vector<std::pair<uint64_t, uint64_t>> arrivals{{0, 0}, {0, row}, {0, 2 * row}, {0, b1}, {0, b2}};
    for (bool every_cycle : {false, true}) {
        const auto done = run_channel(cfg, map, arrivals, every_cycle);
        EXPECT_EQ(done.at(0), 48u);
        EXPECT_EQ(done.at(b1), 58u);
        EXPECT_EQ(done.at(b2), 68u);
        EXPECT_EQ(done.at(row), 118u);
        EXPECT_EQ(done.at(2 * row), 188u);
    }
}

// The TTP authors' mapping (MOBILE gpgpusim.config l.155): the channel is bits 8-9 (256 B
// interleave); without them, bit 7 and bits 12-14 are the bank, bits 15-27 the row.
//   0x000: channel 0, bank 0, row 0          0x080: bit 7 -> bank 1
//   0x100: bit 8 -> channel 1                0x400: channel 0; without the channel 0x100 (column)
//   0x4000: without the channel 0x1000 (bit 12) -> bank 2; 0x20000: 0x8000 (bit 15) -> row 1
// With one slice per channel the slice is the channel.
TEST(AddressMap, GpgpuSimMappingHandWorked) {
    const std::string mobile = "dramid@8;00000000.00000000.00000000.00000000.0000RRRR.RRRRRRRR.RBBBCCCC.BCCSSSSS";
    const AddressMap m(mobile, 4, 16, 2048, 4, 128);
    auto at = [&](uint64_t a) {
        const DramCoord d = m.dram(a);
        return std::vector<uint64_t>{d.channel, d.bank, d.row, m.slice(a)};
    };
    EXPECT_EQ(at(0x000), (std::vector<uint64_t>{0, 0, 0, 0}));
    EXPECT_EQ(at(0x080), (std::vector<uint64_t>{0, 1, 0, 0}));
    EXPECT_EQ(at(0x100), (std::vector<uint64_t>{1, 0, 0, 1}));
    EXPECT_EQ(at(0x300), (std::vector<uint64_t>{3, 0, 0, 3}));
    EXPECT_EQ(at(0x400), (std::vector<uint64_t>{0, 0, 0, 0}));
    EXPECT_EQ(at(0x4000), (std::vector<uint64_t>{0, 2, 0, 0}));
    EXPECT_EQ(at(0x20000), (std::vector<uint64_t>{0, 0, 1, 0}));
    // The slice's own address: the channel bits squeezed out.
    EXPECT_EQ(m.slice_local()(0x4000 + 0x100 + 0x80), 0x1000u + 0x80u);
    // The authors' desktop (RTVR_RTX2060): 12 channels (not a power of two: (addr >> 8) % 12),
    // two sub-partitions each, told apart by the bank's lowest bit (bit 7): 24 slices.
    const AddressMap d(mobile, 12, 16, 2048, 24, 128);
    EXPECT_EQ(d.slice(0x000), 0u);
    EXPECT_EQ(d.slice(0x080), 1u);
    EXPECT_EQ(d.slice(0x100), 2u);
    EXPECT_EQ(d.slice(0x100 * 11 + 0x80), 23u);
    EXPECT_EQ(d.dram(0x100 * 12).channel, 0u);  // wraps: the rest is 0x100, a column bit
    EXPECT_EQ(d.dram(0x100 * 12).bank, 0u);
    EXPECT_EQ(d.slice_local()(0x100 * 12 + 0x80), 0x80u);  // channel digit out, then bit 7 (the sub-partition) out
    // Refused, saying why.
    auto refuses = [&](const std::string& spec, uint32_t ch, uint32_t slices, const std::string& why) {
        try {
            AddressMap(spec, ch, 16, 2048, slices, 128);
            ADD_FAILURE() << spec << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    refuses(mobile, 4, 6, "l2.slices (6) must be dram.channels (4) times a power of two");
    refuses("dramid@8;0000RRRR.RBBBCCCC.BCCSSSSS", 4, 4, "letters; there must be 64");
    refuses("dramid@x;" + mobile.substr(9), 4, 4, "not a number");
    refuses("random", 4, 4, "allowed are 'line'");
    refuses("dramid@8;00000000.00000000.00000000.00000000.0000RRRR.RRRRRRRR.RBBXCCCC.BCCSSSSS", 4, 4, "letter 'X'");
    refuses("dramid@8;00000000.00000000.00000000.00000000.0000RRRR.RRRRRRRR.RRBBCCCC.BCCSSSSS", 4, 4, "3 bank bits");
    refuses("dramid@6;00000000.00000000.00000000.00000000.0000RRRR.RRRRRRRR.RBBBCCCC.BCCSSSSS", 4, 4, "inside a 128 B line");
}

// An L2 slice indexes its sets with its own address. With the line map and 4 slices, slice 0
// holds every 4th line; indexed with the full address, its 64 sets x 16 ways would take only 16
// sets (the line number's low bits are the slice's), so 64 x 16 of its lines evict each other.
// Indexed with the slice's own address they fit. IPOLY spreads them too (a permutation of the
// linear index for each value of the bits above).
TEST(SectorCache, AnL2SliceUsesAllItsSets) {
    const HwConfig hw = Config::load("mobile").resolve();
    const AddressMap map = hw.address_map();
    auto evictions = [&](CacheConfig c) {
        SectorCache l2(c);
        uint64_t n = 0;
        for (uint64_t line = 0; n < 64 * 16; ++line) {
            const uint64_t a = line * 128;
            if (map.slice(a) != 0) continue;
            ++n;
            if (l2.read(a, n, ReqKind::Demand) != CacheOutcome::Hit) l2.fill(a);
        }
        return l2.stats(ReqKind::Demand).evictions;
    };
    CacheConfig c = hw.l2;
    EXPECT_EQ(evictions(c), 0u);
    c.ipoly = true;
    EXPECT_EQ(evictions(c), 0u);
    c.ipoly = false;
    c.local = SliceLocal{};  // the full address: set camping
    EXPECT_EQ(evictions(c), 64u * 16 - 16 * 16);
    for (uint32_t sets : {16u, 32u, 64u})
        for (uint64_t higher : {0ull, 1ull, 0x5a5ull, 0x7ffffull}) {
            std::set<uint32_t> seen;
            for (uint32_t i = 0; i < sets; ++i) seen.insert(ipoly_index(higher, i, sets));
            EXPECT_EQ(seen.size(), sets);
            EXPECT_LT(*seen.rbegin(), sets);
        }
    // Hand-worked: higher = 1 (bit 0) flips index bits 0 and 1 for 64 sets (IPOLY(67)'s rows 0
    // and 1 contain a[0]); for 16 sets, rows 0 and 1 as well.
    EXPECT_EQ(ipoly_index(1, 0, 64), 3u);
    EXPECT_EQ(ipoly_index(1, 0, 16), 3u);
    EXPECT_EQ(ipoly_index(0, 5, 32), 5u);
    // Bit 18 of the higher bits is in IPOLY(67)'s rows 0 and 4; bit 12 in IPOLY(5)'s row 1 only.
    EXPECT_EQ(ipoly_index(uint64_t(1) << 18, 0, 64), 17u);
    EXPECT_EQ(ipoly_index(uint64_t(1) << 12, 1, 16), 3u);
    EXPECT_THROW(ipoly_index(0, 0, 8), std::invalid_argument);
}

// BitPacker packs a mask's bits as pack_bits does, bit by bit: hand-worked, then against
// pack_bits on masks of every shape (empty, full, one bit, alternating, the presets' row and bank
// masks, random) and random values.
TEST(AddressMap, BitPackerPacksAsPackBits) {
    // Bits 4, 5 and 7 of 0b1010'0000: 0, 1, 1.
    EXPECT_EQ(BitPacker(0b1011'0000)(0b1010'0000), 0b110u);
    EXPECT_EQ(BitPacker(0)(~uint64_t(0)), 0u);
    EXPECT_EQ(BitPacker(~uint64_t(0))(0x0123'4567'89ab'cdefull), 0x0123'4567'89ab'cdefull);
    EXPECT_EQ(BitPacker(uint64_t(1) << 63)(~uint64_t(0)), 1u);  // bit 63 alone
    std::mt19937_64 rng(47);
    std::vector<uint64_t> masks = {0, ~uint64_t(0), 1, uint64_t(1) << 63, 0x5555'5555'5555'5555ull, 0xaaaa'aaaa'aaaa'aaaaull,
                                   ~(uint64_t(1) << 7), 0x0fff'8000ull, 0x7080ull, 0xffff'ffff'0000'0001ull};
    for (int i = 0; i < 200; ++i) masks.push_back(rng() & rng());  // sparse
    for (int i = 0; i < 200; ++i) masks.push_back(rng() | rng());  // dense
    for (const uint64_t mask : masks) {
        const BitPacker pack(mask);
        for (int v = 0; v < 20; ++v) {
            const uint64_t value = rng();
            ASSERT_EQ(pack(value), pack_bits(mask, value)) << std::hex << "mask " << mask << " value " << value;
        }
    }
}

// A configuration file whose number JSON cannot hold (1e400) is bad input naming the file, not an
// internal error (issue 16: it ended in exit 3).
// A configuration saved with a UTF-8 byte-order mark (as some Windows editors do) reads as
// without it (docs/robustness.md).
TEST(Config, AByteOrderMarkIsRead) {
    rtu::test::TempDir dir;
    const std::string path = rtu::test::write_text(dir.file("bom.json"), "\xEF\xBB\xBF{\"gpu\": {\"sms\": 4}}");
    EXPECT_EQ(Config::load(path).resolve().sms, 4u);
}

TEST(Config, OutOfRangeNumbersAndDeepNestingAreConfigErrors) {
    rtu::test::TempDir dir;
    const std::string path = rtu::test::write_text(dir.file("big.json"), "{\"l1\": {\"size_kb\": 1e400}}");
    try {
        Config::load(path);
        FAIL() << "1e400 was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find(path + ": not valid JSON"), std::string::npos) << e.what();
    }
    // 100 k nested objects: refused before parsing (it overflowed the stack), a string's braces
    // not counted.
    std::string deep;
    for (int i = 0; i < 100000; ++i) deep += "{\"a\":";
    deep += "1" + std::string(100000, '}');
    const std::string deep_path = rtu::test::write_text(dir.file("deep.json"), deep);
    try {
        Config::load(deep_path);
        FAIL() << "100 k levels were accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find(deep_path + ": nested deeper than 32 levels"), std::string::npos) << e.what();
    }
    const std::string braces = rtu::test::write_text(dir.file("b.json"), "{\"_comment\": \"" + std::string(100, '{') + "\", \"gpu\": {\"sms\": 4}}");
    EXPECT_EQ(Config::load(braces).resolve().sms, 4u);
}

TEST(Config, PresetsLoadAndBadValuesAreRejectedByKey) {
    const Config mobile = Config::load("mobile");
    const HwConfig m = mobile.resolve();
    EXPECT_EQ(m.sms, 8u);
    EXPECT_EQ(m.l1.size_bytes, 32u * 1024);
    EXPECT_EQ(m.l1.assoc, 0u);
    EXPECT_EQ(m.l2_slices * m.l2.size_bytes, 512u * 1024);
    EXPECT_EQ(m.l2_slices * m.l2.mshrs, 768u);
    EXPECT_EQ(m.dram.tRC, 62u);
    EXPECT_EQ(m.l1_hit_latency, 0u);
    const HwConfig d = Config::load("desktop").resolve();
    EXPECT_EQ(d.sms, 30u);
    EXPECT_EQ(d.l1.size_bytes, 64u * 1024);
    EXPECT_EQ(d.l2_slices * d.l2.size_bytes, 3u * 1024 * 1024);

    auto error_of = [](const std::vector<std::string>& sets) -> std::string {
        try {
            Config c = Config::load("mobile");
            for (const auto& s : sets) c.set(s);
            c.resolve();
        } catch (const ConfigError& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(error_of({"l1.size_kb=0"}).find("'l1.size_kb'"), std::string::npos);
    EXPECT_NE(error_of({"l1.line=100"}).find("power of two"), std::string::npos);
    EXPECT_NE(error_of({"l1.mshr_merge=300"}).find("'l1.mshr_merge'"), std::string::npos);
    EXPECT_NE(error_of({"l1.sizekb=3"}).find("unknown key 'l1.sizekb'"), std::string::npos);
    EXPECT_NE(error_of({"gpu.sms=two"}).find("needs a number"), std::string::npos);
    EXPECT_NE(error_of({"gpu.sms=2.5"}).find("whole number"), std::string::npos);
    EXPECT_NE(error_of({"dram.scheduler=random"}).find("'dram.scheduler'"), std::string::npos);
    EXPECT_NE(error_of({"l2.assoc=3"}).find("'l2.assoc'"), std::string::npos);
    EXPECT_NE(error_of({"dram.tRC=10"}).find("'dram.tRC'"), std::string::npos);
    EXPECT_NE(error_of({"l1.sector=256"}).find("'l1.sector'"), std::string::npos);
    EXPECT_EQ(error_of({"l1.size_kb=64", "gpu.sms=30"}), "");
    EXPECT_THROW(Config::load("no-such-preset-or-file"), ConfigError);
    // The effective configuration round-trips through JSON.
    Config c = Config::load("mobile");
    c.set("l2.latency=123");
    EXPECT_EQ(c.to_json()["l2"]["latency"], 123);
}

// PortCalendar against a plain set of taken cycles: every booking gets the earliest cycle at or
// after max(its timestamp, the floor) that no earlier booking took, in any order of timestamps,
// across the ring's growth (bookings up to 200,000 cycles ahead of the floor) and its reuse as
// the floor advances.
TEST(PortCalendar, BooksTheEarliestFreeCycleInAnyOrder) {
    PortCalendar port;
    std::vector<bool> taken;  // by cycle (a bitmap: a std::set took 5 s of this test under ASan)
    auto is_taken = [&](uint64_t c) { return c < taken.size() && taken[c]; };
    std::mt19937_64 rng(7);
    uint64_t floor = 0;
    for (int i = 0; i < 20000; ++i) {
        if (i % 1000 == 999) {
            floor += rng() % 5000;
            port.advance(floor);
        }
        const uint64_t t = floor + (i % 97 == 0 ? rng() % 200000 : rng() % 300);
        uint64_t expect = std::max(t, floor);
        while (is_taken(expect)) ++expect;
        ASSERT_EQ(port.first_free(t), expect) << "booking " << i;
        ASSERT_EQ(port.book(t), expect) << "booking " << i;
        if (expect >= taken.size()) taken.resize(expect + 1);
        taken[expect] = true;
    }
    // Hand-worked: 10, then 11 for the same timestamp, 5 before them, 12 after 10 and 11.
    PortCalendar p;
    EXPECT_EQ(p.book(10), 10u);
    EXPECT_EQ(p.book(10), 11u);
    EXPECT_EQ(p.book(5), 5u);
    EXPECT_EQ(p.first_free(10), 12u);
    EXPECT_EQ(p.book(10), 12u);
    p.advance(11);
    EXPECT_EQ(p.book(0), 13u);  // 11 and 12 are still taken
}

// EventWheel against a min-heap on (at, seq): the same events in the same order, for pushes
// mostly just ahead of the last event handed out (as the interval fidelity's fetches), and some
// far ahead (beyond the window) or behind it, interleaved with pops, and across stretches where
// only far events are left.
TEST(EventWheel, HandsOutAsAHeapOnTimeThenSequence) {
    struct Ev {
        uint64_t at, seq;
        bool operator>(const Ev& o) const { return at != o.at ? at > o.at : seq > o.seq; }
    };
    EventWheel<Ev> wheel;
    std::priority_queue<Ev, std::vector<Ev>, std::greater<Ev>> heap;
    std::mt19937_64 rng(5);
    uint64_t seq = 0, now = 0, popped = 0, far = 0, behind = 0;
    for (int i = 0; i < 200000; ++i) {
        const uint64_t r = rng() % 100;
        if (r < 55 || heap.empty()) {
            uint64_t at = now + rng() % 400;  // ties in time are frequent
            if (r == 0) {
                at = now + EventWheel<Ev>::kWindow + rng() % 100000;
                ++far;
            }
            if (r == 1 && now > 50) {
                at = now - 1 - rng() % 50;
                ++behind;
            }
            wheel.push({at, seq});
            heap.push({at, seq});
            ++seq;
        } else {
            ASSERT_EQ(wheel.size(), heap.size());
            ASSERT_EQ(wheel.top().at, heap.top().at) << "pop " << popped;
            ASSERT_EQ(wheel.top().seq, heap.top().seq) << "pop " << popped;
            now = heap.top().at;
            wheel.pop();
            heap.pop();
            ++popped;
        }
        if (i == 150000)  // drain all: the far events are all that is left at the end
            while (!heap.empty()) {
                ASSERT_EQ(wheel.top().seq, heap.top().seq);
                now = heap.top().at;
                wheel.pop();
                heap.pop();
            }
    }
    EXPECT_GT(popped, 50000u);
    EXPECT_GT(far, 1000u);
    EXPECT_GT(behind, 1000u);
}

// The fast fidelities' DRAM (DramBookings), hand-worked with the mobile preset's timing (memory
// cycles: tRCD = tCL = tRP = 20, a 32 B transfer 8 cycles on a 2 B DDR bus, column slot
// max(tCCD, 8) = 8; a bank's ACTs max(tRC, tRAS + tRP) = max(62, 70) = 70 apart, a channel's
// tRRD = 10 apart). Five reads all timestamped 0, in this call order:
//   A ch0 bank0 row0, closed: bank [0,24), ACT 0; column at tRCD = 20 (slot [20,28)); data 40..48
//   B same row (hit): bank after A's activation, 24; slot after A's: 28; data 48..56
//   C ch0 bank0 row1 (conflict): the bank is free at 28, but its ACT waits for A's + 70: ACT 70,
//     precharge (bank_start) 50, bank [50,94); the precharge and a slot on the command sequence
//     from 50 + tRCD = 70: [70,98), column 90; data 110..118 (AT's channel: the same, test
//     Dram.FrFcfsPrefersRowHitsAndTrcHolds)
//   D ch1 (its own channel): as A, 48
//   E ch0 bank1, closed: its ACT waits for A's + tRRD: 10, bank [10,34); first slot free from
//     30 is [36,44): column 36; data would start at 56, after B's transfer: 56..64
TEST(DramBookings, HandWorkedCommandSequence) {
    const HwConfig hw = Config::load("mobile").resolve();
    const DramConfig& c = hw.dram;
    ASSERT_EQ(c.tRCD, 20u);
    ASSERT_EQ(c.tCL, 20u);
    ASSERT_EQ(c.tRP, 20u);
    ASSERT_EQ(dram_transfer_cycles(c, 32), 8u);  // two bursts of 8 beats x 2 B, two beats per cycle
    DramBookings d(c, hw.address_map());
    EXPECT_EQ(d.access(0, 32, 0, 0), 48u);       // A
    EXPECT_EQ(d.access(32, 32, 0, 0), 56u);      // B
    EXPECT_EQ(d.access(131072, 32, 0, 0), 118u); // C
    EXPECT_EQ(d.access(128, 32, 0, 0), 48u);     // D
    EXPECT_EQ(d.access(8192, 32, 0, 0), 64u);    // E
    const DramStats& s0 = d.stats()[0];
    EXPECT_EQ(s0.reads, 4u);
    EXPECT_EQ(s0.row_hits, 1u);
    EXPECT_EQ(s0.row_misses, 2u);
    EXPECT_EQ(s0.row_conflicts, 1u);
    EXPECT_EQ(d.stats()[1].reads, 1u);
}

// FR-FCFS in the fast fidelities' DRAM: a read is a row hit when its row's epoch is open at its
// arrival or later, whatever the order of the calls. Mobile timing as above; ch0 bank0, rows 0
// and 1 (addresses 0 and 32: row 0; 131072 and 131104: row 1). In this call order:
//   A row 0 at 0, closed bank: bank [0,24), ACT 0, slot [20,28), data 40..48. Epoch row 0 from 0.
//   C row 1 at 0 (conflict): its ACT waits for A's + 70: ACT 70, bank [50,94); precharge and slot
//     on the command sequence from 50 + tRCD = 70: [70,98), column 90, data 110..118. Its
//     decision, 70 - tRCD = 50, closes row 0's epoch there.
//   F row 0 at 10: row 0 is open until 50, so FR-FCFS serves F as a hit before C (call order
//     would have made it a conflict). Bank [24,28); slot [28,36); data 48..56.
//   K row 1 at 50: C's epoch is open: a hit (call order, after F, a conflict). Bank after C's
//     hold, [94,98); slot after C's column, [98,106); data 118..126.
//   G row 0 at 60: row 0's first epoch closed at 50, row 1 is open: a conflict. Bank free at 98,
//     its ACT after C's + 70: ACT 140, bank [120,164); command sequence [140,168), column 160,
//     data 180..188. Decision 120.
//   L row 0 at 70, called after G but arriving before G's row opens: in AT it waits in the queue
//     until G opens row 0, then is a hit. Bank [98,102); slot after G's column, [168,176); data
//     188..196.
TEST(DramBookings, RowHitsFollowTimeNotCallOrder) {
    const HwConfig hw = Config::load("mobile").resolve();
    DramBookings d(hw.dram, hw.address_map());
    EXPECT_EQ(d.access(0, 32, 0, 0), 48u);         // A
    EXPECT_EQ(d.access(131072, 32, 0, 0), 118u);   // C
    EXPECT_EQ(d.access(32, 32, 10, 0), 56u);       // F
    EXPECT_EQ(d.access(131104, 32, 50, 0), 126u);  // K
    EXPECT_EQ(d.access(32, 32, 60, 0), 188u);      // G
    EXPECT_EQ(d.access(0, 32, 70, 0), 196u);       // L
    const DramStats& s = d.stats()[0];
    EXPECT_EQ(s.reads, 6u);
    EXPECT_EQ(s.row_misses, 1u);     // A
    EXPECT_EQ(s.row_conflicts, 2u);  // C, G
    EXPECT_EQ(s.row_hits, 3u);       // F, K, L
    // FCFS serves reads in turn: only the bank's last row is a hit. F finds C's row 1 open, K
    // then F's row 0, G then K's row 1: conflicts; L follows G in row 0.
    HwConfig fcfs = hw;
    fcfs.dram.set_scheduler("fcfs");
    DramBookings f(fcfs.dram, fcfs.address_map());
    for (auto [addr, now] : {std::pair<uint64_t, uint64_t>{0, 0}, {131072, 0}, {32, 10}, {131104, 50}, {32, 60}, {0, 70}})
        f.access(addr, 32, now, 0);
    EXPECT_EQ(f.stats()[0].row_misses, 1u);
    EXPECT_EQ(f.stats()[0].row_conflicts, 4u);
    EXPECT_EQ(f.stats()[0].row_hits, 1u);
}

// Activation spacing in the fast fidelities' DRAM against AT's scheduler (DramChannel, an
// independent implementation): a bank's next ACT no earlier than max(tRC, tRAS + tRP) after its
// last, a channel's no earlier than tRRD after its last. Until 2026-11-27 DramBookings kept
// neither: the first case took 92 cycles, the second 56 (LT on sprng's primary rays 256x256 on
// `paper`, more than half of whose reads are row conflicts: -5.5 % against AT before, -4.2 % after).
TEST(DramBookings, ActivationsKeepAtsSpacing) {
    const HwConfig hw = Config::load("mobile").resolve();
    const AddressMap map = hw.address_map();
    // Each read's data end in AT, the reads queued in this order at cycle 0.
    auto at = [&](const std::vector<uint64_t>& addrs) {
        std::vector<std::pair<uint64_t, uint64_t>> arrivals;
        for (uint64_t a : addrs) arrivals.push_back({0, a});
        const auto by_addr = run_channel(hw.dram, map, arrivals, false);
        std::vector<uint64_t> done;
        for (uint64_t a : addrs) done.push_back(by_addr.at(a));
        return done;
    };
    auto lt = [&](const std::vector<uint64_t>& addrs) {
        DramBookings b(hw.dram, map);
        std::vector<uint64_t> done;
        for (uint64_t a : addrs) done.push_back(b.access(a, 32, 0, 0));
        return done;
    };
    // Rows 0 and 1 of channel 0, bank 0: a closed bank, then a conflict (its ACT at 70: 118).
    const std::vector<uint64_t> conflict{0, 131072};
    ASSERT_EQ(map.dram(131072).bank, map.dram(0).bank);
    EXPECT_EQ(lt(conflict), at(conflict));
    EXPECT_EQ(at(conflict), (std::vector<uint64_t>{48, 118}));
    // Banks 0 and 1 of channel 0, both closed: the second ACT at tRRD = 10, its data 50..58.
    const std::vector<uint64_t> two_banks{0, 8192};
    ASSERT_NE(map.dram(8192).bank, map.dram(0).bank);
    ASSERT_EQ(map.dram(8192).channel, map.dram(0).channel);
    EXPECT_EQ(lt(two_banks), at(two_banks));
    EXPECT_EQ(at(two_banks), (std::vector<uint64_t>{48, 58}));
}

// The fast fidelities' DRAM under frfcfs_banks (every preset's) against AT's (DramChannel, an
// independent implementation, worked by hand in Dram.PerBankSchedulerLetsOtherBanksPassAConflict):
// a conflict's precharge holds only its own bank. `mobile`'s line map puts lines 0, 64, 1024 and
// 68 (addresses 0, 8192, 131072, 8704) in channel 0: bank 0 row 0, bank 1 row 0, bank 0 row 1,
// bank 1 row 0. A and B at 0: 48 and 58 (B's ACT tRRD after A's). C at 100, a conflict: precharge
// 100, ACT 120, column 140, data 160..168. D at 105, a hit in bank 1: column 105, data 125..133,
// in whichever order the fast fidelities book C and D. frfcfs_channel's AT gives D 176 (it waits
// for C's ACT; Dram.PerBankSchedulerLetsOtherBanksPassAConflict).
TEST(DramBookings, PerBankConflictHoldsOnlyItsBank) {
    const HwConfig hw = Config::load("mobile").resolve();
    ASSERT_EQ(hw.dram.scheduler_name, "frfcfs_banks");
    const AddressMap map = hw.address_map();
    const uint64_t a = 0, b = 8192, c = 131072, d = 8704;
    ASSERT_EQ(map.dram(b).channel, 0u);
    ASSERT_EQ(map.dram(b).bank, 1u);
    ASSERT_EQ(map.dram(c).bank, 0u);
    ASSERT_EQ(map.dram(c).row, 1u);
    ASSERT_EQ(map.dram(d).bank, 1u);
    ASSERT_EQ(map.dram(d).row, 0u);
    const std::vector<std::pair<uint64_t, uint64_t>> arrivals{{0, a}, {0, b}, {100, c}, {105, d}};
    const auto at = run_channel(hw.dram, map, arrivals, false);
    EXPECT_EQ(at, (std::map<uint64_t, uint64_t>{{a, 48}, {b, 58}, {c, 168}, {d, 133}}));
    for (bool d_first : {false, true}) {
        DramBookings lt(hw.dram, map);
        EXPECT_EQ(lt.access(a, 32, 0, 0), at.at(a));
        EXPECT_EQ(lt.access(b, 32, 0, 0), at.at(b));
        if (d_first) {
            EXPECT_EQ(lt.access(d, 32, 105, 0), at.at(d));
        }
        EXPECT_EQ(lt.access(c, 32, 100, 0), at.at(c));
        if (!d_first) {
            EXPECT_EQ(lt.access(d, 32, 105, 0), at.at(d));
        }
    }
}

// Calendar against a plain set of busy cycles: each booking gets the earliest run of `len` free
// cycles at or after its timestamp, in any order of timestamps, with horizons that only forget
// bookings no later request can reach; first_free finds the same gap without taking it.
TEST(Calendar, BooksTheEarliestFreeGapInAnyOrder) {
    Calendar cal;
    std::vector<bool> busy;  // by cycle (a bitmap: a std::set took 11 s of this test under ASan)
    auto is_busy = [&](uint64_t c) { return c < busy.size() && busy[c]; };
    std::mt19937_64 rng(11);
    uint64_t horizon = 0;
    for (int i = 0; i < 3000; ++i) {
        if (i % 200 == 199) horizon += rng() % 300;
        const uint64_t t = horizon + rng() % 2000, len = rng() % 12;
        uint64_t expect = t;
        for (bool clash = len > 0; clash;) {
            clash = false;
            for (uint64_t c = expect; c < expect + len; ++c)
                if (is_busy(c)) {
                    expect = c + 1;
                    clash = true;
                    break;
                }
        }
        ASSERT_EQ(cal.first_free(t, len), expect) << "probe " << i;  // what the horizon forgets ends by t
        ASSERT_EQ(cal.book(t, len, horizon), expect) << "booking " << i;
        if (expect + len > busy.size()) busy.resize(expect + len);
        for (uint64_t c = expect; c < expect + len; ++c) busy[c] = true;
    }
    EXPECT_LT(cal.intervals(), 4096u);  // the pruning that keeps the newest half never ran
}

// CacheBookings (LT and interval): requests in any timestamp order against a cache whose tags
// are filled at once. Fully associative, 4 lines, 2 MSHRs merging 3 requests each, hit latency 5.
TEST(CacheBookings, HandWorkedSequence) {
    CacheBookings c(CacheConfig{512, 0, 128, 32, 2, 3, 0}, 5, true);
    using L = CacheBookings::Lookup;
    auto demand = [&](uint64_t addr, uint64_t cycle) { return c.lookup(addr, cycle, ReqKind::Demand); };
    // A: a miss at 10 leaves at 15 (lookup + hit latency); its data comes at 100, from DRAM.
    L a = demand(0x000, 10);
    EXPECT_EQ(a.outcome, L::Miss);
    EXPECT_EQ(a.ready, 15u);
    c.fill(0x000, a, 100, true, ReqKind::Demand);
    // B: a read at 20 waits for it (an MSHR hit), with the data's source.
    L b = demand(0x000, 20);
    EXPECT_EQ(b.outcome, L::InFlight);
    EXPECT_EQ(b.ready, 100u);
    EXPECT_TRUE(b.dram);
    // C: a read timestamped at 8, before the miss left at 10, takes the miss over: its data comes
    // 90 cycles after 8.
    L cc = demand(0x000, 8);
    EXPECT_EQ(cc.outcome, L::InFlight);
    EXPECT_EQ(cc.ready, 98u);
    // D: a third merge exceeds the merge limit of 3 requests: a reservation fail that retries when
    // the sector arrives (98), a hit 5 cycles later; the port is held until then.
    L d = demand(0x000, 30);
    EXPECT_EQ(d.outcome, L::Retry);
    EXPECT_EQ(d.retry_at, 98u);
    EXPECT_EQ(d.ready, 103u);
    // E: the next lookup gets the port at 99; a sector miss with an MSHR free (A's frees at 100).
    L e = demand(0x020, 31);
    EXPECT_EQ(e.cycle, 99u);
    EXPECT_EQ(e.outcome, L::Miss);
    EXPECT_EQ(e.ready, 104u);
    c.fill(0x020, e, 200, true, ReqKind::Demand);
    // F at 100: A's MSHR is free again. G at 101: both MSHRs busy (E until 200, F until 300): the
    // miss waits for E's, a reservation fail, and holds the port until then (AT withholds END_REQ).
    L f = demand(0x040, 100);
    EXPECT_EQ(f.ready, 105u);
    EXPECT_EQ(f.retry_at, 0u);
    c.fill(0x040, f, 300, true, ReqKind::Demand);
    L g = demand(0x060, 101);
    EXPECT_EQ(g.outcome, L::Miss);
    EXPECT_EQ(g.retry_at, 200u);
    EXPECT_EQ(g.ready, 205u);
    c.fill(0x060, g, 400, true, ReqKind::Demand);
    // H at 102 gets the port at 201: a prefetch's miss that waits for F's MSHR (300), holding the
    // port again; I: a demand read (port at 301) finds it on its way (late, useful); J: a second
    // demand read is not counted again.
    L h = c.lookup(0x080, 102, ReqKind::Prefetch);
    EXPECT_EQ(h.cycle, 201u);
    EXPECT_EQ(h.retry_at, 300u);
    EXPECT_EQ(h.ready, 305u);
    c.fill(0x080, h, 500, true, ReqKind::Prefetch);
    EXPECT_EQ(demand(0x080, 103).outcome, L::InFlight);
    EXPECT_EQ(demand(0x080, 104).outcome, L::InFlight);
    // K at 150, after J's port cycle (302): the data is there, a plain hit.
    L k = demand(0x000, 150);
    EXPECT_EQ(k.outcome, L::Hit);
    EXPECT_EQ(k.cycle, 303u);
    EXPECT_EQ(k.ready, 308u);

    const CacheAccessCounts s = c.tags().stats(ReqKind::Demand), p = c.tags().stats(ReqKind::Prefetch);
    const PrefetchedSectorCounts pf = c.tags().counts().prefetched;
    EXPECT_EQ(s.mshr_hits, 4u);          // B, C, I, J
    EXPECT_EQ(s.reservation_fails, 2u);  // D, G
    EXPECT_EQ(s.hits, 2u);               // D's lookup, K
    EXPECT_EQ(s.sector_misses + s.line_misses, 4u);  // A, E, F, G
    EXPECT_EQ(s.accesses, s.hits + s.mshr_hits + s.sector_misses + s.line_misses + s.reservation_fails);
    EXPECT_EQ(p.reservation_fails, 1u);  // H
    EXPECT_EQ(pf.useful, 1u);
    EXPECT_EQ(pf.late, 1u);
}

// CacheBookings of a cache allocated at the fill (GPGPU-Sim's ON_FILL, the presets' L1), as AT's
// tags see it: a missed line takes its way when its data arrives, the LRU victim at that moment;
// until then the line is absent (another sector's read is a line miss) and its ways untouched.
// Fully associative, 2 lines of 128 B, 4 MSHRs, LRU, hit latency 5.
TEST(CacheBookings, AllocationAtTheFillChoosesTheVictimWhenTheDataArrives) {
    CacheConfig cfg{256, 0, 128, 32, 4, 3, 0};
    cfg.allocate_on_fill = true;
    CacheBookings c(cfg, 5, true);
    using L = CacheBookings::Lookup;
    auto read = [&](uint64_t addr, uint64_t cycle) { return c.lookup(addr, cycle, ReqKind::Demand); };
    const uint64_t X = 0x000, Y = 0x080, Z = 0x100;  // three lines
    c.fill(X, read(X, 10), 50, true, ReqKind::Demand);
    c.fill(Y, read(Y, 11), 60, true, ReqKind::Demand);
    EXPECT_EQ(read(X, 70).outcome, L::Hit);  // Y is now the least recently used
    const L z = read(Z, 80);                 // Z's data comes at 200; no victim yet
    EXPECT_EQ(z.outcome, L::Miss);
    c.fill(Z, z, 200, true, ReqKind::Demand);
    // Y is still there at 100 (allocated at the miss, Z would have evicted it at 80), and the
    // read makes X the least recently used.
    EXPECT_EQ(read(Y, 100).outcome, L::Hit);
    // A read of Z's sector at 120 merges into its miss; another sector of Z's line at 150 finds
    // no line: a line miss (allocated at the miss: a sector miss).
    EXPECT_EQ(read(Z, 120).outcome, L::InFlight);
    const L z2 = read(Z + 0x20, 150);
    EXPECT_EQ(z2.outcome, L::Miss);
    c.fill(Z + 0x20, z2, 250, true, ReqKind::Demand);
    // Z's data came at 200 and took X's way, the victim then: X misses at 210; Y still hits.
    const L x = read(X, 210);
    EXPECT_EQ(x.outcome, L::Miss);
    c.fill(X, x, 400, true, ReqKind::Demand);
    EXPECT_EQ(read(Y, 220).outcome, L::Hit);
    // At 300 Z's second sector is in (its line's way already Z's); X's data is still on its way,
    // so nothing was evicted for it: Y and both of Z's sectors hit.
    EXPECT_EQ(read(Z + 0x20, 300).outcome, L::Hit);
    EXPECT_EQ(read(Z, 301).outcome, L::Hit);
    EXPECT_EQ(read(Y, 302).outcome, L::Hit);

    const CacheAccessCounts s = c.tags().stats(ReqKind::Demand);
    EXPECT_EQ(s.line_misses, 5u);  // X, Y, Z at their first reads, Z's second sector, X again
    EXPECT_EQ(s.sector_misses, 0u);
    EXPECT_EQ(s.mshr_hits, 1u);
    EXPECT_EQ(s.hits, 6u);
    EXPECT_EQ(s.evictions, 1u);  // X, by Z's fill
    EXPECT_EQ(s.accesses, s.hits + s.mshr_hits + s.sector_misses + s.line_misses + s.reservation_fails);
}

// Memory policies (docs/timing.md, "Memory policies"): a new replacement policy or DRAM scheduler
// is one class and one registration. Each test below writes one that no preset has, registers it
// and checks it by hand where the cache or the DRAM uses it.
namespace {
// Evicts the most recently used way: the opposite of LRU, so that a hand-worked sequence tells
// the two apart. Ways are kept in a per-set list, most recent first.
class MostRecentlyUsed : public ReplacementPolicy {
public:
    MostRecentlyUsed(uint32_t sets, uint32_t) : order_(sets) {}
    void touched(uint32_t set, uint32_t way) override {
        auto& o = order_[set];
        o.erase(std::remove(o.begin(), o.end(), way), o.end());
        o.insert(o.begin(), way);
    }
    uint32_t first_victim(uint32_t set) const override { return order_[set].empty() ? kNone : order_[set].front(); }
    uint32_t next_victim(uint32_t set, uint32_t way) const override {
        const auto& o = order_[set];
        const auto it = std::find(o.begin(), o.end(), way);
        return it == o.end() || it + 1 == o.end() ? kNone : *(it + 1);
    }
    void clear() override {
        for (auto& o : order_) o.clear();
    }

private:
    std::vector<std::vector<uint32_t>> order_;
};
}  // namespace

// Set 0 of tiny_cache (2 ways) holds lines 0x000 and 0x100; line 0 is then read again, so it is
// the most recently used. 0x200 evicts line 0 under the test's policy (LRU evicts 0x100): line 0
// then misses (and evicts 0x200, the most recent) and 0x100 hits; under LRU the other way round.
TEST(MemoryPolicies, AReplacementPolicyIsOneClassAndOneRegistration) {
    register_replacement({"test-mru", "evicts the most recently used way", 0, 0,
                          [](uint32_t sets, uint32_t assoc) { return std::make_unique<MostRecentlyUsed>(sets, assoc); }});
    for (const std::string policy : {"lru", "test-mru"}) {
        CacheConfig cfg = tiny_cache();
        cfg.replacement = policy;
        SectorCache c(cfg);
        for (uint64_t line : {0x000, 0x100}) {
            ASSERT_EQ(c.read(line, 1, ReqKind::Demand), CacheOutcome::LineMiss);
            c.fill(line);
        }
        ASSERT_EQ(c.read(0x000, 2, ReqKind::Demand), CacheOutcome::Hit);
        ASSERT_EQ(c.read(0x200, 3, ReqKind::Demand), CacheOutcome::LineMiss);
        c.fill(0x200);
        const bool mru = policy == "test-mru";
        EXPECT_EQ(c.read(0x000, 4, ReqKind::Demand), mru ? CacheOutcome::LineMiss : CacheOutcome::Hit) << policy;
        if (mru) c.fill(0x000);
        EXPECT_EQ(c.read(0x100, 5, ReqKind::Demand), mru ? CacheOutcome::Hit : CacheOutcome::LineMiss) << policy;
    }
    // The configuration takes it by name; an unknown one is refused naming the known ones.
    Config config = Config::load("mobile");
    config.set("l1.replacement=test-mru");
    EXPECT_EQ(config.resolve().l1.replacement, "test-mru");
    config.set("l2.replacement=nope");
    try {
        config.resolve();
        ADD_FAILURE() << "an unknown replacement policy was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("allowed are fifo, lru"), std::string::npos) << e.what();
    }
}

// A scheduler that serves the newest waiting request first, one per channel. Requests A (row 0),
// B (row 1) and C (row 2) of bank 0 arrive together at cycle 0: FCFS serves A, B, C; this one
// picks C first (a closed bank: tRCD + tCL + 8 = 48), then B (a conflict: precharge at tRAS = 50,
// ACT at max(50 + tRP, tRC) = 70, data at 70 + 20 + 20 + 8 = 118), then A. The bookings of LT
// and the interval fidelity ask the same policy whether its picks follow row hits: these follow
// age, so the bookings serve a bank's reads in turn.
TEST(MemoryPolicies, ADramSchedulerIsOneClassAndOneRegistration) {
    class NewestFirst : public DramSchedulerPolicy {
    public:
        bool per_bank() const override { return false; }
        size_t pick(size_t n, const bool*) const override { return n - 1; }
    };
    register_dram_scheduler({"test-newest-first", "the newest request first", [] { return std::make_shared<const NewestFirst>(); }});
    DramConfig cfg = dram();
    const AddressMap map("line", cfg.channels, cfg.banks, cfg.row_bytes, cfg.channels, 128);
    const uint64_t row = uint64_t(cfg.row_bytes) * cfg.banks;  // the next row of bank 0
    const std::vector<std::pair<uint64_t, uint64_t>> arrivals = {{0, 0}, {0, row}, {0, 2 * row}};
    cfg.set_scheduler("fcfs");
    const auto fcfs = run_channel(cfg, map, arrivals, false);
    cfg.set_scheduler("test-newest-first");
    const auto newest = run_channel(cfg, map, arrivals, false);
    EXPECT_LT(fcfs.at(0), fcfs.at(row));
    EXPECT_LT(fcfs.at(row), fcfs.at(2 * row));
    EXPECT_EQ(newest.at(2 * row), 48u);
    EXPECT_EQ(newest.at(row), 118u);
    EXPECT_GT(newest.at(0), newest.at(row));
    EXPECT_FALSE(cfg.scheduler->row_hits_first());
    EXPECT_TRUE(dram_scheduler_kind("frfcfs_banks").make()->row_hits_first());
    Config config = Config::load("mobile");
    config.set("dram.scheduler=test-newest-first");
    EXPECT_EQ(config.resolve().dram.scheduler_name, "test-newest-first");
}

// The shader code's reads (workload.shader_reads) open workload.shader_lines_per_read L1 lines per
// read: counted by hand, 0.75 opens a line on reads 1, 2, 3, 5, 6, 7, 9, ... (after read k the
// lines opened must reach 0.75 k), each further read the next sector of the open line; 0.25 reads
// every sector of a line in turn (four a 128 B line); 1 gives every read a line of its own.
TEST(ShaderLoads, ReadsOpenTheirLinesPerRead) {
    using rtu::ShaderLoads;
    using rtu::ShaderReads;
    for (const double p : {0.25, 0.5, 0.75, 1.0}) {
        ShaderLoads s;
        s.start(3, ShaderReads{1.0, p, 128});
        s.owe(400);
        ASSERT_EQ(s.owed(), 400u);
        std::vector<uint64_t> addr;
        while (s.owed()) {
            addr.push_back(s.next());
            s.issued();
        }
        std::map<uint64_t, int> per_line;
        for (size_t i = 0; i < addr.size(); ++i) {
            EXPECT_EQ(addr[i] % 32, 0u);
            if (i) {
                EXPECT_GT(addr[i], addr[i - 1]) << "read " << i << ": never a sector read before";
            }
            ++per_line[addr[i] / 128];
        }
        EXPECT_EQ(addr.front(), ShaderLoads::kRegion + 3 * ShaderLoads::kRegionPerSm) << "SM 3's own region";
        EXPECT_EQ(per_line.size(), size_t(p * 400)) << p;
        for (const auto& [line, n] : per_line) EXPECT_LE(n, 4) << p;
        if (p == 0.25) {
            for (size_t i = 1; i < addr.size(); ++i) EXPECT_EQ(addr[i], addr[i - 1] + 32) << "four sectors a line, in turn";
        }
        if (p == 0.75) {  // lines opened by reads 1, 2, 3, 5, 6, 7, 9: read 4 shares read 3's line
            EXPECT_EQ(addr[3], addr[2] + 32);
            EXPECT_EQ(addr[4] / 128, addr[3] / 128 + 1);
            EXPECT_EQ(addr[1] / 128, addr[0] / 128 + 1);
        }
    }
}
