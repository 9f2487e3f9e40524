#pragma once
// Technique `basic`: Lambert + energy-normalised Blinn-Phong, the first technique, which
// carries the pipeline end to end (CPU and GPU paths, preset, panel, AOVs, a stage).
//   f(wo, wi) = kd/pi * albedo(uv) + ks * (s + 8)/(8 pi) * max(0, n.h)^s,   h = normalize(wo + wi)
//   L(wo)     = sum_lights f * E * max(0, n.wi) + kd/pi * albedo(uv) * E_env(n)
// Surfaces are two-sided: n is flipped to face the viewer. E (W/m^2) is the light's
// irradiance at normal incidence; E_env is the environment's diffuse irradiance (SH9).
#include "core/image.h"
#include "core/math.h"
#include "core/param.h"
#include "core/scene.h"
#include <memory>
#include <optional>
#include <string>

namespace mesolab::basic {

// Material parameters of one object, read from its table in one place.
struct Material {
    vec3 kd{0.8f};
    vec3 ks{0.04f};
    float shininess = 64.f;
    std::string albedo_map;  // resolved path or ""
    static Material from(const ParamTable& t, const std::string& resolved_map);
};

// Blinn-Phong BRDF value (without albedo texture), shared by tests.
vec3 brdf(const Material& m, vec3 n, vec3 wo, vec3 wi, vec3 albedo_tex = vec3(1.f));

// Bilinear, wrapping look-up of an albedo texture at (u, v) with v = 1 at the image top,
// matching OpenGL's GL_LINEAR + GL_REPEAT on a texture uploaded top row first at t = 0 and
// sampled at (u, 1 - v).
vec3 sample_albedo(const Image& img, vec2 uv);

// The image an object's `albedo_map` names (8-bit images are sRGB), for the object stages
// basic.albedo and bumpsynth.albedo; nullopt when it names none.
std::optional<Image> read_albedo_map(const Scene& s, const ParamTable& material);
}  // namespace mesolab::basic
