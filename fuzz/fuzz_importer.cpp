// The parent's side of the mesh importer's pipe (workloads/mesh_io.h, read_importer_answer): the
// bytes Assimp's child process sends back and how it ended. The child runs Assimp on a hostile
// file, so whatever it sends must end as a mesh that holds together or as bad input. The input's
// first byte picks how the child ended (even: exit 0; 1 mod 4: exit with the second byte as its
// status; 3 mod 4: killed by the second byte as a signal); the rest is the answer. fuzz_assimp
// runs the whole path, forking the importer for each input (tens to hundreds per second); this
// harness runs the parent's side alone, thousands of times faster, under the sanitizers.
#include <sys/wait.h>

#include <string>

#include "workloads/input_error.h"
#include "workloads/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 2) return 0;
    // The wait status as Linux encodes it (what WIFEXITED, WEXITSTATUS and WTERMSIG decode).
    const int status = (data[0] & 1) == 0 ? 0 : (data[0] & 3) == 1 ? int(data[1]) << 8 : (data[1] & 0x7f) ?: 9;
    const std::string answer(reinterpret_cast<const char*>(data + 2), size - 2);
    rtu::Scene scene;
    scene.materials.resize(data[1] % 3);  // materials already there: the answer's indices are offset by them
    rtu::Mesh mesh;
    mesh.name = "input.glb";
    try {
        rtu::read_importer_answer(scene, mesh, "input.glb", answer, status);
    } catch (const rtu::InputError&) {
        if (scene.materials.size() != data[1] % 3 || !mesh.vertices.empty()) __builtin_trap();  // refused, yet changed
        return 0;
    }
    // Accepted: what the rest of rtsim relies on holds.
    if (mesh.material.size() != mesh.triangles.size()) __builtin_trap();
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            if (t[k] >= mesh.vertices.size()) __builtin_trap();
    for (uint32_t m : mesh.material)
        if (m < data[1] % 3 || m >= scene.materials.size()) __builtin_trap();
    scene.meshes.push_back(mesh);
    if (!mesh.triangles.empty()) scene.validate();  // InputError or logic_error escape as findings
    return 0;
}
