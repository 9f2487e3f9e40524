#pragma once
// Environment lighting: a constant colour or a lat-long EXR, times an intensity, seen whenever
// a ray leaves the scene. Lat-long mapping (shared with the GPU shaders):
//   theta = angle from +z (0 at the top row), phi = atan2(y, x) in [0, 2pi) from +x;
//   u = phi / 2pi (column), v = theta / pi (row from the top). Bilinear lookup, u wraps.
#include "core/image.h"
#include "core/math.h"
#include <array>
#include <memory>

namespace mesolab {

struct Environment {
    vec3 color{0.f};    // used where there is no map
    float intensity = 1.f;
    std::shared_ptr<const Image> map;  // lat-long, linear; null or empty = constant colour (shared, never copied per frame)

    // dir need not be normalised; a zero-length (or non-finite) dir gives color * intensity.
    // Texel centres sit at ((i + 0.5) / width, (j + 0.5) / height) in (u, v), as GL sampling.
    vec3 radiance(vec3 dir) const;
    // True when radiance() is color * intensity in every direction (no usable map).
    bool constant() const { return !map || map->empty() || map->width <= 0 || map->height <= 0 || map->channels <= 0; }
};

// Order-2 spherical harmonics (9 coefficients per colour channel) of the environment radiance,
// and the irradiance they imply (Ramamoorthi & Hanrahan 2001). For a constant environment L,
// irradiance(n) == pi * L exactly. A map is projected treating each texel as constant over its
// (theta, phi) rectangle, with the basis integrated exactly over it (the texel weights sum to
// 4 pi); parallel (TBB) but bit-identical for any thread count. A 1- or 2-channel map is read as
// grey. sh9_irradiance of a zero-length n gives the mean (band-0) irradiance.
struct SH9 {
    std::array<vec3, 9> c{};
};
SH9 project_sh9(const Environment& env);
vec3 sh9_irradiance(const SH9& sh, vec3 n);
}  // namespace mesolab
