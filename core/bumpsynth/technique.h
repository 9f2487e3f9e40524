#pragma once
// Technique bumpsynth's own internals, shared by the files that implement it (other modules use
// bumpsynth.h and stages.h). BumpsynthTechnique's members are defined by concern, in the files
// every technique uses for them (README.md, "How it is built"):
//   technique.cpp  the parameters and AOVs, the frame's stages and texture size, the agreement, the sweep metric
//   stages.cpp     the stage graph (declare_stages)
//   shading.cpp    CPU shading (shade_cpu)
//   bench.cpp      the timing tables (bench_tables)
// The materials' readers are in bumpsynth.cpp, the BRDF and the synthesis in brdf.cpp.
#include "core/bumpsynth/bumpsynth.h"
#include "core/heightfield/params.h"
#include "core/technique.h"
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace mesolab::bumpsynth {

// [SECTION] The keys the stages read, and when they run
// The bump map an NDF may come from (ndf = normal_map | heightfield, §7): the normal map and the
// heightfield's own keys (core/heightfield/params.h: the same surface as in microgeom).
inline std::vector<std::string> source_keys() {
    std::vector<std::string> k{"ndf", "normal_map", "normal_map_encoding", "normal_map_y"};
    for (const auto& h : heightfield_keys()) k.push_back(h);
    return k;
}
inline const std::vector<std::string> kSourceKeys = source_keys();
inline const std::vector<std::string> kNdfKeys = [] {
    std::vector<std::string> k{"alpha_x", "alpha_y", "rotation", "exponent", "lobes", "ndf_image", "ndf_resolution"};
    k.insert(k.begin(), kSourceKeys.begin(), kSourceKeys.end());
    return k;
}();
inline const std::vector<std::string> kNoiseKeys{"noise_frequency", "noise_gain", "noise_seed", "octaves_max"};

inline std::vector<std::string> keys(const std::vector<std::string>& names) {
    std::vector<std::string> out;
    for (const auto& n : names) out.push_back("bumpsynth." + n);
    return out;
}
inline bool from_bump_map(const SceneObject& o) {
    const std::string& n = o.material.get_string("ndf");
    return n == "normal_map" || n == "heightfield";
}
// §7: the bump map's own normals through the index texture instead of noise.
inline bool index_mode(const SceneObject& o) { return from_bump_map(o) && o.material.get_bool("index_map"); }
inline bool noise_inputs_needed(const SceneObject& o) { return !index_mode(o); }
inline bool texture_noise(const SceneObject& o) { return !index_mode(o) && o.material.get_string("noise") == "texture"; }
inline bool masking(const SceneObject& o) { return o.material.get_bool("masking"); }

// [SECTION] The truth's surface (truth.cpp)
// The NDF the truth shades and synthesises with, whatever bumpsynth.ndf_resolution and lut_size:
// tabulated at kTruthNdfResolution cells per side and inverted exactly (Lut::sample_uniform, no
// entries); its Smith table with masking on; with index_map on, the bump map's index texture into it.
// A bump map's histogram is tabulated at the finest resolution (at least 64) that keeps 2 normals per
// cell of the disk or more: finer, it is a sum of spikes, and a highlight on its flat parts a
// scatter of sparkles that no number of samples resolves. That is the kernel the truth states for
// delta lights on near-mirror facets: one cell of its NDF.
inline constexpr int kTruthNdfResolution = 512;
inline int truth_ndf_resolution(const BumpNormals* histogram) {
    if (!histogram) return kTruthNdfResolution;
    const double r = std::sqrt(double(histogram->m.size()) / (2.0 * 0.785398));
    return std::clamp(int(r), 64, kTruthNdfResolution);
}
struct TruthNdf {
    Ndf ndf;
    Lut lut;
    std::optional<SmithTable> smith;
    std::optional<IndexMap> index_map;
};
// The bump normal at uv that the truth integrates (and LEAN mapping bakes): its inputs at K octaves
// (the noise through `cdfs`, or the index map with `detail`) mapped to a normal by the exact inversion
// of t's NDF (truth.cpp).
vec3 truth_bump_normal(const TruthNdf& t, const NoiseCdfs* cdfs, const IndexDetail& detail, vec2 uv, int K);
// The index map's detail the truth adds (index_map on; else a default IndexDetail).
IndexDetail truth_index_detail(const TruthNdf& t, const ParamTable& m);

// [SECTION] The technique
class BumpsynthTechnique final : public Technique {
public:
    BumpsynthTechnique();
    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override;
    // The paper's frame stages, which kautz-consistent shares (its tables: stages::consistent).
    static std::vector<StageName> pipeline_stages();
    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override;
    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<BenchTable> bench_tables() const override;
    FrameAgreement agreement() const override;
    std::vector<SweepMetricDecl> sweep_metrics() const override;
    std::optional<TruthDecl> truth() const override;
};
}  // namespace mesolab::bumpsynth
