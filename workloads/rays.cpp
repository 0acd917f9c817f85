#include "rays.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "input_error.h"
#include "lumibench.h"
#include "file_io.h"

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

namespace {

class RayFileWorkload : public Workload {
public:
    bool runs_shaders() const override { return false; }
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

void check_workload_params(const WorkloadParams& p) {
    if (p.width < 1 || p.height < 1 || p.width > 16384 || p.height > 16384)
        throw InputError("--width/--height must be 1..16384 (got " + std::to_string(p.width) + "x" + std::to_string(p.height) + ")");
    if (p.spp < 1 || p.spp > 4096) throw InputError("--spp must be 1..4096 (got " + std::to_string(p.spp) + ")");
    if (p.bounces < 1 || p.bounces > 64) throw InputError("--bounces must be 1..64 (got " + std::to_string(p.bounces) + ")");
    // Paths are numbered in 32 bits; counted in 64, so the product itself cannot overflow.
    const uint64_t paths = uint64_t(p.width) * uint64_t(p.height) * uint64_t(p.spp);
    if (paths > UINT32_MAX)
        throw InputError("--width x --height x --spp = " + std::to_string(paths) + " paths: at most " + std::to_string(UINT32_MAX) +
                         " (paths are numbered in 32 bits)");
}

std::unique_ptr<Workload> make_scene_workload(WorkloadKind kind, const Scene& scene, const WorkloadParams& p) {
    check_workload_params(p);
    if (kind == WorkloadKind::RayFile) throw std::logic_error("ray files use make_ray_file_workload");
    return lumibench::make_workload(kind, scene, p);
}

namespace {

// The 48-byte ray records of rtsim --dump-rays and the peripheral (include/rtunit/rtu_regs.h,
// rtu_ray): org[3], tnear, dir[3], tfar as little-endian floats at bytes 0-31, flags at 32 (bit 0:
// any hit; any other bit makes the ray invalid), user at 36, reserved at 40-47.
constexpr size_t kRayRecordBytes = 48;

std::vector<RayFileEntry> read_ray_records(const std::string& path, const std::string& bytes) {
    if (bytes.size() % kRayRecordBytes != 0)
        throw InputError(path + ": binary data of " + std::to_string(bytes.size()) +
                         " bytes: neither a text ray file (one ray a line) nor a whole number of 48-byte ray records "
                         "(rtsim --dump-rays, include/rtunit/rtu_regs.h)");
    std::vector<RayFileEntry> rays(bytes.size() / kRayRecordBytes);
    for (size_t i = 0; i < rays.size(); ++i) {
        const char* r = bytes.data() + i * kRayRecordBytes;
        float v[8];
        uint32_t flags;
        std::memcpy(v, r, sizeof v);
        std::memcpy(&flags, r + 32, sizeof flags);
        RayFileEntry& e = rays[i];
        e.line = i + 1;
        e.ray.org = {v[0], v[1], v[2]};
        e.ray.tnear = v[3];
        e.ray.dir = {v[4], v[5], v[6]};
        e.ray.tfar = v[7];
        if (flags & 1u) e.ray.query = Query::Any;
        if (flags & ~1u) e.problem = "record " + std::to_string(i + 1) + ": flags " + std::to_string(flags) + " (only bit 0, any hit, is defined)";
        else if (!is_valid_ray(e.ray)) e.problem = "record " + std::to_string(i + 1) + ": invalid ray (a NaN, an infinite origin or direction, a zero direction, or tnear < 0 or > tfar)";
        e.valid = e.problem.empty();
        if (!e.valid) e.ray.org.x = NAN;
    }
    return rays;
}

}  // namespace

std::vector<RayFileEntry> read_ray_file(const std::string& path) {
    const std::string bytes = read_file_maybe_gz(path);
    // A NUL byte never occurs in a text ray file and always in a ray record (its reserved words):
    // such a file is read as records, or refused.
    if (bytes.find('\0') != std::string::npos) return read_ray_records(path, bytes);
    std::istringstream in(bytes);
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
