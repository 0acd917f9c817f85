// What the libFuzzer harnesses share: the input written to a file of this process (the parsers
// read files, as rtsim does), and the rule of what a harness lets through. Bad input must end in
// InputError or ConfigError (rtsim: exit 2); any other exception escapes the harness and
// libFuzzer reports it as a finding (rtsim would exit 3), as are crashes, sanitizer reports,
// timeouts and memory beyond -rss_limit_mb.
#pragma once
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace rtu::fuzz {

// Writes the input to /tmp/rtu-fuzz-PID/input.EXT (one folder per process; overwritten each time).
inline std::string write_input(const uint8_t* data, size_t size, const std::string& ext) {
    static const std::string dir = [] {
        std::string d = "/tmp/rtu-fuzz-" + std::to_string(getpid());
        mkdir(d.c_str(), 0700);
        return d;
    }();
    const std::string path = dir + "/input." + ext;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) __builtin_trap();
    if (size) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return path;
}

}  // namespace rtu::fuzz
