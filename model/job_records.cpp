#include "job_records.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace rtu {

JobSpec job_of_descriptor(const rtu_job_desc& d) {
    JobSpec j;
    j.bvh_base = d.bvh_base, j.bvh_size = d.bvh_size, j.ray_base = d.ray_base, j.hit_base = d.hit_base;
    j.ray_count = d.ray_count, j.flags = d.flags, j.job_id = d.job_id, j.next = d.next;
    j.ray_stride = job_stride(d.ray_stride, sizeof(rtu_ray));
    j.hit_stride = job_stride(d.hit_stride, sizeof(rtu_hit));
    return j;
}

JobFieldError check_job_fields(const JobSpec& j) {
    if (j.flags & ~(RTU_JOB_IRQ_ON_DONE | RTU_JOB_CHECK_BVH)) return {RTU_ERR_BAD_FLAGS, 0};
    if (j.bvh_base % 64) return {RTU_ERR_BAD_ALIGN, j.bvh_base};
    if (j.ray_base % 16) return {RTU_ERR_BAD_ALIGN, j.ray_base};
    if (j.hit_base % 16) return {RTU_ERR_BAD_ALIGN, j.hit_base};
    if (j.ray_stride < 48 || j.ray_stride % 16) return {RTU_ERR_BAD_ALIGN, j.ray_base};
    if (j.hit_stride < 48 || j.hit_stride % 16) return {RTU_ERR_BAD_ALIGN, j.hit_base};
    // The image, the rays and the hits are held in host memory: sizes beyond the limits are
    // refused, not allocated (a ray count of 2^32 - 1 would ask for 200 GB).
    if (j.bvh_size < kBlockBytes) return {RTU_ERR_BAD_BVH, j.bvh_base};
    if (j.bvh_size > RTU_MAX_BVH_BYTES) return {RTU_ERR_TOO_LARGE, j.bvh_base};
    if (j.ray_count > RTU_MAX_RAYS) return {RTU_ERR_TOO_LARGE, j.ray_base};
    return {};
}

// The records are little-endian, as the host's memory is read byte for byte into them.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the peripheral's records are little-endian");

rtu_ray make_ray_record(const float org[3], const float dir[3], float tnear, float tfar, bool any_hit, uint32_t user) {
    rtu_ray r{};
    for (int i = 0; i < 3; ++i) {
        r.org[i] = org[i];
        r.dir[i] = dir[i];
    }
    r.tnear = tnear;
    r.tfar = tfar;
    r.flags = any_hit ? RTU_RAY_ANY_HIT : 0u;
    r.user = user;
    return r;
}

Ray ray_of_record(const rtu_ray& r, bool& valid) {
    Ray ray;
    ray.org = {r.org[0], r.org[1], r.org[2]};
    ray.dir = {r.dir[0], r.dir[1], r.dir[2]};
    ray.tnear = r.tnear;
    ray.tfar = r.tfar;
    ray.query = (r.flags & RTU_RAY_ANY_HIT) ? Query::Any : Query::Closest;
    valid = (r.flags & ~RTU_RAY_ANY_HIT) == 0 && is_valid_ray(ray);
    // As read_ray_file does with a line it rejects: an invalid ray can never be traced.
    if (!valid) ray.org.x = std::numeric_limits<float>::quiet_NaN();
    return ray;
}

rtu_hit hit_record(const Hit& h, uint32_t nodes_visited, bool invalid_ray, uint32_t user) {
    rtu_hit o{};
    o.status = (h.hit ? RTU_HIT_HIT : 0u) | (invalid_ray ? RTU_HIT_INVALID_RAY : 0u);
    o.t = h.hit ? h.t : -1.0f;
    o.geom = h.hit ? h.geom : kNoId;
    o.prim = h.hit ? h.prim : kNoId;
    o.u = h.hit ? h.u : 0.0f;
    o.v = h.hit ? h.v : 0.0f;
    for (int i = 0; i < 3; ++i) o.ng[i] = h.hit ? h.ng[i] : 0.0f;
    o.nodes_visited = nodes_visited;
    o.user = user;
    return o;
}

uint64_t max_node_visits(const BvhImage& image) {
    const uint64_t blocks = image.size() / kBlockBytes;
    if (!image.header().has_instances) return blocks;
    // blocks + blocks / 2 x blocks, saturating.
    const uint64_t half = blocks / 2;
    if (half != 0 && blocks > (std::numeric_limits<uint64_t>::max() - blocks) / half) return std::numeric_limits<uint64_t>::max();
    return blocks + half * blocks;
}

rtu_hit trace_record(const BvhImage& image, const rtu_ray& r, TraversalOrder order, std::vector<StackEntry>* fetched) {
    bool valid = false;
    const Ray ray = ray_of_record(r, valid);
    if (!valid) return hit_record(Hit{}, 0, true, r.user);
    const TraceResult t = trace_ray(image, ray, order, nullptr, fetched, false, max_node_visits(image));
    return hit_record(t.hit, t.nodes_visited, false, r.user);
}

std::vector<rtu_hit> reference_hits(const uint8_t* bvh, size_t bvh_size, const uint8_t* rays, uint32_t count, uint32_t ray_stride,
                                    RecordTraversal order) {
    if (ray_stride < sizeof(rtu_ray)) throw std::invalid_argument("ray stride below 48 bytes");
    BvhImage image;
    try {
        image = BvhImage::view(bvh, bvh_size);
    } catch (const std::runtime_error& e) {
        throw std::invalid_argument(std::string("not a BVH image: ") + e.what());
    }
    const TraversalOrder o = order == RecordTraversal::Bfs ? TraversalOrder::BFS : TraversalOrder::DFS;
    std::vector<rtu_hit> hits(count);
    for (uint32_t i = 0; i < count; ++i) {
        rtu_ray r;
        std::memcpy(&r, rays + size_t(i) * ray_stride, sizeof r);
        try {
            hits[i] = trace_record(image, r, o);
        } catch (const std::out_of_range&) {
            throw;
        } catch (const std::length_error&) {
            throw;
        } catch (const std::runtime_error& e) {  // a node no encoder makes (decode_internal)
            throw std::invalid_argument(std::string("not a BVH image: ") + e.what());
        }
    }
    return hits;
}

}  // namespace rtu
