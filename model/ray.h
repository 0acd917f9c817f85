// Rays and hits as the RT unit sees them. Plain C++17, no SystemC.
#pragma once
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

namespace rtu {

enum class Query : uint8_t { Closest, Any };

struct Ray {
    glm::vec3 org{0.0f};
    glm::vec3 dir{0.0f, 0.0f, 1.0f};
    float tnear = 0.0f;
    float tfar = std::numeric_limits<float>::infinity();
    Query query = Query::Closest;
};

constexpr uint32_t kNoId = 0xFFFFFFFFu;

struct Hit {
    bool hit = false;
    float t = -1.0f;
    uint32_t geom = kNoId;  // mesh index in the scene
    uint32_t prim = kNoId;  // triangle / procedural primitive index within that mesh
    float u = 0.0f, v = 0.0f;  // barycentrics of v1 and v2 (triangles only)
    glm::vec3 ng{0.0f};        // geometric normal in world space (unnormalised)
    // The hit's t as the TTP authors' simulator and application compute it, in float: a
    // triangle's by Moller-Trumbore on the object-space ray of unit direction, a sphere's by
    // LumiBench's intersection shader (model/traversal.h). It orders the hits (which of two
    // coincident triangles wins, as in their traversal) and is what the shaders see; `t` is the
    // robust one (hits files, verification).
    float app_t = -1.0f;
};

// What the ray-file contract calls a valid ray: finite origin and direction, direction not
// all zero, 0 <= tnear <= tfar, tfar finite or +inf. NaN anywhere is invalid.
bool is_valid_ray(const Ray& r);

}  // namespace rtu
