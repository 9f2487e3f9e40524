// Technique bumpsynth: the stage graph (handles in stages.h).
#include "core/basic/basic.h"
#include "core/bumpsynth/consistent.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/error.h"

namespace mesolab::bumpsynth {

void BumpsynthTechnique::declare_stages(StageGraph& g) const {
    // Every stage is an object stage: one result per object, shared by objects with equal keys.
    const auto object = [](StageDecl d) {
        d.scope = StageScope::Object;
        d.technique = "bumpsynth";
        return d;
    };
    const auto when = [](bool (*f)(const SceneObject&)) { return [f](const Scene&, const SceneObject& o) { return f(o); }; };
    g.add(stages::bump_normals, object({.help = "Read the bump map (a normal map, or a heightfield's normals) whose histogram is the NDF (§7)",
                  .params = keys(kSourceKeys),
                  .applies = when(from_bump_map),
                  .when_text = "bumpsynth.ndf is normal_map or heightfield",
                  .run = [](StageContext& ctx) { return stage_result(stages::bump_normals, bump_normals_from_material(ctx.scene, ctx.material())); }}));
    g.add(stages::ndf, object({.help = "Tabulate the normal density function over the normal's (x, y) disk",
                  .params = keys(kNdfKeys),
                  .inputs = {stages::bump_normals},
                  .memory = [](const StageContext& ctx) {
                      const double R = double(ctx.material().get_int("ndf_resolution"));
                      return MemoryEstimate{R * R * 2.0 * sizeof(double), "NDF: " + std::to_string(int(R)) + "^2 cells", {"bumpsynth.ndf_resolution"}};
                  },
                  .run = [](StageContext& ctx) {
                      const auto n = ctx.input(stages::bump_normals);
                      const ParamTable& m = ctx.material();
                      if (n) {
                          // A histogram with fewer normals than cells is spiky: highlights sparkle.
                          const double R = double(m.get_int("ndf_resolution")), cells = 0.785398 * R * R;
                          const double per_cell = double(n->m.size()) / cells;
                          if (per_cell < 2.0) {
                              char msg[320];
                              std::snprintf(msg, sizeof msg,
                                            "the NDF of a %dx%d bump map at %dx%d cells has %.2g normals per cell of the disk, so it is "
                                            "spiky (highlights sparkle); lower bumpsynth.ndf_resolution (to %d or less) or use a larger map",
                                            n->width, n->height, int(R), int(R), per_cell,
                                            std::max(64, int(std::sqrt(double(n->m.size()) / (2.0 * 0.785398)))));
                              ctx.warn(msg);
                          }
                      }
                      return stage_result(stages::ndf, ndf_from_material(ctx.scene, m, n.get()));
                  }}));
    g.add(stages::lut, object({.help = "Invert the NDF's marginal and conditional CDFs into the normal look-up table L(r1, r2) with tangent frames (§4)",
                  .params = keys({"lut_size"}),
                  .inputs = {stages::ndf},
                  .memory = [](const StageContext& ctx) {
                      const double n = double(ctx.material().get_int("lut_size"));
                      return MemoryEstimate{n * n * double(sizeof(LutEntry)), "look-up table: " + std::to_string(int(n)) + "^2 entries",
                                            {"bumpsynth.lut_size"}};
                  },
                  .run = [](StageContext& ctx) {
                      return stage_result(stages::lut, build_lut(*ctx.input(stages::ndf), int(ctx.material().get_int("lut_size"))));
                  }}));
    g.add(stages::index_map, object({.help = "Turn the bump map's normals into an index texture of look-up-table inputs (§7)",
                  .params = keys({"index_map"}),
                  .inputs = {stages::bump_normals, stages::lut},
                  .applies = when(index_mode),
                  .when_text = "bumpsynth.index_map is on",
                  .run = [](StageContext& ctx) {
                      return stage_result(stages::index_map, make_index_map(*ctx.input(stages::bump_normals), *ctx.input(stages::lut)));
                  }}));
    g.add(stages::noise_cdf, object({.help = "Measure the CDF G_k of the fractal noise for every octave count k (§4)",
                  .params = keys(kNoiseKeys),
                  .applies = when(noise_inputs_needed),
                  .when_text = "an object synthesises its bumps from noise (bumpsynth.index_map off)",
                  .run = [](StageContext& ctx) { return stage_result(stages::noise_cdf, measure_noise_cdfs(noise_from_material(ctx.material()))); }}));
    g.add(stages::noise_texture, object({.help = "Bake the mip-mapped noise texture: each coarser level one octave less (§5.2.2)",
                  .params = keys({"noise", "noise_texture_size"}),
                  .inputs = {stages::noise_cdf},
                  .applies = when(texture_noise),
                  .when_text = "bumpsynth.noise is texture",
                  .memory = [](const StageContext& ctx) {
                      const double n = double(ctx.material().get_int("noise_texture_size"));
                      // Two channels of floats over the mip chain (4/3 of the finest level).
                      return MemoryEstimate{n * n * 4.0 / 3.0 * 2.0 * sizeof(float), "noise texture: " + std::to_string(int(n)) + "^2 texels with mip levels",
                                            {"bumpsynth.noise_texture_size"}};
                  },
                  .run = [](StageContext& ctx) {
                      return stage_result(stages::noise_texture, make_noise_texture(*ctx.input(stages::noise_cdf), int(ctx.material().get_int("noise_texture_size"))));
                  }}));
    g.add(stages::masking, object({.help = "Tabulate the Smith masking function G1 of the NDF",
                  .params = keys({"masking"}),
                  .inputs = {stages::ndf},
                  .applies = when(masking),
                  .when_text = "bumpsynth.masking is on",
                  .run = [](StageContext& ctx) { return stage_result(stages::masking, SmithTable::build(*ctx.input(stages::ndf))); }}));
    g.add(stages::truth_ndf, object({.help = "Tabulate the truth's NDF (512^2 cells; a bump map's histogram at 2 normals per cell or more), its exact inversion, Smith table (masking on) and index texture (index_map on)",
                  .params = [] {
                      std::vector<std::string> k;
                      for (const auto& key : keys(kNdfKeys))
                          if (key != "bumpsynth.ndf_resolution") k.push_back(key);
                      k.push_back("bumpsynth.masking");
                      k.push_back("bumpsynth.index_map");
                      return k;
                  }(),
                  .inputs = {stages::bump_normals},
                  .memory = [](const StageContext&) {
                      const double R = kTruthNdfResolution;
                      return MemoryEstimate{R * R * 4.0 * sizeof(double), "truth NDF: 512^2 cells and their CDFs", {}};
                  },
                  .run = [](StageContext& ctx) {
                      const auto n = ctx.input(stages::bump_normals);
                      const ParamTable& m = ctx.material();
                      TruthNdf t{ndf_from_material(ctx.scene, m, n.get(), truth_ndf_resolution(n.get())), {}, {}, {}};
                      t.lut = build_lut(t.ndf, Lut::kMinSize);
                      if (m.get_bool("masking")) t.smith = SmithTable::build(t.ndf);
                      if (n && from_bump_map(ctx.obj()) && m.get_bool("index_map")) t.index_map = make_index_map(*n, t.lut);
                      return stage_result(stages::truth_ndf, std::move(t));
                  }}));
    g.add(stages::consistent, object({.help = "Measure, for every octave count, the NDF the unresolved octaves' bumps produce (D self-convolved at 0 octaves), "
                                              "its mean normal and Smith table (masking on)",
                  .params = [] {
                      std::vector<std::string> k = keys({"method", "consistent_samples", "octaves_max", "masking", "index_noise"});
                      for (const auto& key : keys(kNoiseKeys)) k.push_back(key);
                      return k;
                  }(),
                  .inputs = {stages::ndf, stages::lut, stages::index_map, stages::noise_cdf, stages::noise_texture},
                  .applies = [](const Scene&, const SceneObject& o) { return o.material.get_string("method") == "kautz-consistent"; },
                  .when_text = "bumpsynth.method is kautz-consistent",
                  .run = [](StageContext& ctx) {
                      const ParamTable& m = ctx.material();
                      const auto ndf = ctx.input(stages::ndf);
                      const auto lut = ctx.input(stages::lut);
                      const auto index = ctx.input(stages::index_map);
                      const auto cdfs = ctx.input(stages::noise_cdf);
                      const auto tex = ctx.input(stages::noise_texture);
                      Synthesis syn;
                      syn.ndf = ndf.get();
                      syn.lut = lut.get();
                      syn.octaves_max = int(m.get_int("octaves_max"));
                      if (index) {
                          syn.index_map = index.get();
                          syn.index_detail = index_detail(*index, noise_from_material(m), float(m.get_float("index_noise")));
                      } else {
                          if (!cdfs) throw std::logic_error("bumpsynth/kautz-consistent: no noise CDFs for a noise-synthesised object");
                          syn.cdfs = cdfs.get();
                          syn.noise_texture = tex.get();
                      }
                      return stage_result(stages::consistent,
                                          build_consistent_ndfs(*ndf, [&](vec2 uv, int k) { return synthesis_facet(syn, uv, k); }, syn.octaves_max,
                                                                int(m.get_int("consistent_samples")), m.get_bool("masking")));
                  }}));
    g.add(stages::albedo, object({.help = "Read the object's albedo map",
                  .params = {"bumpsynth.albedo_map"},
                  .run = [](StageContext& ctx) -> std::any {
                      auto img = basic::read_albedo_map(ctx.scene, ctx.material());
                      return img ? stage_result(stages::albedo, std::move(*img)) : std::any();
                  }}));
}
}  // namespace mesolab::bumpsynth
