// Ray workloads: camera primary rays, path tracing, ambient occlusion, shadow rays and ray
// files. A workload hands out rays and consumes their hits; follow-up rays (bounces, AO and
// shadow rays) are made from the hits, so the same workload drives the functional loop here
// and, later, the timing model. Every random number comes from a generator seeded by
// (seed, path, depth), so results do not depend on the order in which rays complete.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "model/ray.h"
#include "scene.h"

namespace rtu {

// SplitMix64-seeded xorshift generator; uniform floats in [0, 1).
class Rng {
public:
    explicit Rng(uint64_t seed);
    Rng(uint64_t seed, uint64_t a, uint64_t b);
    float uniform();
    uint64_t next();

private:
    uint64_t s_;
};

struct WorkRay {
    Ray ray;
    uint32_t path = 0;   // pixel sample (or ray-file line order) this ray belongs to
    uint16_t depth = 0;  // 0 primary, then bounces / secondary rays
};

struct WorkloadParams {
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1;
};

enum class WorkloadKind { Primary, PathTrace, AmbientOcclusion, Shadow, RayFile };
WorkloadKind parse_workload(const std::string& name);  // throws InputError
const char* workload_name(WorkloadKind k);

class Workload {
public:
    virtual ~Workload() = default;
    // First rays (camera rays, or every ray of a ray file).
    virtual void begin(std::vector<WorkRay>& out) = 0;
    // Consumes the hit of a traced ray and appends the rays it causes.
    virtual void complete(const WorkRay& r, const Hit& hit, std::vector<WorkRay>& out) = 0;
    // Linear RGB per pixel (row-major, top row first), or empty if the workload has no image.
    virtual std::vector<glm::vec3> image() const { return {}; }
};

std::unique_ptr<Workload> make_scene_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p);

// A camera ray through pixel (px, py) with jitter (jx, jy) in [0,1)^2 and lens sample (lx, ly).
Ray camera_ray(const Camera& cam, int px, int py, int width, int height, float jx, float jy, float lx, float ly);

// Ray file (shared/interfaces.md): one ray per line "ox oy oz dx dy dz tnear tfar [closest|any]".
struct RayFileEntry {
    Ray ray;
    size_t line = 0;
    bool valid = false;
    std::string problem;  // why the ray is invalid
};
std::vector<RayFileEntry> read_ray_file(const std::string& path);  // throws InputError if unreadable
std::unique_ptr<Workload> make_ray_file_workload(const std::vector<RayFileEntry>& rays);

}  // namespace rtu
