#pragma once
// Technique bumpsynth: the handles of its stages (core/stage.h), declared once. What each computes:
// bumpsynth.h; the declarations: the technique's stage graph.
#include "core/stage.h"

namespace mesolab {
struct Image;
}  // namespace mesolab

namespace mesolab::bumpsynth {
struct BumpNormals;
class Ndf;
class Lut;
struct IndexMap;
struct NoiseCdfs;
struct NoiseTexture;
class SmithTable;
struct TruthNdf;
struct LeanMap;
struct ConsistentNdfs;

namespace stages {
inline constexpr Stage<BumpNormals> bump_normals{"bumpsynth.bump_normals"};
inline constexpr Stage<Ndf> ndf{"bumpsynth.ndf_table"};
inline constexpr Stage<Lut> lut{"bumpsynth.lut"};
inline constexpr Stage<IndexMap> index_map{"bumpsynth.index_texture"};
inline constexpr Stage<NoiseCdfs> noise_cdf{"bumpsynth.noise_cdf"};
inline constexpr Stage<NoiseTexture> noise_texture{"bumpsynth.noise_texture"};
inline constexpr Stage<SmithTable> masking{"bumpsynth.smith_table"};
inline constexpr Stage<Image> albedo{"bumpsynth.albedo"};
inline constexpr Stage<TruthNdf> truth_ndf{"bumpsynth.truth_ndf"};
inline constexpr Stage<LeanMap> lean_map{"bumpsynth.lean_map"};  // method lean (lean.h)
inline constexpr Stage<ConsistentNdfs> consistent{"bumpsynth.consistent_ndf"};  // method kautz-consistent (consistent.h)
}  // namespace stages
}  // namespace mesolab::bumpsynth
