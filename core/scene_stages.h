#pragma once
// Scene-level stages every frame uses, whatever the techniques:
//   scene.geometry  — per object: tessellate its procedural shape / read its mesh file (object
//                     space, a TriMesh); loading one object's mesh never reloads the others'
//   env.map         — read the lat-long environment EXR (absent when env.map is "")
//   env.irradiance  — SH9 projection of env.map, needed only by effects.environment
#include "core/env.h"
#include "core/mesh.h"
#include "core/stage.h"
#include <vector>

namespace mesolab {

// The scene-wide stages' handles (core/stage.h).
namespace stages {
inline constexpr Stage<TriMesh> geometry{"scene.geometry"};
inline constexpr Stage<Image> env_map{"env.image"};
inline constexpr Stage<SH9> env_irradiance{"env.irradiance"};
}  // namespace stages

void declare_scene_stages(StageGraph& g);
// The object -> world matrix of an object (geometry.scale, geometry.position).
mat4 object_to_world(const SceneObject& o);
}  // namespace mesolab
