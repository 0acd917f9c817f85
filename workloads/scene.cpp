#include "scene.h"

#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include "input_error.h"

namespace rtu {
namespace {
void grow(Aabb& b, const glm::vec3& p) {
    b.lo = glm::min(b.lo, p);
    b.hi = glm::max(b.hi, p);
}
void grow(Aabb& b, const Aabb& o) {
    b.lo = glm::min(b.lo, o.lo);
    b.hi = glm::max(b.hi, o.hi);
}
}  // namespace

Aabb Mesh::prim_bounds(size_t i) const {
    Aabb b;
    if (procedural()) {
        // centre -+ radius in float, as LumiBench gives the driver a sphere's box (Sphere.hpp
        // l.21-24); the node quantization above it rounds outward.
        const Sphere& s = spheres[i];
        b.lo = s.center - s.radius;
        b.hi = s.center + s.radius;
        return b;
    }
    const glm::uvec3& t = triangles[i];
    for (int k = 0; k < 3; ++k) grow(b, vertices[t[k]]);
    return b;
}

Aabb Mesh::bounds() const {
    Aabb b;
    for (size_t i = 0; i < primitives(); ++i) grow(b, prim_bounds(i));
    return b;
}

bool Scene::two_level() const {
    for (const Instance& i : instances)
        if (!is_identity(i.object_to_world)) return true;
    return !flatten;
}

bool Scene::has_procedural() const {
    for (const Mesh& m : meshes)
        if (m.procedural()) return true;
    return false;
}

uint64_t Scene::triangle_count() const {
    uint64_t n = 0;
    for (const Mesh& m : meshes) n += m.triangles.size();
    return n;
}

uint64_t Scene::primitive_count() const {
    uint64_t n = 0;
    for (const Mesh& m : meshes) n += m.primitives();
    return n;
}

Aabb Scene::world_bounds() const {
    Aabb b;
    for (const Instance& inst : instances) {
        const Aabb mb = meshes[inst.mesh].bounds();
        for (int c = 0; c < 8; ++c) {
            glm::vec3 p((c & 1) ? mb.hi.x : mb.lo.x, (c & 2) ? mb.hi.y : mb.lo.y, (c & 4) ? mb.hi.z : mb.lo.z);
            grow(b, transform_point(inst.object_to_world, p));
        }
    }
    return b;
}

const Instance& Scene::instance_of(uint32_t mesh) const {
    // Called per hit (shading, verification): the usual layout, instance i placing mesh i,
    // answers at once; other layouts are searched.
    if (mesh < instances.size() && instances[mesh].mesh == mesh) return instances[mesh];
    for (const Instance& i : instances)
        if (i.mesh == mesh) return i;
    throw std::logic_error("mesh without instance");
}

void Scene::validate() const {
    if (primitive_count() == 0) throw InputError(name + ": empty scene (no triangles or primitives)");
    for (const Mesh& m : meshes) {
        for (size_t i = 0; i < m.vertices.size(); ++i)
            for (int a = 0; a < 3; ++a)
                if (!std::isfinite(m.vertices[i][a]))
                    throw InputError(m.name + ": vertex " + std::to_string(i) + " is not finite");
        for (const glm::uvec3& t : m.triangles)
            for (int k = 0; k < 3; ++k)
                if (t[k] >= m.vertices.size()) throw InputError(m.name + ": triangle index out of range");
        for (const Sphere& s : m.spheres)
            if (!std::isfinite(s.center.x) || !std::isfinite(s.center.y) || !std::isfinite(s.center.z) ||
                !(s.radius > 0.0f) || !std::isfinite(s.radius))
                throw InputError(m.name + ": invalid sphere");
        if (m.material.size() != m.primitives()) throw std::logic_error(m.name + ": material per primitive");
    }
    for (const Instance& i : instances) {
        if (i.mesh >= meshes.size()) throw std::logic_error("instance of unknown mesh");
        for (float f : i.object_to_world)
            if (!std::isfinite(f)) throw InputError(name + ": instance transform not finite");
    }
}

void compute_smooth_normals(Mesh& m) {
    if (m.procedural()) return;
    m.normals.assign(m.vertices.size(), glm::vec3(0.0f));
    for (const glm::uvec3& t : m.triangles) {
        const glm::vec3 n = glm::normalize(glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
        // A degenerate triangle has no normal (LumiBench's would make its vertices' NaN).
        if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) continue;
        for (int k = 0; k < 3; ++k) m.normals[t[k]] += n;
    }
    for (glm::vec3& n : m.normals) n = glm::normalize(n);
}

void bake_transform(Mesh& mesh, const float m[16]) {
    const glm::mat4 M = glm::make_mat4(m);
    const glm::mat3 N = glm::inverseTranspose(glm::mat3(M));
    for (glm::vec3& p : mesh.vertices) p = glm::vec3(M * glm::vec4(p, 1.0f));
    for (glm::vec3& n : mesh.normals) n = N * n;
}

uint32_t add_material(Scene& s, Material m) {
    s.materials.push_back(std::move(m));
    return uint32_t(s.materials.size() - 1);
}

void add_identity_instances(Scene& s) {
    if (!s.instances.empty()) return;
    for (uint32_t i = 0; i < s.meshes.size(); ++i) s.instances.push_back({i, identity_affine()});
}

Camera default_camera(const Aabb& b) {
    Camera c;
    const glm::vec3 center = 0.5f * (b.lo + b.hi);
    const float radius = std::max(0.5f * glm::length(b.hi - b.lo), 1e-6f);
    c.vfov = 45.0f;
    const float dist = radius / std::sin(glm::radians(c.vfov * 0.5f)) * 1.05f;
    c.lookat = center;
    c.eye = center + glm::vec3(0.0f, 0.0f, dist);
    c.focus_dist = dist;
    return c;
}

}  // namespace rtu
