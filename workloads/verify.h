// Comparing our traversal's answer for a ray with Embree's. Disagreement is allowed only in
// the documented classes below (README "Verification"); everything else is a mismatch.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "model/ray.h"
#include "scene.h"

namespace rtu {

enum class Agreement : uint8_t {
    Agree,            // same answer (same primitive and t, or both miss; any-hit: both hit)
    TUlps,            // same primitive, same point: t within kUlpTolerance ulps of t or of the coordinates
    SameTOtherPrim,   // different primitive at the same point (as TUlps): a shared edge or vertex
    Coincident,       // different triangle with the same three vertex positions (a duplicated face)
    BoundaryT,        // the answers differ by a hit within kUlpTolerance ulps of tnear or tfar, or at the ray's start
                      // within kLooseUlpTolerance ulps of the coordinates (a ray leaving a surface); or one side
                      // hits a triangle whose plane the ray starts on, within kUlpTolerance ulps of the coordinates
    VertexEmbreeMiss, // we hit a triangle at a vertex (two barycentrics ~0) that Embree's robust mode misses
    ZeroDirFace,      // one side misses a ray with an exactly-zero direction component (box face plane, sign of zero)
    SphereFloatError, // a sphere where Embree's float solver errs: a long-double solve confirms our answer
    TErrorBound,      // same triangle; both hit points within kLooseUlpTolerance ulps of the coordinates,
                      // divided by cos(incidence), of the long-double plane hit: grazing rays, and rays
                      // transformed to an instance's object space in float (by us as by Embree)
    EdgeFloatError,   // the nearer answer's triangle is hit or missed by an edge decision that lies within
                      // the rounding error of the float edge test (edge_decision_within_float_error)
    SimulatorOrder,   // another triangle, no farther by the TTP authors' simulator's float t (moller_trumbore_t,
                      // which orders hits), the two exact t's closer together than those float t's errors:
                      // near-coincident surfaces (the ship's double-sided sails) that the float t cannot order
    SimulatorOverflow,  // Embree hits a triangle whose float t by the TTP authors' simulator (moller_trumbore_t,
                      // by which rtunit accepts a hit) overflows: its triple product |v2 - v0| |o - v0| |v1 - v0|
                      // passes 3.4e38 (huge scenes seen from far): the modelled hardware misses it, and so do we
    Mismatch,
    Count
};
constexpr int kUlpTolerance = 8;
constexpr int kLooseUlpTolerance = 128;
const char* agreement_name(Agreement a);

// Distance in float ulps between a and b (0 if equal, huge if signs differ or NaN).
uint32_t ulp_distance(float a, float b);

// `ref_closest` is Embree's closest hit for the same ray (used to classify an any-hit query).
// `scene` gives the primitives for the long-double check of sphere disagreements.
Agreement classify(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& ref, const Hit& ref_closest);

// Distance to the plane of triangle `prim` of mesh `geom` (placed by its instance transform),
// in long double; nullopt for a ray parallel to the plane. `cosine` receives |cos| of the
// angle between the ray and the plane's normal.
std::optional<long double> exact_triangle_t(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim,
                                            long double* cosine = nullptr);
// Nearest root in [tnear, tfar] of the ray with sphere `prim` of mesh `geom`, solved in long
// double; nullopt if there is none, or if the sphere is not a procedural one in world space.
std::optional<long double> exact_sphere_t(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim);

// Whether the float edge test of intersect_triangle (model/robust.h) may decide either way for
// the ray and triangle `prim` of mesh `geom` (placed by an identity instance): some edge function,
// evaluated in long double in the test's own sheared frame, has the sign that disagrees with the
// others and a magnitude within a first-order bound of the float computation's rounding error.
// False for instanced and procedural geometry (no claim is made there).
bool edge_decision_within_float_error(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim);

// Whether hit `ours` (a triangle) is no farther than `other` (another triangle) by the TTP
// authors' simulator's float t (moller_trumbore_t, which orders hits), while the two triangles'
// long-double plane t's are closer together than those float t's are off them: the float t
// cannot order the two surfaces. Identity-placed meshes only (false otherwise).
bool simulator_float_order(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& other);

struct VerifyCounts {
    std::array<uint64_t, size_t(Agreement::Count)> by_class{};
    uint64_t rays = 0, skipped = 0;
    uint64_t mismatches() const { return by_class[size_t(Agreement::Mismatch)]; }
};

}  // namespace rtu
