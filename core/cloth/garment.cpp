// Procedural garments (see garment.h).
#include "core/cloth/garment.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

namespace mesolab::cloth {

namespace {
// A (nu + 1) × (nv + 1) grid of P(s, t), s, t in [0, 1]; uv = (u(s, t), t); normals from the
// cross product of the parameter derivatives (central differences).
TriMesh grid_mesh(int nu, int nv, const std::function<vec3(float, float)>& P, const std::function<float(float, float)>& U) {
    TriMesh m;
    m.has_uv = true;
    const float e = 1e-3f;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            const float s = float(i) / float(nu), t = float(j) / float(nv);
            m.position.push_back(P(s, t));
            m.uv.push_back(vec2(U(s, t), t));
            const vec3 ds = P(std::min(1.f, s + e), t) - P(std::max(0.f, s - e), t);
            const vec3 dt = P(s, std::min(1.f, t + e)) - P(s, std::max(0.f, t - e));
            const vec3 n = glm::normalize(glm::cross(ds, dt));
            const vec3 tan = glm::normalize(ds - n * glm::dot(ds, n));
            m.normal.push_back(n);
            m.tangent.push_back(tan);
        }
    const uint32_t row = uint32_t(nu + 1);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const uint32_t a = uint32_t(j) * row + uint32_t(i), b = a + 1, c = a + row, d = c + 1;
            m.index.insert(m.index.end(), {a, b, d, a, d, c});
        }
    return m;
}
}  // namespace

TriMesh make_curtain(int folds, float depth, int resolution) {
    if (resolution < 4 || resolution > 4096) throw InputError("cloth.garment_resolution: " + std::to_string(resolution) + " must be in [4, 4096]");
    folds = std::max(0, folds);
    auto y = [&](float x, float z) { return depth * (0.6f + 0.2f * (1.f - z)) * std::sin(kPi * float(folds) * (x + 1.f)); };
    auto P = [&](float s, float t) {
        const float x = 2.f * s - 1.f, z = 2.f * t - 1.f;
        return vec3(x, y(x, z), z);
    };
    // u by arc length along each row (the fold's width), normalised to [0, 1].
    const int n = 256;
    auto U = [&](float s, float t) {
        float len = 0.f, at = 0.f;
        vec3 prev = P(0.f, t);
        for (int k = 1; k <= n; ++k) {
            const vec3 q = P(float(k) / float(n), t);
            len += glm::length(q - prev);
            if (float(k) / float(n) <= s + 1e-7f) at = len;
            prev = q;
        }
        return len > 0.f ? at / len : s;
    };
    // Seen from −y: ds × dt = x × z = −y already faces the viewer.
    return grid_mesh(resolution, std::max(2, resolution / 2), P, U);
}

TriMesh make_sleeve(float bend, int resolution) {
    if (resolution < 4 || resolution > 4096) throw InputError("cloth.garment_resolution: " + std::to_string(resolution) + " must be in [4, 4096]");
    const float r = 0.35f, L = 2.f;
    // The axis: an arc of length L bent by `bend` in the xz plane (straight along z when 0).
    auto axis = [&](float t, vec3& c, vec3& d, vec3& side) {
        const float a = bend * (t - 0.5f);
        if (std::abs(bend) < 1e-4f) {
            c = vec3(0.f, 0.f, L * (t - 0.5f));
        } else {
            const float R = L / bend;
            c = vec3(R * (1.f - std::cos(a)), 0.f, R * std::sin(a));
        }
        d = vec3(std::sin(a), 0.f, std::cos(a));
        side = vec3(std::cos(a), 0.f, -std::sin(a));
    };
    auto P = [&](float s, float t) {
        vec3 c, d, side;
        axis(t, c, d, side);
        const float phi = 2.f * kPi * s;
        return c + r * (std::cos(phi) * side + std::sin(phi) * vec3(0.f, 1.f, 0.f));
    };
    // ds × dt = (around) × (along) points out of the tube.
    return grid_mesh(resolution, std::max(2, resolution / 2), P, [](float s, float) { return s; });
}

TriMesh make_garment(const std::string& name, int resolution) {
    if (name == "curtain") return make_curtain(4, 0.18f, resolution);
    if (name == "sleeve") return make_sleeve(1.0f, resolution);
    throw InputError("cloth.garment: \"" + name + "\" must be curtain or sleeve (cloth.garment = geometry wears the object's own mesh)");
}
}  // namespace mesolab::cloth
