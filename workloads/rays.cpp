#include "rays.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "input_error.h"
#include "mesh_io.h"

namespace rtu {

// --- random numbers --------------------------------------------------------------------------

namespace {
uint64_t splitmix64(uint64_t& x) {
    uint64_t z = (x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
}  // namespace

Rng::Rng(uint64_t seed) : s_(seed) { splitmix64(s_); }
Rng::Rng(uint64_t seed, uint64_t a, uint64_t b) {
    uint64_t x = seed;
    x = splitmix64(x) ^ a;
    x = splitmix64(x) ^ b;
    s_ = splitmix64(x);
}
uint64_t Rng::next() { return splitmix64(s_); }
float Rng::uniform() { return float(next() >> 40) * 0x1p-24f; }

WorkloadKind parse_workload(const std::string& n) {
    if (n == "primary") return WorkloadKind::Primary;
    if (n == "pt") return WorkloadKind::PathTrace;
    if (n == "ao") return WorkloadKind::AmbientOcclusion;
    if (n == "sh") return WorkloadKind::Shadow;
    throw InputError("--workload '" + n + "': allowed are primary, pt, ao, sh");
}

const char* workload_name(WorkloadKind k) {
    switch (k) {
        case WorkloadKind::Primary: return "primary";
        case WorkloadKind::PathTrace: return "pt";
        case WorkloadKind::AmbientOcclusion: return "ao";
        case WorkloadKind::Shadow: return "sh";
        case WorkloadKind::RayFile: return "rays";
    }
    return "?";
}

Ray camera_ray(const Camera& cam, int px, int py, int width, int height, float jx, float jy, float lx, float ly) {
    const float theta = glm::radians(cam.vfov);
    const float h = std::tan(theta / 2);
    const float vh = 2.0f * h, vw = vh * float(width) / float(height);
    const glm::vec3 w = glm::normalize(cam.eye - cam.lookat);
    const glm::vec3 u = glm::normalize(glm::cross(cam.up, w));
    const glm::vec3 v = glm::cross(w, u);
    const float fd = cam.focus_dist;
    const glm::vec3 horiz = fd * vw * u, vert = fd * vh * v;
    const glm::vec3 lower_left = cam.eye - horiz / 2.0f - vert / 2.0f - fd * w;
    const float s = (float(px) + jx) / float(width);
    const float t = 1.0f - (float(py) + jy) / float(height);  // row 0 is the top
    glm::vec3 offset(0.0f);
    if (cam.aperture > 0.0f) {
        // Uniform point on the lens disk (concentric polar form).
        const float r = 0.5f * cam.aperture * std::sqrt(lx);
        const float phi = 2.0f * float(M_PI) * ly;
        offset = u * (r * std::cos(phi)) + v * (r * std::sin(phi));
    }
    Ray ray;
    ray.org = cam.eye + offset;
    ray.dir = lower_left + s * horiz + t * vert - ray.org;
    return ray;
}

namespace {

glm::vec3 random_unit_vector(Rng& rng) {
    const float z = 1.0f - 2.0f * rng.uniform();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = 2.0f * float(M_PI) * rng.uniform();
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform point in the unit ball (draws are sequenced so results never depend on the compiler).
glm::vec3 random_in_ball(Rng& rng) {
    const glm::vec3 d = random_unit_vector(rng);
    return d * std::cbrt(rng.uniform());
}

// Cosine-weighted direction around unit normal n.
glm::vec3 cosine_direction(const glm::vec3& n, Rng& rng) {
    glm::vec3 d = n + random_unit_vector(rng);
    if (glm::dot(d, d) < 1e-12f) d = n;
    return glm::normalize(d);
}

struct Surface {
    glm::vec3 p;   // world-space hit point (from barycentrics / the sphere, not o + t d)
    glm::vec3 n;   // unit geometric normal facing the incoming ray
    bool front;    // the ray hit the side the stored normal points to
    float err;     // extra absolute error of p beyond a few ulps of p (spheres)
    const Material* mat;
};

Surface surface_at(const Scene& scene, const Ray& ray, const Hit& h) {
    const Mesh& mesh = scene.meshes.at(h.geom);
    const Instance& inst = scene.instance_of(h.geom);
    glm::vec3 p;
    float err = 0.0f;
    if (mesh.procedural()) {
        const Sphere& s = mesh.spheres.at(h.prim);
        const glm::vec3 pw = ray.org + h.t * ray.dir;
        const bool placed = !is_identity(inst.object_to_world);  // the inverse is needed only then
        const glm::vec3 po = placed ? transform_point(invert_affine(inst.object_to_world), pw) : pw;
        const glm::vec3 d = po - s.center;
        const float len = glm::length(d);
        p = transform_point(inst.object_to_world, len > 0.0f ? s.center + d * (s.radius / len) : po);
        // The surface point of a sphere is only known to float precision of its centre and
        // radius, not of p itself (the ground sphere of wknd: r = 1000 around y = 0): the
        // spawn offset must cover that error as well as Wachter-Binder's.
        err = (std::max({std::fabs(s.center.x), std::fabs(s.center.y), std::fabs(s.center.z)}) + s.radius) * 0x1p-20f;
    } else {
        const glm::uvec3& t = mesh.triangles.at(h.prim);
        const glm::vec3 po = (1.0f - h.u - h.v) * mesh.vertices[t[0]] + h.u * mesh.vertices[t[1]] + h.v * mesh.vertices[t[2]];
        p = transform_point(inst.object_to_world, po);
    }
    // A non-identity instance transform mixes the components: the rounding of the largest
    // coordinate reaches all of them (in object space, where the next ray is tested), which
    // Wachter-Binder's per-component offset does not cover.
    if (!is_identity(inst.object_to_world))
        err = std::max(err, std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) * 0x1p-20f);
    Surface s;
    s.p = p;
    s.err = err;
    glm::vec3 n = h.ng;
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : -glm::normalize(ray.dir);
    s.front = glm::dot(n, ray.dir) < 0.0f;
    s.n = s.front ? n : -n;
    s.mat = &scene.materials.at(mesh.material.at(h.prim));
    return s;
}

Ray spawn(const Surface& s, const glm::vec3& dir, float tfar, Query q) {
    Ray r;
    // Offset to the side the new ray leaves from (Wachter-Binder), then start at t = 0.
    const glm::vec3 side = glm::dot(dir, s.n) >= 0.0f ? s.n : -s.n;
    r.org = offset_ray_origin(s.p, side) + s.err * side;
    r.dir = dir;
    r.tnear = 0.0f;
    r.tfar = tfar;
    r.query = q;
    return r;
}

glm::vec3 sky_colour(const glm::vec3& dir) {
    const float t = 0.5f * (glm::normalize(dir).y + 1.0f);
    return (1.0f - t) * glm::vec3(1.0f) + t * glm::vec3(0.5f, 0.7f, 1.0f);
}

float schlick(float cosine, float ratio) {
    float r0 = (1 - ratio) / (1 + ratio);
    r0 = r0 * r0;
    return r0 + (1 - r0) * std::pow(1 - cosine, 5.0f);
}

// Shared frame bookkeeping: pixel samples, camera rays, per-pixel accumulation.
class FrameWorkload : public Workload {
public:
    FrameWorkload(const Scene& scene, const WorkloadParams& p) : scene_(scene), p_(p), pixels_(size_t(p.width) * p.height, glm::vec3(0.0f)) {}

    void begin(std::vector<WorkRay>& out) override {
        const uint32_t paths = uint32_t(p_.width) * p_.height * p_.spp;
        out.reserve(out.size() + paths);  // one allocation: a 1024x1024 frame at 2 spp is 2 M rays
        for (uint32_t path = 0; path < paths; ++path) {
            const uint32_t pixel = path / p_.spp;
            Rng rng(p_.seed, path, 0xCA11);
            const float jx = p_.spp > 1 ? rng.uniform() : 0.5f, jy = p_.spp > 1 ? rng.uniform() : 0.5f;
            const float lx = rng.uniform(), ly = rng.uniform();
            WorkRay w;
            w.ray = camera_ray(scene_.camera, int(pixel % p_.width), int(pixel / p_.width), p_.width, p_.height, jx, jy, lx, ly);
            w.path = path;
            out.push_back(w);
        }
    }

    std::vector<glm::vec3> image() const override {
        std::vector<glm::vec3> img(pixels_.size());
        for (size_t i = 0; i < img.size(); ++i) img[i] = pixels_[i] / float(p_.spp);
        return img;
    }

protected:
    void add(uint32_t path, const glm::vec3& c) {
        if (std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) pixels_[path / p_.spp] += c;
    }
    glm::vec3 background(const glm::vec3& dir) const { return scene_.sky ? sky_colour(dir) : glm::vec3(0.0f); }

    const Scene& scene_;
    WorkloadParams p_;
    std::vector<glm::vec3> pixels_;
};

class PrimaryWorkload : public FrameWorkload {
public:
    using FrameWorkload::FrameWorkload;
    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>&) override {
        if (!h.hit) return add(r.path, background(r.ray.dir));
        const Surface s = surface_at(scene_, r.ray, h);
        add(r.path, s.mat->kind == Material::Kind::Emitter ? s.mat->emission : s.mat->albedo * (0.2f + 0.8f * std::fabs(glm::dot(s.n, glm::normalize(r.ray.dir)))));
    }
};

class PathTraceWorkload : public FrameWorkload {
public:
    PathTraceWorkload(const Scene& scene, const WorkloadParams& p)
        : FrameWorkload(scene, p), throughput_(size_t(p.width) * p.height * p.spp, glm::vec3(1.0f)) {}

    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>& out) override {
        glm::vec3& beta = throughput_[r.path];
        if (!h.hit) return add(r.path, beta * background(r.ray.dir));
        const Surface s = surface_at(scene_, r.ray, h);
        const Material& m = *s.mat;
        if (m.kind == Material::Kind::Emitter) return add(r.path, beta * m.emission);
        if (r.depth + 1 >= p_.bounces) return;  // path length limit: no more rays
        Rng rng(p_.seed, r.path, 0xB0 + r.depth);
        const glm::vec3 in = glm::normalize(r.ray.dir);
        glm::vec3 dir;
        switch (m.kind) {
            case Material::Kind::Metal: {
                dir = glm::reflect(in, s.n) + m.fuzz * random_in_ball(rng);
                if (glm::dot(dir, s.n) <= 0.0f) return;  // absorbed
                beta *= m.albedo;
                break;
            }
            case Material::Kind::Glass: {
                const float ratio = s.front ? 1.0f / m.ior : m.ior;
                const float cos_t = std::fmin(glm::dot(-in, s.n), 1.0f);
                const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
                if (ratio * sin_t > 1.0f || schlick(cos_t, ratio) > rng.uniform())
                    dir = glm::reflect(in, s.n);
                else
                    dir = glm::refract(in, s.n, ratio);
                break;
            }
            default:
                dir = cosine_direction(s.n, rng);
                beta *= m.albedo;
        }
        WorkRay next;
        next.ray = spawn(s, dir, INFINITY, Query::Closest);
        next.path = r.path;
        next.depth = uint16_t(r.depth + 1);
        out.push_back(next);
    }

private:
    std::vector<glm::vec3> throughput_;
};

// Primary hit, then `n` any-hit rays; the pixel shows the unoccluded fraction.
class SecondaryWorkload : public FrameWorkload {
public:
    SecondaryWorkload(const Scene& scene, const WorkloadParams& p, bool ao) : FrameWorkload(scene, p), ao_(ao) {}

    void complete(const WorkRay& r, const Hit& h, std::vector<WorkRay>& out) override {
        const int n = ao_ ? 4 : 2;
        if (r.depth > 0) {
            if (!h.hit) add(r.path, glm::vec3(1.0f / n));
            return;
        }
        if (!h.hit) return add(r.path, background(r.ray.dir));
        const Surface s = surface_at(scene_, r.ray, h);
        if (s.mat->kind == Material::Kind::Emitter) return add(r.path, glm::vec3(1.0f));
        Rng rng(p_.seed, r.path, 0x5EC);
        for (int i = 0; i < n; ++i) {
            WorkRay w;
            w.path = r.path;
            w.depth = 1;
            if (ao_) {
                w.ray = spawn(s, cosine_direction(s.n, rng), 10.0f, Query::Any);
            } else if (scene_.light) {
                // Towards a jittered point on the light: t in [0, 1) reaches it.
                const glm::vec3 target = *scene_.light + scene_.light_radius * random_in_ball(rng);
                const Ray probe = spawn(s, target - s.p, 1.0f, Query::Any);
                w.ray = probe;
                w.ray.dir = target - w.ray.org;
                w.ray.tfar = 1.0f - 0x1p-12f;
                if (w.ray.dir == glm::vec3(0.0f)) continue;
            } else {
                w.ray = spawn(s, glm::vec3(0.0f, 1.0f, 0.0f), INFINITY, Query::Any);  // sky: straight up
            }
            out.push_back(w);
        }
    }

private:
    bool ao_;
};

class RayFileWorkload : public Workload {
public:
    explicit RayFileWorkload(const std::vector<RayFileEntry>& rays) : rays_(rays) {}
    void begin(std::vector<WorkRay>& out) override {
        for (uint32_t i = 0; i < rays_.size(); ++i) {
            WorkRay w;
            w.ray = rays_[i].ray;
            w.path = i;
            out.push_back(w);
        }
    }
    void complete(const WorkRay&, const Hit&, std::vector<WorkRay>&) override {}

private:
    const std::vector<RayFileEntry>& rays_;
};

}  // namespace

std::unique_ptr<Workload> make_scene_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p) {
    if (p.width < 1 || p.height < 1 || p.width > 16384 || p.height > 16384)
        throw InputError("--width/--height must be 1..16384 (got " + std::to_string(p.width) + "x" + std::to_string(p.height) + ")");
    if (p.spp < 1 || p.spp > 4096) throw InputError("--spp must be 1..4096 (got " + std::to_string(p.spp) + ")");
    if (p.bounces < 1 || p.bounces > 64) throw InputError("--bounces must be 1..64 (got " + std::to_string(p.bounces) + ")");
    // Paths are numbered in 32 bits; counted in 64, so the product itself cannot overflow.
    const uint64_t paths = uint64_t(p.width) * uint64_t(p.height) * uint64_t(p.spp);
    if (paths > UINT32_MAX)
        throw InputError("--width x --height x --spp = " + std::to_string(paths) + " paths: at most " + std::to_string(UINT32_MAX) +
                         " (paths are numbered in 32 bits)");
    switch (kind) {
        case WorkloadKind::Primary: return std::make_unique<PrimaryWorkload>(scene, p);
        case WorkloadKind::PathTrace: return std::make_unique<PathTraceWorkload>(scene, p);
        case WorkloadKind::AmbientOcclusion: return std::make_unique<SecondaryWorkload>(scene, p, true);
        case WorkloadKind::Shadow: return std::make_unique<SecondaryWorkload>(scene, p, false);
        case WorkloadKind::RayFile: break;
    }
    throw std::logic_error("ray files use make_ray_file_workload");
}

std::vector<RayFileEntry> read_ray_file(const std::string& path) {
    std::istringstream in(read_file_maybe_gz(path));
    std::vector<RayFileEntry> rays;
    std::string line;
    size_t lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream ls(line);
        std::vector<std::string> tok;
        std::string t;
        while (ls >> t) tok.push_back(t);
        if (tok.empty()) continue;
        RayFileEntry e;
        e.line = lineno;
        float v[8] = {};
        if (tok.size() < 8 || tok.size() > 9) {
            e.problem = "expected 8 numbers and an optional closest|any, got " + std::to_string(tok.size()) + " fields";
        } else {
            for (int i = 0; i < 8 && e.problem.empty(); ++i) {
                char* end = nullptr;
                v[i] = std::strtof(tok[i].c_str(), &end);
                if (end == tok[i].c_str() || *end) e.problem = "field " + std::to_string(i + 1) + " '" + tok[i] + "' is not a number";
            }
            if (e.problem.empty() && tok.size() == 9) {
                if (tok[8] == "any") e.ray.query = Query::Any;
                else if (tok[8] != "closest") e.problem = "query '" + tok[8] + "' is not closest or any";
            }
        }
        e.ray.org = {v[0], v[1], v[2]};
        e.ray.dir = {v[3], v[4], v[5]};
        e.ray.tnear = v[6];
        e.ray.tfar = v[7];
        if (e.problem.empty() && !is_valid_ray(e.ray)) {
            static const char* names[8] = {"ox", "oy", "oz", "dx", "dy", "dz", "tnear", "tfar"};
            for (int i = 0; i < 8 && e.problem.empty(); ++i)
                if (std::isnan(v[i]) || (i < 7 && std::isinf(v[i])) || (i == 7 && v[i] < 0 && std::isinf(v[i])))
                    e.problem = std::string("invalid ray: ") + names[i] + " = '" + tok[i] + "' (must be finite" +
                                (i == 7 ? " or +inf)" : ")");
            if (e.problem.empty() && v[3] == 0.0f && v[4] == 0.0f && v[5] == 0.0f) e.problem = "invalid ray: zero direction";
            if (e.problem.empty() && v[6] < 0.0f) e.problem = "invalid ray: tnear = '" + tok[6] + "' is negative";
            if (e.problem.empty()) e.problem = "invalid ray: tnear = '" + tok[6] + "' > tfar = '" + tok[7] + "'";
        }
        e.valid = e.problem.empty();
        if (!e.valid) e.ray.org.x = NAN;  // an unparsed line must never be traced as a ray
        rays.push_back(e);
    }
    return rays;
}

std::unique_ptr<Workload> make_ray_file_workload(const std::vector<RayFileEntry>& rays) {
    return std::make_unique<RayFileWorkload>(rays);
}

}  // namespace rtu
