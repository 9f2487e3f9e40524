#pragma once
// Technique translucency: the handles of its stages and frame steps (core/stage.h), declared
// once. What each computes: translucency.h; the declarations: the technique's stage graph.
#include "core/math.h"
#include "core/stage.h"
#include <map>
#include <vector>

namespace mesolab::translucency {
struct PreparedMesh;
struct AtlasStage;
struct LocalKernels;
struct VertexFactors;
struct Blended;
struct Gather;
struct VertexValues;
struct Maps;
// One value per object of the technique, by object index (a frame step's output).
template <class T>
using PerObject = std::map<int, T>;

namespace stages {
inline constexpr Stage<PreparedMesh> mesh{"translucency.mesh"};
inline constexpr Stage<AtlasStage> atlas{"translucency.atlas"};
inline constexpr Stage<LocalKernels> kernels{"translucency.kernels"};
inline constexpr Stage<VertexFactors> factors{"translucency.factors"};
inline constexpr Stage<Blended> blend{"translucency.blended"};
inline constexpr Stage<Gather> gather{"translucency.gather"};
inline constexpr Stage<std::vector<vec3>> albedo{"translucency.albedo"};  // rho per texel
}  // namespace stages

// The frame steps, in the order a frame runs them.
namespace steps {
inline constexpr FrameStep<PerObject<std::vector<vec3>>> illumination{"translucency.illumination"};  // E per texel
inline constexpr FrameStep<PerObject<VertexValues>> vertices{"translucency.vertex_values"};
inline constexpr FrameStep<PerObject<std::vector<vec3>>> local{"translucency.local"};  // local response per texel
inline constexpr FrameStep<PerObject<std::vector<vec3>>> global{"translucency.global"};  // global response per vertex
inline constexpr FrameStep<PerObject<Maps>> combine{"translucency.combine"};
inline constexpr FrameStep<PerObject<std::vector<vec3>>> reference{"translucency.reference"};  // brute force per texel
}  // namespace steps
}  // namespace mesolab::translucency
