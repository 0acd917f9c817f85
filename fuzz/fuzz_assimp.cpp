// The Assimp path through load_mesh_file, as rtsim's --scene FILE.gltf|.glb: the first input
// byte picks the extension (glTF, GLB), the rest is the file. Every input forks the importer's
// child process (workloads/mesh_io.cpp), so this harness runs at tens of inputs per second where
// fuzz_mesh runs thousands. It checks that whatever Assimp does with an input (a mesh, an error,
// an assertion, a crash, a spin, a huge allocation) ends in rtsim as a mesh or as bad input; it
// does not explore Assimp's own code (no coverage crosses the fork). The importer's CPU limit is
// 0.25 s here (rtsim's is 5 s): inputs that keep Assimp busy (the seed found_assimp_spin and its
// mutations) end on the same path 20 times sooner; the 5 s limit itself has its own test
// (MeshFiles.ImporterThatSpinsStopsWithinItsCpuLimit). The parent's side alone is fuzz_importer.
#include "fuzz_util.h"
#include "workloads/input_error.h"
#include "workloads/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const char* const kExt[] = {"gltf", "glb"};
    if (size == 0) return 0;
    const std::string path = rtu::fuzz::write_input(data + 1, size - 1, kExt[data[0] % 2]);
    rtu::Scene scene;
    try {
        rtu::load_mesh_file(scene, path, rtu::ImporterLimits{0.25, 1.0});
    } catch (const rtu::InputError&) {
    }
    return 0;
}
