#include "host_memory.h"

#include <fstream>
#include <sstream>

#include <sys/resource.h>

namespace rtu {

namespace {

// A "Key:   N kB" line of a /proc file, in bytes; ~0 if absent.
uint64_t proc_kb(const char* file, const std::string& key) {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line))
        if (line.compare(0, key.size() + 1, key + ":") == 0) {
            std::istringstream v(line.substr(key.size() + 1));
            uint64_t kb = 0;
            if (v >> kb) return kb * 1024;
        }
    return ~0ull;
}

// cgroup v2: the process's group is the "0::/path" line of /proc/self/cgroup.
uint64_t cgroup_value(const std::string& name) {
    std::ifstream in("/proc/self/cgroup");
    std::string line;
    while (std::getline(in, line))
        if (line.compare(0, 3, "0::") == 0) {
            std::ifstream f("/sys/fs/cgroup" + line.substr(3) + "/" + name);
            std::string v;
            if (f >> v && v != "max") {
                try {
                    return std::stoull(v);
                } catch (const std::exception&) {
                }
            }
        }
    return ~0ull;
}

}  // namespace

HostMemory host_memory_available() {
    HostMemory h;
    const auto take = [&h](uint64_t bytes, const std::string& what) {
        if (bytes < h.available) h.available = bytes, h.limit = what;
    };
    take(proc_kb("/proc/meminfo", "MemAvailable"), "the machine's available memory (MemAvailable)");
    struct rlimit rl {};
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        const uint64_t used = proc_kb("/proc/self/status", "VmSize");
        take(used < rl.rlim_cur ? rl.rlim_cur - used : 0, "the address-space limit (ulimit -v)");
    }
    const uint64_t max = cgroup_value("memory.max"), current = cgroup_value("memory.current");
    if (max != ~0ull && current != ~0ull) take(current < max ? max - current : 0, "the cgroup's memory.max (a batch job's or container's limit)");
    return h;
}

}  // namespace rtu
