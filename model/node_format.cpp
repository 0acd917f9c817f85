#include "node_format.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rtu {
namespace {

static_assert(sizeof(float) == 4 && sizeof(uint32_t) == 4, "image layout assumes 32-bit floats");

template <typename T>
void put(uint8_t* p, const T& v) { std::memcpy(p, &v, sizeof(T)); }
template <typename T>
T get(const uint8_t* p) { T v; std::memcpy(&v, p, sizeof(T)); return v; }

// The next float above x (x finite, not NaN); inline bit arithmetic instead of libm's nextafter,
// since decoding a node does this up to 36 times.
inline float next_up(float x) {
    if (x == 0.0f) return std::numeric_limits<float>::denorm_min();
    uint32_t b;
    std::memcpy(&b, &x, 4);
    b += x > 0.0f ? 1 : -1;
    std::memcpy(&x, &b, 4);
    return x;
}
inline float next_down(float x) { return -next_up(-x); }

// origin + x rounded toward -inf (lo) or +inf (hi). x = q * 2^k is exact; the sum is rounded to
// nearest, and Knuth's TwoSum recovers the rounding error exactly, which tells which way to step.
inline float add_outward(float origin, float x, bool round_up) {
    const float s = origin + x;
    const float bb = s - origin;
    const float err = (origin - (s - bb)) + (x - bb);
    if (round_up && err > 0.0f) return next_up(s);
    if (!round_up && err < 0.0f) return next_down(s);
    return s;
}

constexpr int kMinExp = -100, kMaxExp = 127;

// 2^(exp-8) as a normal float, built from its bits (exp in [kMinExp, kMaxExp]).
inline float quantum(int exp) {
    const uint32_t b = uint32_t(exp - 8 + 127) << 23;
    float f;
    std::memcpy(&f, &b, 4);
    return f;
}

inline float decode_bound(float origin, int exp, uint8_t q, bool hi) {
    return add_outward(origin, float(q) * quantum(exp), hi);
}

// Quantizes one axis of all children with exponent e; false if e is too small.
bool quantize_axis(float origin, int e, int count, const Aabb* boxes, int axis,
                   uint8_t qlo[kMaxChildren], uint8_t qhi[kMaxChildren]) {
    const double scale = std::ldexp(1.0, e - 8);
    for (int i = 0; i < count; ++i) {
        const float lo = boxes[i].lo[axis], hi = boxes[i].hi[axis];
        double fl = std::floor((double(lo) - origin) / scale);
        int ql = int(std::fmax(0.0, std::fmin(255.0, fl)));
        while (ql > 0 && decode_bound(origin, e, uint8_t(ql), false) > lo) --ql;
        if (decode_bound(origin, e, uint8_t(ql), false) > lo) return false;  // below origin
        double ch = std::ceil((double(hi) - origin) / scale);
        int qh = int(std::fmax(0.0, std::fmin(255.0, ch)));
        while (qh < 255 && decode_bound(origin, e, uint8_t(qh), true) < hi) ++qh;
        if (decode_bound(origin, e, uint8_t(qh), true) < hi) return false;
        qlo[i] = uint8_t(ql);
        qhi[i] = uint8_t(qh);
    }
    return true;
}

}  // namespace

uint32_t node_bytes(NodeType t) {
    switch (t) {
        case NodeType::Empty: return 0;
        case NodeType::Instance: return 2 * kBlockBytes;
        default: return kBlockBytes;
    }
}

const char* node_type_name(NodeType t) {
    switch (t) {
        case NodeType::Empty: return "empty";
        case NodeType::Internal: return "internal";
        case NodeType::Triangle: return "triangle";
        case NodeType::Procedural: return "procedural";
        case NodeType::Instance: return "instance";
        case NodeType::Header: return "header";
    }
    return "?";
}

void encode_internal(const Aabb& node_box, int count, const NodeType* types, const Aabb* boxes,
                     uint64_t first_child_addr, uint8_t out[kBlockBytes]) {
    if (count < 1 || count > kMaxChildren) throw std::logic_error("internal node child count");
    if (first_child_addr % kBlockBytes != 0 || first_child_addr / kBlockBytes > 0xFFFFFFFFull)
        throw std::logic_error("child block address out of range");
    std::memset(out, 0, kBlockBytes);
    uint8_t qlo[3][kMaxChildren] = {}, qhi[3][kMaxChildren] = {};
    int8_t exps[3];
    for (int a = 0; a < 3; ++a) {
        const float origin = node_box.lo[a];
        const double extent = double(node_box.hi[a]) - origin;
        int e = kMinExp;
        if (extent > 0.0) {
            int ex;
            std::frexp(extent * 256.0 / 255.0, &ex);  // extent*256/255 < 2^ex
            e = std::max(kMinExp, ex);
        }
        while (!quantize_axis(origin, e, count, boxes, a, qlo[a], qhi[a])) {
            if (++e > kMaxExp) throw std::runtime_error("node box too large to quantize");
        }
        exps[a] = int8_t(e);
        put(out + 4 * a, origin);
    }
    std::memcpy(out + 12, exps, 3);
    out[15] = uint8_t(count);
    put(out + 16, uint32_t(first_child_addr / kBlockBytes));
    for (int i = 0; i < count; ++i) {
        out[20 + i] = uint8_t(types[i]);
        uint8_t* q = out + 26 + 6 * i;
        for (int a = 0; a < 3; ++a) {
            q[a] = qlo[a][i];
            q[3 + a] = qhi[a][i];
        }
    }
}

InternalNode decode_internal(const uint8_t* bytes) {
    InternalNode n;
    float origin[3];
    int8_t exps[3];
    for (int a = 0; a < 3; ++a) origin[a] = get<float>(bytes + 4 * a);
    std::memcpy(exps, bytes + 12, 3);
    n.count = bytes[15];
    // An image from untrusted memory (the SoC peripheral's) may hold anything: a node no encoder
    // makes is refused here, before traversal indexes its children by it.
    if (n.count > kMaxChildren) throw std::runtime_error("internal node with " + std::to_string(n.count) + " children (at most 6)");
    uint64_t addr = uint64_t(get<uint32_t>(bytes + 16)) * kBlockBytes;
    const float scale[3] = {quantum(exps[0]), quantum(exps[1]), quantum(exps[2])};
    for (int i = 0; i < n.count; ++i) {
        n.type[i] = NodeType(bytes[20 + i]);
        if (bytes[20 + i] > uint8_t(NodeType::Instance)) throw std::runtime_error("internal node's child of type " + std::to_string(bytes[20 + i]));
        n.addr[i] = addr;
        addr += node_bytes(n.type[i]);
        const uint8_t* q = bytes + 26 + 6 * i;
        for (int a = 0; a < 3; ++a) {
            n.lo[a][i] = add_outward(origin[a], float(q[a]) * scale[a], false);
            n.hi[a][i] = add_outward(origin[a], float(q[3 + a]) * scale[a], true);
        }
    }
    return n;
}

void encode_triangle(const TriangleLeaf& t, uint8_t out[kBlockBytes]) {
    std::memset(out, 0, kBlockBytes);
    const glm::vec3* v[3] = {&t.v0, &t.v1, &t.v2};
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) put(out + 12 * i + 4 * a, (*v[i])[a]);
    put(out + 36, t.geom);
    put(out + 40, t.prim);
}

TriangleLeaf decode_triangle(const uint8_t* bytes) {
    TriangleLeaf t;
    glm::vec3* v[3] = {&t.v0, &t.v1, &t.v2};
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) (*v[i])[a] = get<float>(bytes + 12 * i + 4 * a);
    t.geom = get<uint32_t>(bytes + 36);
    t.prim = get<uint32_t>(bytes + 40);
    return t;
}

void encode_sphere(const SphereLeaf& s, uint8_t out[kBlockBytes]) {
    std::memset(out, 0, kBlockBytes);
    put(out, uint32_t(1));
    for (int a = 0; a < 3; ++a) put(out + 4 + 4 * a, s.center[a]);
    put(out + 16, s.radius);
    put(out + 20, s.geom);
    put(out + 24, s.prim);
}

SphereLeaf decode_sphere(const uint8_t* bytes) {
    SphereLeaf s;
    for (int a = 0; a < 3; ++a) s.center[a] = get<float>(bytes + 4 + 4 * a);
    s.radius = get<float>(bytes + 16);
    s.geom = get<uint32_t>(bytes + 20);
    s.prim = get<uint32_t>(bytes + 24);
    return s;
}

// Each component is a fused dot product: accumulated in double (exact products of floats) and
// rounded once, as an instance-transform unit with a wide accumulator would. Rounding after
// every operation instead loses up to ~60 ulps when a large translation cancels (LumiBench's
// ship: scale 100, translation (173, -9, -377)).
glm::vec3 transform_point(const Affine& m, const glm::vec3& p) {
    glm::vec3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = float(double(m[4 * i]) * p.x + double(m[4 * i + 1]) * p.y + double(m[4 * i + 2]) * p.z + double(m[4 * i + 3]));
    return r;
}

glm::vec3 transform_vector(const Affine& m, const glm::vec3& v) {
    glm::vec3 r;
    for (int i = 0; i < 3; ++i) r[i] = float(double(m[4 * i]) * v.x + double(m[4 * i + 1]) * v.y + double(m[4 * i + 2]) * v.z);
    return r;
}

Affine invert_affine(const Affine& m) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) a[i][j] = m[4 * i + j];
    const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                       a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (det == 0.0 || !std::isfinite(det)) throw std::runtime_error("singular instance transform");
    double inv[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            inv[i][j] = (a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1]) / det;
        }
    Affine r;
    for (int i = 0; i < 3; ++i) {
        double t = 0.0;
        for (int j = 0; j < 3; ++j) {
            r[4 * i + j] = float(inv[i][j]);
            t -= inv[i][j] * m[4 * j + 3];
        }
        r[4 * i + 3] = float(t);
    }
    return r;
}

Affine identity_affine() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}; }

bool is_identity(const Affine& m) { return m == identity_affine(); }

void encode_instance(const InstanceLeaf& inst, uint8_t out[2 * kBlockBytes]) {
    std::memset(out, 0, 2 * kBlockBytes);
    for (int i = 0; i < 12; ++i) put(out + 4 * i, inst.world_to_object[i]);
    for (int i = 0; i < 12; ++i) put(out + 48 + 4 * i, inst.object_to_world[i]);
    put(out + 96, uint32_t(inst.blas_root / kBlockBytes));
    put(out + 100, inst.instance);
    put(out + 104, inst.geom);
}

InstanceLeaf decode_instance(const uint8_t* bytes) {
    InstanceLeaf inst;
    for (int i = 0; i < 12; ++i) inst.world_to_object[i] = get<float>(bytes + 4 * i);
    for (int i = 0; i < 12; ++i) inst.object_to_world[i] = get<float>(bytes + 48 + 4 * i);
    inst.blas_root = uint64_t(get<uint32_t>(bytes + 96)) * kBlockBytes;
    inst.instance = get<uint32_t>(bytes + 100);
    inst.geom = get<uint32_t>(bytes + 104);
    return inst;
}

void encode_header(const ImageHeader& h, uint8_t out[kBlockBytes]) {
    std::memset(out, 0, kBlockBytes);
    std::memcpy(out, "RTUBVH01", 8);
    for (int a = 0; a < 3; ++a) {
        put(out + 8 + 4 * a, h.root_box.lo[a]);
        put(out + 20 + 4 * a, h.root_box.hi[a]);
    }
    put(out + 32, uint32_t(h.root / kBlockBytes));
    put(out + 36, uint32_t((h.has_instances ? 1u : 0u) | (h.has_procedural ? 2u : 0u) | (h.has_headers ? 4u : 0u)));
    put(out + 40, h.leaves);
}

ImageHeader decode_header(const uint8_t* bytes) {
    if (std::memcmp(bytes, "RTUBVH01", 8) != 0) throw std::runtime_error("not an rtunit BVH image");
    ImageHeader h;
    for (int a = 0; a < 3; ++a) {
        h.root_box.lo[a] = get<float>(bytes + 8 + 4 * a);
        h.root_box.hi[a] = get<float>(bytes + 20 + 4 * a);
    }
    h.root = uint64_t(get<uint32_t>(bytes + 32)) * kBlockBytes;
    const uint32_t flags = get<uint32_t>(bytes + 36);
    h.has_instances = flags & 1u;
    h.has_procedural = flags & 2u;
    h.has_headers = flags & 4u;
    h.leaves = get<uint32_t>(bytes + 40);
    return h;
}

}  // namespace rtu
