// Technique translucency: ρ per texel: the albedo map and the procedural veins (see translucency.h).
#include "core/translucency/translucency.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/basic/basic.h"
#include "core/error.h"
#include "core/image.h"
#include "core/raster.h"

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/blocked_range.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>
#include <utility>

namespace mesolab::translucency {

// [SECTION] ρ: albedo map and veins
namespace {
uint32_t hash3(int x, int y, int z) {
    uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ uint32_t(z) * 0xcb1ab31fu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return h;
}
float value_noise(vec3 p) {
    const vec3 f = glm::floor(p);
    const vec3 t = p - f;
    const vec3 s = t * t * (3.f - 2.f * t);
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    float v[8];
    for (int k = 0; k < 8; ++k) v[k] = float(hash3(x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2)) >> 8) * (1.f / 16777216.f);
    const float a = glm::mix(glm::mix(v[0], v[1], s.x), glm::mix(v[2], v[3], s.x), s.y);
    const float b = glm::mix(glm::mix(v[4], v[5], s.x), glm::mix(v[6], v[7], s.x), s.y);
    return glm::mix(a, b, s.z);
}
}  // namespace

float vein(vec3 x_mm, double scale_mm) {
    const vec3 p = x_mm / float(scale_mm);
    float fbm = 0.f, amp = 0.5f;
    vec3 q = p;
    for (int o = 0; o < 5; ++o, amp *= 0.5f, q *= 2.03f) fbm += amp * value_noise(q + vec3(17.f * float(o)));
    const float t = p.x + 0.6f * p.y + 3.f * fbm;
    return std::pow(1.f - std::abs(std::sin(kPi * t)), 8.f);
}

std::vector<vec3> texel_albedo(const Scene& scene, const Settings& s, const PreparedMesh& mesh, const AtlasStage& a) {
    std::vector<vec3> rho(a.texel_position.size(), vec3(1.f));
    std::optional<Image> img;
    if (!s.albedo_map.empty()) {
        const std::string path = scene.resolve(s.albedo_map);
        if (mesh.corner_uv.empty())
            throw InputError("translucency.albedo_map: " + path + " needs texture coordinates, and the object's mesh has none (use translucency.veins, or a mesh with uv)");
        img = read_image(path, true, true);
    }
    mesolab::parallel_for(size_t(0), a.nonempty.size(), [&](size_t k) {
        const size_t t = size_t(a.nonempty[k]);
        vec3 r(1.f);
        if (img) {
            const size_t f = size_t(a.atlas.texel_face[t]);
            const vec3 w = a.atlas.texel_bary[t];
            const vec2 uv = w.x * mesh.corner_uv[3 * f] + w.y * mesh.corner_uv[3 * f + 1] + w.z * mesh.corner_uv[3 * f + 2];
            r = basic::sample_albedo(*img, uv);
        }
        if (s.veins > 0.f) r *= glm::mix(vec3(1.f), s.vein_color, s.veins * vein(a.texel_position[t] * float(s.mm_per_unit), s.vein_scale));
        rho[t] = r;
    });
    return fill_texels(a, rho);
}
}  // namespace mesolab::translucency
