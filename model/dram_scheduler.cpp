#include "dram_scheduler.h"

#include "registry.h"

namespace rtu {
namespace {

// First ready, first come, first served: the oldest request to the open row, else the oldest
// (GPGPU-Sim's frfcfs_scheduler, dram_sched.cc).
size_t first_row_hit_else_oldest(size_t n, const bool* row_hit) {
    for (size_t i = 0; i < n; ++i)
        if (row_hit[i]) return i;
    return 0;
}

// frfcfs_banks: GPGPU-Sim's DRAM, every bank serving a request of its own (every preset).
class FrfcfsBanks : public DramSchedulerPolicy {
public:
    bool per_bank() const override { return true; }
    size_t pick(size_t n, const bool* row_hit) const override { return first_row_hit_else_oldest(n, row_hit); }
};

// frfcfs_channel: FR-FCFS with one request at a time per channel.
class FrfcfsChannel : public DramSchedulerPolicy {
public:
    bool per_bank() const override { return false; }
    size_t pick(size_t n, const bool* row_hit) const override { return first_row_hit_else_oldest(n, row_hit); }
};

// fcfs: one request at a time per channel, in arrival order.
class Fcfs : public DramSchedulerPolicy {
public:
    bool per_bank() const override { return false; }
    size_t pick(size_t, const bool*) const override { return 0; }
};

NamedRegistry<DramSchedulerKind>& schedulers() {
    static NamedRegistry<DramSchedulerKind> r("DRAM scheduler");
    static const bool built_in = [] {
        auto add = [](const char* name, const char* what, auto make) { r.add({name, what, make}); };
        add("frfcfs_banks", "GPGPU-Sim's FR-FCFS: every bank serves a request of its own, a command a cycle (every preset)",
            [] { return std::make_shared<const FrfcfsBanks>(); });
        add("frfcfs_channel", "FR-FCFS, one request at a time per channel", [] { return std::make_shared<const FrfcfsChannel>(); });
        add("fcfs", "one request at a time per channel, oldest first", [] { return std::make_shared<const Fcfs>(); });
        return true;
    }();
    (void)built_in;
    return r;
}

}  // namespace

bool register_dram_scheduler(DramSchedulerKind kind) {
    schedulers().add(std::move(kind));
    return true;
}

const DramSchedulerKind& dram_scheduler_kind(const std::string& name) { return schedulers().at(name); }

std::vector<std::string> dram_scheduler_names() { return schedulers().names(); }

}  // namespace rtu
