// How much more host memory this process may take: the least of the kernel's MemAvailable, the
// address-space limit (ulimit -v) and the cgroup's memory.max (a Slurm task's --mem, a container's
// limit), each less what the process already holds against it. A timing run's estimate
// (model/memory_estimate.h) is checked against it before its model is elaborated.
#pragma once
#include <cstdint>
#include <string>

namespace rtu {

struct HostMemory {
    uint64_t available = ~0ull;  // bytes; ~0: nothing known
    std::string limit;           // which limit it is, for a message
};

HostMemory host_memory_available();

}  // namespace rtu
