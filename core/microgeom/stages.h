#pragma once
// Technique microgeom: the handles of its stages (core/stage.h), declared once. What each
// computes, and from which keys: microgeom.h; the declarations: stages.cpp.
#include "core/stage.h"

namespace mesolab {
struct Heightfield;
struct TriMesh;
}  // namespace mesolab

namespace mesolab::microgeom {
struct CurvedEllipses;
struct DirectionalScatter;
struct DirectionSet;
struct EllipseMap;
struct Importance;
struct LightScatter;
struct LightsScatter;
struct SimulatedBrdf;
struct Visibility;

namespace stages {
inline constexpr Stage<Heightfield> heightfield{"microgeom.heights"};
inline constexpr Stage<DirectionSet> directions{"microgeom.direction_set"};
inline constexpr Stage<Visibility> visibility{"microgeom.visibility"};
inline constexpr Stage<Importance> importance{"microgeom.importance"};
inline constexpr Stage<CurvedEllipses> ellipses_curved{"microgeom.ellipses_curved"};
inline constexpr Stage<EllipseMap> ellipses{"microgeom.ellipses"};
inline constexpr Stage<TriMesh> displaced{"microgeom.displaced"};
inline constexpr Stage<SimulatedBrdf> brdf{"microgeom.simulated_brdf"};
inline constexpr Stage<LightScatter> scatter_env{"microgeom.scatter_env"};
inline constexpr Stage<LightsScatter> scatter{"microgeom.scatter"};
inline constexpr Stage<DirectionalScatter> scatter_directions{"microgeom.scatter_directions"};
// The truth's explicit micro-geometry (lod.h, truth_surface): only `--backend truth` evaluates it.
inline constexpr Stage<TriMesh> truth_surface{"microgeom.truth_surface"};
}  // namespace stages
}  // namespace mesolab::microgeom
