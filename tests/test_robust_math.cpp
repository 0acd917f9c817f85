// Hard cases for the robust ray/box, ray/triangle and ray/sphere tests.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/geometric.hpp>

#include "model/robust.h"

using namespace rtu;

namespace {
using glm::vec3;
bool tri(const vec3& o, const vec3& d, const vec3& a, const vec3& b, const vec3& c, float tmin = 0.0f,
         float tmax = INFINITY, TriangleHit* h = nullptr) {
    TriangleHit tmp;
    return intersect_triangle(o, d, a, b, c, tmin, tmax, h ? h : &tmp);
}
bool box(const vec3& o, const vec3& d, const Aabb& b, float tmin = 0.0f, float tmax = INFINITY) {
    return intersect_box(make_box_test_ray(o, d), b, tmin, tmax, nullptr);
}
}  // namespace

// A ray through the shared edge of two triangles hits at least one of them, from either side
// and with an oblique direction, for edge points with short and with full-length mantissas.
TEST(RobustTriangle, SharedEdgeIsHitFromBothSides) {
    const vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0);  // quad split along x = y
    std::mt19937 g(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f), off(-0.3f, 0.3f);
    int rays = 0;
    for (int i = 0; i < 2000; ++i) {
        const float p = i < 64 ? float(i) / 64.0f : u(g);
        for (float side : {-1.0f, 1.0f}) {
            const float s = i % 2 ? off(g) : 0.0f;   // oblique: passes through (p', p', 0) exactly
            const float x = p + s;                    // rounded; the ray is x - s*t, exactly on x = y at t = 1
            const vec3 o(x, x, side), dir(-s, -s, -side);
            const bool h1 = tri(o, dir, a, b, c), h2 = tri(o, dir, a, c, d);
            EXPECT_TRUE(h1 || h2) << "edge point " << p << " side " << side << " slope " << s;
            ++rays;
        }
    }
    EXPECT_EQ(rays, 4000);
}

// Rays aimed at points of an edge shared by two triangles of random shape and orientation: at
// least one triangle is hit, and almost never both. In float the edge value is exactly zero for
// ~3 % of such rays, which would count them twice; the double re-evaluation of the edge (Woop's
// fallback) decides its sign for all but the rays exactly through the edge.
TEST(RobustTriangle, SharedEdgeHitOnceWithDoubleFallback) {
    std::mt19937 g(17);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int both = 0, none = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        const vec3 a(u(g), u(g), u(g)), b(u(g), u(g), u(g)), c(u(g), u(g), u(g));
        const vec3 m = 0.5f * (a + b);
        const vec3 c2 = m + (m - c);  // on the other side of edge ab
        const vec3 o(u(g) * 4, u(g) * 4, u(g) * 4);
        // Edge points away from the vertices with full mantissas: after rounding the ray
        // passes beside the edge, not through it, so one triangle is right and one is wrong.
        const float s = 0.05f + 0.9f * (0.5f + 0.5f * u(g));
        const vec3 d = (a + s * (b - a)) - o;
        const bool h1 = tri(o, d, a, b, c), h2 = tri(o, d, b, a, c2);
        both += h1 && h2;
        none += !h1 && !h2;
    }
    EXPECT_EQ(none, 0);
    EXPECT_LT(both, n / 1000) << "rays counted by both triangles of a shared edge";
}

// A ray exactly through a vertex shared by a closed fan of triangles hits at least one of them.
TEST(RobustTriangle, SharedVertexOfAFanIsHit) {
    std::mt19937 g(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int trial = 0; trial < 500; ++trial) {
        const vec3 centre(u(g) * 8, u(g) * 8, u(g) * 8);
        // Fan of 7 triangles around `centre`, in a tilted plane.
        const vec3 e1 = glm::normalize(vec3(1.0f, u(g) * 0.5f, u(g) * 0.5f));
        const vec3 e2 = glm::normalize(glm::cross(vec3(u(g) * 0.3f, 1.0f, u(g) * 0.3f), e1));
        const int n = 7;
        vec3 ring[n];
        for (int k = 0; k < n; ++k) {
            const float ang = 2.0f * float(M_PI) * k / n;
            ring[k] = centre + std::cos(ang) * e1 + std::sin(ang) * e2;
        }
        for (float side : {-1.0f, 1.0f}) {
            // Origin chosen so that o + 1 * (centre - o) = centre: the direction is exact
            // whenever (centre - o) is, which it is for an origin at the scaled origin 0.
            const vec3 o(0.0f), dir = centre * side;
            const vec3 org = side > 0 ? o : 2.0f * centre;  // from the far side: centre - (-centre)
            int hits = 0;
            for (int k = 0; k < n; ++k) hits += tri(org, dir, centre, ring[k], ring[(k + 1) % n], 0.0f, INFINITY);
            EXPECT_GE(hits, 1) << "trial " << trial << " side " << side;
        }
    }
}

TEST(RobustTriangle, DegenerateTrianglesAreNeverHit) {
    const vec3 o(1, 1, -1), d(0, 0, 1);
    EXPECT_FALSE(tri(o, d, {0, 0, 0}, {1, 1, 0}, {2, 2, 0}));   // collinear, ray through its middle
    EXPECT_FALSE(tri(o, d, {1, 1, 0}, {1, 1, 0}, {1, 1, 0}));   // a point, ray through it
    EXPECT_FALSE(tri({0.5f, 0.5f, -1}, d, {0, 0, 0}, {1, 1, 0}, {2, 2, 0}));
    EXPECT_FALSE(tri(o, d, {0, 0, 0}, {0, 0, 0}, {2, 2, 0}));   // two equal vertices
}

TEST(RobustTriangle, RayInThePlaneIsNeverHitAndGrazingRaysAreExact) {
    const vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    EXPECT_FALSE(tri({-1, 0.25f, 0}, {1, 0, 0}, a, b, c));
    EXPECT_FALSE(tri({0.1f, 0.1f, 0}, {1, 1, 0}, a, b, c));  // starts inside, in the plane
    // Grazing: 1e-6 rad above the plane, meeting it at (0.5, 0.25, 0) at t = 1.
    TriangleHit h;
    ASSERT_TRUE(tri({-0.5f, 0.25f, 1e-6f}, {1, 0, -1e-6f}, a, b, c, 0, INFINITY, &h));
    EXPECT_NEAR(h.t, 1.0f, 4 * 0x1p-24f);
    // Embree-free check of the barycentrics: (0.5, 0.25) = 0.25 a + 0.5 b + 0.25 c.
    EXPECT_NEAR(h.u, 0.5f, 1e-6f);
    EXPECT_NEAR(h.v, 0.25f, 1e-6f);
}

TEST(RobustTriangle, TnearAndTfarAreInclusive) {
    const vec3 a(-5, -5, 2), b(5, -5, 2), c(0, 5, 2), o(0.125f, 0.125f, 0), d(0, 0, 1);
    const float two = 2.0f;
    EXPECT_TRUE(tri(o, d, a, b, c, 0.0f, two));
    EXPECT_FALSE(tri(o, d, a, b, c, 0.0f, std::nextafter(two, 0.0f)));
    EXPECT_TRUE(tri(o, d, a, b, c, two, INFINITY));
    EXPECT_FALSE(tri(o, d, a, b, c, std::nextafter(two, 3.0f), INFINITY));
    // A hit behind the origin is not a hit.
    EXPECT_FALSE(tri(o, -d, a, b, c));
}

// Far from the origin (1e5..1e7) a triangle a few dozen ulps wide is still hit at its centre,
// missed beside it, and t is right to float precision.
TEST(RobustTriangle, HugeOffsetsAndTinyTriangles) {
    for (float offset : {1e5f, 1e6f, 1e7f, -1e7f}) {
        const float ulp = std::nextafter(std::fabs(offset), INFINITY) - std::fabs(offset);
        const float s = 64 * ulp;
        const vec3 a(offset, offset, offset), b(offset + s, offset, offset), c(offset, offset + s, offset);
        const vec3 o(offset + s / 4, offset + s / 4, offset - 100.0f * ulp);
        TriangleHit h;
        ASSERT_TRUE(tri(o, {0, 0, 1}, a, b, c, 0, INFINITY, &h)) << offset;
        EXPECT_NEAR(h.t, 100.0f * ulp, 1e-3f * 100.0f * ulp);
        EXPECT_FALSE(tri({offset - s / 4, offset + s / 4, o.z}, {0, 0, 1}, a, b, c)) << offset;
        // Oblique ray from far away aimed at the centroid.
        const vec3 centroid(offset + s / 3, offset + s / 3, offset);
        const vec3 from = centroid + vec3(-1000.0f, 500.0f, -2000.0f);
        EXPECT_TRUE(tri(from, centroid - from, a, b, c)) << offset;
    }
    // A tiny triangle (1e-6 wide) at the origin seen from 1e3 away.
    const float s = 1e-6f;
    EXPECT_TRUE(tri({s / 4, s / 4, -1e3f}, {0, 0, 1}, {0, 0, 0}, {s, 0, 0}, {0, s, 0}));
    EXPECT_FALSE(tri({s, s, -1e3f}, {0, 0, 1}, {0, 0, 0}, {s, 0, 0}, {0, s, 0}));
}

// A ray lying in a face plane of a box (zero direction component, +0 or -0) hits the box: boxes
// are closed. Just outside the plane it misses.
TEST(RobustBox, ZeroDirectionComponentsInFacePlanes) {
    Aabb b;
    b.lo = {0, 0, 0};
    b.hi = {1, 1, 1};
    for (float zero : {0.0f, -0.0f}) {
        EXPECT_TRUE(box({0.5f, 1.0f, -1}, {0, zero, 1}, b)) << "upper face, signbit " << std::signbit(zero);
        EXPECT_TRUE(box({0.5f, 0.0f, -1}, {0, zero, 1}, b)) << "lower face";
        EXPECT_TRUE(box({1.0f, 1.0f, -1}, {zero, zero, 1}, b)) << "edge line";
        EXPECT_FALSE(box({0.5f, std::nextafter(1.0f, 2.0f), -1}, {0, zero, 1}, b));
        EXPECT_FALSE(box({0.5f, std::nextafter(0.0f, -1.0f), -1}, {0, zero, 1}, b));
        EXPECT_TRUE(box({0.5f, 0.5f, 0.5f}, {zero, zero, 1}, b)) << "inside";
        EXPECT_TRUE(box({1.0f, 0.5f, 2}, {zero, 0, -1}, b)) << "x = hi plane, going -z";
    }
}

// The slab test never loses a box that a long-double slab test says the ray touches: rays aimed
// at box corners and edges from random origins, at scales up to 1e6.
TEST(RobustBox, NeverMissesABoxTheRayTouches) {
    std::mt19937 g(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int touching = 0;
    for (int i = 0; i < 20000; ++i) {
        const float scale = std::pow(10.0f, float(i % 7));
        Aabb b;
        for (int a = 0; a < 3; ++a) {
            const float x = u(g) * scale, y = u(g) * scale;
            b.lo[a] = std::min(x, y);
            b.hi[a] = std::max(x, y);
        }
        const vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
        const vec3 o(u(g) * 3 * scale, u(g) * 3 * scale, u(g) * 3 * scale);
        const vec3 d = corner - o;
        // Long-double slab test on the same float ray and box.
        long double t0 = 0, t1 = INFINITY;
        for (int a = 0; a < 3; ++a) {
            if (d[a] == 0) {
                if (o[a] < b.lo[a] || o[a] > b.hi[a]) t0 = 1, t1 = 0;
                continue;
            }
            long double ta = ((long double)b.lo[a] - o[a]) / d[a], tb = ((long double)b.hi[a] - o[a]) / d[a];
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        if (t0 <= t1) {
            ++touching;
            EXPECT_TRUE(box(o, d, b)) << "box " << i;
        }
    }
    EXPECT_GT(touching, 2000);
}

TEST(RobustSphere, LargeSphereMatchesLongDouble) {
    std::mt19937 g(13);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const vec3 c(0, -1000, 0);
    const float r = 1000;
    int hits = 0;
    for (int i = 0; i < 5000; ++i) {
        const vec3 o(u(g) * 20, 0.5f + u(g) * 0.5f, u(g) * 20);
        const vec3 d(u(g), -std::fabs(u(g)) * 0.2f, u(g));  // down to grazing
        float t;
        const bool h = intersect_sphere(o, d, c, r, 0.0f, INFINITY, &t);
        using LD = long double;
        const LD f[3] = {LD(o.x) - c.x, LD(o.y) - c.y, LD(o.z) - c.z};
        const LD a = LD(d.x) * d.x + LD(d.y) * d.y + LD(d.z) * d.z;
        const LD b = f[0] * d.x + f[1] * d.y + f[2] * d.z;
        const LD cc = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - LD(r) * r;
        const LD disc = b * b - a * cc;
        if (disc < 0) {
            EXPECT_FALSE(h && disc < -1e-6L * b * b) << i;
            continue;
        }
        const LD t0 = (-b - std::sqrt(disc)) / a;
        if (t0 < 0) continue;
        ASSERT_TRUE(h) << i;
        EXPECT_LE(std::fabs(t - t0), 1e-6L * t0 + 1e-30L) << i;
        ++hits;
    }
    EXPECT_GT(hits, 1000);
}

TEST(RobustRay, InvalidRaysAreRecognised) {
    Ray r;
    r.org = {0, 0, 0};
    r.dir = {0, 0, 1};
    EXPECT_TRUE(is_valid_ray(r));
    Ray bad = r;
    bad.org.x = NAN;
    EXPECT_FALSE(is_valid_ray(bad));
    bad = r;
    bad.dir.y = INFINITY;
    EXPECT_FALSE(is_valid_ray(bad));
    bad = r;
    bad.dir = {0, -0.0f, 0};
    EXPECT_FALSE(is_valid_ray(bad));
    bad = r;
    bad.tnear = -1e-30f;
    EXPECT_FALSE(is_valid_ray(bad));
    bad = r;
    bad.tnear = 2;
    bad.tfar = 1;
    EXPECT_FALSE(is_valid_ray(bad));
    bad = r;
    bad.tfar = NAN;
    EXPECT_FALSE(is_valid_ray(bad));
    Ray ok = r;
    ok.tnear = ok.tfar = 5;  // empty-length interval is valid
    EXPECT_TRUE(is_valid_ray(ok));
}

TEST(RobustRay, DirectionScalingIsAnExactChangeOfUnits) {
    for (float m : {1e-20f, 3e-5f, 1.0f, 7e12f, 1e30f}) {
        Ray r;
        r.dir = {m, -0.5f * m, 0.25f * m};
        r.tnear = 0.5f / m;
        r.tfar = 4.0f / m;
        Ray s = r;
        const int k = scale_direction(s);
        const float mx = std::max({std::fabs(s.dir.x), std::fabs(s.dir.y), std::fabs(s.dir.z)});
        EXPECT_GE(mx, 1.0f);
        EXPECT_LT(mx, 2.0f);
        EXPECT_EQ(std::ldexp(s.dir.x, k), r.dir.x);
        EXPECT_EQ(std::ldexp(s.tfar, -k), r.tfar);
        EXPECT_EQ(std::ldexp(s.tnear, -k), r.tnear);
    }
}

TEST(RobustRay, SpawnOffsetLeavesTheSurfaceOnTheNormalSide) {
    for (float x : {0.0f, 1e-3f, 0.5f, 555.0f, -1e6f}) {
        const vec3 p(x, x, x), n = glm::normalize(vec3(1, 2, 3));
        const vec3 q = offset_ray_origin(p, n);
        EXPECT_GT(glm::dot(q - p, n), 0.0f) << x;
        const vec3 q2 = offset_ray_origin(p, -n);
        EXPECT_LT(glm::dot(q2 - p, n), 0.0f) << x;
    }
}
