#include "embree_reference.h"

#include <cmath>
#include <stdexcept>

#include <embree3/rtcore.h>

namespace rtu {

struct EmbreeReference::Impl {
    RTCDevice dev = nullptr;
    RTCScene top = nullptr;
    std::vector<RTCScene> blas;            // per mesh (two-level)
    std::vector<uint32_t> inst_mesh;       // Embree instance (or, single-level, geometry) ID -> mesh index
    bool two_level = false;

    RTCGeometry make_geometry(const Mesh& m) {
        RTCGeometry g;
        if (m.procedural()) {
            g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
            float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                                   4 * sizeof(float), m.spheres.size()));
            for (size_t i = 0; i < m.spheres.size(); ++i) {
                v[4 * i + 0] = m.spheres[i].center.x;
                v[4 * i + 1] = m.spheres[i].center.y;
                v[4 * i + 2] = m.spheres[i].center.z;
                v[4 * i + 3] = m.spheres[i].radius;
            }
        } else {
            g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
            float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                   3 * sizeof(float), m.vertices.size()));
            for (size_t i = 0; i < m.vertices.size(); ++i)
                for (int a = 0; a < 3; ++a) v[3 * i + a] = m.vertices[i][a];
            unsigned* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                          3 * sizeof(unsigned), m.triangles.size()));
            for (size_t i = 0; i < m.triangles.size(); ++i)
                for (int a = 0; a < 3; ++a) idx[3 * i + a] = m.triangles[i][a];
        }
        rtcSetGeometryMask(g, 0xFFFFFFFFu);
        rtcCommitGeometry(g);
        return g;
    }

    RTCScene new_scene() {
        RTCScene s = rtcNewScene(dev);
        rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
        return s;
    }
};

EmbreeReference::EmbreeReference(const Scene& scene) : impl_(new Impl) {
    Impl& m = *impl_;
    m.dev = rtcNewDevice("threads=0");
    if (!m.dev) throw std::runtime_error("Embree device creation failed");
    m.top = m.new_scene();
    m.two_level = scene.two_level();
    if (!m.two_level) {
        // Every (identity-placed) mesh straight into one scene; geomID -> mesh index.
        std::vector<uint8_t> used(scene.meshes.size(), 0);
        for (const Instance& inst : scene.instances) {
            if (used[inst.mesh]++ || scene.meshes[inst.mesh].primitives() == 0) continue;
            RTCGeometry g = m.make_geometry(scene.meshes[inst.mesh]);
            const unsigned id = rtcAttachGeometry(m.top, g);
            rtcReleaseGeometry(g);
            if (m.inst_mesh.size() <= id) m.inst_mesh.resize(id + 1, kNoId);
            m.inst_mesh[id] = inst.mesh;
        }
    } else {
        m.blas.assign(scene.meshes.size(), nullptr);
        for (const Instance& inst : scene.instances) {
            const Mesh& mesh = scene.meshes[inst.mesh];
            if (mesh.primitives() == 0) continue;
            if (!m.blas[inst.mesh]) {
                m.blas[inst.mesh] = m.new_scene();
                RTCGeometry g = m.make_geometry(mesh);
                rtcAttachGeometry(m.blas[inst.mesh], g);
                rtcReleaseGeometry(g);
                rtcCommitScene(m.blas[inst.mesh]);
            }
            RTCGeometry ig = rtcNewGeometry(m.dev, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(ig, m.blas[inst.mesh]);
            rtcSetGeometryTransform(ig, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, inst.object_to_world.data());
            rtcSetGeometryMask(ig, 0xFFFFFFFFu);
            rtcCommitGeometry(ig);
            const unsigned id = rtcAttachGeometry(m.top, ig);
            rtcReleaseGeometry(ig);
            if (m.inst_mesh.size() <= id) m.inst_mesh.resize(id + 1, kNoId);
            m.inst_mesh[id] = inst.mesh;
        }
    }
    rtcCommitScene(m.top);
}

EmbreeReference::~EmbreeReference() {
    for (RTCScene s : impl_->blas)
        if (s) rtcReleaseScene(s);
    rtcReleaseScene(impl_->top);
    rtcReleaseDevice(impl_->dev);
}

Hit EmbreeReference::trace(const Ray& ray) const {
    if (!is_valid_ray(ray)) return Hit{};
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    Hit h;
    if (ray.query == Query::Any) {
        RTCRay r{};
        r.org_x = ray.org.x; r.org_y = ray.org.y; r.org_z = ray.org.z;
        r.dir_x = ray.dir.x; r.dir_y = ray.dir.y; r.dir_z = ray.dir.z;
        r.tnear = ray.tnear;
        r.tfar = ray.tfar;
        r.mask = 0xFFFFFFFFu;
        r.flags = 0;
        rtcOccluded1(impl_->top, &ctx, &r);
        if (r.tfar == -INFINITY) {
            h.hit = true;
            h.t = ray.tfar;
        }
        return h;
    }
    RTCRayHit rh{};
    rh.ray.org_x = ray.org.x; rh.ray.org_y = ray.org.y; rh.ray.org_z = ray.org.z;
    rh.ray.dir_x = ray.dir.x; rh.ray.dir_y = ray.dir.y; rh.ray.dir_z = ray.dir.z;
    rh.ray.tnear = ray.tnear;
    rh.ray.tfar = ray.tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->top, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.hit = true;
    h.t = rh.ray.tfar;
    h.prim = rh.hit.primID;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    h.ng = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    h.geom = impl_->inst_mesh.at(impl_->two_level ? rh.hit.instID[0] : rh.hit.geomID);
    return h;
}

}  // namespace rtu
