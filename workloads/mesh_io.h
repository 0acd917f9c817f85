// Mesh files: OBJ and PLY (ASCII or binary, optionally gzipped) with our own readers, so that
// triangles keep file order across groups/materials and errors name the file, line and value;
// glTF/GLB, OFF and the other formats Assimp reads through Assimp.
#pragma once
#include <string>

#include "scene.h"

namespace rtu {

// The limits of the mesh importer's process (Assimp runs in a forked child, mesh_io.cpp): CPU
// time `cpu_s` plus `cpu_s_per_mb` per MB of the file, and in wall time twice that plus 5 s.
// rtsim uses the defaults; fuzz/fuzz_assimp a short CPU limit, so that an input that keeps
// Assimp busy costs it a fraction of a second rather than 5 s (the path is the same).
struct ImporterLimits {
    double cpu_s = 5.0;
    double cpu_s_per_mb = 1.0;
};

// Loads one mesh file as one geometry of `scene` (vertices as-is, in the file's coordinates),
// as LumiBench's model loader reads an OBJ (every shape of the file in one mesh; materials
// Lambertian of Kd; the file's normals, else smooth ones). Polygons are fanned (v0,v1,v2),
// (v0,v2,v3), ...; with `tinyobj` (LumiBench's own scenes) they are triangulated as LumiBench's
// loader does: a quad split along its shorter diagonal, a larger polygon's ears clipped.
// Returns the new mesh index. Throws InputError.
uint32_t load_mesh_file(Scene& scene, const std::string& path, const ImporterLimits& limits = {}, bool tinyobj = false);

// The parent's side of the importer's pipe: what the child sent (`answer`) and how it ended
// (`wait_status`, as waitpid gives it) made into `mesh` and the materials it adds to `scene`, or
// an InputError naming `path`. Nothing from the child is trusted, since it ran Assimp on the
// file: an answer is read only from a child that exited 0, to its last byte, and is refused
// unless its counts agree, its numbers are finite and its indices are in range. Exposed for
// fuzz/fuzz_importer, which feeds it any bytes and any status.
void read_importer_answer(Scene& scene, Mesh& mesh, const std::string& path, const std::string& answer, int wait_status);

// True if `path` names a format load_mesh_file accepts (by extension).
bool is_mesh_file(const std::string& path);

}  // namespace rtu
