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
    TUlps,            // same primitive, t within kUlpTolerance ulps
    SameTOtherPrim,   // different primitive at equal t (within kUlpTolerance ulps): shared edge/vertex
    BoundaryT,        // one hits, one misses, and the hit lies within kUlpTolerance ulps of tnear or tfar
    VertexEmbreeMiss, // we hit a triangle at a vertex (two barycentrics ~0) that Embree's robust mode misses
    ZeroDirFace,      // one side misses a ray with an exactly-zero direction component (box face plane, sign of zero)
    SphereFloatError, // a sphere where Embree's float solver errs: a long-double solve confirms our answer
    Mismatch,
    Count
};
constexpr int kUlpTolerance = 8;
const char* agreement_name(Agreement a);

// Distance in float ulps between a and b (0 if equal, huge if signs differ or NaN).
uint32_t ulp_distance(float a, float b);

// `ref_closest` is Embree's closest hit for the same ray (used to classify an any-hit query).
// `scene` gives the primitives for the long-double check of sphere disagreements.
Agreement classify(const Scene& scene, const Ray& ray, const Hit& ours, const Hit& ref, const Hit& ref_closest);

// Nearest root in [tnear, tfar] of the ray with sphere `prim` of mesh `geom`, solved in long
// double; nullopt if there is none, or if the sphere is not a procedural one in world space.
std::optional<long double> exact_sphere_t(const Scene& scene, const Ray& ray, uint32_t geom, uint32_t prim);

struct VerifyCounts {
    std::array<uint64_t, size_t(Agreement::Count)> by_class{};
    uint64_t rays = 0, skipped = 0;
    uint64_t mismatches() const { return by_class[size_t(Agreement::Mismatch)]; }
};

}  // namespace rtu
