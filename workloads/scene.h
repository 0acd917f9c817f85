// Scenes as the workload sees them: meshes (triangles or procedural spheres), materials,
// instances placing meshes in the world, a camera and lights.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "model/node_format.h"
#include "model/robust.h"

namespace rtu {

struct Material {
    enum class Kind : uint8_t { Diffuse, Metal, Glass, Emitter } kind = Kind::Diffuse;
    glm::vec3 albedo{0.7f};
    float fuzz = 0.0f;  // metal
    float ior = 1.5f;   // glass
    glm::vec3 emission{0.0f};
    std::string name;
};

struct Sphere {
    glm::vec3 center;
    float radius;
};

// One geometry (one `geom` number): triangles or spheres, never both.
struct Mesh {
    std::string name;
    std::vector<glm::vec3> vertices;
    std::vector<glm::vec3> normals;     // per vertex: the shading normals (not unit length after a transform)
    std::vector<glm::uvec3> triangles;  // indices into vertices, in file order
    std::vector<Sphere> spheres;        // procedural primitives
    std::vector<uint32_t> material;     // per primitive, index into Scene::materials
    std::vector<uint32_t> file_materials;  // the mesh file's materials in its library's order (LumiBench's per-model list)
    bool procedural() const { return !spheres.empty(); }
    size_t primitives() const { return procedural() ? spheres.size() : triangles.size(); }
    Aabb prim_bounds(size_t i) const;
    Aabb bounds() const;
};

struct Instance {
    uint32_t mesh;
    Affine object_to_world;
};

struct Camera {
    glm::vec3 eye{0.0f, 0.0f, 1.0f}, lookat{0.0f}, up{0.0f, 1.0f, 0.0f};
    float vfov = 45.0f;  // degrees
    float aperture = 0.0f, focus_dist = 1.0f;
};

struct Scene {
    std::string name;
    std::vector<Mesh> meshes;
    std::vector<Material> materials;
    std::vector<Instance> instances;  // every mesh appears in at least one instance
    Camera camera;
    bool sky = true;                  // rays that miss see a sky (else black)
    std::optional<glm::vec3> light;   // point light for shadow rays
    float light_radius = 0.0f;

    // With only identity instances, build one single-level BVH over all meshes (`--flatten`):
    // no instance leaves, no transforms, fewer levels. Off by default: LumiBench builds every
    // model (mesh) into a BLAS of its own under one TLAS.
    bool flatten = false;

    // Two-level (a TLAS of instance leaves over one BLAS per mesh) unless `flatten` applies to
    // identity instances only.
    bool two_level() const;
    bool has_procedural() const;
    uint64_t triangle_count() const;
    uint64_t primitive_count() const;
    Aabb world_bounds() const;
    // An instance placing the mesh (used to map hits back to world space): instance i when it
    // places mesh i, else the first that does. Meshes placed twice are not distinguished.
    const Instance& instance_of(uint32_t mesh) const;
    // Checks invariants (non-empty, finite vertices, valid indices); throws InputError.
    void validate() const;
};

// Smooth vertex normals as LumiBench's loader makes them for a mesh without normals
// (RayTracingInVulkan src/Assets/Model.cpp l.146-168): each vertex's is the sum of the unit face
// normals of the triangles that use it, normalised. Procedural meshes get none.
void compute_smooth_normals(Mesh& m);
// Places a mesh as LumiBench's Model::Transform does (Model.cpp l.786-795): every vertex p
// becomes M p and every normal n inverse-transpose(M) n, not renormalised. `m` is column-major
// (glm), its last row (0, 0, 0, 1).
void bake_transform(Mesh& mesh, const float m[16]);

// Adds a material and returns its index.
uint32_t add_material(Scene& s, Material m);
// Places every mesh once with an identity transform (if no instances were given).
void add_identity_instances(Scene& s);
// A camera framing the scene's bounding box, looking down -Z.
Camera default_camera(const Aabb& bounds);

}  // namespace rtu
