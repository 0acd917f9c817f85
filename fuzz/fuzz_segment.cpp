// What the merge of a split sample reads (platforms/segment_file.h): a segment's statistics
// (JSON, from rtsim --segment) when the input's first byte is even, a sample plan (binary, from
// --sample-plan) when it is odd; the rest of the input is the file. Both carry a checksum, which
// a mutated input almost never matches: with the first byte's second bit set, the harness seals
// the input first (a plan gets its checksum appended, a segment's JSON is sealed as rtsim seals
// it), so that the readers behind the checksum are fuzzed too; without it, the checksum check is.
#include <nlohmann/json.hpp>

#include "fuzz_util.h"
#include "platforms/segment_file.h"
#include "sampling/plan.h"
#include "workloads/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const bool plan = data[0] & 1;
    std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
    if (data[0] & 2) {
        if (plan) {
            const uint64_t sum = rtu::fnv1a(bytes.data(), bytes.size());
            bytes.append(reinterpret_cast<const char*>(&sum), sizeof sum);
        } else {
            try {
                nlohmann::ordered_json doc = nlohmann::ordered_json::parse(bytes, [](int depth, nlohmann::ordered_json::parse_event_t, nlohmann::ordered_json&) {
                    return depth <= 16;
                });
                if (doc.is_object() && doc.contains("segment") && doc["segment"].is_object()) {
                    rtu::seal_segment(doc);
                    bytes = doc.dump();
                }
            } catch (const nlohmann::json::exception&) {
            }
        }
    }
    const std::string path = rtu::fuzz::write_input(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), plan ? "plan" : "json");
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
