#include "core/raytrace.h"

#include <embree3/rtcore.h>
#include <stdexcept>
#include <vector>

namespace mesolab {

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    int count = 0;
    std::vector<size_t> triangles;  // per geometry
};

RayScene::RayScene() : impl_(std::make_unique<Impl>()) {
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device) throw std::runtime_error("Embree could not create a device");
    impl_->scene = rtcNewScene(impl_->device);
}

RayScene::~RayScene() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

int RayScene::add(const TriMesh& m, const mat4& to_world) {
    RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertex_count()));
    for (size_t i = 0; i < m.vertex_count(); ++i) {
        const vec3 p = vec3(to_world * vec4(m.position[i], 1.f));
        v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
    }
    auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.triangle_count()));
    for (size_t i = 0; i < m.index.size(); ++i) ix[i] = m.index[i];
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(impl_->scene, g);
    rtcReleaseGeometry(g);
    if (int(id) != impl_->count) throw std::logic_error("RayScene: Embree numbered the geometries out of order");
    impl_->triangles.push_back(m.triangle_count());
    return impl_->count++;
}

void RayScene::commit() {
    rtcCommitScene(impl_->scene);
    if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE) throw std::runtime_error("Embree could not build the scene");
}

RayHit RayScene::intersect(vec3 o, vec3 d, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = tnear, rh.ray.tfar = tfar;
    rh.ray.mask = 0xffffffffu, rh.ray.flags = 0, rh.ray.time = 0.f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    RayHit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.geometry = int(rh.hit.geomID), h.triangle = int(rh.hit.primID);
    h.u = rh.hit.u, h.v = rh.hit.v, h.t = rh.ray.tfar;
    h.ng = vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    return h;
}

int RayScene::geometry_count() const { return impl_->count; }
size_t RayScene::triangle_count(int geometry) const { return impl_->triangles.at(size_t(geometry)); }

void RayScene::triangle(int geometry, size_t t, vec3& a, vec3& b, vec3& c) const {
    RTCGeometry g = rtcGetGeometry(impl_->scene, unsigned(geometry));
    const auto* v = static_cast<const float*>(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, 0));
    const auto* ix = static_cast<const unsigned*>(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_INDEX, 0));
    const unsigned* f = ix + 3 * t;
    a = vec3(v[3 * f[0]], v[3 * f[0] + 1], v[3 * f[0] + 2]);
    b = vec3(v[3 * f[1]], v[3 * f[1] + 1], v[3 * f[1] + 2]);
    c = vec3(v[3 * f[2]], v[3 * f[2] + 1], v[3 * f[2] + 2]);
}

bool RayScene::occluded(vec3 o, vec3 d, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = o.x, r.org_y = o.y, r.org_z = o.z;
    r.dir_x = d.x, r.dir_y = d.y, r.dir_z = d.z;
    r.tnear = tnear, r.tfar = tfar;
    r.mask = 0xffffffffu, r.flags = 0, r.time = 0.f;
    rtcOccluded1(impl_->scene, &ctx, &r);
    return r.tfar < 0.f;  // Embree marks a blocked ray with tfar = -inf
}
}  // namespace mesolab
