// Node codec: round trip and conservativeness of the quantized child boxes.
#include <gtest/gtest.h>

#include <cstring>

#include <cmath>
#include <random>

#include <glm/common.hpp>

#include "model/node_format.h"

using namespace rtu;

namespace {

Aabb random_box_inside(std::mt19937& g, const Aabb& outer) {
    Aabb b;
    for (int a = 0; a < 3; ++a) {
        std::uniform_real_distribution<float> d(outer.lo[a], outer.hi[a]);
        float x = d(g), y = d(g);
        b.lo[a] = std::min(x, y);
        b.hi[a] = std::max(x, y);
    }
    return b;
}

}  // namespace

TEST(NodeFormat, NodeSizesFollowTheDesign) {
    EXPECT_EQ(node_bytes(NodeType::Internal), 64u);
    EXPECT_EQ(node_bytes(NodeType::Triangle), 64u);
    EXPECT_EQ(node_bytes(NodeType::Procedural), 64u);
    EXPECT_EQ(node_bytes(NodeType::Instance), 128u);
}

// Decoded child boxes always contain the exact child boxes, for boxes of every scale and offset
// (including flat boxes and offsets up to 1e7), and are not much larger than one quantization
// step plus rounding.
TEST(NodeFormat, QuantizedChildBoxesAreConservativeAndTight) {
    std::mt19937 g(7);
    const float scales[] = {1e-4f, 1e-1f, 1.0f, 555.0f, 1e4f, 1e6f};
    const float offsets[] = {0.0f, -3.5f, 1e5f, -1e7f};
    int checked = 0;
    for (float scale : scales)
        for (float off : offsets)
            for (int trial = 0; trial < 40; ++trial) {
                Aabb outer;
                outer.lo = glm::vec3(off);
                outer.hi = glm::vec3(off + scale);
                const int n = 1 + trial % kMaxChildren;
                Aabb boxes[kMaxChildren];
                NodeType types[kMaxChildren];
                Aabb node;
                for (int i = 0; i < n; ++i) {
                    boxes[i] = random_box_inside(g, outer);
                    if (trial % 7 == 0) boxes[i].hi.y = boxes[i].lo.y;  // flat, like a wall
                    types[i] = (i % 2) ? NodeType::Triangle : NodeType::Internal;
                    node.lo = glm::min(node.lo, boxes[i].lo);
                    node.hi = glm::max(node.hi, boxes[i].hi);
                }
                uint8_t bytes[kBlockBytes];
                encode_internal(node, n, types, boxes, 64 * 1000, bytes);
                const InternalNode dec = decode_internal(bytes);
                ASSERT_EQ(dec.count, n);
                uint64_t addr = 64 * 1000;
                for (int i = 0; i < n; ++i) {
                    EXPECT_EQ(dec.type[i], types[i]);
                    EXPECT_EQ(dec.addr[i], addr);
                    addr += node_bytes(types[i]);
                    ASSERT_TRUE(dec.box(i).contains(boxes[i]))
                        << "child " << i << " scale " << scale << " offset " << off;
                    for (int a = 0; a < 3; ++a) {
                        const float extent = node.hi[a] - node.lo[a];
                        // One 1/255 step of the node extent (times 2 for the power-of-two
                        // exponent) plus a few ulps of the coordinates.
                        const float slack = 2.0f * extent / 255.0f + 4.0f * std::fabs(node.lo[a]) * 0x1p-23f + 1e-30f;
                        EXPECT_LE(boxes[i].lo[a] - dec.box(i).lo[a], slack);
                        EXPECT_LE(dec.box(i).hi[a] - boxes[i].hi[a], slack);
                    }
                    ++checked;
                }
            }
    EXPECT_GT(checked, 1000);
}

TEST(NodeFormat, LeavesAndHeaderRoundTripExactly) {
    uint8_t b[2 * kBlockBytes];
    const TriangleLeaf t{{1.5f, -2, 3}, {1e7f, 0.1f, -0.0f}, {-1e-30f, 4, 5}, 7, 12345};
    encode_triangle(t, b);
    const TriangleLeaf t2 = decode_triangle(b);
    EXPECT_EQ(t2.v0, t.v0);
    EXPECT_EQ(t2.v1, t.v1);
    EXPECT_EQ(t2.v2, t.v2);
    EXPECT_EQ(t2.geom, 7u);
    EXPECT_EQ(t2.prim, 12345u);
    EXPECT_TRUE(std::signbit(t2.v1.z));

    encode_sphere({{0, -1000, 0}, 1000, 0, 3}, b);
    const SphereLeaf s = decode_sphere(b);
    EXPECT_EQ(s.center, glm::vec3(0, -1000, 0));
    EXPECT_EQ(s.radius, 1000.0f);
    EXPECT_EQ(s.prim, 3u);

    InstanceLeaf inst;
    inst.object_to_world = {2, 0, 0, 1, 0, 2, 0, 2, 0, 0, 2, 3};
    inst.world_to_object = invert_affine(inst.object_to_world);
    inst.blas_root = 64 * 77;
    inst.instance = 4;
    inst.geom = 9;
    encode_instance(inst, b);
    const InstanceLeaf i2 = decode_instance(b);
    EXPECT_EQ(i2.object_to_world, inst.object_to_world);
    EXPECT_EQ(i2.world_to_object, inst.world_to_object);
    EXPECT_EQ(i2.blas_root, inst.blas_root);
    EXPECT_EQ(i2.geom, 9u);
    // The inverse really inverts: a point goes there and back.
    const glm::vec3 p(0.25f, -3.0f, 8.0f);
    const glm::vec3 q = transform_point(i2.world_to_object, transform_point(i2.object_to_world, p));
    EXPECT_NEAR(q.x, p.x, 1e-6f);
    EXPECT_NEAR(q.y, p.y, 1e-6f);
    EXPECT_NEAR(q.z, p.z, 1e-6f);

    ImageHeader h;
    h.root_box.lo = {-1, -2, -3};
    h.root_box.hi = {4, 5, 6};
    h.root = 128;
    h.has_instances = true;
    h.leaves = 99;
    encode_header(h, b);
    const ImageHeader h2 = decode_header(b);
    EXPECT_EQ(h2.root, 128u);
    EXPECT_TRUE(h2.has_instances);
    EXPECT_FALSE(h2.has_procedural);
    EXPECT_EQ(h2.leaves, 99u);
    EXPECT_EQ(h2.root_box.hi, h.root_box.hi);
    b[0] = 'X';
    EXPECT_THROW(decode_header(b), std::runtime_error);
}

// Bytes from untrusted memory (the SoC peripheral's images): an internal node no encoder makes
// (more than 6 children, a child type past Instance) is refused, not traversed. Found by
// fuzz_image: a child count of 7 made traversal index the 6-entry child arrays past their end.
TEST(NodeFormat, InternalNodesNoEncoderMakesAreRefused) {
    Aabb box;
    box.lo = glm::vec3(0.0f);
    box.hi = glm::vec3(1.0f);
    const Aabb boxes[2] = {box, box};
    const NodeType types[2] = {NodeType::Triangle, NodeType::Instance};
    uint8_t bytes[kBlockBytes];
    encode_internal(box, 2, types, boxes, 64, bytes);
    EXPECT_EQ(decode_internal(bytes).count, 2);
    uint8_t bad[kBlockBytes];
    std::memcpy(bad, bytes, kBlockBytes);
    bad[15] = 7;  // the child count
    EXPECT_THROW(decode_internal(bad), std::runtime_error);
    std::memcpy(bad, bytes, kBlockBytes);
    bad[21] = uint8_t(NodeType::Instance) + 1;  // the second child's type
    EXPECT_THROW(decode_internal(bad), std::runtime_error);
}

TEST(NodeFormat, SingularInstanceTransformIsRejected) {
    EXPECT_THROW(invert_affine({1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0}), std::runtime_error);
}
