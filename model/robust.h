// Robust ray/box, ray/triangle and ray/sphere tests.
//
// Floating-point reasoning follows pbrt-v4 (Pharr, Jakob, Humphreys, "Physically Based
// Rendering", 4th ed., ch. 6.8): every basic float operation rounds to nearest, so a result
// carries a relative error of at most u = 2^-24 per operation, and n chained operations are
// bounded by gamma(n) = n u / (1 - n u).
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "ray.h"

namespace rtu {

constexpr float kMachineEpsilon = std::numeric_limits<float>::epsilon() * 0.5f;  // 2^-24
constexpr float gamma_f(int n) { return (n * kMachineEpsilon) / (1 - n * kMachineEpsilon); }

// NaN-safe min/max: if b is NaN the result is a. The slab test relies on this to ignore an
// axis where (bound - origin) * (1/dir) is 0 * inf = NaN (ray lying in a face plane).
inline float safe_min(float a, float b) { return b < a ? b : a; }
inline float safe_max(float a, float b) { return b > a ? b : a; }

// A ray prepared for repeated box tests: reciprocal direction and per-axis sign bits.
struct BoxTestRay {
    glm::vec3 org;
    glm::vec3 inv_dir;
    int neg[3];  // sign bit of the direction component (so -0 counts as negative)
};
BoxTestRay make_box_test_ray(const glm::vec3& org, const glm::vec3& dir);

struct Aabb {
    glm::vec3 lo{std::numeric_limits<float>::infinity()};
    glm::vec3 hi{-std::numeric_limits<float>::infinity()};
    bool contains(const Aabb& o) const {
        return lo.x <= o.lo.x && lo.y <= o.lo.y && lo.z <= o.lo.z && hi.x >= o.hi.x &&
               hi.y >= o.hi.y && hi.z >= o.hi.z;
    }
};

// The far distances' widening of the slab test below, shared with the test of four children at
// a time (child_hits, traversal.h), which must decide as intersect_box does.
constexpr float kBoxFarScale = 1.0f + 2.0f * gamma_f(3);

// Conservative slab test (pbrt-v4 Bounds3::IntersectP): near/far planes are chosen by the sign
// bit of the direction, min/max are NaN-safe, and the far distance is scaled by 1 + 2 gamma(3)
// so that rounding in (bound - org) * inv_dir never loses a box the ray really touches.
// A box is closed: a ray lying in a face plane hits it. Returns true and the entry distance
// when the ray overlaps the box within [tmin, tmax].
// Inline: traversal runs it for every child of every internal node it visits.
inline bool intersect_box(const BoxTestRay& r, const Aabb& b, float tmin, float tmax, float* t_entry) {
    const glm::vec3* bounds[2] = {&b.lo, &b.hi};
    float t0 = tmin;
    // The far end of the interval is widened the same way as each slab's far distance, so a
    // box whose entry equals tmax (e.g. the closest hit so far) is not lost to rounding.
    float t1 = tmax * kBoxFarScale;
    for (int a = 0; a < 3; ++a) {
        float tn = ((*bounds[r.neg[a]])[a] - r.org[a]) * r.inv_dir[a];
        float tf = ((*bounds[1 - r.neg[a]])[a] - r.org[a]) * r.inv_dir[a];
        tf *= kBoxFarScale;
        t0 = safe_max(t0, tn);
        t1 = safe_min(t1, tf);
        if (t0 > t1) return false;
    }
    if (t_entry) *t_entry = t0;
    return true;
}

// Watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013). Edge functions are evaluated
// in float and re-evaluated in double when one is exactly zero, so that a ray through a shared
// edge or vertex is decided consistently for the triangles that share it. Both faces count.
// A degenerate (zero-area) triangle, or a ray in the triangle's plane, is never hit.
struct TriangleHit {
    float t, u, v;  // u, v: barycentric weights of v1 and v2
};
bool intersect_triangle(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& v0,
                        const glm::vec3& v1, const glm::vec3& v2, float tmin, float tmax,
                        TriangleHit* out);

// Robust ray/sphere test, evaluated in double with the discriminant written as
// r^2 - |f - (f.d / d.d) d|^2 (Haines et al., "Precision Improvements for Ray/Sphere
// Intersection", Ray Tracing Gems ch. 7), which stays accurate for large spheres and far
// origins. Returns the nearest root in [tmin, tmax] (the exit root if the entry is before tmin).
bool intersect_sphere(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center,
                      float radius, float tmin, float tmax, float* t_hit);

// Secondary-ray origin offset of Wachter and Binder ("A Fast and Robust Method for Avoiding
// Self-Intersection", Ray Tracing Gems ch. 6): moves p along the geometric normal n by a few
// float ulps (integer steps for large coordinates, a fixed step near the origin).
glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& n);

}  // namespace rtu

namespace rtu {
// Scales the direction by a power of two 2^-k so that its largest component lies in [1, 2),
// and tnear/tfar by 2^k: an exact change of units that keeps tiny (1e-20) and huge (1e30)
// directions inside float range in every test. Returns k; a distance t' found for the scaled
// ray is t = ldexp(t', -k) for the original one.
int scale_direction(Ray& r);
}  // namespace rtu
