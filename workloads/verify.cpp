#include "verify.h"

#include "model/traversal.h"

#include <cmath>
#include <algorithm>
#include <cstring>
#include <limits>

namespace rtu {

const char* agreement_name(Agreement a) {
    switch (a) {
        case Agreement::Agree: return "agree";
        case Agreement::TUlps: return "t_within_ulps";
        case Agreement::SameTOtherPrim: return "other_prim_same_t";
        case Agreement::Coincident: return "coincident_duplicate";
        case Agreement::BoundaryT: return "hit_at_tnear_tfar";
        case Agreement::VertexEmbreeMiss: return "vertex_hit_embree_misses";
        case Agreement::ZeroDirFace: return "zero_dir_in_face_plane";
        case Agreement::SphereFloatError: return "embree_sphere_float_error";
        case Agreement::TErrorBound: return "t_within_error_bound";
        case Agreement::EdgeFloatError: return "edge_within_float_error";
        case Agreement::SimulatorOrder: return "simulator_float_order";
        case Agreement::SimulatorOverflow: return "simulator_float_overflow";
        case Agreement::Mismatch: return "mismatch";
        case Agreement::Count: break;
    }
    return "?";
}

uint32_t ulp_distance(float a, float b) {
    if (a == b) return 0;
    if (std::isnan(a) || std::isnan(b) || std::signbit(a) != std::signbit(b)) return std::numeric_limits<uint32_t>::max();
    int32_t ia, ib;
    std::memcpy(&ia, &a, 4);
    std::memcpy(&ib, &b, 4);
    const int64_t d = int64_t(ia) - int64_t(ib);
    return uint32_t(d < 0 ? -d : d);
}

namespace {
bool same_point(const Ray& r, long double t1, long double t2, int ulps);
bool near_bound(const Ray& r, float t) {
    return ulp_distance(t, r.tnear) <= kUlpTolerance || (std::isfinite(r.tfar) && ulp_distance(t, r.tfar) <= kUlpTolerance);
}
// The hit lies at the ray's start within the float error of the coordinates (kLooseUlpTolerance
// ulps of them): whether it is beyond tnear is a matter of each test's rounding. Rays that start
// on the surface they leave (LumiBench's: o + t d, tnear 0.001, TraceAO.rgen's 0.01 offset) meet
// their own surface there; the simulator's float t (Hit::app_t), which rtunit's traversal
// follows, may put it on either side of tnear.
bool near_start(const Ray& r, float t) { return same_point(r, t, r.tnear, kLooseUlpTolerance);
}
float max_abs(const glm::vec3& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

// Two distances name the same point when they are within kUlpTolerance ulps of each other, or
// when the points o + t d differ by at most kUlpTolerance ulps of the coordinates involved:
// float hit distances are only as exact as (vertex - origin), whose error scales with the
// coordinates, not with t (a short hit near a wall at x = 555 carries 555's ulps).
bool same_point(const Ray& r, long double t1, long double t2, int ulps) {
    if (ulp_distance(float(t1), float(t2)) <= uint32_t(ulps)) return true;
    const float scale = std::max(max_abs(r.org), max_abs(r.org + float(t1) * r.dir));
    return std::fabs(t1 - t2) * max_abs(r.dir) <= ulps * 0x1p-24L * scale;
}

// Two triangles with the same three vertex positions (duplicated faces: 909 of the ship's 6,255),
// in one mesh or in two meshes placed by the same transform (PARTY repeats faces across files).
bool coincident(const Scene& scene, const Hit& a, const Hit& b) {
    const Mesh &ma = scene.meshes.at(a.geom), &mb = scene.meshes.at(b.geom);
    if (ma.procedural() || mb.procedural()) return false;
    if (a.geom != b.geom && scene.instance_of(a.geom).object_to_world != scene.instance_of(b.geom).object_to_world) return false;
    auto corners = [](const Mesh& m, uint32_t prim) {
        std::array<std::array<float, 3>, 3> c;
        for (int k = 0; k < 3; ++k) {
            const glm::vec3& v = m.vertices[m.triangles.at(prim)[k]];
            c[k] = {v.x, v.y, v.z};
        }
        std::sort(c.begin(), c.end());
        return c;
    };
    return corners(ma, a.prim) == corners(mb, b.prim);
}

bool instanced(const Scene& scene, const Hit& h) {
    return h.hit && !is_identity(scene.instance_of(h.geom).object_to_world);
}

bool has_zero_dir(const Ray& r) { return r.dir.x == 0.0f || r.dir.y == 0.0f || r.dir.z == 0.0f; }
bool at_vertex(const Hit& h) {
    const float w = 1.0f - h.u - h.v;
    const float eps = 1e-6f;
    return (std::fabs(h.u) < eps) + (std::fabs(h.v) < eps) + (std::fabs(w) < eps) >= 2;
}

bool is_sphere(const Scene& scene, const Hit& h) { return h.hit && scene.meshes.at(h.geom).procedural(); }

// The ray starts on the plane of the triangle it hits, within kUlpTolerance ulps of the
// coordinates there: a ray leaving a surface almost along it (an AO ray of the ship, under
// 1e-4 rad off the plane) meets the plane at a t far beyond tnear, yet whether it meets it at
// all past tnear is each test's rounding (that hit at t = 0.16 moves by 0.002 when the origin is
// rounded to 9 digits).
bool starts_on_plane(const Scene& scene, const Ray& r, const Hit& h) {
    if (!h.hit || scene.meshes.at(h.geom).procedural()) return false;
    long double cosine = 1;
    const auto t = exact_triangle_t(scene, r, h.geom, h.prim, &cosine);
    if (!t) return false;
    const long double length = std::sqrt((long double)r.dir.x * r.dir.x + (long double)r.dir.y * r.dir.y + (long double)r.dir.z * r.dir.z);
    const long double off_plane = std::fabs(*t - r.tnear) * length * cosine;  // the start's distance from the plane
    const float scale = std::max(max_abs(r.org + r.tnear * r.dir), max_abs(r.org + h.t * r.dir));
    return off_plane <= kUlpTolerance * 0x1p-24L * scale;
}

// The triangle of hit `h` as the traversal's leaf, for the simulator's float t in object space:
// only for meshes placed as they are, where object space is the world's (false otherwise).
bool identity_placed_triangle(const Scene& scene, const Hit& h, TriangleLeaf* leaf) {
    const Mesh& m = scene.meshes.at(h.geom);
    if (m.procedural() || !is_identity(scene.instance_of(h.geom).object_to_world)) return false;
    const glm::uvec3& tri = m.triangles.at(h.prim);
    *leaf = TriangleLeaf{m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]], h.geom, h.prim};
    return true;
}

// Embree's hit `h` is one the TTP authors' simulator cannot take: its float Moller-Trumbore t
// (moller_trumbore_t) is not a number, and the same arithmetic in double has a product beyond
// the float range (the numerator of t, or the cross product before it). Identity-placed meshes
// only (the simulator's t is in object space).
bool simulator_t_overflows(const Scene& scene, const Ray& r, const Hit& h) {
    TriangleLeaf leaf;
    if (!h.hit || !identity_placed_triangle(scene, h, &leaf)) return false;
    const glm::vec3 &v0 = leaf.v0, &v1 = leaf.v1, &v2 = leaf.v2;
    float ft;
    if (moller_trumbore_t(r.org, r.dir, leaf, &ft)) return false;
    const double e1[3] = {double(v1.x) - v0.x, double(v1.y) - v0.y, double(v1.z) - v0.z};
    const double e2[3] = {double(v2.x) - v0.x, double(v2.y) - v0.y, double(v2.z) - v0.z};
    const double s[3] = {double(r.org.x) - v0.x, double(r.org.y) - v0.y, double(r.org.z) - v0.z};
    const double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    const double num = e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2];
    constexpr double kFloatMax = 3.4028234663852886e38;
    return std::fabs(num) > kFloatMax || std::fabs(q[0]) > kFloatMax || std::fabs(q[1]) > kFloatMax || std::fabs(q[2]) > kFloatMax;
}

// One side hits (`h`), the other misses.
Agreement one_sided(const Scene& scene, const Ray& r, const Hit& h, bool ours_hit) {
    if (!ours_hit && simulator_t_overflows(scene, r, h)) return Agreement::SimulatorOverflow;
    if (near_bound(r, h.t) || near_start(r, h.t) || starts_on_plane(scene, r, h)) return Agreement::BoundaryT;
    if (has_zero_dir(r)) return Agreement::ZeroDirFace;
    if (ours_hit && !is_sphere(scene, h) && at_vertex(h)) return Agreement::VertexEmbreeMiss;
    return Agreement::Mismatch;
}

// For a disagreement involving a sphere: true when a long-double solve agrees with our answer
// (our t to 1e-6 relative, and Embree's primitive no nearer than ours / not hit at all).
bool long_double_confirms_ours(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& ref) {
    if (!is_sphere(scene, ours) && !is_sphere(scene, ref)) return false;
    std::optional<long double> eo;
    if (ours.hit) {
        if (!is_sphere(scene, ours)) return false;
        eo = exact_sphere_t(scene, ray, ours.geom, ours.prim);
        if (!eo || std::fabs(*eo - ours.t) > 1e-6L * std::fabs(*eo)) return false;
    }
    if (ref.hit) {
        if (!is_sphere(scene, ref)) return false;
        const auto er = exact_sphere_t(scene, ray, ref.geom, ref.prim);
        if (er && (!eo || *er < *eo)) return false;
    }
    return true;
}
}  // namespace

std::optional<long double> exact_sphere_t(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim) {
    const Mesh& m = scene.meshes.at(geom);
    if (!m.procedural() || !is_identity(scene.instance_of(geom).object_to_world)) return std::nullopt;
    const Sphere& s = m.spheres.at(prim);
    using LD = long double;
    const LD f[3] = {LD(ray.org.x) - s.center.x, LD(ray.org.y) - s.center.y, LD(ray.org.z) - s.center.z};
    const LD d[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
    const LD a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const LD b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
    const LD c = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - LD(s.radius) * s.radius;
    const LD disc = b * b - a * c;
    if (disc < 0) return std::nullopt;
    const LD q = -(b + std::copysign(std::sqrt(disc), b));
    LD t0 = q / a, t1 = q != 0 ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    for (LD t : {t0, t1})
        if (t >= ray.tnear && t <= ray.tfar) return t;
    return std::nullopt;
}

std::optional<long double> exact_triangle_t(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim,
                                            long double* cosine) {
    using LD = long double;
    const Mesh& m = scene.meshes.at(geom);
    if (m.procedural()) return std::nullopt;
    const Affine& x = scene.instance_of(geom).object_to_world;
    const glm::uvec3& tri = m.triangles.at(prim);
    LD v[3][3];
    for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = m.vertices[tri[k]];
        for (int i = 0; i < 3; ++i) v[k][i] = LD(x[4 * i]) * p.x + LD(x[4 * i + 1]) * p.y + LD(x[4 * i + 2]) * p.z + LD(x[4 * i + 3]);
    }
    const LD e1[3] = {v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
    const LD e2[3] = {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
    const LD n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const LD dn = n[0] * ray.dir.x + n[1] * ray.dir.y + n[2] * ray.dir.z;
    if (dn == 0) return std::nullopt;
    const LD t = (n[0] * (v[0][0] - ray.org.x) + n[1] * (v[0][1] - ray.org.y) + n[2] * (v[0][2] - ray.org.z)) / dn;
    if (cosine) {
        const LD nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const LD dd = std::sqrt(LD(ray.dir.x) * ray.dir.x + LD(ray.dir.y) * ray.dir.y + LD(ray.dir.z) * ray.dir.z);
        *cosine = std::fabs(dn) / (nn * dd);
    }
    return t;  // plane distance (inside-ness is not checked)
}

// The traversal computes the float t in object space; for identity-placed meshes that is the
// world's, so only those are compared.
bool simulator_float_order(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& other) {
    auto float_t = [&](const Hit& h, float* t) {
        TriangleLeaf leaf;
        return identity_placed_triangle(scene, h, &leaf) && moller_trumbore_t(ray.org, ray.dir, leaf, t);
    };
    float fo, fr;
    if (!float_t(ours, &fo) || !float_t(other, &fr) || !(fo <= fr)) return false;
    const auto eo = exact_triangle_t(scene, ray, ours.geom, ours.prim), er = exact_triangle_t(scene, ray, other.geom, other.prim);
    if (!eo || !er) return false;
    return std::fabs(*eo - *er) <= std::fabs(fo - *eo) + std::fabs(fr - *er);
}

bool edge_decision_within_float_error(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim) {
    using LD = long double;
    const Mesh& m = scene.meshes.at(geom);
    if (m.procedural() || !is_identity(scene.instance_of(geom).object_to_world)) return false;
    // The traversal rescales the direction by a power of two, which changes no decision below.
    const glm::vec3 d = ray.dir, o = ray.org;
    const glm::vec3 ad(std::fabs(d.x), std::fabs(d.y), std::fabs(d.z));
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0f) std::swap(kx, ky);
    const LD sx = LD(d[kx]) / d[kz], sy = LD(d[ky]) / d[kz];
    // Exact sheared coordinates and, per coordinate, the float computation's error bound:
    // a = v - o (one rounding), s = d[kx] / d[kz] (one), s * a[kz] (one), the difference (one):
    // |error| <= gamma(4) (|a[kx]| + |s a[kz]|), gamma(n) = n u / (1 - n u), u = 2^-24.
    const LD u = 0x1p-24L, g2 = 2 * u / (1 - 2 * u), g4 = 4 * u / (1 - 4 * u);
    LD x[3], y[3], ex[3], ey[3];
    for (int k = 0; k < 3; ++k) {
        const glm::vec3& v = m.vertices[m.triangles.at(prim)[k]];
        const LD a[3] = {LD(v.x) - o.x, LD(v.y) - o.y, LD(v.z) - o.z};
        x[k] = a[kx] - sx * a[kz];
        y[k] = a[ky] - sy * a[kz];
        ex[k] = g4 * (std::fabs(a[kx]) + std::fabs(sx * a[kz]));
        ey[k] = g4 * (std::fabs(a[ky]) + std::fabs(sy * a[kz]));
    }
    // Edge functions as intersect_triangle forms them (u from c and b, v from a and c, w from b
    // and a), and the bound of their float evaluation: the products' and difference's rounding,
    // gamma(2) (|p q| + |r s|), plus the inputs' errors to first order, doubled for the
    // second-order terms this leaves out.
    const int edges[3][2] = {{2, 1}, {0, 2}, {1, 0}};
    LD e[3], bound[3];
    for (int i = 0; i < 3; ++i) {
        const int p = edges[i][0], q = edges[i][1];
        e[i] = x[p] * y[q] - y[p] * x[q];
        bound[i] = 2 * (g2 * (std::fabs(x[p] * y[q]) + std::fabs(y[p] * x[q])) + std::fabs(y[q]) * ex[p] + std::fabs(x[p]) * ey[q] +
                        std::fabs(x[q]) * ey[p] + std::fabs(y[p]) * ex[q]);
    }
    // Decided either way: after flipping the edges within their bound, both an inside and an
    // outside verdict are reachable.
    bool can_inside_pos = true, can_inside_neg = true, can_outside = false;
    for (int i = 0; i < 3; ++i) {
        const bool uncertain = std::fabs(e[i]) <= bound[i];
        can_inside_pos &= e[i] >= 0 || uncertain;
        can_inside_neg &= e[i] <= 0 || uncertain;
    }
    bool pos = false, neg = false;
    for (int i = 0; i < 3; ++i) {
        pos |= e[i] > 0 || std::fabs(e[i]) <= bound[i];
        neg |= e[i] < 0 || std::fabs(e[i]) <= bound[i];
    }
    can_outside = pos && neg;
    return (can_inside_pos || can_inside_neg) && can_outside;
}

Agreement classify(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& ref, const Hit& ref_closest) {
    Agreement a;
    const Hit& other = ray.query == Query::Any ? ref_closest : ref;
    if (ray.query == Query::Any) {
        if (ours.hit == ref.hit) return Agreement::Agree;
        a = ours.hit ? one_sided(scene, ray, ours, true) : one_sided(scene, ray, ref_closest, false);
    } else if (!ours.hit && !ref.hit) {
        return Agreement::Agree;
    } else if (ours.hit != ref.hit) {
        a = ours.hit ? one_sided(scene, ray, ours, true) : one_sided(scene, ray, ref, false);
    } else {
        const bool inst = instanced(scene, ours) || instanced(scene, ref);
        const bool same = same_point(ray, ours.t, ref.t, inst ? kLooseUlpTolerance : kUlpTolerance);
        if (ours.geom == ref.geom && ours.prim == ref.prim) {
            if (ours.t == ref.t) return Agreement::Agree;
            a = Agreement::Mismatch;
            if (same_point(ray, ours.t, ref.t, kUlpTolerance)) {
                a = Agreement::TUlps;
            } else if (!scene.meshes.at(ours.geom).procedural()) {
                // Both answers must lie near the long-double hit on the placed triangle.
                // A position error e along the normal moves t by e / cos(incidence).
                long double cosine = 1;
                const auto exact = exact_triangle_t(scene, ray, ours.geom, ours.prim, &cosine);
                const int tol = int(std::min<long double>(kLooseUlpTolerance / std::max<long double>(cosine, 1e-3L), 1 << 20));
                if (exact && same_point(ray, *exact, ours.t, tol) && same_point(ray, *exact, ref.t, tol))
                    a = Agreement::TErrorBound;
            }
        } else if (coincident(scene, ours, ref)) {
            a = Agreement::Coincident;  // the same surface: any t difference is rounding (grazing rays)
        } else {
            a = same ? Agreement::SameTOtherPrim : Agreement::Mismatch;
        }
    }
    // The nearer of two answers is decided by an edge within the float test's rounding error:
    // either side's answer is a correct rounding of the exact one.
    if (a == Agreement::Mismatch) {
        const Hit* nearer = !ref.hit || (ours.hit && ours.t < other.t) ? &ours : &other;
        if (nearer->hit && !scene.meshes.at(nearer->geom).procedural() &&
            edge_decision_within_float_error(scene, ray, nearer->geom, nearer->prim))
            a = Agreement::EdgeFloatError;
    }
    if (a == Agreement::Mismatch && long_double_confirms_ours(scene, ray, ours, other)) return Agreement::SphereFloatError;
    if (a == Agreement::Mismatch && ours.hit && other.hit && simulator_float_order(scene, ray, ours, other)) a = Agreement::SimulatorOrder;
    // The nearer answer lies at the ray's start: the other side took it for before tnear.
    if (a == Agreement::Mismatch) {
        const Hit& nearer = !other.hit || (ours.hit && ours.t < other.t) ? ours : other;
        if (nearer.hit && near_start(ray, nearer.t)) a = Agreement::BoundaryT;
    }
    return a;
}

}  // namespace rtu
