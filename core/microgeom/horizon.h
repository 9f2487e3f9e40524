#pragma once
// [SECTION] Horizon mapping: microgeom.method = horizon
// Shadows and ambient visibility of the heightfield from per-texel horizon angles (Max 1988,
// "Horizon mapping: shadows for bump-mapped surfaces", The Visual Computer 4; Sloan and Cohen
// 2000, "Interactive horizon mapping", EGWR), with the multi-bounce fit of ground-truth ambient
// occlusion for the light the field reflects onto itself (Jimenez, Wu, Pesce and Jarabo 2016,
// "Practical realtime strategies for accurate indirect occlusion", SIGGRAPH course; their eq. 10).
//
// Units: texel space as in parallax occlusion mapping (pom.h): (c, r) texel coordinates, heights
// z = (h - mean h) / texel_size in texels (the stage microgeom.pom_field), so slopes are
// dimensionless and angles true.
//
// [SECTION] The map (the stage microgeom.horizon_map)
// For each texel (x, y) and each of n = horizon_directions azimuths φ_j = 2π j / n (direction
// (cos φ_j, sin φ_j) in the tangent frame: +c along x, -r along y), the horizon's elevation
//     θ_j(x, y) = atan max_{t} (z(p + t d_j) - z(p)) / t,    R = horizon_radius texels
// over t at every texel centre the direction passes (axes, diagonals; other directions: every
// texel) up to R, and at R itself
// with z bilinear and periodic; stored as sin θ_j (may be negative on a peak). Along an axis the
// samples fall on texel centres, where the bilinear surface is piecewise linear with vertices at the
// centres: (z(t) - z0)/t is monotonic between vertices, so the maximum over the samples is the exact
// horizon of the surface within R. Along a diagonal the samples fall on centres too, exact where the
// field is linear between them (the V-groove: tested); elsewhere, and in other directions (samples
// one texel apart), a narrow ridge between two samples can be missed.
//
// [SECTION] Shading (at the base point, no parallax)
// The heightfield's bilinear normal and albedo as the bump level reads them. A light at azimuth φ
// and elevation θ_l in the tangent frame is seen where sin θ_l > sin θ(φ), θ(φ) interpolated
// linearly between the two nearest azimuths and bilinearly between texels (Sloan and Cohen's
// linear basis): hard shadows. The environment's irradiance at the micro normal is scaled by the
// ambient visibility
//     A = 1 - (1/n) Σ_j max(0, sin θ_j)²
// (the cosine-weighted fraction of the hemisphere above the horizon about the macro normal: a
// slice of azimuth whose horizon rises to θ keeps 1 - sin²θ of its cosine weight), then by GTAO's
// multi-bounce fit with the albedo ρ:
//     A' = max(A, ((a A + b) A + c) A),  a = 2.0404 ρ - 0.3324, b = -4.7951 ρ + 0.6417, c = 2.7552 ρ + 0.6903
// (per colour channel). Limits: the visibility is about the macro normal, not the micro normal; no
// parallax (the base point is shaded); the sun's light reflected inside the field (the paper's
// `depth`) is missing, only the environment's gets the multi-bounce fit; horizons beyond R texels
// are not seen; between azimuths the interpolated horizon can miss a narrow gap or ridge.
#include "core/microgeom/pom.h"
#include "core/stage.h"

#include <vector>

namespace mesolab::microgeom {

struct HorizonMap {
    int width = 0, height = 0, directions = 0;
    std::vector<float> sin_theta;  // [direction][row][column]
    float at(int j, int x, int y) const { return sin_theta[(size_t(j) * size_t(height) + size_t(y)) * size_t(width) + size_t(x)]; }
    size_t bytes() const { return sin_theta.size() * sizeof(float); }
    // The horizon's sin θ towards the azimuth φ (radians, tangent frame) at texel coordinates (c, r):
    // bilinear between texels (periodic), linear between the two nearest azimuths.
    float sin_horizon(float c, float r, float phi) const;
    // The ambient visibility A at (c, r) (bilinear).
    float ambient(float c, float r) const;
};

// The map of `f` with n directions and radius R texels (InputError naming the key for n < 1 or R < 1).
HorizonMap make_horizon_map(const PomField& f, int directions, int radius);

// GTAO's multi-bounce fit A' (Jimenez et al. 2016) of visibility A for albedo rho.
inline float gtao_multibounce(float A, float rho) {
    const float a = 2.0404f * rho - 0.3324f, b = -4.7951f * rho + 0.6417f, c = 2.7552f * rho + 0.6903f;
    const float v = ((a * A + b) * A + c) * A;
    return v > A ? v : A;
}

namespace stages {
inline constexpr Stage<HorizonMap> horizon_map{"microgeom.horizon_map"};
}  // namespace stages
}  // namespace mesolab::microgeom
