#pragma once
// Technique cloth: the handles of its stages (core/stage.h), declared once. What each computes:
// technique.h; the declarations: the technique's stage graph.
#include "core/stage.h"

namespace mesolab {
struct TriMesh;
}  // namespace mesolab

namespace mesolab::cloth {
struct StitchMesh;
struct SampleGrid;
struct BrdfPyramid;
struct TruthFabric;

namespace stages {
inline constexpr Stage<StitchMesh> stitch{"cloth.stitch_mesh"};        // the stitch's micro-geometry
inline constexpr Stage<SampleGrid> acquire{"cloth.acquire"};      // virtual acquisition
inline constexpr Stage<BrdfPyramid> fit{"cloth.fit"};             // the fitted BRDF array and its mip levels
inline constexpr Stage<TriMesh> garment{"cloth.garment_mesh"};         // the procedural garment drawn
inline constexpr Stage<TruthFabric> truth_stitch{"cloth.truth_stitch"};  // the truth's tile of yarns (truth.h)
inline constexpr Stage<TruthFabric> truth_fabric{"cloth.truth_fabric"};  // the truth's yarns over the garment
}  // namespace stages
}  // namespace mesolab::cloth
