// The rays of LumiBench's application (the RayTracingInVulkan fork the TTP paper ran,
// ubc-aamodt-group/RayTracingInVulkan f5932e7): its ray generation and hit shaders as rtsim's
// workloads, draw for draw, so that rtsim casts the rays the authors' simulator casts. Every
// choice cites its shader and line in docs/lumibench.md. Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <memory>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "rays.h"
#include "scene.h"

namespace rtu::lumibench {

// assets/shaders/Random.glsl: a 16-round TEA hash to seed each pixel's stream, Numerical
// Recipes' LCG, and floats from its low 24 bits. The vector draws take their components in
// order (GLSL evaluates arguments left to right).
uint32_t init_random_seed(uint32_t v0, uint32_t v1);
inline uint32_t random_int(uint32_t& seed) { return seed = 1664525u * seed + 1013904223u; }
inline float random_float(uint32_t& seed) { return float(random_int(seed) & 0x00FFFFFFu) / float(0x01000000); }
glm::vec2 random_in_unit_disk(uint32_t& seed);
glm::vec3 random_in_unit_sphere(uint32_t& seed);

// The camera as the application sets up its uniform buffer (src/RayTracer.cpp l.38-65) and the
// ray generation shaders use it (RayTracing.rgen l.37-43): lookAt and perspective with Vulkan's
// flipped y, their inverses, a thin lens of the camera's aperture.
struct CameraRays {
    CameraRays(const Camera& cam, int width, int height);
    // The ray through `pixel` (launch coordinates plus jitter) with the lens sample `disk` (in
    // the unit disk); the direction is of unit length.
    Ray ray(glm::vec2 pixel, glm::vec2 disk) const;
    glm::mat4 model_view_inverse, projection_inverse;
    glm::vec2 launch_size;
    float aperture, focus;
};

// Scatter.glsl: a material's scattered ray for a ray along `world_dir` that hits a surface of
// shading normal `normal` (unit length), drawing from `seed` as the shader does.
struct Scattered {
    glm::vec3 color;      // the attenuation (a light's emission)
    glm::vec3 direction;  // not normalised
    bool scattered;       // false: the path ends (a light, or a Lambertian surface hit from behind)
};
Scattered scatter(const Material& m, const glm::vec3& world_dir, const glm::vec3& normal, uint32_t& seed);

// The workload of one shader type: 0 path tracing (RayTracing.rgen), 1 shadows
// (TraceShadow.rgen, 2 rays), 2 ambient occlusion (TraceAO.rgen, 4 rays); primary: the camera
// rays alone (rtsim's, with LumiBench's camera and random numbers). A path is a pixel, traced by
// one thread of its shader warp sample after sample; WorkRay::phase orders its rays as the
// warp's SIMT execution does (see rays.h).
std::unique_ptr<Workload> make_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p);

}  // namespace rtu::lumibench
