// Mesh files: OBJ and PLY (ASCII or binary, optionally gzipped) with our own readers, so that
// triangles keep file order across groups/materials and errors name the file, line and value;
// glTF/GLB, OFF and the other formats Assimp reads through Assimp.
#pragma once
#include <string>

#include "scene.h"

namespace rtu {

// Loads one mesh file as one geometry of `scene` (vertices as-is, in the file's coordinates).
// Polygons are fanned (v0,v1,v2), (v0,v2,v3), ... Returns the new mesh index. Throws InputError.
uint32_t load_mesh_file(Scene& scene, const std::string& path);

// Whole file, transparently gunzipped. Throws InputError if it cannot be read.
std::string read_file_maybe_gz(const std::string& path);

// True if `path` names a format load_mesh_file accepts (by extension).
bool is_mesh_file(const std::string& path);

}  // namespace rtu
