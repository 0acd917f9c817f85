// rtsim's own mesh readers through load_mesh_file, as rtsim's --scene FILE: the first input byte
// picks the format (OBJ, PLY, gzipped PLY, OFF), the rest is the file. These run in rtsim's
// process; the formats read by Assimp in its child process have their own harness (fuzz_assimp),
// so that its fork per input does not slow this one down.
#include "fuzz_util.h"
#include "workloads/input_error.h"
#include "workloads/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const char* const kExt[] = {"obj", "ply", "ply.gz", "off"};
    if (size == 0) return 0;
    const std::string path = rtu::fuzz::write_input(data + 1, size - 1, kExt[data[0] % 4]);
    rtu::Scene scene;
    try {
        rtu::load_mesh_file(scene, path);
    } catch (const rtu::InputError&) {
    }
    return 0;
}
