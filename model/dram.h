// DRAM channel timing: banks with open rows, the command timing of the paper's Table 2 (docs/paper-preset.md: tCL,
// tRCD, tRP, tRAS, tRC, tRRD, tCCD, tWL, tWR, in memory clock cycles), a shared data bus of
// bus_bytes x 2 (double data rate) per memory cycle, and an FR-FCFS (or FCFS) scheduler over a
// bounded request queue. Plain C++ (no SystemC); the tlm/ DRAM module drives it.
#pragma once
#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "address_map.h"
#include "calendar.h"
#include "config.h"
#include "stats.h"

namespace rtu {

// Data-bus cycles (memory clock) of one transfer of `bytes`: whole bursts of `burst` beats of
// bus_bytes each, beats_per_cycle beats per memory cycle. 32 B on the mobile preset's 2 B bus
// with bursts of 8 at 2 beats a cycle: two bursts of 16 B, 16 beats, 8 cycles (GPGPU-Sim: two
// column commands of BL / dram_data_command_freq_ratio = 4 cycles each). The authors' desktop
// (bursts of 16 at 4 beats a cycle): one burst of 32 B, 4 cycles.
// Whole bursts of bus_bytes x burst bytes in a transfer of `bytes` (GPGPU-Sim: column commands
// of dram_atom_size each).
inline uint64_t dram_bursts(const DramConfig& c, uint32_t bytes) {
    const uint64_t burst_bytes = uint64_t(c.bus_bytes) * c.burst;
    return (bytes + burst_bytes - 1) / burst_bytes;
}

inline uint64_t dram_transfer_cycles(const DramConfig& c, uint32_t bytes) {
    const uint64_t beats = dram_bursts(c, bytes) * c.burst;
    return (beats + c.beats_per_cycle - 1) / c.beats_per_cycle;
}

struct DramRequest {
    uint64_t addr = 0;
    uint32_t bytes = 32;
    bool write = false;
    uint64_t token = 0;
    uint64_t arrival = 0;  // memory cycle it entered the queue
    DramCoord at{};
};

// One channel's counters (statistics group "dram", per channel).
struct DramStats {
    uint64_t reads = 0, writes = 0, row_hits = 0, row_misses = 0, row_conflicts = 0;
    uint64_t bytes = 0, data_cycles = 0;  // data-bus occupancy, for bandwidth utilisation
    uint64_t queue_wait = 0;              // sum of (issue - arrival), memory cycles
    static constexpr Counter<DramStats> kCounters[] = {
        {"reads", &DramStats::reads, "requests", "read requests (32 B sectors from L2 misses)"},
        {"writes", &DramStats::writes, "requests", "write requests"},
        {"bytes", &DramStats::bytes, "bytes", "bytes read and written"},
        {"row_hits", &DramStats::row_hits, "requests", "to the bank's open row"},
        {"row_misses", &DramStats::row_misses, "requests", "to a closed bank (an activation)"},
        {"row_conflicts", &DramStats::row_conflicts, "requests", "to another row than the open one (a precharge and an activation)"},
        {"data_cycles", &DramStats::data_cycles, "memory cycles", "cycles the data bus carried data"},
        {"queue_wait", &DramStats::queue_wait, "memory cycles", "waits beyond the unloaded latency, summed over requests"},
    };
};

// One channel's DRAM controller, shaped by its scheduler policy (dram.scheduler,
// model/dram_scheduler.h: per_bank() and pick()); the built-in ones:
// - frfcfs_channel / fcfs: one request at a time per channel (rtunit's only scheduler until
//   2026-11-27). The scheduler picks a request (the oldest row hit, else the oldest; fcfs: the
//   oldest) and issues its commands at their earliest legal cycles; it picks the next tRCD before
//   the column bus frees, so a closed bank's ACT overlaps the transfers ahead of it. A picked row
//   conflict holds the channel until its ACT, so it holds back row hits to the other banks: on
//   DRAM-bound frames frfcfs_banks takes up to 44 % fewer cycles in AT (docs/accuracy.md).
// - frfcfs_banks (every preset): GPGPU-Sim's DRAM (dram.cc `dram_t::cycle`, dram_sched.cc, branch
//   traversal_trend_prefetcher of the TTP authors' simulator), memory cycle by memory cycle. Each
//   bank holds one request of its own; a bank without one takes, at most one bank a cycle in
//   rotating priority, the oldest request of the row it last took (a row streak), else the
//   oldest of its requests. Then, in the same priority order, at most one column command a
//   cycle (tCCD apart, tRCD after the bank's ACT) and, if no column command went before it, one
//   row command: an ACT to an idle bank (tRP after its precharge, tRC after its last ACT, tRRD
//   after the channel's last), or a precharge of a bank open on another row (tRAS after its
//   ACT, burst / beats_per_cycle after its last read's column). So a conflict waiting for its
//   precharge holds only its own bank. A request moves bus_bytes x burst bytes a column
//   command; its data ends tCL (tWL) + burst / beats_per_cycle after its last. Not modelled:
//   bank groups (tCCDL and tRTPL are 4 in the authors' configuration, as tCCD and a read's
//   burst are), read-write turnaround, the return queue's bound.
class DramChannel {
public:
    explicit DramChannel(const DramConfig& c);
    bool full() const { return queue_.size() >= cfg_.queue; }
    bool empty() const { return queue_.empty() && serving_ == 0; }
    size_t depth() const { return queue_.size() + serving_; }
    void enqueue(const DramRequest& r) {
        queue_.push_back(r);
        if (cfg_.per_bank()) ++banks_[r.at.bank].queued;
    }
    // Earliest memory cycle at which schedule() may do anything. frfcfs_channel, fcfs: tRCD before the
    // column bus frees, so that a row miss's ACT overlaps the transfers ahead of it while row
    // hits that arrive meanwhile can still be preferred. frfcfs_banks: the next cycle after the
    // last it ran at which a bank can take a request or its timing lets a command issue.
    uint64_t next_decision() const;
    // At memory cycle `now` (not before next_decision()): frfcfs_channel and fcfs pick a request and issue
    // its commands at their earliest legal cycles; frfcfs_banks runs the cycle `now`. True with
    // the request whose last column command issued and the cycle its data transfer ends.
    bool schedule(uint64_t now, DramRequest* out, uint64_t* done);
    const DramStats& stats() const { return stats_; }

    // Data cycles of one transfer of `bytes`.
    uint64_t transfer_cycles(uint32_t bytes) const { return dram_transfer_cycles(cfg_, bytes); }

private:
    struct Bank {
        bool open = false;
        uint64_t row = 0;
        uint64_t act = 0;          // cycle of the last ACT
        bool activated = false;
        uint64_t write_done = 0;   // end of write recovery
        // frfcfs_banks: the request the bank serves and its command timing, as the cycles from
        // which each command is allowed (GPGPU-Sim's counters RCDc, RASc, RCc, RPc, RTPc, WTPc).
        uint32_t queued = 0;  // requests of this bank in the queue
        bool serving = false;
        DramRequest req;
        uint32_t columns_left = 0;
        uint64_t column_ok = 0, precharge_ok = 0, act_ok = 0;
    };
    bool schedule_channel(uint64_t now, DramRequest* out, uint64_t* done);
    bool schedule_banks(uint64_t now, DramRequest* out, uint64_t* done);
    void take_request();  // frfcfs_banks: a bank without a request takes one
    bool column_command(uint64_t now, Bank& b, bool* finished, DramRequest* out, uint64_t* done);
    bool row_command(uint64_t now, Bank& b, uint32_t j);
    // frfcfs_banks: column commands of a request, one per burst (at least one).
    uint32_t columns(uint32_t bytes) const { return uint32_t(std::max<uint64_t>(1, dram_bursts(cfg_, bytes))); }

    DramConfig cfg_;
    std::deque<DramRequest> queue_;
    std::vector<Bank> banks_;
    uint64_t next_col_ = 0, bus_free_ = 0, last_act_ = 0;
    bool any_act_ = false;
    // frfcfs_banks: requests held by banks, the last cycle run, the channel's next ACT cycle
    // (RRDc; next_col_ is its CCDc) and the banks' rotating priority.
    uint32_t serving_ = 0;
    uint64_t last_cycle_ = 0;
    bool ran_ = false;
    uint64_t channel_act_ok_ = 0;
    uint32_t prio_ = 0;
    // The scheduler's candidates (queue positions) and their row hits: scratch.
    std::vector<size_t> candidates_;
    std::unique_ptr<bool[]> row_hit_;
    size_t row_hit_size_ = 0;
    bool* row_hits(size_t n);  // room for n flags
    DramStats stats_;
};

// DRAM of the fast fidelities (LT, interval): a read's timestamp books, in calendars, its bank,
// its channel's command sequence and its data bus, so the order of calls does not matter. The
// command sequence follows AT's scheduler (DramChannel): a column slot (max(tCCD, transfer)) per
// read, an activation of a closed bank overlapping the transfers ahead of it. frfcfs_channel and
// fcfs: one request at a time per channel, so a conflict's precharge (tRP) takes the sequence's
// time too (booking banks alone let conflicts run in parallel across banks, and LT came out up
// to 14 % fast against that AT on the memory-bound scenes). frfcfs_banks: a bank precharges and
// activates on its own, and the sequence gives only the column slot, tRCD after the ACT.
// FR-FCFS is kept in time, not in call order: each bank remembers the rows it opened as epochs
// [decision, next epoch's decision), the decision being the cycle AT's scheduler would take the
// activating request (frfcfs_channel: its command slot less tRCD; frfcfs_banks: when its bank
// starts on it). A read that finds its row's epoch still open at its own timestamp or later is a
// row hit, as FR-FCFS would serve it before the conflict that closes the row; otherwise it opens
// a new epoch. Before, open rows followed call order, and the interval fidelity, calling in time
// order, found down to 0.67x AT's row hits (bunny mesh).
// Activations keep AT's spacing (tRC, tRAS + tRP per bank, tRRD per channel; until 2026-11-27
// they did not: LT on sprng's primary rays 256x256 on `paper`, where more than half the reads
// are row conflicts, -5.5 % against frfcfs_channel's AT before, -4.2 % after). Not modelled: the
// request queue's bound, frfcfs_channel's AT waiting for a conflict's activation before it picks
// any other request, the one command a cycle of frfcfs_banks, and a hit overtaking the conflicts
// booked before it (it takes the first free column slot, so the channel's throughput is AT's
// but FR-FCFS's spread of latencies, short for hits and long for conflicts, is not; giving hits
// their own slots while still taking one from the sequence made the interval fidelity 2-10 %
// fast on primary rays).
class DramBookings {
public:
    DramBookings(const DramConfig& c, const AddressMap& map);
    // A transfer of `bytes` arriving at memory cycle `now`; returns the memory cycle its data
    // transfer ends. No later call may be timestamped before `horizon` (memory cycles).
    uint64_t access(uint64_t addr, uint32_t bytes, uint64_t now, uint64_t horizon);
    const std::vector<DramStats>& stats() const { return stats_; }  // per channel

private:
    struct Epoch {  // a row open in a bank
        uint64_t row;
        uint64_t decision;      // the cycle its activating request was picked
        uint64_t first_column;  // that request's column command
        uint64_t until;         // the next epoch's decision (~0: still open)
    };
    struct Bank {
        std::deque<Epoch> epochs;  // by decision; until of each is the next one's decision
        Calendar busy;
        Calendar activations;  // [ACT, ACT + act_gap_) per activation
    };
    DramConfig cfg_;
    AddressMap map_;
    std::vector<std::vector<Bank>> banks_;  // per channel
    std::vector<Calendar> bus_, commands_;  // per channel: data bus, command sequence
    std::vector<Calendar> activations_;     // per channel: [ACT, ACT + tRRD) per activation
    std::vector<DramStats> stats_;
    uint64_t act_gap_;  // a bank's ACT to its next ACT: max(tRC, tRAS + tRP)
    bool row_hits_first_;  // the scheduler's: a row hit goes ahead of older requests (FR-FCFS)
};

}  // namespace rtu
