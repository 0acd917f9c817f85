// LumiBench's shaders as rtunit casts them (workloads/lumibench.h): each material's scattered ray
// against draws worked by hand from Random.glsl's LCG, and path lengths on scenes whose answer
// follows from the shader's rules alone.
#include <gtest/gtest.h>

#include <map>

#include "platforms/functional_run.h"
#include "test_util.h"
#include "workloads/bvh_builder.h"
#include "workloads/lumibench.h"
#include "workloads/scene.h"

using namespace rtu;
using namespace rtu::lumibench;

namespace {
void expect_vec(const glm::vec3& got, const glm::vec3& want, float tol = 1e-6f) {
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}
Material material(Material::Kind kind) {
    Material m;
    m.kind = kind;
    m.albedo = glm::vec3(0.5f);
    return m;
}
}  // namespace

// From seed 12345, Random.glsl's LCG (seed = 1664525 seed + 1013904223, a float from its low
// 24 bits) gives RandomInUnitSphere = (0.8953755, -0.2453917, 0.2032600) on its first triple
// (worked in double from the integers, then rounded to float, as the shader's float does):
// - Lambertian hit from the front (ray -z, normal +z): scattered along N + that point;
// - Lambertian hit from behind: absorbed, the path ends (but the point is drawn all the same);
// - metal, fuzz 0.1: reflect(d, N) + 0.1 x the point;
// - glass (IOR 1.5), ray (0.6, 0, -0.8): the first RandomFloat, 0.22308755, is above Schlick's
//   reflectance 0.04 + 0.96 x 0.2^5 = 0.0403072, so the ray refracts to (0.4, 0, -0.9165151);
//   from seed 6 (first draw 0.028681576) it reflects, to (0.6, 0, 0.8);
// - a light: no scatter, its emission, no draw.
TEST(LumiBench, EachMaterialScattersAsWorkedByHand) {
    const glm::vec3 point(0.8953755f, -0.24539173f, 0.20326f);
    const glm::vec3 n(0, 0, 1);
    uint32_t seed = 12345;
    Scattered s = scatter(material(Material::Kind::Diffuse), {0, 0, -1}, n, seed);
    EXPECT_TRUE(s.scattered);
    expect_vec(s.direction, n + point);
    expect_vec(s.color, glm::vec3(0.5f));
    EXPECT_EQ(seed, 2560230508u);  // one triple drawn: the first point lies in the sphere
    seed = 12345;
    s = scatter(material(Material::Kind::Diffuse), {0, 0, 1}, n, seed);
    EXPECT_FALSE(s.scattered);
    EXPECT_EQ(seed, 2560230508u);
    seed = 12345;
    Material metal = material(Material::Kind::Metal);
    metal.fuzz = 0.1f;
    s = scatter(metal, {0, 0, -1}, n, seed);
    EXPECT_TRUE(s.scattered);
    expect_vec(s.direction, glm::vec3(0, 0, 1) + 0.1f * point);
    Material glass = material(Material::Kind::Glass);
    glass.ior = 1.5f;
    seed = 12345;
    s = scatter(glass, {0.6f, 0, -0.8f}, n, seed);
    EXPECT_TRUE(s.scattered);
    expect_vec(s.direction, {0.4f, 0.0f, -0.91651514f});
    expect_vec(s.color, glm::vec3(1.0f));
    seed = 6;
    s = scatter(glass, {0.6f, 0, -0.8f}, n, seed);
    expect_vec(s.direction, {0.6f, 0.0f, 0.8f});
    Material light = material(Material::Kind::Emitter);
    light.emission = glm::vec3(15.0f);
    seed = 12345;
    s = scatter(light, {0, 0, -1}, n, seed);
    EXPECT_FALSE(s.scattered);
    expect_vec(s.color, glm::vec3(15.0f));
    EXPECT_EQ(seed, 12345u);
}

namespace {
// A closed cube [-1, 1]^3 of one material, each face two triangles with its inward normal at its
// four corners, the camera at its centre.
Scene closed_cube(Material m) {
    Scene s;
    s.name = "cube";
    s.materials.push_back(m);
    Mesh mesh;
    mesh.name = "cube";
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const uint32_t base = uint32_t(mesh.vertices.size());
            for (auto [a, b] : {std::pair{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}}) {
                glm::vec3 p(0.0f), normal(0.0f);
                p[axis] = side;
                p[u] = a;
                p[v] = b;
                normal[axis] = -side;  // inward
                mesh.vertices.push_back(p);
                mesh.normals.push_back(normal);
            }
            mesh.triangles.push_back({base, base + 1, base + 2});
            mesh.triangles.push_back({base, base + 2, base + 3});
        }
    mesh.material.assign(mesh.triangles.size(), 0);
    s.meshes.push_back(mesh);
    add_identity_instances(s);
    s.camera.eye = {0, 0, 0};
    s.camera.lookat = {0, 0, -1};
    s.camera.vfov = 60;
    s.sky = false;
    return s;
}
// Rays per path (pixel) of a path-tracing frame of the scene, by count of paths.
std::map<size_t, size_t> path_lengths(const Scene& s, int bounces) {
    const BvhImage image = build_bvh_image(s);
    WorkloadParams p;
    p.width = p.height = 8;
    p.spp = 1;
    p.bounces = bounces;
    auto w = make_workload(WorkloadKind::PathTrace, s, p);
    const FunctionalResult f = run_functional(s, image, *w, FunctionalOptions{}, nullptr);
    std::map<uint32_t, size_t> per_path;
    for (uint32_t path : f.path) ++per_path[path];
    std::map<size_t, size_t> by_length;
    for (const auto& [path, n] : per_path) ++by_length[n];
    return by_length;
}
}  // namespace

// The bounce count distribution, from the shader's rules (RayTracing.rgen l.47-80): inside a
// closed Lambertian cube every ray hits a wall from the front and scatters, so every path is
// cut by the bounce limit (16, or 5): 64 paths of exactly that many rays. Inside a cube of lights
// every path ends at its first hit: 64 paths of one ray. With the camera outside, looking away,
// every camera ray misses: one ray each.
TEST(LumiBench, PathLengthsFollowTheShadersRules) {
    const Scene lambert = closed_cube(Material{});
    EXPECT_EQ(path_lengths(lambert, 16), (std::map<size_t, size_t>{{16, 64}}));
    EXPECT_EQ(path_lengths(lambert, 5), (std::map<size_t, size_t>{{5, 64}}));
    Material light;
    light.kind = Material::Kind::Emitter;
    light.emission = glm::vec3(15.0f);
    EXPECT_EQ(path_lengths(closed_cube(light), 16), (std::map<size_t, size_t>{{1, 64}}));
    Scene outside = closed_cube(Material{});
    outside.camera.eye = {0, 0, 5};
    outside.camera.lookat = {0, 0, 10};
    EXPECT_EQ(path_lengths(outside, 16), (std::map<size_t, size_t>{{1, 64}}));
}
