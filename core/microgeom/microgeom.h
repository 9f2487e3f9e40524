#pragma once
// Technique `microgeom`: Heidrich, Daubert, Kautz, Seidel 2000, "Illuminating Micro Geometry
// Based on Precomputed Visibility". A heightfield (procedural or an image) applied as a bump map
// to the object's (u,v) space (tiled `microgeom.tiling` times; 1:1 in camera.mode=texture), lit
// with exact shadows from the visibility textures S_i (§4) and with light scattered inside the
// heightfield by the Method of Dependent Tests (§3).
//
// Stages (results hold one entry per scene object; objects with equal settings share it):
//   microgeom.heightfield  heights and albedo                (microgeom.heightfield, resolution, ...)
//   microgeom.directions   N directions + triangulation      (microgeom.directions)
//   microgeom.visibility   S_i                               (heightfield, directions)  — never the light
//   microgeom.scatter_env  environment light scattered        (visibility, env.*, depth)      effects.environment
//   microgeom.scatter      the first light scattered          (visibility, light.*, depth)    effects.indirect
//
// Scope of this version (see the issue notes): micro-BRDF Lambertian for every bounce (the
// Blinn-Phong lobe applies to the direct light seen by the viewer); the scattering solution uses
// the first light; on non-planar base geometry its light-driven part is computed for light along
// the macro normal and scaled by the macro cosine. Not yet: ellipse shadows, curvature (§5),
// geometry/BRDF levels of detail, BTF export, GPU compute of S_i and scattering.
#include "core/microgeom/directions.h"
#include "core/microgeom/heightfield.h"
#include "core/microgeom/scatter.h"
#include "core/microgeom/visibility.h"
#include "core/param.h"
#include <memory>
#include <vector>

namespace mesolab::microgeom {

// A stage result with one entry per scene object (null for objects using other techniques).
template <class T>
struct PerObject {
    std::vector<std::shared_ptr<const T>> items;
    const T* get(int object) const { return size_t(object) < items.size() ? items[size_t(object)].get() : nullptr; }
};

// The light-driven scattering solution of one object: unit irradiance from `light_dir`.
struct LightScatter {
    ScatterResult result;
    vec3 light_dir{0, 0, 1};  // local frame
    bool planar = true;       // light_dir is the real light's (plane) or the macro normal (curved base)
};

ProceduralParams procedural_params(const ParamTable& material);
}  // namespace mesolab::microgeom
