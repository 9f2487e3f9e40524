#pragma once
// [SECTION] Parallax occlusion mapping: microgeom.method = pom
// The modern counterpart of the paper's bump level: the same heightfield marched per pixel, for
// the view ray (parallax, occlusion) and towards each light (self-shadowing), with no
// interreflection (Tatarchuk 2006, "Dynamic parallax occlusion mapping with approximate soft
// shadows", I3D; Policarpo, Oliveira and Comba 2005, "Real-time relief mapping on arbitrary
// polygonal surfaces", I3D).
//
// Units: the march runs in texel space, (c, r) texel coordinates as the shading reads them
// (c along +u, r along -v) and heights z in texels: z = (h - mean h) / texel_size, the
// displacement the geometry level of detail and the truth give the base surface (lod.h), so one
// texel across is one texel up. The base surface is z = 0; the field spans [z_min, z_max].
//
// The view ray through the base point (c0, r0) towards the eye v (tangent frame, z along the
// macro normal) is parametrised by height: p(z) = (c0 + z vx / vz, r0 - z vy / vz, z).
//  1. Linear search (Tatarchuk's eq. 1-3): z_i = z_max - i (z_max - z_min) / pom_steps, the
//     first z_i at or below the field's height H(p(z_i)) (bilinear, periodic) brackets the hit.
//  2. Refinement: pom_refine halvings of the bracket (Policarpo et al.'s binary search), then one
//     secant step through the bracket's two ends (Tatarchuk's linear intersection of the ray
//     with the segment between the two height samples).
//  3. Shading at the hit (c, r): the heightfield's normal and albedo, bilinear, as the bump level
//     reads them; a light is seen when the ray from the hit towards it stays above the field at
//     pom_shadow_steps heights between the hit and z_max (hard shadows; 0 steps: none).
//  4. Environment light: its irradiance at the micro normal, unoccluded (no ambient occlusion).
// Limits: the base is taken as locally flat (curved bases bend nothing; silhouettes stay the
// base's), the view and light directions are clamped at 1/64 above the macro horizon, there is no
// interreflection (microgeom.depth's bounces are the paper's method's), and the linear search
// can step over features thinner than (z_max - z_min) / pom_steps along the ray.
#include "core/heightfield/heightfield.h"
#include "core/stage.h"

#include <vector>

namespace mesolab::microgeom {

// The heights in texel units above the base surface, and their range (the stage microgeom.pom_field).
struct PomField {
    int width = 0, height = 0;
    std::vector<float> z;   // (h - mean) / texel_size, row-major like the heightfield
    float z_min = 0, z_max = 0;
    static PomField from(const Heightfield& hf);
    // Bilinear, periodic, at texel coordinates (c, r) (texel (x, y) at (x, y)).
    float at(float c, float r) const { return sample_bilinear(z, width, height, true, c, r); }
    size_t bytes() const { return z.size() * sizeof(float); }
};

struct PomSettings {
    int steps = 32;         // microgeom.pom_steps
    int refine = 4;         // microgeom.pom_refine
    int shadow_steps = 32;  // microgeom.pom_shadow_steps (0: no self-shadowing)
};

// The smallest height of a direction above the macro horizon the march accepts (|w.z| below it is raised to it).
inline constexpr float kPomMinCos = 1.f / 64.f;

struct PomHit {
    float c = 0, r = 0, z = 0;  // texel coordinates and height of the hit
};
// The view ray's first hit with the field, from base point (c0, r0) with v the direction to the
// eye in the tangent frame (z along the macro normal).
PomHit pom_march(const PomField& f, float c0, float r0, vec3 v, int steps, int refine);
// 1 when the ray from (c, r, z) towards l (tangent frame) stays above the field at `steps`
// heights up to z_max, else 0; 0 for l at or below the macro horizon; 1 for steps = 0.
float pom_visibility(const PomField& f, float c, float r, float z, vec3 l, int steps);

namespace stages {
inline constexpr Stage<PomField> pom_field{"microgeom.pom_field"};
}  // namespace stages
}  // namespace mesolab::microgeom
