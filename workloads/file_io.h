// Whole files, transparently gunzipped: what the mesh readers and the ray-file reader read.
// Apart from the scene importer (mesh_io.h), so that a program that reads ray files without
// loading scenes (the SoC peripheral's library) does not link Assimp.
#pragma once
#include <string>

namespace rtu {

// Whole file, transparently gunzipped. Throws InputError if it cannot be read.
std::string read_file_maybe_gz(const std::string& path);

}  // namespace rtu
