// Scene catalogue: built-in procedural scenes, LumiBench placements and plain files/folders.
#pragma once
#include <string>
#include <vector>

#include "scene.h"

namespace rtu {

// Ray Tracing in One Weekend's final scene as LumiBench builds it (shared/scenes/README.md).
// One procedural geometry (geom 0): prim 0 is the ground sphere, then the small spheres in
// generation order, then the glass, diffuse and metal spheres of radius 1.
Scene make_wknd();
// The LumiBench Cornell box: one mesh (geom 0), two triangles per wall in the order left,
// right, back, floor, ceiling, then the two light triangles (prims 10 and 11).
Scene make_cornell();

// Resolves --scene NAME|PATH [--assets DIR]:
//   wknd, cornell                  built in;
//   ship, bunny, ref, bath, sprng, party  LumiBench placements of the asset folder DIR;
//   a mesh file                    one mesh, geom 0, default camera framing it;
//   a folder                       one mesh per mesh file, geom = index in byte-wise sorted
//                                  file-name order, camera from a .camera file if present.
// Throws InputError for unknown names, missing files and bad content.
Scene load_scene(const std::string& scene, const std::string& assets);

// Names accepted as built-in or LumiBench scenes.
std::vector<std::string> scene_names();

// Reads a LumiBench .camera file (eye xyz, then look-at xyz; up +Y).
Camera read_camera_file(const std::string& path, float vfov);

}  // namespace rtu
