#include "traversal.h"

#include "treelet.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rtu {

namespace {

// Float arithmetic as the authors' simulator writes it (vulkan_ray_tracing.cc), each operation
// in its order: the hit t's it computes decide which of two coincident triangles wins and where
// the application's next ray starts, so rtunit computes them the same way beside its robust tests.
float dotf(glm::vec3 a, glm::vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
glm::vec3 crossf(glm::vec3 a, glm::vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

}  // namespace

bool moller_trumbore_t(const glm::vec3& o, const glm::vec3& dir, const TriangleLeaf& tl, float* t) {
    const float mult = std::sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    const glm::vec3 d(dir.x / mult, dir.y / mult, dir.z / mult);
    const glm::vec3 v0v1 = tl.v1 - tl.v0, v0v2 = tl.v2 - tl.v0;
    const glm::vec3 pvec = crossf(d, v0v2);
    const float idet = 1 / dotf(v0v1, pvec);
    const glm::vec3 tvec = o - tl.v0;
    const glm::vec3 qvec = crossf(tvec, v0v1);
    *t = dotf(v0v2, qvec) * idet / mult;
    return std::isfinite(*t);
}

namespace {

// LumiBench's sphere intersection shader (RayTracing.Procedural.rint l.24-39) in float: the
// entry root if it is at or beyond tmin, else the exit root; `robust` where the float
// discriminant says the ray misses (a graze the robust test takes).
float shader_sphere_t(const glm::vec3& o, const glm::vec3& d, const SphereLeaf& s, float tmin, float robust) {
    const glm::vec3 oc = o - s.center;
    const float a = dotf(d, d), b = dotf(oc, d), c = dotf(oc, oc) - s.radius * s.radius;
    const float disc = b * b - a * c;
    if (!(disc >= 0)) return robust;
    const float t1 = (-b - std::sqrt(disc)) / a, t2 = (-b + std::sqrt(disc)) / a;
    return tmin <= t1 ? t1 : t2;
}

}  // namespace

uint32_t TraversalThread::next_treelet() const {
    if (!treelets_) return ~0u;
    if (!has_next_ && stack_.empty() && !deferred_.empty()) return treelets_->treelet_of(deferred_.back().addr);
    return deferred_.empty() ? ~0u : treelets_->treelet_of(deferred_.back().addr);
}

void TraversalThread::start(const Ray& ray, const ImageHeader& header, TraversalOrder order, const Treelets* treelets,
                            bool next_node_register) {
    ray_ = ray;
    tmax_ = ray.tfar;
    order_ = order;
    headers_ = header.has_headers;
    register_ = next_node_register && order != TraversalOrder::BFS;
    treelets_ = order == TraversalOrder::Treelet ? treelets : nullptr;
    if (order == TraversalOrder::Treelet && !treelets_) throw std::logic_error("treelet traversal needs treelets");
    current_treelet_ = treelets_ ? treelets_->treelet_of(header.root) : ~0u;
    hit_ = Hit{};
    stack_.clear();
    deferred_.clear();
    has_next_ = false;
    nodes_visited_ = candidates_ = 0;
    space_inst_ = kNoId;
    org_ = ray.org;
    dir_ = ray.dir;
    world_box_ray_ = box_ray_ = make_box_test_ray(org_, dir_);
    if (header.has_headers) {
        // The image header is read first (not a pop); its step tests the root box.
        next_ = StackEntry{0, NodeType::Header, kNoId};
        has_next_ = true;
        root_box_ = header.root_box;
        root_ = header.root;
        return;
    }
    if (intersect_box(world_box_ray_, header.root_box, ray_.tnear, ray_.tfar, nullptr)) {
        const StackEntry root{header.root, NodeType::Internal, kNoId};
        if (register_) {
            next_ = root;
            has_next_ = true;
        } else {
            stack_.push_back(root);  // the first read is a pop too (Algorithm 1, lines 1-2)
        }
    }
}

void TraversalThread::push_next(const StackEntry& e, StepInfo& info) {
    if (treelets_ && treelets_->treelet_of(e.addr) != current_treelet_) {
        deferred_.push_back(e);
        ++info.pushed;
    } else if (register_) {
        next_ = e;
        has_next_ = true;
    } else {
        stack_.push_back(e);
        ++info.pushed;
    }
}

bool TraversalThread::take_hit(float t, float app_t, float u, float v, uint32_t geom, uint32_t prim, const glm::vec3& ng) {
    if (hit_.hit && !(app_t < hit_.app_t)) return false;
    hit_.hit = true;
    hit_.t = t;
    hit_.app_t = app_t;
    hit_.u = u;
    hit_.v = v;
    hit_.geom = geom;
    hit_.prim = prim;
    hit_.ng = ng;
    return true;
}

void TraversalThread::enter_space(const BvhImage& image, uint32_t inst_block) {
    space_inst_ = inst_block;
    if (inst_block == kNoId) {
        org_ = ray_.org;
        dir_ = ray_.dir;
        box_ray_ = world_box_ray_;
        return;
    }
    // Functional side read of the instance's transform (its fetch was timed when the instance
    // leaf itself was visited). An affine map keeps the ray parameter t unchanged.
    const InstanceLeaf inst =
        decode_instance(image.at(uint64_t(inst_block) * kBlockBytes, node_bytes(NodeType::Instance)));
    org_ = transform_point(inst.world_to_object, ray_.org);
    dir_ = transform_vector(inst.world_to_object, ray_.dir);
    box_ray_ = make_box_test_ray(org_, dir_);
}

glm::vec3 TraversalThread::normal_to_world(const BvhImage& image, const glm::vec3& n) const {
    if (space_inst_ == kNoId) return n;
    // Normals transform with the inverse transpose of object_to_world, which is the transpose
    // of world_to_object's linear part.
    const Affine w = decode_instance(image.at(uint64_t(space_inst_) * kBlockBytes,
                                              node_bytes(NodeType::Instance)))
                         .world_to_object;
    return glm::vec3(w[0] * n.x + w[4] * n.y + w[8] * n.z, w[1] * n.x + w[5] * n.y + w[9] * n.z,
                     w[2] * n.x + w[6] * n.y + w[10] * n.z);
}

// Four children at a time: every lane does intersect_box's float operations (robust.h) in its
// order, so the results are the same bits. intersect_box leaves as soon as t0 > t1; here all
// three axes are taken and t0 <= t1 checked at the end, which decides the same, since t0 only
// grows and t1 only shrinks and neither is ever NaN (a NaN slab distance is ignored by the
// NaN-safe max and min, and tmin and tmax * kBoxFarScale are not NaN).
unsigned child_hits(const BoxTestRay& r, const InternalNode& n, float tmin, float tmax) {
    unsigned hits = 0;
#if defined(__SSE2__)
    for (int base = 0; base < n.count; base += 4) {
        __m128 t0 = _mm_set1_ps(tmin), t1 = _mm_set1_ps(tmax * kBoxFarScale);
        for (int a = 0; a < 3; ++a) {
            const float* near = (r.neg[a] ? n.hi[a] : n.lo[a]).data() + base;
            const float* far = (r.neg[a] ? n.lo[a] : n.hi[a]).data() + base;
            const __m128 org = _mm_set1_ps(r.org[a]), inv = _mm_set1_ps(r.inv_dir[a]);
            const __m128 tn = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(near), org), inv);
            const __m128 tf = _mm_mul_ps(_mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(far), org), inv), _mm_set1_ps(kBoxFarScale));
            // MAXPS(x, y) is x > y ? x : y, so MAXPS(tn, t0) is safe_max(t0, tn); MINPS alike.
            t0 = _mm_max_ps(tn, t0);
            t1 = _mm_min_ps(tf, t1);
        }
        hits |= unsigned(_mm_movemask_ps(_mm_cmple_ps(t0, t1))) << base;
    }
#else
    for (int i = 0; i < n.count; ++i)
        if (intersect_box(r, n.box(i), tmin, tmax, nullptr)) hits |= 1u << i;
#endif
    return hits & ((1u << n.count) - 1u);
}

void TraversalThread::push_children(const InternalNode& n, uint32_t inst_block, StepInfo& info) {
    bool first = true;
    // Culls children whose entry lies beyond the closest hit so far (ray_.tfar).
    const unsigned hits = child_hits(box_ray_, n, ray_.tnear, ray_.tfar);
    for (int i = 0; i < n.count; ++i) {
        if (n.type[i] == NodeType::Empty || !(hits >> i & 1u)) continue;
        // Entries are written in place, field by field: a whole entry built first and then
        // copied in is read back as one 16-byte word from three narrower stores, which the host
        // CPU cannot forward (a stall of about 15 cycles per child, 5 % of a functional run).
        // A child in another treelet waits until this one is finished (deferred_).
        const bool other_treelet = treelets_ && treelets_->treelet_of(n.addr[i]) != current_treelet_;
        if (!other_treelet && first && register_) {
            next_ = StackEntry{n.addr[i], n.type[i], inst_block};
            has_next_ = true;
            first = false;
            continue;
        }
        if (!other_treelet) first = false;
        StackEntry& child = (other_treelet ? deferred_ : stack_).emplace_back();
        child.addr = n.addr[i];
        child.type = n.type[i];
        child.inst_block = inst_block;
        ++info.pushed;
    }
}

StepInfo TraversalThread::step(const BvhImage& image) {
    StepInfo info;
    StackEntry e;
    if (has_next_) {
        e = next_;
        has_next_ = false;
    } else if (order_ == TraversalOrder::DFS || (order_ == TraversalOrder::Treelet && !stack_.empty())) {
        e = stack_.back();
        stack_.pop_back();
        info.from_stack = true;
    } else if (order_ == TraversalOrder::Treelet) {
        // The current treelet is finished: move to the one on top of the deferred stack. The
        // Treelet code both papers ran (vulkan_ray_tracing.cc traceRayWithTreelets, l.1749-1754 at
        // yavuz650/vulkan-sim 62af1437) sets its current treelet to the popped entry's host
        // address, while treelets are named by device addresses (l.468-490; device_offset is
        // never 0), so no node matches it again: every later child is deferred and popped last in,
        // first out, a DFS over what the root treelet left (RootThenDfs; kNoTreelet, since
        // treelet_of gives ~0 for an address outside every treelet).
        e = deferred_.back();
        deferred_.pop_back();
        current_treelet_ = treelets_->order == TreeletOrder::RootThenDfs ? kNoTreelet : treelets_->treelet_of(e.addr);
        info.from_stack = true;
    } else {
        e = stack_.front();
        stack_.pop_front();
        info.from_stack = true;
    }
    info.type = e.type;
    if (e.type == NodeType::Header) {
        image.at(e.addr, node_bytes(e.type));  // in the image, as every fetch
        if (e.addr == 0) {
            // The image header: the root, if its box is hit.
            if (intersect_box(world_box_ray_, root_box_, ray_.tnear, ray_.tfar, nullptr))
                push_next(StackEntry{root_, NodeType::Internal, kNoId}, info);
        } else {
            // A BLAS's header: its root follows it, entered without a box test.
            push_next(StackEntry{e.addr + kBlockBytes, NodeType::Internal, e.inst_block}, info);
        }
        return info;
    }
    ++nodes_visited_;
    select_space(image, e.inst_block);
    const uint8_t* bytes = image.at(e.addr, node_bytes(e.type));

    switch (e.type) {
        case NodeType::Internal: {
            // The image decodes the top of the tree up front; a node it did not is decoded here,
            // apart, so that the common path does not construct (and zero) a 200-byte node.
            const InternalNode* pre = image.decoded_internal(e.addr);
            if (pre) {
                push_children(*pre, e.inst_block, info);
            } else {
                const InternalNode n = decode_internal(bytes);
                push_children(n, e.inst_block, info);
            }
            break;
        }
        case NodeType::Instance: {
            const InstanceLeaf inst = decode_instance(bytes);
            const uint32_t block = uint32_t(e.addr / kBlockBytes);
            if (headers_) {
                // The BLAS's header is read next, by this same pop (not a pop of its own).
                if (inst.blas_root < kBlockBytes) throw std::runtime_error("instance leaf's BLAS root has no header before it");
                next_ = StackEntry{inst.blas_root - kBlockBytes, NodeType::Header, block};
                has_next_ = true;
            } else {
                push_next(StackEntry{inst.blas_root, NodeType::Internal, block}, info);
            }
            break;
        }
        case NodeType::Triangle: {
            const TriangleLeaf t = decode_triangle(bytes);
            TriangleHit th;
            float app_t;
            // The robust test decides the hit (as Embree would); the simulator's arithmetic
            // gives its t, by which it is accepted (t >= tmin, closer than the closest triangle
            // hit so far, strictly: of coincident triangles the first visited wins) and culls.
            if (intersect_triangle(org_, dir_, t.v0, t.v1, t.v2, ray_.tnear, tmax_, &th) && moller_trumbore_t(org_, dir_, t, &app_t) &&
                app_t >= ray_.tnear && app_t < ray_.tfar) {
                info.hit = true;
                ray_.tfar = app_t;  // culls from now on
                take_hit(th.t, app_t, th.u, th.v, t.geom, t.prim, normal_to_world(image, glm::cross(t.v1 - t.v0, t.v2 - t.v0)));
            }
            break;
        }
        case NodeType::Procedural: {
            // Recorded for the intersection shader, which runs after the traversal: its hit is
            // taken if it is the closest, but culls nothing (see the file comment).
            ++candidates_;
            const SphereLeaf s = decode_sphere(bytes);
            float th;
            float app_t = 0.0f;
            if (intersect_sphere(org_, dir_, s.center, s.radius, ray_.tnear, tmax_, &th)) {
                app_t = shader_sphere_t(org_, dir_, s, ray_.tnear, th);
                take_hit(th, app_t, 0.0f, 0.0f, s.geom, s.prim, normal_to_world(image, (org_ + th * dir_) - s.center));  // outward
            }
            break;
        }
        case NodeType::Empty:
        case NodeType::Header:
            break;
    }
    if (info.hit && ray_.query == Query::Any) finish();
    return info;
}

TraceResult trace_ray(const BvhImage& image, const Ray& ray, TraversalOrder order, const Treelets* treelets,
                      std::vector<StackEntry>* fetched, bool next_node_register, uint64_t max_nodes) {
    TraceResult r;
    if (!is_valid_ray(ray)) return r;
    Ray scaled = ray;
    const int k = scale_direction(scaled);
    // One traversal state per host thread, reused: start() resets all of it, whereas a new one
    // per ray allocated its two stacks (std::deque) for every ray (the sampling pre-pass traces
    // the whole frame this way).
    thread_local TraversalThread th;
    th.start(scaled, image.header(), order, treelets, next_node_register);
    while (!th.done()) {
        if (fetched) fetched->push_back(th.peek());
        th.step(image);
        if (th.nodes_visited() > max_nodes)
            throw std::length_error("traversal visited more than " + std::to_string(max_nodes) + " nodes (a cycle in the image?)");
    }
    r.hit = th.hit();
    if (r.hit.hit) {
        r.hit.t = std::ldexp(r.hit.t, -k);
        r.hit.app_t = std::ldexp(r.hit.app_t, -k);
    }
    r.nodes_visited = th.nodes_visited();
    r.candidates = th.candidates();
    return r;
}

}  // namespace rtu
