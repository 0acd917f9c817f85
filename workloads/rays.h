// Ray workloads: camera primary rays, path tracing, ambient occlusion, shadow rays (LumiBench's
// application, workloads/lumibench.h) and ray files. A workload hands out rays and consumes their
// hits; follow-up rays (bounces, AO and shadow rays) are made from the hits, so the same workload
// drives the functional loop and the timing model. A pixel's random numbers are its own stream,
// drawn in its rays' order, so results do not depend on the order in which pixels complete.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "model/ray.h"
#include "scene.h"

namespace rtu {

// SplitMix64-seeded generator; uniform floats in [0, 1) (the sample design's draws).
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
    uint32_t path = 0;   // the pixel (one thread of its shader warp) or ray-file line this ray belongs to
    uint16_t depth = 0;  // the ray's place in its sample: 0 the camera ray, then bounces or secondary rays
    // Where the thread is in the ray generation shader (sample << 8 | trace of the sample): a
    // shader warp executes its threads' trace calls together, as SIMT hardware does, so a trace
    // takes the rays of the warp's threads that are furthest behind (the lowest phase) and the
    // others wait (a thread done with its sample waits for the warp's other threads to finish
    // theirs: the sample loop reconverges; docs/lumibench.md).
    uint32_t phase = 0;
};

struct WorkloadParams {
    int width = 128, height = 128, spp = 2, bounces = 16;
    uint64_t seed = 1;  // LumiBench's frame number: TotalNumberOfSamples = spp x seed seeds the pixels
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
    // Sets the workload up for a caller that restart()s every path before tracing it (the
    // sampling pre-pass's own copies of the workload): as begin(), without the first rays where
    // the workload can leave them out.
    virtual void begin_for_restarts() {
        std::vector<WorkRay> dropped;
        begin(dropped);
    }
    // Puts path `path` back as begin() left it (its first ray emitted), so that it can be traced
    // again from that ray with the same results: the sampling pre-pass and the caches' warming
    // trace a shader warp more than once, on workloads that other warps have advanced.
    virtual void restart(uint32_t path) { (void)path; }
    // Linear RGB per pixel (row-major, top row first), or empty if the workload has no image.
    virtual std::vector<glm::vec3> image() const { return {}; }
    // Whether shader code makes the rays (a frame's ray generation and hit shaders: a kernel
    // launch, and shading before every trace), or they are given (a ray file).
    virtual bool runs_shaders() const { return true; }
};

// The frame's size, samples and bounces within their ranges, and at most 2^32 - 1 paths;
// InputError naming the options otherwise.
void check_workload_params(const WorkloadParams& p);
// The scene's workload as LumiBench's application casts it (workloads/lumibench.h).
std::unique_ptr<Workload> make_scene_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p);

// Ray file (shared/interfaces.md): one ray per line "ox oy oz dx dy dz tnear tfar [closest|any]";
// or 48-byte ray records as rtsim --dump-rays writes them (a file with a NUL byte; `line` is then
// the record's number). Binary data that is not whole records is an InputError.
struct RayFileEntry {
    Ray ray;
    size_t line = 0;
    bool valid = false;
    std::string problem;  // why the ray is invalid
};
std::vector<RayFileEntry> read_ray_file(const std::string& path);  // throws InputError if unreadable
std::unique_ptr<Workload> make_ray_file_workload(const std::vector<RayFileEntry>& rays);

}  // namespace rtu
