// The ray file reader (shared/interfaces.md), as rtsim's --rays FILE.
#include "fuzz_util.h"
#include "workloads/input_error.h"
#include "workloads/rays.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = rtu::fuzz::write_input(data, size, "rays");
    try {
        (void)rtu::read_ray_file(path);
    } catch (const rtu::InputError&) {
    }
    return 0;
}
