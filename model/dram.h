// DRAM channel timing: banks with open rows, the command timing of DESIGN.md section 5 (tCL,
// tRCD, tRP, tRAS, tRC, tRRD, tCCD, tWL, tWR, in memory clock cycles), a shared data bus of
// bus_bytes x 2 (double data rate) per memory cycle, and an FR-FCFS (or FCFS) scheduler over a
// bounded request queue. Plain C++ (no SystemC); the tlm/ DRAM module drives it.
#pragma once
#include <cstdint>
#include <deque>
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
inline uint64_t dram_transfer_cycles(const DramConfig& c, uint32_t bytes) {
    const uint64_t burst_bytes = uint64_t(c.bus_bytes) * c.burst;
    const uint64_t beats = (bytes + burst_bytes - 1) / burst_bytes * c.burst;
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

class DramChannel {
public:
    explicit DramChannel(const DramConfig& c);
    bool full() const { return queue_.size() >= cfg_.queue; }
    bool empty() const { return queue_.empty(); }
    size_t depth() const { return queue_.size(); }
    void enqueue(const DramRequest& r) { queue_.push_back(r); }
    // Earliest memory cycle at which the scheduler picks the next request: tRCD before the
    // column bus frees, so that a row miss's ACT overlaps the transfers ahead of it while row
    // hits that arrive meanwhile can still be preferred.
    uint64_t next_decision() const { return next_col_ > cfg_.tRCD ? next_col_ - cfg_.tRCD : 0; }
    // Picks a request at memory cycle `now` (FR-FCFS: the oldest row hit, else the oldest),
    // issues its commands at their earliest legal cycles and returns it with the cycle its
    // data transfer ends. False if the queue is empty.
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
    };
    DramConfig cfg_;
    std::deque<DramRequest> queue_;
    std::vector<Bank> banks_;
    uint64_t next_col_ = 0, bus_free_ = 0, last_act_ = 0;
    bool any_act_ = false;
    DramStats stats_;
};

// DRAM of the fast fidelities (LT, interval): a read's timestamp books, in calendars, its bank,
// its channel's command sequence and its data bus, so the order of calls does not matter. The
// command sequence is AT's scheduler's: one request at a time per channel, a column slot
// (max(tCCD, transfer)) each, an activation of a closed bank overlapping the transfer ahead of
// it, a conflict's precharge (tRP) not. Without it, booking banks alone let conflicts run in
// parallel across banks and LT came out up to 14 % fast on the memory-bound scenes.
// FR-FCFS is kept in time, not in call order: each bank remembers the rows it opened as epochs
// [decision, next epoch's decision), the decision being the cycle AT's scheduler would pick the
// activating request (its command slot less tRCD). A read that finds its row's epoch still open
// at its own timestamp or later is a row hit, as FR-FCFS would serve it before the conflict that
// closes the row; otherwise it opens a new epoch. Before, open rows followed call order, and the
// interval fidelity, calling in time order, found down to 0.67x AT's row hits (bunny mesh).
// Activations keep AT's spacing (tRC, tRAS + tRP per bank, tRRD per channel; until 2026-11-27
// they did not: LT on sprng's primary rays 256x256 on `paper`, where more than half the reads
// are row conflicts, -5.5 % against AT before, -4.2 % after). Not modelled: the request queue's
// bound, AT's channel waiting for a conflict's activation before it picks any other request
// (docs/accuracy.md), and a hit overtaking the conflicts
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
};

}  // namespace rtu
