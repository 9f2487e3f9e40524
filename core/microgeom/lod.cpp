#include "core/microgeom/lod.h"
#include "core/parallel.h"
#include "core/microgeom/scatter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mesolab::microgeom {

// [SECTION] Tessellation rate
int displacement_resolution(const std::string& type, int base_resolution, int field_width, int field_height, float tiling, int cap, bool* capped) {
    // Segments along u; the sphere has half as many along v (mesh.h), so it needs twice the rate,
    // and so does the teapot (its atlas has 8 patch cells along u, 4 along v, resolution/8 segments per patch side).
    const double along_u = double(field_width) * tiling, along_v = double(field_height) * tiling;
    const bool half_along_v = type == "sphere" || type == "teapot";
    double need = std::max(along_u, half_along_v ? 2.0 * along_v : along_v);
    need = std::ceil(need);
    if (capped) *capped = need > cap;
    return int(std::clamp(need, double(base_resolution), double(std::max(cap, base_resolution))));
}

// [SECTION] Displacement
namespace {
// Moves every vertex of `m` along its normal by height(c, r) (world units, at the vertex's texel
// coordinates) minus the field's mean, in texels times the texel's world length there.
template <class HeightAt>
void displace_by(TriMesh& m, const Heightfield& hf, float tiling, HeightAt height) {
    const size_t nv = m.vertex_count();
    // World length per uv unit at each vertex: sqrt(sum world area / sum uv area) of its triangles.
    std::vector<double> area_w(nv, 0.0), area_uv(nv, 0.0);
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const uint32_t a = m.index[3 * t], b = m.index[3 * t + 1], c = m.index[3 * t + 2];
        const double aw = 0.5 * double(glm::length(glm::cross(m.position[b] - m.position[a], m.position[c] - m.position[a])));
        const vec2 e1 = m.uv[b] - m.uv[a], e2 = m.uv[c] - m.uv[a];
        const double auv = 0.5 * std::fabs(double(e1.x) * e2.y - double(e1.y) * e2.x);
        for (uint32_t v : {a, b, c}) area_w[v] += aw, area_uv[v] += auv;
    }
    double mean = 0.0;
    for (float h : hf.h) mean += h;
    mean /= double(std::max<size_t>(1, hf.h.size()));
    const float inv_s = 1.f / hf.texel_size;
    mesolab::parallel_for(size_t(0), nv, [&](size_t v) {
        const vec2 uv = m.uv[v];
        const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
        const double per_uv = area_uv[v] > 0.0 ? std::sqrt(area_w[v] / area_uv[v]) : 0.0;
        const float texel = float(per_uv / (double(hf.width) * tiling));
        m.position[v] += m.normal[v] * ((height(c, r) - float(mean)) * inv_s * texel);
    });
}
}  // namespace

TriMesh displace(const TriMesh& base, const Heightfield& hf, float tiling) {
    TriMesh m = base;
    displace_by(m, hf, tiling, [&](float c, float r) { return sample_bilinear(hf.h, hf.width, hf.height, true, c, r); });
    return m;
}

// [SECTION] The truth's surface
float height_through_centres(const Heightfield& hf, float c, float r) {
    const float x0f = std::floor(c), y0f = std::floor(r), fx = c - x0f, fy = r - y0f;
    auto at = [&](int x, int y) {
        x = ((x % hf.width) + hf.width) % hf.width, y = ((y % hf.height) + hf.height) % hf.height;
        return hf.h[hf.index(x, y)];
    };
    const int x0 = int(x0f), y0 = int(y0f);
    const float h10 = at(x0 + 1, y0), h01 = at(x0, y0 + 1);
    // The diagonal from low (u, v) to high (u, v) joins (x0, y0 + 1) and (x0 + 1, y0): r grows as v falls.
    if (fx + fy <= 1.f) {
        const float h00 = at(x0, y0);
        return h00 + fx * (h10 - h00) + fy * (h01 - h00);
    }
    const float h11 = at(x0 + 1, y0 + 1);
    return h11 + (1.f - fx) * (h01 - h11) + (1.f - fy) * (h10 - h11);
}

int truth_surface_resolution(Primitive base, int base_resolution, int field_width, int field_height, float tiling, bool* capped) {
    constexpr double kCap = 16384.0;
    const double along_u = 2.0 * double(field_width) * tiling, along_v = 2.0 * double(field_height) * tiling;
    const bool half_along_v = base == Primitive::Sphere || base == Primitive::Teapot;
    double need = std::ceil(std::max(along_u, half_along_v ? 2.0 * along_v : along_v));
    if (base == Primitive::Teapot) need = 8.0 * std::ceil(need / 8.0);
    need = std::max(need, double(base_resolution));
    if (capped) *capped = need > kCap;
    return int(std::min(need, kCap));
}

double truth_surface_triangles(Primitive base, int n) {
    if (base == Primitive::Teapot) return 32.0 * 2.0 * std::pow(std::max(2.0, double(n / 8)), 2.0);
    return 2.0 * double(n) * double(base == Primitive::Sphere ? std::max(2, n / 2) : n);
}

TriMesh truth_surface(Primitive base, int resolution, float minor_ratio, const Heightfield& hf, float tiling, float curvature_u_deg,
                      float curvature_v_deg) {
    TriMesh m = make_primitive(base, resolution, minor_ratio);
    displace_by(m, hf, tiling, [&](float c, float r) { return height_through_centres(hf, c, r); });
    if (base == Primitive::Plane) {
        // A cylinder of the plane's length 2 over the whole bend (one tile's bend times the tiling):
        // x -> the arc of radius R = 2 / angle, z measured from the arc outwards.
        auto bend = [&](float deg, int axis) {
            const double angle = double(deg) * std::numbers::pi / 180.0 * double(tiling);
            if (angle == 0.0) return;
            const double R = 2.0 / angle;
            for (vec3& p : m.position) {
                const double s = p[axis], z = p.z, phi = s / R;
                p[axis] = float(std::sin(phi) * (R + z));
                p.z = float(std::cos(phi) * (R + z) - R);
            }
        };
        bend(curvature_u_deg, 0);
        bend(curvature_v_deg, 1);
    }
    m.normal.clear();
    m.tangent.clear();
    return m;
}
}  // namespace mesolab::microgeom
