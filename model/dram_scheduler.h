// dram.scheduler: which waiting request a DRAM channel serves next, a policy object chosen by name
// from a registry (as DRAMSys chooses its scheduler). It decides two things: the controller's
// shape (each bank serving a request of its own, GPGPU-Sim's dram_t, or the channel one request at
// a time) and which of the waiting requests goes next (pick). AT's DRAM (DramChannel, model/dram.h)
// calls pick for each bank or for the channel as it runs cycle by cycle. The fast fidelities' DRAM
// (DramBookings) books each read at its timestamp, in call order, with no queue to pick from; it
// asks the same pick the one question that decides a booking's row hits: do its picks follow row
// hits (FR-FCFS) or not (FCFS). The two DRAM engines
// stay apart because AT's resolves contention among requests that coexist in time, which the
// bookings cannot see when a call comes; they share the policy object and DramConfig's timings.
// A new scheduler is one class and one register_dram_scheduler call (docs/timing.md, "Memory
// policies"). Plain C++ (no SystemC).
#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace rtu {

class DramSchedulerPolicy {
public:
    virtual ~DramSchedulerPolicy() = default;
    // Each bank takes a request of its own and the channel issues a command a cycle among them
    // (true), or the channel serves one request at a time (false).
    virtual bool per_bank() const = 0;
    // Which of `n` > 0 waiting requests (of one bank, or of the channel), in arrival order, to
    // serve next: an index below n. row_hit[i]: request i goes to its bank's open row.
    virtual size_t pick(size_t n, const bool* row_hit) const = 0;
    // The question DramBookings asks: do the picks follow row hits (a request to the open row
    // goes ahead of an older one, and an older row hit ahead of a younger miss)? Yes: FR-FCFS.
    // No: the bookings serve a bank's reads in arrival order, as FCFS does (a policy that orders
    // by something else is booked as FCFS: the bookings see one read at a time, not a queue).
    bool row_hits_first() const {
        const bool younger_hit[2] = {false, true}, older_hit[2] = {true, false};
        return pick(2, younger_hit) == 1 && pick(2, older_hit) == 0;
    }
};

struct DramSchedulerKind {
    std::string name, what;
    std::function<std::shared_ptr<const DramSchedulerPolicy>()> make;
};

// Registers a scheduler under its name (replaces one of the same name); returns true.
bool register_dram_scheduler(DramSchedulerKind kind);
// The scheduler registered as `name`; std::invalid_argument naming the known ones otherwise.
const DramSchedulerKind& dram_scheduler_kind(const std::string& name);
std::vector<std::string> dram_scheduler_names();

}  // namespace rtu
