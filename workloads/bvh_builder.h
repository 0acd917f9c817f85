// Builds the scene's BVH with Embree's rtcBuildBVH (6-wide, one primitive per leaf, medium
// quality binned SAH, max depth 32) and lays it out in the memory image of model/node_format.h:
// header, then each tree depth-first with every node's children in one contiguous block.
// Two-level scenes get a TLAS of 128 B instance leaves followed by one BLAS per mesh.
#pragma once
#include "model/bvh_image.h"
#include "scene.h"

namespace rtu {

BvhImage build_bvh_image(const Scene& scene);

}  // namespace rtu
