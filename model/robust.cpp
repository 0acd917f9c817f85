#include "robust.h"

#include <algorithm>
#include <cstring>

namespace rtu {

bool is_valid_ray(const Ray& r) {
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(r.org[i]) || !std::isfinite(r.dir[i])) return false;
    if (r.dir.x == 0.0f && r.dir.y == 0.0f && r.dir.z == 0.0f) return false;
    if (std::isnan(r.tnear) || std::isnan(r.tfar)) return false;
    if (!std::isfinite(r.tnear)) return false;
    if (r.tfar == -std::numeric_limits<float>::infinity()) return false;
    return r.tnear >= 0.0f && r.tnear <= r.tfar;
}

BoxTestRay make_box_test_ray(const glm::vec3& org, const glm::vec3& dir) {
    BoxTestRay r;
    r.org = org;
    for (int i = 0; i < 3; ++i) {
        r.inv_dir[i] = 1.0f / dir[i];  // +0 -> +inf, -0 -> -inf: the sign survives
        r.neg[i] = std::signbit(dir[i]) ? 1 : 0;
    }
    return r;
}

bool intersect_triangle(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& v0,
                        const glm::vec3& v1, const glm::vec3& v2, float tmin, float tmax,
                        TriangleHit* out) {
    // Permute so that z is the dominant direction axis; swap x/y to keep the winding.
    const glm::vec3 ad = glm::vec3(std::fabs(dir.x), std::fabs(dir.y), std::fabs(dir.z));
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (dir[kz] < 0.0f) std::swap(kx, ky);

    // Shear so that the ray points along +z from the origin.
    const float sx = dir[kx] / dir[kz], sy = dir[ky] / dir[kz];
    const glm::vec3 a = v0 - org, b = v1 - org, c = v2 - org;
    const float ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
    const float bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
    const float cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];

    // Scaled barycentric edge functions. Products of floats are exact in double, so the
    // double re-evaluation decides the sign of an edge exactly through a shared edge/vertex.
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = float(double(cx) * double(by) - double(cy) * double(bx));
        v = float(double(ax) * double(cy) - double(ay) * double(cx));
        w = float(double(bx) * double(ay) - double(by) * double(ax));
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    const float det = u + v + w;
    if (det == 0.0f) return false;  // degenerate triangle, or ray in its plane

    // The hit decision above is Woop's and watertight. The distance is then taken from the
    // plane equation in double, t = n.(v0 - o) / n.d, and rounded once: Woop's sheared float
    // distance loses hundreds of ulps on long thin triangles far from the origin (LumiBench's
    // ship), while the products and sums here are exact or nearly so in double.
    const double e1[3] = {double(v1.x) - v0.x, double(v1.y) - v0.y, double(v1.z) - v0.z};
    const double e2[3] = {double(v2.x) - v0.x, double(v2.y) - v0.y, double(v2.z) - v0.z};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double dn = n[0] * dir.x + n[1] * dir.y + n[2] * dir.z;
    if (dn == 0.0) return false;
    const double tp = (n[0] * (double(v0.x) - org.x) + n[1] * (double(v0.y) - org.y) + n[2] * (double(v0.z) - org.z)) / dn;
    const float t = float(tp);
    if (!(t >= tmin && t <= tmax)) return false;  // also rejects NaN
    if (out) {
        const float inv = 1.0f / det;
        out->t = t;
        out->u = v * inv;
        out->v = w * inv;
    }
    return true;
}

bool intersect_sphere(const glm::vec3& org, const glm::vec3& dir, const glm::vec3& center,
                      float radius, float tmin, float tmax, float* t_hit) {
    const double fx = double(org.x) - center.x, fy = double(org.y) - center.y,
                 fz = double(org.z) - center.z;
    const double dx = dir.x, dy = dir.y, dz = dir.z;
    const double a = dx * dx + dy * dy + dz * dz;
    const double b = fx * dx + fy * dy + fz * dz;  // half the linear coefficient
    const double r = radius;
    const double s = b / a;
    const double lx = fx - s * dx, ly = fy - s * dy, lz = fz - s * dz;
    const double disc = a * (r * r - (lx * lx + ly * ly + lz * lz));
    if (disc < 0.0) return false;
    const double c = fx * fx + fy * fy + fz * fz - r * r;
    const double sq = std::sqrt(disc);
    const double q = -(b + std::copysign(sq, b));
    double t0 = q / a, t1 = (q != 0.0) ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    for (double tt : {t0, t1}) {
        const float tf = float(tt);
        if (tf >= tmin && tf <= tmax) {
            if (t_hit) *t_hit = tf;
            return true;
        }
    }
    return false;
}

glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& n) {
    constexpr float kOrigin = 1.0f / 32.0f;
    constexpr float kFloatScale = 1.0f / 65536.0f;
    constexpr float kIntScale = 256.0f;
    glm::vec3 out;
    for (int i = 0; i < 3; ++i) {
        const int32_t step = int32_t(kIntScale * n[i]);
        int32_t bits;
        std::memcpy(&bits, &p[i], 4);
        bits += (p[i] < 0.0f) ? -step : step;
        float moved;
        std::memcpy(&moved, &bits, 4);
        out[i] = std::fabs(p[i]) < kOrigin ? p[i] + kFloatScale * n[i] : moved;
    }
    return out;
}

}  // namespace rtu

namespace rtu {
int scale_direction(Ray& r) {
    const float m = std::max({std::fabs(r.dir.x), std::fabs(r.dir.y), std::fabs(r.dir.z)});
    if (!(m > 0.0f) || !std::isfinite(m)) return 0;
    int e;
    std::frexp(m, &e);  // m in [2^(e-1), 2^e)
    const int k = e - 1;
    if (k == 0) return 0;
    for (int i = 0; i < 3; ++i) r.dir[i] = std::ldexp(r.dir[i], -k);
    r.tnear = std::ldexp(r.tnear, k);
    r.tfar = std::ldexp(r.tfar, k);
    return k;
}
}  // namespace rtu
