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
// `fetched`, when given, receives every node the traversal reads (as trace_ray).
rtu_hit trace_record(const BvhImage& image, const rtu_ray& r, TraversalOrder order, std::vector<StackEntry>* fetched = nullptr);

// A job as software gave it (the registers, or a descriptor).
struct JobSpec {
    uint64_t bvh_base = 0, bvh_size = 0, ray_base = 0, hit_base = 0, next = 0;
    uint32_t ray_count = 0, ray_stride = sizeof(rtu_ray), hit_stride = sizeof(rtu_hit), flags = 0, job_id = 0;
};
// A job's stride as software wrote it (a descriptor's field or the STRIDES register): 0 means the
// record's own size.
inline uint32_t job_stride(uint32_t field, uint32_t record_bytes) { return field == 0 ? record_bytes : field; }
// A descriptor's job (strides by job_stride); its magic is the caller's check.
JobSpec job_of_descriptor(const rtu_job_desc& d);
// The first error a job's own fields give, before any memory is read: an RTU_ERR_* code (0:
// none) and the address it concerns. Sizes beyond RTU_MAX_BVH_BYTES and RTU_MAX_RAYS are refused
// here, before anything is allocated.
struct JobFieldError {
    uint32_t code = 0;
    uint64_t addr = 0;
};
JobFieldError check_job_fields(const JobSpec& j);

}  // namespace rtu
