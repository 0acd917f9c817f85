#include "lumibench.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>

namespace rtu::lumibench {

uint32_t init_random_seed(uint32_t v0, uint32_t v1) {
    uint32_t s0 = 0;
    for (uint32_t n = 0; n < 16; ++n) {
        s0 += 0x9e3779b9u;
        v0 += ((v1 << 4) + 0xa341316cu) ^ (v1 + s0) ^ ((v1 >> 5) + 0xc8013ea4u);
        v1 += ((v0 << 4) + 0xad90777du) ^ (v0 + s0) ^ ((v0 >> 5) + 0x7e95761eu);
    }
    return v0;
}

glm::vec2 random_in_unit_disk(uint32_t& seed) {
    for (;;) {
        const float x = random_float(seed), y = random_float(seed);
        const glm::vec2 p = 2.0f * glm::vec2(x, y) - 1.0f;
        if (glm::dot(p, p) < 1.0f) return p;
    }
}

glm::vec3 random_in_unit_sphere(uint32_t& seed) {
    for (;;) {
        const float x = random_float(seed), y = random_float(seed), z = random_float(seed);
        const glm::vec3 p = 2.0f * glm::vec3(x, y, z) - 1.0f;
        if (glm::dot(p, p) < 1.0f) return p;
    }
}

CameraRays::CameraRays(const Camera& cam, int width, int height)
    : launch_size(float(width), float(height)), aperture(cam.aperture), focus(cam.focus_dist) {
    const glm::mat4 model_view = glm::lookAt(cam.eye, cam.lookat, glm::vec3(0, 1, 0));
    glm::mat4 projection = glm::perspective(glm::radians(cam.vfov), float(width) / float(height), 0.1f, 10000.0f);
    projection[1][1] *= -1.0f;  // Vulkan's y points down (RayTracer.cpp l.44)
    model_view_inverse = glm::inverse(model_view);
    projection_inverse = glm::inverse(projection);
}

Ray CameraRays::ray(glm::vec2 pixel, glm::vec2 disk) const {
    const glm::vec2 uv = (pixel / launch_size) * 2.0f - 1.0f;
    const glm::vec2 offset = aperture / 2.0f * disk;
    const glm::vec4 origin = model_view_inverse * glm::vec4(offset, 0, 1);
    const glm::vec4 target = projection_inverse * glm::vec4(uv.x, uv.y, 1, 1);
    const glm::vec4 direction = model_view_inverse * glm::vec4(glm::normalize(glm::vec3(target) * focus - glm::vec3(offset, 0)), 0);
    Ray r;
    r.org = glm::vec3(origin);
    r.dir = glm::vec3(direction);
    return r;
}

namespace {

constexpr float kTMin = 0.001f, kTMax = 10000.0f;  // RayTracing.rgen l.49-50 (every shader type)

// RayPayload.glsl: what a hit or miss shader leaves for the ray generation shader.
struct Payload {
    glm::vec3 color{0.0f};
    float t = -1.0f;            // ColorAndDistance.w: the hit's t, -1 on a miss
    glm::vec3 scatter{0.0f};    // ScatterDirection.xyz
    bool scattered = false;     // ScatterDirection.w
    glm::vec3 surface_normal{0.0f};
};

float schlick(float cosine, float ior) {  // Scatter.glsl l.7-12
    float r0 = (1 - ior) / (1 + ior);
    r0 *= r0;
    return r0 + (1 - r0) * std::pow(1 - cosine, 5.0f);
}

// GLSL's refract(I, N, eta); zero on total internal reflection.
glm::vec3 refract(const glm::vec3& i, const glm::vec3& n, float eta) {
    const float d = glm::dot(n, i);
    const float k = 1.0f - eta * eta * (1.0f - d * d);
    return k < 0.0f ? glm::vec3(0.0f) : eta * i - (eta * d + std::sqrt(k)) * n;
}

// Scatter.glsl l.65-80: each material's scattered ray, drawing its random numbers.
void scatter_payload(const Material& m, const glm::vec3& world_dir, const glm::vec3& normal, float t, uint32_t& seed, Payload& out) {
    const glm::vec3 d = glm::normalize(world_dir);
    out.t = t;
    switch (m.kind) {
        case Material::Kind::Diffuse: {  // l.15-23: scattered off the front of the shading normal only
            out.scattered = glm::dot(d, normal) < 0;
            out.color = m.albedo;
            out.scatter = normal + random_in_unit_sphere(seed);
            break;
        }
        case Material::Kind::Metal: {  // l.26-36
            const glm::vec3 reflected = glm::reflect(d, normal);
            out.scattered = glm::dot(reflected, normal) > 0;
            out.color = m.albedo;
            out.scatter = reflected + m.fuzz * random_in_unit_sphere(seed);
            break;
        }
        case Material::Kind::Glass: {  // l.39-54
            const float dn = glm::dot(d, normal);
            const glm::vec3 outward = dn > 0 ? -normal : normal;
            const float ni_over_nt = dn > 0 ? m.ior : 1 / m.ior;
            const float cosine = dn > 0 ? m.ior * dn : -dn;
            const glm::vec3 refracted = refract(d, outward, ni_over_nt);
            const float reflect_prob = refracted != glm::vec3(0.0f) ? schlick(cosine, m.ior) : 1.0f;
            out.color = glm::vec3(1.0f);
            out.scattered = true;
            out.scatter = random_float(seed) < reflect_prob ? glm::reflect(d, normal) : refracted;
            break;
        }
        case Material::Kind::Emitter:  // l.57-63: a light ends the path
            out.color = m.emission;
            out.scattered = false;
            out.scatter = glm::vec3(1, 0, 0);
            break;
    }
}

// The hit as the closest-hit shaders see it: its material and normal. Triangles
// (RayTracing.rchit l.29-46): the vertex normals interpolated and normalised, the material of
// the triangle's first vertex (which is the triangle's, as the model loader splits vertices by
// material). Spheres (RayTracing.Procedural.rchit l.33-52): (o + t d - centre) / radius.
struct Surface {
    const Material* mat = nullptr;
    glm::vec3 normal{0.0f}, point{0.0f};
    bool sphere = false;
};

Surface surface(const Scene& scene, const Ray& ray, const Hit& h) {
    const Mesh& m = scene.meshes.at(h.geom);
    Surface s;
    s.mat = &scene.materials.at(m.material.at(h.prim));
    s.point = ray.org + h.app_t * ray.dir;
    if (m.procedural()) {
        const Sphere& sp = m.spheres.at(h.prim);
        s.normal = (s.point - sp.center) / sp.radius;
        s.sphere = true;
    } else {
        const glm::uvec3& t = m.triangles.at(h.prim);
        const float b0 = 1.0f - h.u - h.v;
        s.normal = glm::normalize(m.normals[t[0]] * b0 + m.normals[t[1]] * h.u + m.normals[t[2]] * h.v);
    }
    return s;
}

// The closest-hit shader of path tracing (RayTracing.rchit, RayTracing.Procedural.rchit).
void closest_hit_pt(const Scene& scene, const Ray& ray, const Hit& h, uint32_t& seed, Payload& p) {
    const Surface s = surface(scene, ray, h);
    scatter_payload(*s.mat, ray.dir, s.normal, h.app_t, seed, p);
    if (s.sphere) p.surface_normal = s.normal;
}

// The closest-hit shader of the shadow and AO shaders: triangles TraceShadow.rchit (the normal
// turned to face the ray, l.44-47; the hit point into ScatterDirection, l.53), spheres
// RayTracing.Procedural.rchit (the outward normal, the scattered direction).
void closest_hit_secondary(const Scene& scene, const Ray& ray, const Hit& h, uint32_t& seed, Payload& p) {
    Surface s = surface(scene, ray, h);
    if (!s.sphere && glm::dot(s.normal, ray.dir) > 0.0f) s.normal = -s.normal;
    scatter_payload(*s.mat, ray.dir, s.normal, h.app_t, seed, p);
    if (!s.sphere) p.scatter = s.point;
    p.surface_normal = s.normal;
}

// RayTracing.rmiss: the sky's colour (or black), t = -1; nothing else of the payload changes.
void miss(const Scene& scene, const Ray& ray, Payload& p) {
    if (scene.sky) {
        const float t = 0.5f * (glm::normalize(ray.dir).y + 1.0f);
        p.color = (1.0f - t) * glm::vec3(1.0f) + t * glm::vec3(0.5f, 0.7f, 1.0f);
    } else {
        p.color = glm::vec3(0.0f);
    }
    p.t = -1.0f;
}

// One pixel's thread: its random stream, where it is, and what it carries between traces.
struct Pixel {
    uint32_t seed = 0;           // Ray.RandomSeed
    uint16_t sample = 0, step = 0;  // the sample; its bounce (path tracing) or its trace (primary 0, secondary 1..)
    glm::vec3 color{1.0f};       // path tracing: rayColor; shadows, AO: hitColor
    glm::vec3 point{0.0f}, normal{0.0f};  // shadows: the shadow rays' origin and the primary normal; AO: the AO origin
    glm::vec3 payload_normal{0.0f};       // the payload's SurfaceNormal (AO reads it back each time)
};

// The frame of one shader: launch coordinates, the per-sample jitter, per-pixel threads.
class LumiWorkload : public Workload {
public:
    LumiWorkload(const Scene& scene, const WorkloadParams& p)
        : scene_(scene), p_(p), cam_(scene.camera, p.width, p.height), pixels_(size_t(p.width) * p.height),
          image_(pixels_.size(), glm::vec3(0.0f)) {
        // pixelRandomSeed = Camera.RandomSeed = 1 for every pixel (RayTracer.cpp l.59): the
        // same two jitter draws per sample everywhere (RayTracing.rgen l.27, l.37).
        uint32_t pixel_seed = 1;
        for (int s = 0; s < p.spp; ++s) {
            const float jx = random_float(pixel_seed), jy = random_float(pixel_seed);
            jitter_.push_back({jx, jy});
        }
    }

    void begin(std::vector<WorkRay>& out) override {
        out.reserve(out.size() + pixels_.size());
        // The frame is LumiBench's frame number `seed` (1: the first, which the simulator runs):
        // TotalNumberOfSamples = spp x seed seeds every pixel's stream (RayTracing.rgen l.29).
        for (uint32_t path = 0; path < pixels_.size(); ++path) {
            pixels_[path] = first_state(path);
            start_sample(path, out);
        }
    }

    // Every path is restart()ed before it is traced: nothing to set up.
    void begin_for_restarts() override {}

    // The state begin() left; its first ray is already in the caller's hands, so it is not made
    // again (the sampling pre-pass restarts every path it traces: a camera ray and a vector here
    // were about a tenth of a sampled primary-ray run's samples in perf).
    void restart(uint32_t path) override {
        pixels_.at(path) = first_state(path);
        draw_sample(path);
    }

    std::vector<glm::vec3> image() const override {
        std::vector<glm::vec3> img(image_.size());
        for (size_t i = 0; i < img.size(); ++i) img[i] = image_[i] / float(p_.spp);
        return img;
    }

protected:
    // The pixel's thread before its first sample: its random stream seeded from its launch
    // coordinates and the frame (RayTracing.rgen l.29).
    Pixel first_state(uint32_t path) const {
        Pixel px;
        const uint32_t total = uint32_t(uint64_t(p_.spp) * p_.seed);
        px.seed = init_random_seed(init_random_seed(path % uint32_t(p_.width), path / uint32_t(p_.width)), total);
        return px;
    }
    // The camera ray of the pixel's current sample (RayTracing.rgen l.37-43): the lens sample is
    // drawn from the pixel's stream whatever the aperture.
    void start_sample(uint32_t path, std::vector<WorkRay>& out) {
        const glm::vec2 disk = draw_sample(path);
        const Pixel& px = pixels_[path];
        const glm::vec2 pixel(float(path % uint32_t(p_.width)) + jitter_[px.sample].x, float(path / uint32_t(p_.width)) + jitter_[px.sample].y);
        emit(path, cam_.ray(pixel, disk), Query::Closest, kTMax, out);
    }
    // The pixel's state at the start of its current sample: its lens sample drawn (returned), its
    // colour and trace count reset.
    glm::vec2 draw_sample(uint32_t path) {
        Pixel& px = pixels_[path];
        const glm::vec2 disk = random_in_unit_disk(px.seed);
        px.step = 0;
        px.color = glm::vec3(1.0f);
        return disk;
    }
    // The pixel's sample is done with `color`: the next sample, if any.
    void end_sample(uint32_t path, const glm::vec3& color, std::vector<WorkRay>& out) {
        if (std::isfinite(color.x) && std::isfinite(color.y) && std::isfinite(color.z)) image_[path] += color;
        Pixel& px = pixels_[path];
        if (++px.sample < uint32_t(p_.spp)) start_sample(path, out);
    }
    void emit(uint32_t path, const Ray& r, Query q, float tmax, std::vector<WorkRay>& out) {
        WorkRay w;
        w.ray = r;
        w.ray.tnear = kTMin;
        w.ray.tfar = tmax;
        w.ray.query = q;
        w.path = path;
        const Pixel& px = pixels_[path];
        w.depth = px.step;
        w.phase = uint32_t(px.sample) << 8 | px.step;
        out.push_back(w);
    }

    const Scene& scene_;
    WorkloadParams p_;
    CameraRays cam_;
    std::vector<glm::vec2> jitter_;  // per sample
    std::vector<Pixel> pixels_;
    std::vector<glm::vec3> image_;
};

// RayTracing.rgen l.47-80: up to `bounces` traces a sample; a miss or a ray that does not scatter
// ends it; the next ray leaves from o + t d along the scattered direction, not normalised.
class PathTrace : public LumiWorkload {
public:
    using LumiWorkload::LumiWorkload;
    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>& out) override {
        Pixel& px = pixels_[r.path];
        Payload p;
        if (h.hit) closest_hit_pt(scene_, r.ray, h, px.seed, p);
        else miss(scene_, r.ray, p);
        px.color *= p.color;
        if (p.t < 0 || !p.scattered) return end_sample(r.path, px.color, out);
        if (++px.step == uint32_t(p_.bounces)) return end_sample(r.path, glm::vec3(0.0f), out);  // l.54-58
        Ray next;
        next.org = r.ray.org + p.t * r.ray.dir;
        next.dir = p.scatter;
        emit(r.path, next, Query::Closest, kTMax, out);
    }
};

// TraceShadow.rgen (2 rays) and TraceAO.rgen (4 rays): the primary hit, then its secondary rays
// one trace each; every hit of a secondary ray runs its closest-hit shader too (drawing from the
// pixel's stream).
class Secondary : public LumiWorkload {
public:
    Secondary(const Scene& scene, const WorkloadParams& p, bool ao) : LumiWorkload(scene, p), ao_(ao) {}

    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>& out) override {
        Pixel& px = pixels_[r.path];
        Payload p;
        p.surface_normal = px.payload_normal;
        if (h.hit) closest_hit_secondary(scene_, r.ray, h, px.seed, p);
        else miss(scene_, r.ray, p);
        px.payload_normal = p.surface_normal;
        if (px.step == 0) {
            if (p.t < 0) return end_sample(r.path, p.color, out);  // a miss: the sky (or black)
            px.color = p.color;
            if (ao_) {
                px.point = p.scatter;  // TraceAO.rgen l.62: the hit point of a triangle, a sphere's scattered direction
            } else {
                px.point = r.ray.org + p.t * r.ray.dir + p.surface_normal * 0.001f;  // TraceShadow.rgen l.61-62
                px.normal = p.surface_normal;
            }
        } else if (p.t > 0) {
            px.color *= ao_ ? 0.9f : 0.3f;  // occluded
        }
        next(r.path, out);
    }

private:
    // The pixel's next secondary ray, or the end of its sample.
    void next(uint32_t path, std::vector<WorkRay>& out) {
        Pixel& px = pixels_[path];
        const uint32_t n = ao_ ? 4 : 2;  // lumibench.sh: --shadowrays 4 (AO), 2 (shadows)
        while (px.step < n) {
            ++px.step;
            Ray ray;
            if (ao_) {  // TraceAO.rgen l.63-79: a unit direction in the hemisphere of the payload's normal
                glm::vec3 d = glm::normalize(random_in_unit_sphere(px.seed));
                if (glm::dot(d, px.payload_normal) <= 0) d = -1.0f * d;
                ray.org = px.point + d * 0.01f;
                ray.dir = d;
                return emit(path, ray, Query::Any, 10.0f, out);
            }
            // TraceShadow.rgen l.65-98: straight up under a sky, else towards a point of the light.
            float tmax = kTMax;
            glm::vec3 d(0, 1, 0);
            if (!scene_.sky) {
                const glm::vec3 light = scene_.light.value_or(glm::vec3(0.0f)) + scene_.light_radius * random_in_unit_sphere(px.seed);
                d = light - px.point;
                tmax = glm::length(d);
                d = glm::normalize(d);
            }
            if (glm::dot(d, px.normal) > 0) {
                ray.org = px.point;
                ray.dir = d;
                return emit(path, ray, Query::Any, tmax, out);
            }
            px.color *= 0.3f;  // a ray not traced counts as occluded (`occluded` starts at 1, l.83)
        }
        end_sample(path, px.color, out);
    }
    bool ao_;
};

// rtsim's primary-ray workload: LumiBench's camera rays alone, each pixel shaded by its hit's
// colour and the angle to its normal (a frame that shows the geometry).
class Primary : public LumiWorkload {
public:
    using LumiWorkload::LumiWorkload;
    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>& out) override {
        Payload p;
        if (!h.hit) {
            miss(scene_, r.ray, p);
            return end_sample(r.path, p.color, out);
        }
        const Surface s = surface(scene_, r.ray, h);
        const glm::vec3 c = s.mat->kind == Material::Kind::Emitter ? s.mat->emission
                                                                   : s.mat->albedo * (0.2f + 0.8f * std::fabs(glm::dot(s.normal, glm::normalize(r.ray.dir))));
        end_sample(r.path, c, out);
    }
};

}  // namespace

Scattered scatter(const Material& m, const glm::vec3& world_dir, const glm::vec3& normal, uint32_t& seed) {
    Payload p;
    scatter_payload(m, world_dir, normal, 0.0f, seed, p);
    return {p.color, p.scatter, p.scattered};
}

std::unique_ptr<Workload> make_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p) {
    switch (kind) {
        case WorkloadKind::Primary: return std::make_unique<Primary>(scene, p);
        case WorkloadKind::PathTrace: return std::make_unique<PathTrace>(scene, p);
        case WorkloadKind::AmbientOcclusion: return std::make_unique<Secondary>(scene, p, true);
        case WorkloadKind::Shadow: return std::make_unique<Secondary>(scene, p, false);
        case WorkloadKind::RayFile: break;
    }
    throw std::logic_error("lumibench::make_workload: not a scene workload");
}

}  // namespace rtu::lumibench
