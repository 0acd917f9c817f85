// What the merge of a split sample reads (platforms/sample_segments.h): a segment's statistics
// (JSON, from rtsim --segment) when the input's first byte is even, a sample plan (binary, from
// --sample-plan) when it is odd; the rest of the input is the file.
#include "fuzz_util.h"
#include "platforms/sample_segments.h"
#include "sampling/plan.h"
#include "workloads/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const bool plan = data[0] & 1;
    const std::string path = rtu::fuzz::write_input(data + 1, size - 1, plan ? "plan" : "json");
    try {
        if (plan)
            (void)rtu::read_plan(path, "scene=cornell\n");
        else
            (void)rtu::read_segment(path);
    } catch (const rtu::InputError&) {
    }
    return 0;
}

// libsystemc needs an sc_main to link; the harness never elaborates.
extern "C" int sc_main(int, char**) { return 0; }
