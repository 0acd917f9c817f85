// The golden reference: the same scene traced by Embree in robust mode (RTC_SCENE_FLAG_ROBUST,
// mask all ones). Triangles are Embree triangle meshes, spheres Embree's own sphere points,
// instances Embree instances with the same 3x4 transforms, so every answer is Embree's, not ours.
#pragma once
#include <memory>

#include "model/ray.h"
#include "scene.h"

namespace rtu {

class EmbreeReference {
public:
    explicit EmbreeReference(const Scene& scene);
    ~EmbreeReference();
    EmbreeReference(const EmbreeReference&) = delete;
    EmbreeReference& operator=(const EmbreeReference&) = delete;

    // Traces a valid ray (never hand Embree NaN/inf, tnear < 0 or huge components: Debian's
    // build aborts). Any-hit queries report hit/miss only (t = tfar, ids unknown).
    Hit trace(const Ray& ray) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtu
