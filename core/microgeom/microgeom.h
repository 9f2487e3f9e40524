#pragma once
// Technique `microgeom`: Heidrich, Daubert, Kautz, Seidel 2000, "Illuminating Micro Geometry
// Based on Precomputed Visibility". A heightfield (procedural or an image) applied as a bump map
// to the object's (u,v) space (tiled `microgeom.tiling` times; 1:1 in camera.mode=texture), lit
// with exact shadows from the visibility textures S_i (§4) and with light scattered inside the
// heightfield by the Method of Dependent Tests (§3).
//
// Stages (object stages: one result per object using microgeom; objects with equal settings share it):
//   microgeom.heightfield      heights and albedo            (microgeom.heightfield, resolution, texel_size, albedo_map, ...)
//   microgeom.directions       N directions + triangulation  (microgeom.directions)
//   microgeom.visibility       S_i                           (heightfield, directions) — never the light or the curvature
//   microgeom.importance       bent directions' fan areas    (curvature_u/v)                   curved bases (§5)
//   microgeom.ellipses_curved  ellipses at 5 curvatures      (ellipse_bend)                    shadows = ellipse, curved
//   microgeom.ellipses         ellipses (fitted, or interpolated at the curvature)             shadows = ellipse
//   microgeom.scatter_env      environment light scattered   (env.*, depth)                    effects.environment
//   microgeom.scatter          every light scattered         (light.*, depth)                  effects.indirect, planes, directional lights
//   microgeom.scatter_directions  light scattered for each direction above the horizon
//                                 (depth; never the light)                                     effects.indirect, non-planar bases, point lights
//   microgeom.displaced        displaced geometry            (lod, tiling, geometry.*)         lod = geometry (lod.h)
//   microgeom.brdf             simulated BRDF (goniometer)   (lod, brdf_*, depth, shadows)     lod = brdf (goniometer.h)
//
// Levels of detail (lod.h): geometry and bump shade per pixel with the texture-space results;
// brdf shades a smooth surface with the table: AOV direct = the lights' part (their scattering
// included), indirect = the environment's part (exact for a constant environment, scaled by the
// irradiance at the macro normal for a map), shadow = the masked average shadow fraction.
// Micro-BRDF (microgeom.brdf), per pixel with the bilinear, renormalised micro-normal n, the
// bilinear albedo rho, s = microgeom.shininess and h = normalize(wi + wo):
//   lambert      f = rho/pi
//   blinn-phong  f = rho/pi + ks (s + 8)/(8 pi) max(0, n.h)^s   (the normalised lobe, as goniometer.h)
// applied to the direct light only: L_direct = sum over lights f E max(0, n.wi) V; the scattered
// and environment light are Lambert, L_indirect = rho/pi E_indirect (shade_cpu, microgeom.frag).
// Scope: micro-BRDF Lambertian for every bounce (the Blinn-Phong lobe applies to the direct light
// seen by the viewer); every light gets its own scattering solution: on a planar base under
// directional lights one solve for each light's direction (microgeom.scatter); on a non-planar
// base (sphere, cylinder, torus, teapot, mesh) or under a point light, where the tangent-space
// light direction changes from pixel to pixel, the light-driven scattering is tabulated once for
// the M ~ N/2 set directions above the horizon (microgeom.scatter_directions, DirectionalScatter
// in scatter.h: M x texels x RGB floats, M solves) and blended per pixel and light over the
// spherical triangle containing the light's tangent-space direction, as the exact shadows are;
// moving a light never recomputes it. Exact shadows ignore the base curvature (ellipse shadows
// follow it).
//
// The heightfield and its parameters are the shared module core/heightfield (heightfield.h,
// params.h); the technique itself is implemented in the files technique.h lists.
#include "core/heightfield/heightfield.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/ellipse.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/scatter.h"
#include "core/microgeom/visibility.h"
#include "core/stage.h"
#include <algorithm>
#include <cmath>
#include <vector>

namespace mesolab::microgeom {

// One scattering solution of one object: unit irradiance from `light_dir` (microgeom.scatter), or
// the environment's (microgeom.scatter_env).
struct LightScatter {
    ScatterResult result;
    vec3 light_dir{0, 0, 1};  // local frame
};

// microgeom.scatter (planar bases, directional lights only): one solution per scene light (same order as Scene::lights),
// each at unit irradiance; the shaders scale each by its light's irradiance at the pixel.
// Non-planar bases and scenes with a point light have no entry here: they use microgeom.scatter_directions, a
// DirectionalScatter per object (scatter.h).
struct LightsScatter {
    std::vector<LightScatter> lights;
};
// The material parameters the shading reads, parsed once per frame (CPU and GPU alike).
struct Material {
    float tiling = 4.f;     // microgeom.tiling
    bool phong = false;     // microgeom.brdf == blinn-phong
    vec3 ks{0.f};           // Blinn-Phong lobe (0 for Lambert)
    float shininess = 32.f;
    bool shadows = true;    // microgeom.shadows != none
    static Material from(const ParamTable& m);
};

// [SECTION] The bump level's look-up, shared by every method
// The heightfield's micro normal (bilinear in the texels' normals, normalised; local frame) and
// albedo (bilinear) at texel coordinates (c, r), periodic, with the four texels (columns tx, rows
// ty) and their weights w (w[k] for texel (tx[k & 1], ty[k >> 1])).
struct FieldSample {
    int tx[2]{}, ty[2]{};
    float w[4]{};
    vec3 n_loc{0, 0, 1};
    vec3 albedo{0.f};
};
FieldSample sample_field(const Heightfield& hf, float c, float r);
// The micro-BRDF's and the tiling's keys as the counterparts read them (tiling 1 in texture mode).
struct FieldMaterial {
    float tiling = 1;
    bool phong = false;
    vec3 ks{0.f};
    float shininess = 1;
    static FieldMaterial from(const ParamTable& m, bool texture_mode) {
        FieldMaterial f;
        f.tiling = texture_mode ? 1.f : float(m.get_float("tiling"));
        f.phong = m.get_string("brdf") == "blinn-phong";
        f.ks = f.phong ? m.get_vec3("ks") : vec3(0.f);
        f.shininess = float(m.get_float("shininess"));
        return f;
    }
};
// The micro-BRDF (sr⁻¹): Lambert with `albedo`, plus the energy-normalised Blinn-Phong lobe
// ks (e + 8)/(8π) max(0, n·h)^e when `phong` (h the half vector of the unit wo and wi).
inline vec3 micro_brdf(vec3 albedo, vec3 n, vec3 wo, vec3 wi, bool phong, vec3 ks, float shininess) {
    vec3 f = albedo * kInvPi;
    if (phong) {
        const vec3 h = glm::normalize(wo + wi);
        f += ks * (shininess + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(n, h)), shininess);
    }
    return f;
}

// An object's stage results for a frame (null where a stage did not run) and its material.
struct ObjectFrame {
    Material material;
    std::shared_ptr<const Heightfield> hf;
    std::shared_ptr<const DirectionSet> dirs;
    std::shared_ptr<const Visibility> vis;
    std::shared_ptr<const LightScatter> env;           // microgeom.scatter_env
    std::shared_ptr<const LightsScatter> lights;       // microgeom.scatter (planar bases)
    std::shared_ptr<const DirectionalScatter> table;   // microgeom.scatter_directions (non-planar bases)
    std::shared_ptr<const Importance> imp;
    std::shared_ptr<const EllipseMap> ell;
    std::shared_ptr<const SimulatedBrdf> brdf;         // lod = brdf
    static ObjectFrame from(const Scene& s, const Evaluation& ev, int object);
};
}  // namespace mesolab::microgeom
