// DRAM channel timing: banks with open rows, the command timing of DESIGN.md section 5 (tCL,
// tRCD, tRP, tRAS, tRC, tRRD, tCCD, tWL, tWR, in memory clock cycles), a shared data bus of
// bus_bytes x 2 (double data rate) per memory cycle, and an FR-FCFS (or FCFS) scheduler over a
// bounded request queue. Plain C++ (no SystemC); the tlm/ DRAM module drives it.
#pragma once
#include <cstdint>
#include <deque>
#include <vector>

#include "calendar.h"
#include "config.h"
#include "stats.h"

namespace rtu {

struct DramCoord {
    uint32_t channel, bank;
    uint64_t row;
};

// Lines are interleaved across channels; within a channel consecutive lines fill a row, then
// move to the next bank.
class DramAddressMap {
public:
    DramAddressMap(const DramConfig& c, uint32_t line_bytes);
    DramCoord map(uint64_t addr) const;

private:
    uint32_t channels_, banks_, line_, lines_per_row_;
};

// Data-bus cycles (memory clock) of one transfer of `bytes`: whole bursts of `burst` beats of
// bus_bytes each, two beats per memory cycle (double data rate). 32 B on the mobile preset's
// 2 B bus with bursts of 8: two bursts of 16 B, 16 beats, 8 cycles.
inline uint64_t dram_transfer_cycles(const DramConfig& c, uint32_t bytes) {
    const uint64_t burst_bytes = uint64_t(c.bus_bytes) * c.burst;
    const uint64_t beats = (bytes + burst_bytes - 1) / burst_bytes * c.burst;
    return (beats + 1) / 2;
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
// its channel's command sequence and its data bus, so the order of calls does not matter; open
// rows follow call order (the approximation). The command sequence is AT's scheduler's: one
// request at a time per channel, a column slot (max(tCCD, transfer)) each, an activation of a
// closed bank overlapping the transfer ahead of it, a conflict's precharge (tRP) not. Without
// it, booking banks alone let conflicts run in parallel across banks and LT came out up to 14 %
// fast on the memory-bound scenes. No request queue, no FR-FCFS reordering, no tRAS/tRC/tRRD.
class DramBookings {
public:
    DramBookings(const DramConfig& c, uint32_t line_bytes);
    // A transfer of `bytes` arriving at memory cycle `now`; returns the memory cycle its data
    // transfer ends. No later call may be timestamped before `horizon` (memory cycles).
    uint64_t access(uint64_t addr, uint32_t bytes, uint64_t now, uint64_t horizon);
    const std::vector<DramStats>& stats() const { return stats_; }  // per channel

private:
    struct Bank {
        bool open = false;
        uint64_t row = 0;
        Calendar busy;
    };
    DramConfig cfg_;
    DramAddressMap map_;
    std::vector<std::vector<Bank>> banks_;  // per channel
    std::vector<Calendar> bus_, commands_;  // per channel: data bus, command sequence
    std::vector<DramStats> stats_;
};

}  // namespace rtu
