// The peripheral's ray and hit records (include/rtunit/rtu_regs.h) against the model's Ray and
// Hit: one home for decoding a ray record and encoding a hit record, used by the reference
// (reference_hits) and by the peripheral's timing fidelities alike.
#pragma once
#include <rtunit/job.h>

#include "bvh_image.h"
#include "ray.h"
#include "traversal.h"

namespace rtu {

// The ray a record asks for; `valid` is false for a ray the ray-file contract rejects or one
// with a reserved flag bit set (its origin is then NaN, so it can never be traced).
Ray ray_of_record(const rtu_ray& r, bool& valid);
// The record of a hit (t in the units of the ray's direction as given).
rtu_hit hit_record(const Hit& h, uint32_t nodes_visited, bool invalid_ray, uint32_t user);
// The most node visits one ray may make in a well-formed `image`: each block once, and with
// instances each block once more per instance leaf (128 B each, so at most blocks / 2) leading
// into it; more means the nodes form a cycle. Quadratic in the image with instances: a cycle in a
// large two-level image takes long to find, but is found.
uint64_t max_node_visits(const BvhImage& image);
// One record traced functionally (throws as trace_ray does on a broken image).
rtu_hit trace_record(const BvhImage& image, const rtu_ray& r, TraversalOrder order);

}  // namespace rtu
