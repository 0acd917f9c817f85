// The camera file of a scene folder (two lines: eye xyz, look-at xyz).
#include "fuzz_util.h"
#include "workloads/input_error.h"
#include "workloads/scenes.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = rtu::fuzz::write_input(data, size, "camera");
    try {
        (void)rtu::read_camera_file(path, 45.0f);
    } catch (const rtu::InputError&) {
    }
    return 0;
}
