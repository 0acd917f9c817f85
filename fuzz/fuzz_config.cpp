// The configuration: a JSON file (--config FILE) and one --set KEY=VALUE, then the cross-key
// checks. The input's first line is the assignment, the rest the file.
#include "fuzz_util.h"
#include "model/config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string in(reinterpret_cast<const char*>(data), size);
    const size_t nl = in.find('\n');
    const std::string assignment = in.substr(0, nl);
    const std::string file = nl == std::string::npos ? std::string() : in.substr(nl + 1);
    const std::string path = rtu::fuzz::write_input(reinterpret_cast<const uint8_t*>(file.data()), file.size(), "json");
    try {
        rtu::Config c = rtu::Config::load(path);
        c.set(assignment);
        (void)c.resolve();
    } catch (const rtu::ConfigError&) {
    }
    return 0;
}
