#include "bvh_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <stdexcept>
#include <utility>

#include <embree3/rtcore.h>
#include <glm/common.hpp>

#include "input_error.h"

namespace rtu {
namespace {

// Nodes of the tree Embree's builder hands back through our callbacks. Leaves are small (one
// per primitive: 871 k for the full dragon), internal nodes carry six child boxes.
struct NodeBase {
    bool leaf = false;
};
struct BuildLeaf : NodeBase {
    uint32_t geom = 0, prim = 0;  // which primitive (geom: the build primitive's geomID)
};
struct BuildNode : NodeBase {
    uint32_t count = 0;
    NodeBase* child[kMaxChildren] = {};
    Aabb box[kMaxChildren];
};
const BuildLeaf* as_leaf(const NodeBase* n) { return static_cast<const BuildLeaf*>(n); }
const BuildNode* as_node(const NodeBase* n) { return static_cast<const BuildNode*>(n); }

Aabb to_aabb(const RTCBounds& b) {
    Aabb a;
    a.lo = {b.lower_x, b.lower_y, b.lower_z};
    a.hi = {b.upper_x, b.upper_y, b.upper_z};
    return a;
}

struct EmbreeDevice {
    RTCDevice dev = rtcNewDevice("threads=0");
    EmbreeDevice() {
        if (!dev) throw std::runtime_error("Embree device creation failed");
    }
    ~EmbreeDevice() { rtcReleaseDevice(dev); }
};

// Builds a 6-wide tree over `prims`; returns the root (never a bare leaf) and the root box.
NodeBase* build_tree(RTCDevice dev, RTCBVH bvh, std::vector<RTCBuildPrimitive>& prims) {
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.byteSize = sizeof(args);
    args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = kMaxChildren;
    args.maxDepth = 32;
    args.minLeafSize = 1;
    args.maxLeafSize = 1;
    args.bvh = bvh;
    args.primitives = prims.data();
    args.primitiveCount = prims.size();
    args.primitiveArrayCapacity = prims.size();
    args.createNode = [](RTCThreadLocalAllocator alloc, unsigned n, void*) -> void* {
        void* p = rtcThreadLocalAlloc(alloc, sizeof(BuildNode), 16);
        BuildNode* node = new (p) BuildNode();
        node->count = n;
        return node;
    };
    args.setNodeChildren = [](void* node, void** children, unsigned n, void*) {
        for (unsigned i = 0; i < n; ++i) static_cast<BuildNode*>(node)->child[i] = static_cast<NodeBase*>(children[i]);
    };
    args.setNodeBounds = [](void* node, const RTCBounds** bounds, unsigned n, void*) {
        for (unsigned i = 0; i < n; ++i) static_cast<BuildNode*>(node)->box[i] = to_aabb(*bounds[i]);
    };
    args.createLeaf = [](RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* p, size_t n, void*) -> void* {
        if (n != 1) throw std::logic_error("Embree made a leaf with more than one primitive");
        void* mem = rtcThreadLocalAlloc(alloc, sizeof(BuildLeaf), 16);
        BuildLeaf* node = new (mem) BuildLeaf();
        node->leaf = true;
        node->geom = p[0].geomID;
        node->prim = p[0].primID;
        return node;
    };
    (void)dev;
    NodeBase* root = static_cast<NodeBase*>(rtcBuildBVH(&args));
    if (!root) throw std::runtime_error("Embree rtcBuildBVH failed");
    return root;
}

Aabb union_of(const BuildNode* n) {
    Aabb b;
    for (uint32_t i = 0; i < n->count; ++i) {
        b.lo = glm::min(b.lo, n->box[i].lo);
        b.hi = glm::max(b.hi, n->box[i].hi);
    }
    return b;
}

// An acceleration structure's header bounds as the driver writes them (Mesa's lavapipe,
// lvp_acceleration_structure.c l.1348-1360): per axis, the lowest child bound of the root
// (calc_bounds' origin) and origin + the highest quantized upper bound times the root's
// quantum, in float. The TLAS's bounds are the ray's first test; a BLAS's are its instance's box
// in the TLAS build.
Aabb mesa_header_bounds(const BuildNode* root) {
    Aabb out;
    for (int a = 0; a < 3; ++a) {
        float lo = root->box[0].lo[a], hi = root->box[0].hi[a];
        for (uint32_t i = 1; i < root->count; ++i) lo = std::min(lo, root->box[i].lo[a]), hi = std::max(hi, root->box[i].hi[a]);
        const float total = hi - lo;
        out.lo[a] = lo;
        if (std::isinf(total)) {
            out.hi[a] = INFINITY;
            continue;
        }
        int exp = 0;
        const float m = std::frexp(total, &exp);
        if (m > 255.0f / 256.0f) ++exp;
        exp = std::max(exp, -128);
        float top = 0.0f;
        for (uint32_t i = 0; i < root->count; ++i) top = std::max(top, std::ceil(std::ldexp(root->box[i].hi[a] - lo, 8 - exp)));
        out.hi[a] = std::max(hi, lo + std::ldexp(top, exp - 8));  // never inside the exact box
    }
    return out;
}

// The node type of child `i` of `n` in its child block: its leaf's (`leaf_type`) or internal.
template <typename LeafType>
NodeType child_type(const BuildNode* n, uint32_t i, const LeafType& leaf_type) {
    return n->child[i]->leaf ? leaf_type(as_leaf(n->child[i])) : NodeType::Internal;
}

class ImageWriter {
public:
    std::vector<uint8_t> bytes;
    BvhStats stats;

    uint64_t alloc(uint64_t n) {
        const uint64_t at = bytes.size();
        bytes.resize(at + n, 0);
        return at;
    }

    // Writes the internal node `n` (whose own box is `box`) at `addr`, then its child block and
    // the subtrees below it depth-first. `leaf_type` gives the node type of each leaf;
    // `write_leaf` encodes leaf `n` at a given address. Returns the subtree's internal depth.
    template <typename LeafType, typename LeafWriter>
    uint32_t write_internal(const BuildNode* n, const Aabb& box, uint64_t addr, const LeafType& leaf_type,
                            LeafWriter& write_leaf) {
        ++stats.internal_nodes;
        NodeType types[kMaxChildren];
        uint64_t block = 0;
        for (uint32_t i = 0; i < n->count; ++i) {
            types[i] = child_type(n, i, leaf_type);
            block += node_bytes(types[i]);
        }
        const uint64_t base = alloc(block);
        encode_internal(box, int(n->count), types, n->box, base, &bytes[addr]);
        uint32_t depth = 0;
        uint64_t at = base;
        for (uint32_t i = 0; i < n->count; ++i) {
            if (types[i] == NodeType::Internal)
                depth = std::max(depth, write_internal(as_node(n->child[i]), n->box[i], at, leaf_type, write_leaf));
            else
                write_leaf(as_leaf(n->child[i]), at);
            at += node_bytes(types[i]);
        }
        return depth + 1;
    }
};

// The bytes write_internal lays out for the subtree below `n` (its child block and theirs), so that
// the image is allocated once at its size: grown by alloc() alone, its vector doubled about 26
// times on party (83 MB), each time copying and faulting in the image so far (the writing was
// 17 % of a functional run's profile, its copies 3.9 %: docs/performance.md, "Earlier speed work").
template <typename LeafType>
uint64_t subtree_bytes(const BuildNode* n, const LeafType& leaf_type) {
    uint64_t bytes = 0;
    for (uint32_t i = 0; i < n->count; ++i) {
        const NodeType t = child_type(n, i, leaf_type);
        bytes += node_bytes(t) + (t == NodeType::Internal ? subtree_bytes(as_node(n->child[i]), leaf_type) : 0);
    }
    return bytes;
}

// A bare leaf root (one primitive) is wrapped in an internal node with one child.
const BuildNode* ensure_internal_root(NodeBase* root, const Aabb& box, BuildNode& holder) {
    if (!root->leaf) return as_node(root);
    holder.count = 1;
    holder.child[0] = root;
    holder.box[0] = box;
    return &holder;
}

// Copies of one face that the BVH keeps. Every copy of a face has the same box, which its
// plane crosses: a ray that hits the face enters every copy's box before it reaches the face, so
// it tests every copy whatever the traversal culls (115,195 copies of one triangle, a 900 KB OBJ,
// took 54 s at 64x64: issue 50). Real assets repeat a face a few times (sprng's grass is
// two-sided by copies; ship's schooner has up to 3 copies of a face; the 2.0 M triangles of
// ../shared/scenes have no face with more), and the authors' BVH keeps those, so this does too.
constexpr uint32_t kCopiesKept = 8;

// The faces of `m` that repeat an earlier face of it (the same three corner positions, bit for
// bit, in any order) beyond kCopiesKept copies: a mask over its triangles (empty: none).
std::vector<uint8_t> repeats_left_out(const Mesh& m) {
    if (m.procedural() || m.triangles.size() <= kCopiesKept) return {};
    using Corners = std::array<uint32_t, 9>;
    auto corners = [&m](size_t i) {
        std::array<std::array<uint32_t, 3>, 3> c;
        for (int k = 0; k < 3; ++k) std::memcpy(c[k].data(), &m.vertices[m.triangles[i][k]][0], 3 * sizeof(float));
        std::sort(c.begin(), c.end());
        Corners out;
        for (int k = 0; k < 3; ++k) std::copy(c[k].begin(), c[k].end(), out.begin() + 3 * k);
        return out;
    };
    // Sorted by a hash of the corners first (16 B a face), exact corners only where a hash is
    // shared by more faces than are kept.
    std::vector<std::pair<uint64_t, uint32_t>> by_hash(m.triangles.size());
    for (size_t i = 0; i < m.triangles.size(); ++i) {
        uint64_t h = 1469598103934665603ull;
        for (uint32_t v : corners(i)) h = (h ^ v) * 1099511628211ull;
        by_hash[i] = {h, uint32_t(i)};
    }
    std::sort(by_hash.begin(), by_hash.end());
    std::vector<uint8_t> out;
    for (size_t a = 0, b; a < by_hash.size(); a = b) {
        for (b = a + 1; b < by_hash.size() && by_hash[b].first == by_hash[a].first; ++b) {}
        if (b - a <= kCopiesKept) continue;
        std::map<Corners, uint32_t> seen;  // in face order: the earliest copies are kept
        for (size_t k = a; k < b; ++k)
            if (++seen[corners(by_hash[k].second)] > kCopiesKept) {
                if (out.empty()) out.assign(m.triangles.size(), 0);
                out[by_hash[k].second] = 1;
            }
    }
    return out;
}

std::vector<RTCBuildPrimitive> mesh_primitives(const Mesh& m, uint32_t geom, BvhStats& stats) {
    const std::vector<uint8_t> left_out = repeats_left_out(m);
    std::vector<RTCBuildPrimitive> prims;
    prims.reserve(m.primitives());
    for (size_t i = 0; i < m.primitives(); ++i) {
        if (!left_out.empty() && left_out[i]) continue;
        const Aabb b = m.prim_bounds(i);
        prims.push_back({b.lo.x, b.lo.y, b.lo.z, geom, b.hi.x, b.hi.y, b.hi.z, uint32_t(i)});
    }
    if (const size_t n = m.primitives() - prims.size()) {
        stats.repeats_left_out += n;
        std::cerr << "warning: mesh " << geom << (m.name.empty() ? std::string() : " (" + m.name + ")") << ": " << n
                  << " faces are copies of another face beyond its first " << kCopiesKept
                  << " and are left out of the BVH (a ray that hits a face tests every copy of it); they keep their numbers, "
                     "and a hit names an earlier copy\n";
    }
    return prims;
}

// World box of a transformed object box: corners transformed in double, rounded outward, then
// widened by a relative 2^-20 of the extent to cover the transformed ray's rounding.
Aabb transformed_box(const Aabb& b, const Affine& m) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
        for (int i = 0; i < 3; ++i) {
            const double v = double(m[4 * i]) * p[0] + double(m[4 * i + 1]) * p[1] + double(m[4 * i + 2]) * p[2] + m[4 * i + 3];
            lo[i] = std::min(lo[i], v);
            hi[i] = std::max(hi[i], v);
        }
    }
    Aabb r;
    for (int i = 0; i < 3; ++i) {
        const double pad = (hi[i] - lo[i]) * 0x1p-20 + (std::fabs(lo[i]) + std::fabs(hi[i])) * 0x1p-22;
        r.lo[i] = std::nextafter(float(lo[i] - pad), -INFINITY);
        r.hi[i] = std::nextafter(float(hi[i] + pad), INFINITY);
    }
    return r;
}

}  // namespace

namespace {

// Coordinates Embree's builder can take. Its SAH multiplies half-areas of boxes by primitive
// counts in float: coordinates near the float limit (3e38) make areas infinite and the costs NaN,
// and a debug assertion in the builder aborts the process (issue 16: a triangle at +-3e38). A box
// within +-E has a half-area of at most 3 (2E)^2 = 12 E^2; times the primitives N of the scene
// (a bound on any one build's count) it stays within FLT_MAX with a margin of 3 when
// E <= sqrt(FLT_MAX / (36 N)): 9.7e14 for 10 million primitives, 3.1e18 for one. Beyond 1e18
// Debian's Embree takes no ray (|component| <= 1.8e18), so no hit there could be checked: that is
// the cap. Measured (a triangle of vertices at +-E, rtsim --verify): at 1e15, 1e17 and 1e18 rays
// near it hit as Embree's do; rays from far away miss it as the modelled hardware's float
// Moller-Trumbore t overflows (verify class simulator_float_overflow, docs/verification.md).
float max_coordinate(size_t primitives_and_instances) {
    return float(std::min(1e18, std::sqrt(3.4028234663852886e38 / (36.0 * std::max<double>(1.0, double(primitives_and_instances))))));
}

void check_coordinates(const Scene& scene) {
    size_t primitives = 0;
    for (const Mesh& m : scene.meshes) primitives += m.primitives();
    const float limit_all = max_coordinate(primitives + scene.instances.size());  // for every coordinate of the scene
    char limit_text[32];
    std::snprintf(limit_text, sizeof limit_text, "%.2g", double(limit_all));
    auto refuse = [&](const Mesh& m, size_t geom, const std::string& what, double v) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", v);
        throw InputError("mesh " + std::to_string(geom) + (m.name.empty() ? std::string() : " (" + m.name + ")") + ": " + what + " " +
                         value + " is beyond +-" + limit_text + ", the coordinates the BVH builder takes for a scene of " +
                         std::to_string(primitives) + " primitives (its SAH's areas times counts must stay finite in float; "
                         "scale the scene down)");
    };
    for (size_t g = 0; g < scene.meshes.size(); ++g) {
        const Mesh& m = scene.meshes[g];
        for (size_t i = 0; i < m.vertices.size(); ++i)
            for (int a = 0; a < 3; ++a)
                if (!(std::fabs(m.vertices[i][a]) <= limit_all)) refuse(m, g, "vertex " + std::to_string(i) + " coordinate", m.vertices[i][a]);
        for (size_t i = 0; i < m.spheres.size(); ++i) {
            const Sphere& sp = m.spheres[i];
            for (int a = 0; a < 3; ++a)
                if (!(std::fabs(sp.center[a]) + std::fabs(sp.radius) <= limit_all))
                    refuse(m, g, "sphere " + std::to_string(i) + " extent", std::fabs(sp.center[a]) + std::fabs(sp.radius));
        }
    }
    // An instance's transform places its mesh in the TLAS: its world box (transformed_box) must
    // be within the same range, and the transform invertible with a finite float inverse (the
    // instance leaf stores both; traversal moves rays into object space with the inverse).
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& inst = scene.instances[i];
        const Mesh& m = scene.meshes.at(inst.mesh);
        if (m.primitives() == 0) continue;
        const std::string which = "instance " + std::to_string(i) + " of";
        const auto bad_transform = [&](const std::string& why) {
            throw InputError("mesh " + std::to_string(inst.mesh) + (m.name.empty() ? std::string() : " (" + m.name + ")") + ": " + which +
                             " it has " + why + ": it cannot be traversed");
        };
        for (float v : inst.object_to_world)
            if (!std::isfinite(v)) bad_transform("a transform with an entry that is not a finite number");
        // The box is padded outward by about 2^-20 of its extent: a mesh placed as it is, with
        // vertices at the limit itself, stays within the limit widened by 2^-18.
        const Aabb b = transformed_box(m.bounds(), inst.object_to_world);
        const float limit = limit_all * (1.0f + 0x1p-18f);
        for (int a = 0; a < 3; ++a)
            if (!(std::fabs(b.lo[a]) <= limit && std::fabs(b.hi[a]) <= limit))
                refuse(m, inst.mesh, which + " it, placed by its transform, reaches coordinate",
                       std::fabs(b.lo[a]) > std::fabs(b.hi[a]) ? b.lo[a] : b.hi[a]);
        Affine inv{};
        try {
            inv = invert_affine(inst.object_to_world);
        } catch (const std::runtime_error&) {
            bad_transform("a singular transform (determinant 0)");
        }
        for (float v : inv)
            if (!std::isfinite(v)) bad_transform("a transform so nearly singular that its inverse overflows a float");
    }
}

}  // namespace

BvhImage build_bvh_image(const Scene& scene) {
    check_coordinates(scene);
    EmbreeDevice device;
    ImageWriter w;
    ImageHeader header;
    w.alloc(kBlockBytes);  // header block

    // Leaf writer for a mesh's own primitives.
    auto mesh_leaf_writer = [&](const Mesh& mesh, uint32_t geom) {
        return [&w, &mesh, geom](const BuildLeaf* leaf, uint64_t at) {
            if (mesh.procedural()) {
                const Sphere& s = mesh.spheres[leaf->prim];
                encode_sphere({s.center, s.radius, geom, leaf->prim}, &w.bytes[at]);
                ++w.stats.procedural_leaves;
            } else {
                const glm::uvec3& t = mesh.triangles[leaf->prim];
                encode_triangle({mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], geom, leaf->prim}, &w.bytes[at]);
                ++w.stats.triangle_leaves;
            }
        };
    };

    auto mesh_leaf_type = [&](const BuildLeaf* leaf) {
        return scene.meshes[leaf->geom].procedural() ? NodeType::Procedural : NodeType::Triangle;
    };
    if (!scene.two_level()) {
        // One tree over the primitives of every (identity-placed) mesh; leaves keep their geom.
        std::vector<RTCBuildPrimitive> prims;
        std::vector<uint8_t> used(scene.meshes.size(), 0);
        Aabb box;
        for (const Instance& inst : scene.instances) {
            if (used[inst.mesh]++) continue;
            const Mesh& mesh = scene.meshes[inst.mesh];
            if (mesh.primitives() == 0) continue;
            auto p = mesh_primitives(mesh, inst.mesh, w.stats);
            prims.insert(prims.end(), p.begin(), p.end());
            const Aabb b = mesh.bounds();
            box.lo = glm::min(box.lo, b.lo);
            box.hi = glm::max(box.hi, b.hi);
        }
        RTCBVH bvh = rtcNewBVH(device.dev);
        BuildNode holder;
        const BuildNode* root = ensure_internal_root(build_tree(device.dev, bvh, prims), box, holder);
        w.bytes.reserve(2 * kBlockBytes + subtree_bytes(root, mesh_leaf_type));  // the header, the root and the rest
        header.root = w.alloc(kBlockBytes);
        header.root_box = box;
        auto writer = [&](const BuildLeaf* leaf, uint64_t at) { mesh_leaf_writer(scene.meshes[leaf->geom], leaf->geom)(leaf, at); };
        w.stats.depth = w.write_internal(root, union_of(root), header.root, mesh_leaf_type, writer) + 1;
        rtcReleaseBVH(bvh);
    } else {
        // Every BLAS is built first, as the driver builds the BLASes before the TLAS: an
        // instance's box in the TLAS build is its BLAS header's bounds (mesa_header_bounds).
        struct Blas {
            RTCBVH bvh = nullptr;
            BuildNode holder;
            const BuildNode* root = nullptr;
            Aabb header_bounds;
        };
        std::vector<Blas> blas(scene.meshes.size());
        for (const Instance& in : scene.instances) {
            Blas& b = blas[in.mesh];
            const Mesh& mesh = scene.meshes[in.mesh];
            if (b.bvh || mesh.primitives() == 0) continue;
            auto prims = mesh_primitives(mesh, in.mesh, w.stats);
            b.bvh = rtcNewBVH(device.dev);
            b.root = ensure_internal_root(build_tree(device.dev, b.bvh, prims), mesh.bounds(), b.holder);
            b.header_bounds = mesa_header_bounds(b.root);
        }
        // TLAS over the instances of non-empty meshes.
        std::vector<RTCBuildPrimitive> inst_prims;
        for (uint32_t i = 0; i < scene.instances.size(); ++i) {
            const Instance& in = scene.instances[i];
            if (!blas[in.mesh].bvh) continue;
            const Aabb b = is_identity(in.object_to_world) ? blas[in.mesh].header_bounds : transformed_box(blas[in.mesh].header_bounds, in.object_to_world);
            inst_prims.push_back({b.lo.x, b.lo.y, b.lo.z, 0, b.hi.x, b.hi.y, b.hi.z, i});
        }
        RTCBVH tlas_bvh = rtcNewBVH(device.dev);
        BuildNode holder;
        NodeBase* tree = build_tree(device.dev, tlas_bvh, inst_prims);
        Aabb world;
        for (const auto& p : inst_prims) {
            world.lo = glm::min(world.lo, glm::vec3(p.lower_x, p.lower_y, p.lower_z));
            world.hi = glm::max(world.hi, glm::vec3(p.upper_x, p.upper_y, p.upper_z));
        }
        const BuildNode* troot = ensure_internal_root(tree, world, holder);
        auto instance_type = [](const BuildLeaf*) { return NodeType::Instance; };
        // The header, the TLAS's root and the rest, then each BLAS's header, root and the rest:
        // every mesh with a BLAS has an instance in the TLAS, and its BLAS is written once.
        uint64_t size = 2 * kBlockBytes + subtree_bytes(troot, instance_type);
        for (const Blas& b : blas)
            if (b.bvh) size += 2 * kBlockBytes + subtree_bytes(b.root, mesh_leaf_type);
        w.bytes.reserve(size);
        header.root = w.alloc(kBlockBytes);
        header.root_box = mesa_header_bounds(troot);
        header.has_instances = true;
        std::vector<std::pair<uint32_t, uint64_t>> inst_leaves;  // instance, leaf address
        auto inst_writer = [&](const BuildLeaf* leaf, uint64_t at) {
            inst_leaves.push_back({leaf->prim, at});
            ++w.stats.instance_leaves;
        };
        w.stats.tlas_depth = w.write_internal(troot, union_of(troot), header.root, instance_type, inst_writer);
        rtcReleaseBVH(tlas_bvh);

        // One BLAS per mesh that is instanced, laid out after the TLAS in the order its first
        // instance leaf is, each its header and then its tree.
        std::vector<uint64_t> blas_root(scene.meshes.size(), 0);
        std::vector<uint32_t> blas_depth(scene.meshes.size(), 0);
        for (const auto& [inst, at] : inst_leaves) {
            const uint32_t geom = scene.instances[inst].mesh;
            if (blas_root[geom] != 0) continue;
            const Mesh& mesh = scene.meshes[geom];
            const Blas& b = blas[geom];
            const uint64_t blas_header = w.alloc(kBlockBytes);
            blas_root[geom] = w.alloc(kBlockBytes);
            const uint64_t leaves_before = w.stats.triangle_leaves + w.stats.procedural_leaves;
            auto writer = mesh_leaf_writer(mesh, geom);
            blas_depth[geom] = w.write_internal(b.root, union_of(b.root), blas_root[geom], mesh_leaf_type, writer);
            ImageHeader bh;
            bh.root = blas_root[geom];
            bh.root_box = b.header_bounds;
            bh.leaves = uint32_t(w.stats.triangle_leaves + w.stats.procedural_leaves - leaves_before);
            encode_header(bh, &w.bytes[blas_header]);
            ++w.stats.blas_count;
        }
        for (Blas& b : blas)
            if (b.bvh) rtcReleaseBVH(b.bvh);
        uint32_t deepest = 0;
        for (const auto& [inst, at] : inst_leaves) {
            const Instance& in = scene.instances[inst];
            InstanceLeaf leaf;
            leaf.object_to_world = in.object_to_world;
            leaf.world_to_object = invert_affine(in.object_to_world);
            leaf.blas_root = blas_root[in.mesh];
            leaf.instance = inst;
            leaf.geom = in.mesh;
            encode_instance(leaf, &w.bytes[at]);
            deepest = std::max(deepest, blas_depth[in.mesh]);
        }
        w.stats.depth = w.stats.tlas_depth + 1 + deepest + 1;  // + instance leaf + primitive leaf
    }
    header.has_procedural = scene.has_procedural();
    header.has_headers = true;
    header.leaves = uint32_t(w.stats.triangle_leaves + w.stats.procedural_leaves + w.stats.instance_leaves);
    encode_header(header, w.bytes.data());
    BvhStats stats = w.stats;
    stats.image_bytes = w.bytes.size();
    BvhImage image(std::move(w.bytes));
    image.stats = stats;
    return image;
}

}  // namespace rtu
