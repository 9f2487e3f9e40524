#pragma once
// [SECTION] The heightfield's parameters, declared once for every technique that shows one.
// heightfield_keys(): the procedural name or image (heightfield), resolution, height_scale,
// texel_size, periodic and the procedural shapes' parameters (vgroove_angle, rms_slope,
// correlation, seed). Each technique declares them in its own group (microgeom.resolution,
// bumpsynth.resolution, ...) with declare_heightfield_params, so that every technique can show the
// same surface from the same settings; the albedo and the albedo map are the technique's own.
#include "core/heightfield/heightfield.h"
#include "core/param.h"
#include "core/scene.h"
#include <functional>
#include <string>
#include <vector>

namespace mesolab {

const std::vector<std::string>& heightfield_keys();
// Declares heightfield_keys() in `p`. `each` may amend every declaration (e.g. bumpsynth marks
// them used only when its ndf is heightfield).
void declare_heightfield_params(ParamGroup& p, const std::function<void(ParamDecl&)>& each = {});
// The procedural parameters a material holds (its albedo too, where its group declares one).
ProceduralParams procedural_params(const ParamTable& material);
// The heightfield a material describes (procedural or image), without the albedo map; errors name
// the material's group (microgeom.resolution, bumpsynth.resolution, ...).
Heightfield heightfield_from_material(const Scene& s, const ParamTable& material);
}  // namespace mesolab
