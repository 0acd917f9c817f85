// The BVH memory image: byte layout of every node the RT unit fetches (docs/foundation.md, "BVH images and functional speed").
//
// All nodes live in 64 B blocks; addresses are byte addresses into the image and always
// 64 B aligned. Siblings are contiguous: an internal node stores one base address and the
// type of each child; child i starts at base + (sum of the sizes of children 0..i-1).
//
// Internal node, 64 B:
//   0  float origin[3]      lower corner of the node's own box
//   12 int8  exp[3]         per-axis power-of-two exponent: scale = 2^(exp-8)
//   15 uint8 child_count    1..6
//   16 uint32 child_base    block index (address / 64) of the first child
//   20 uint8 child_type[6]  NodeType of each child (Empty for unused slots)
//   26 uint8 q[6][6]        per child lo.x lo.y lo.z hi.x hi.y hi.z, 8-bit quantized
//   62 2 bytes reserved
// Decoded bound = origin + q * scale, rounded outward to float, so that every decoded child
// box contains the exact child box (conservative quantization).
//
// Triangle leaf, 64 B:   float v0[3] v1[3] v2[3]; uint32 geom, prim.
// Procedural leaf, 64 B: uint32 kind (1 = sphere); float center[3], radius; uint32 geom, prim.
// Instance leaf, 128 B:  float world_to_object[3][4], object_to_world[3][4]; uint32 blas_root
//                        (block index), uint32 instance id, uint32 geom (mesh of the BLAS).
// Image header at address 0, 64 B: "RTUBVH01", float root box lo[3] hi[3], uint32 root block,
//                        uint32 flags (bit 0 instances, bit 1 procedural, bit 2 headers),
//                        uint32 leaf count. It is the TLAS's (or the single-level BVH's) header.
// BLAS header, 64 B, the block before each BLAS's root (flag bit 2): the same layout, of that BLAS
//                        (its root box and root block; flags 0; its leaf count).
// With flag bit 2 the RT unit reads the image header at the start of every ray and a BLAS's
// header after each instance leaf that leads into it, as the TTP authors' simulator reads the
// acceleration structures' 64 B headers (vulkan_ray_tracing.cc traceRay_BFS l.1667, l.1901).
// A header read is a fetch (NodeType::Header), not a node visit: it is not a pop and is not
// counted in the nodes a ray visits.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/mat3x4.hpp>
#include <glm/vec3.hpp>

#include "robust.h"

namespace rtu {

constexpr uint32_t kBlockBytes = 64;
constexpr int kMaxChildren = 6;

enum class NodeType : uint8_t { Empty = 0, Internal = 1, Triangle = 2, Procedural = 3, Instance = 4, Header = 5 };

// Size of a node of this type in bytes (what the RT unit fetches for it).
uint32_t node_bytes(NodeType t);
const char* node_type_name(NodeType t);

struct InternalNode {
    int count = 0;
    std::array<NodeType, kMaxChildren> type{};
    std::array<uint64_t, kMaxChildren> addr{};  // byte address of each child
    // The decoded (conservative) child boxes as a structure of arrays, lo[axis][child] and
    // hi[axis][child], padded to kLanes children so that a box test can take four children at a
    // time (TraversalThread::push_children); lanes from `count` on are unused.
    static constexpr int kLanes = 8;
    alignas(16) std::array<std::array<float, kLanes>, 3> lo{}, hi{};
    Aabb box(int i) const {
        Aabb b;
        for (int a = 0; a < 3; ++a) b.lo[a] = lo[a][i], b.hi[a] = hi[a][i];
        return b;
    }
};

// Encodes an internal node. `node_box` must contain every child box. Child i is placed at
// `first_child_addr` + sizes of the children before it.
void encode_internal(const Aabb& node_box, int count, const NodeType* types, const Aabb* boxes,
                     uint64_t first_child_addr, uint8_t out[kBlockBytes]);
InternalNode decode_internal(const uint8_t* bytes);

struct TriangleLeaf {
    glm::vec3 v0, v1, v2;
    uint32_t geom, prim;
};
void encode_triangle(const TriangleLeaf& t, uint8_t out[kBlockBytes]);
TriangleLeaf decode_triangle(const uint8_t* bytes);

struct SphereLeaf {
    glm::vec3 center;
    float radius;
    uint32_t geom, prim;
};
void encode_sphere(const SphereLeaf& s, uint8_t out[kBlockBytes]);
SphereLeaf decode_sphere(const uint8_t* bytes);

// Row-major 3x4 affine transforms: p' = M[:, 0:3] p + M[:, 3].
using Affine = std::array<float, 12>;
glm::vec3 transform_point(const Affine& m, const glm::vec3& p);
glm::vec3 transform_vector(const Affine& m, const glm::vec3& v);
// Inverse computed in double and rounded once to float.
Affine invert_affine(const Affine& m);
bool is_identity(const Affine& m);
Affine identity_affine();

struct InstanceLeaf {
    Affine world_to_object, object_to_world;
    uint64_t blas_root;  // byte address
    uint32_t instance, geom;
};
void encode_instance(const InstanceLeaf& inst, uint8_t out[2 * kBlockBytes]);
InstanceLeaf decode_instance(const uint8_t* bytes);

struct ImageHeader {
    Aabb root_box;
    uint64_t root = 0;  // byte address of the root internal node
    bool has_instances = false, has_procedural = false;
    bool has_headers = false;  // the TLAS and every BLAS have a header the RT unit reads (flag bit 2)
    uint32_t leaves = 0;
};
void encode_header(const ImageHeader& h, uint8_t out[kBlockBytes]);
// Throws std::runtime_error when the magic does not match.
ImageHeader decode_header(const uint8_t* bytes);

}  // namespace rtu
