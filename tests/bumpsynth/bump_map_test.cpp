// bumpsynth §7: existing bump maps. Their NDF (a normal map's or a heightfield's normal histogram),
// the same heightfield as microgeom, the index texture (round trip, texel centres, wrapping), detail
// noise when zooming in, the stages that run, rendering the map's own normals, CPU vs GPU, bad maps.
#include "app/workbench.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/bump_map.h"
#include "core/bumpsynth/bumpsynth.h"
#include "core/heightfield/params.h"
#include "core/image.h"
#include "core/scene.h"
#include "support/cli.h"
#include "support/errors.h"
#include "support/frames.h"
#include "stats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {

Heightfield gaussian_field(float rms_slope, int resolution = 256, float correlation = 3.f) {
    ProceduralParams p;
    p.name = "gaussian";
    p.resolution = resolution;
    p.rms_slope = rms_slope;
    p.correlation = correlation;
    p.seed = 7;
    return make_procedural(p);
}

// A bumpsynth scene whose NDF is a procedural heightfield's (plane, texture mode at full detail).
Scene heightfield_scene(const char* field, bool index_map, bool texture_mode = true) {
    Scene s = default_scene("bumpsynth");
    apply_set(s, "geometry.type", "plane");
    if (texture_mode) apply_set(s, "camera.mode", "texture");
    apply_set(s, "bumpsynth.ndf", "heightfield");
    apply_set(s, "bumpsynth.heightfield", field);
    apply_set(s, "bumpsynth.resolution", "64");
    apply_set(s, "bumpsynth.index_map", index_map ? "true" : "false");
    return s;
}
}  // namespace

// [SECTION] NDF sources
// A Gaussian random surface with RMS slope m (central differences) has Beckmann's NDF with α = m:
// each slope component is normal with variance m²/2 = α²/2. The histogram of its 256² normals has
// that variance within 5% (the field has ~256²/(π·3²) independent patches), and over 16 x 16 bins
// of the disk it is within a total variation of 0.06 of the Beckmann table (the sampling noise of
// ~2,000 independent patches is ~0.04).
TEST(BumpsynthBumpMap, GaussianHeightfieldHasBeckmannsNdfWithAlphaTheRmsSlope) {
    const float m = 0.3f;
    const Ndf hist = Ndf::from_normals(normals_of(gaussian_field(m)).m, 64);
    const Ndf beckmann = Ndf::from_lobe(Lobe::beckmann(m, m), 64);
    double sx = 0.0, sy = 0.0, total = 0.0;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) {
            const vec2 c = hist.cell_centre(i, j);
            const double z2 = std::max(1e-6, 1.0 - double(glm::dot(c, c)));
            sx += hist.mass(i, j) * c.x * c.x / z2, sy += hist.mass(i, j) * c.y * c.y / z2;
            total += hist.mass(i, j);
        }
    EXPECT_NEAR(total, 1.0, 1e-9);
    EXPECT_NEAR(sx, m * m / 2.0, 0.05 * m * m / 2.0);
    EXPECT_NEAR(sy, m * m / 2.0, 0.05 * m * m / 2.0);
    double tv = 0.0;
    for (int J = 0; J < 16; ++J)
        for (int I = 0; I < 16; ++I) {
            double p = 0.0, q = 0.0;
            for (int j = 4 * J; j < 4 * J + 4; ++j)
                for (int i = 4 * I; i < 4 * I + 4; ++i) p += hist.mass(i, j), q += beckmann.mass(i, j);
            tv += 0.5 * std::fabs(p - q);
        }
    std::printf("[          ] Gaussian field (rms slope %.2f): slope variances %.5f, %.5f (Beckmann %.5f), TV %.4f\n", m, sx, sy, m * m / 2.0, tv);
    EXPECT_LT(tv, 0.06);
}

// bumpsynth declares the heightfield's keys as microgeom does (core/heightfield/params.h), so with
// ndf = heightfield the same settings give the same surface in both techniques; and errors name
// bumpsynth's keys.
TEST(BumpsynthBumpMap, HeightfieldSettingsGiveMicrogeomsSurface) {
    Scene s = default_scene("bumpsynth");
    apply_set(s, "bumpsynth.ndf", "heightfield");
    Scene g = default_scene("microgeom");
    for (const auto& [k, v] : std::vector<std::pair<std::string, std::string>>{
             {"heightfield", "gaussian"}, {"resolution", "48"}, {"rms_slope", "0.7"}, {"correlation", "2.5"}, {"seed", "11"}, {"height_scale", "0.5"}}) {
        apply_set(s, "bumpsynth." + k, v);
        apply_set(g, "microgeom." + k, v);
    }
    const Heightfield field = heightfield_from_material(g, g.objects[0].material);
    const BumpNormals ours = bump_normals_from_material(s, s.objects[0].material);
    ASSERT_EQ(ours.width, 48);
    ASSERT_EQ(ours.height, 48);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) ASSERT_EQ(ours.at(x, y), field.normal(x, y)) << x << ", " << y;

    apply_set(s, "bumpsynth.resolution", "8");
    apply_set(s, "bumpsynth.correlation", "16");
    test::expect_input_error([&] { bump_normals_from_material(s, s.objects[0].material); }, {"bumpsynth.correlation"});
    EXPECT_THROW(apply_set(g, "microgeom.index_map", "true"), InputError);  // bumpsynth's keys stay bumpsynth's
}

// Normal maps: 2v - 1 or as stored, y up or down, normalised.
TEST(BumpsynthBumpMap, NormalMapsDecodeTheirEncodingAndConvention) {
    const std::vector<float> px{0.5f, 0.5f, 1.f, 1.f, 0.5f, 0.5f, 0.5f, 1.f, 1.f};  // 3 x 1, RGB
    const BumpNormals u = decode_normal_map(px, 3, 1, 3, {}, "map.png");
    EXPECT_NEAR(glm::distance(u.at(0, 0), vec3(0, 0, 1)), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(u.at(1, 0), vec3(1, 0, 0)), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(u.at(2, 0), glm::normalize(vec3(0, 1, 1))), 0.f, 1e-6f);
    const BumpNormals d = decode_normal_map(px, 3, 1, 3, {NormalEncoding::unsigned_unit, true}, "map.png");
    EXPECT_NEAR(glm::distance(d.at(2, 0), glm::normalize(vec3(0, -1, 1))), 0.f, 1e-6f);
    const std::vector<float> sp{0.f, 0.f, 2.f, 0.6f, 0.f, 0.8f};
    const BumpNormals s = decode_normal_map(sp, 2, 1, 3, {NormalEncoding::signed_unit, false}, "map.exr");
    EXPECT_NEAR(glm::distance(s.at(0, 0), vec3(0, 0, 1)), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(s.at(1, 0), vec3(0.6f, 0, 0.8f)), 0.f, 1e-6f);
}

TEST(BumpsynthBumpMap, BadNormalMapsAreClearErrors) {
    test::expect_input_error([] { decode_normal_map({0.5f, 0.5f}, 2, 1, 1, {}, "gray.png"); }, {"gray.png", "3 channels", "has 1"});
    test::expect_input_error([] { decode_normal_map({0.5f, 0.5f, 0.5f}, 1, 1, 3, {}, "zero.png"); }, {"zero.png", "texel (0, 0)", "no direction"});
    test::expect_input_error([] { decode_normal_map({0.f, 0.f, 1.f, 0.f, 0.f, -1.f}, 2, 1, 3, {NormalEncoding::signed_unit, false}, "under.exr"); },
                             {"under.exr", "texel (1, 0)", "below the surface", "normal_map_encoding"});
    // A signed map read as unsigned: z = 2 * 0.2 - 1 < 0, caught with the hint.
    test::expect_input_error([] { decode_normal_map({0.f, 0.f, 0.2f}, 1, 1, 3, {}, "signed.exr"); }, {"signed.exr", "below the surface"});

    test::TempDir dir("bumpsynth-normal-map");
    Image nan_map(2, 2, 3, 0.5f);
    nan_map.at(1, 1)[2] = std::nanf("");
    const std::string nan_path = (dir.path / "nan.exr").string();
    write_exr(nan_path, nan_map);
    Scene s = default_scene("bumpsynth");
    apply_set(s, "bumpsynth.ndf", "normal_map");
    test::expect_input_error([&] { ndf_from_material(s, s.objects[0].material); }, {"bumpsynth.normal_map", "no image"});
    apply_set(s, "bumpsynth.normal_map", nan_path);
    test::expect_input_error([&] { ndf_from_material(s, s.objects[0].material); }, {"nan.exr", "NaN"});
    test::expect_input_error([&] { apply_set(s, "bumpsynth.normal_map", (dir.path / "missing.png").string()); }, {"bumpsynth.normal_map", "missing.png", "not found"});
}

// A normal map read from a file: its NDF holds exactly its normals' cells.
TEST(BumpsynthBumpMap, NormalMapFileGivesItsHistogram) {
    test::TempDir dir("bumpsynth-normal-map-file");
    Image map(4, 4, 3);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            const vec3 n = x < 2 ? vec3(0, 0, 1) : glm::normalize(vec3(0.5f, 0, 1));
            for (int c = 0; c < 3; ++c) map.at(x, y)[c] = 0.5f * n[c] + 0.5f;
        }
    const std::string path = (dir.path / "two.exr").string();
    write_exr(path, map);
    Scene s = default_scene("bumpsynth");
    apply_set(s, "bumpsynth.ndf", "normal_map");
    apply_set(s, "bumpsynth.normal_map", path);
    const Ndf ndf = ndf_from_material(s, s.objects[0].material);
    double at_normal = 0.0, at_tilt = 0.0;
    const float h = ndf.cell_size();
    const auto cell = [&](float x) { return int(std::floor((x + 1.f) / h)); };
    at_normal = ndf.mass(cell(0.f), cell(0.f));
    at_tilt = ndf.mass(cell(glm::normalize(vec3(0.5f, 0, 1)).x), cell(0.f));
    EXPECT_NEAR(at_normal, 0.5, 1e-9);
    EXPECT_NEAR(at_tilt, 0.5, 1e-9);
}

// [SECTION] Index texture
// normal -> index texture -> normal within 1e-3 wherever the NDF is non-zero (it is at every texel's
// own normal, since the NDF is their histogram), over a whole Gaussian field.
TEST(BumpsynthBumpMap, IndexTextureRoundTripsEveryTexelsNormal) {
    const BumpNormals n = normals_of(gaussian_field(0.5f, 128));
    const Ndf ndf = Ndf::from_normals(n.m, 128);
    const Lut lut = build_lut(ndf, 256);
    const IndexMap map = make_index_map(n, lut);
    double worst = 0.0;
    for (int y = 0; y < n.height; ++y)
        for (int x = 0; x < n.width; ++x) {
            const vec2 u = map.at(x, y);
            ASSERT_TRUE(u.x >= 0.f && u.x <= 1.f && u.y >= 0.f && u.y <= 1.f);
            worst = std::max(worst, double(glm::distance(lut.sample(u).m, n.at(x, y))));
        }
    std::printf("[          ] worst round-trip error over 128^2 texels: %.2e\n", worst);
    EXPECT_LT(worst, 1e-3);
}

// Bilinear like GL_LINEAR + GL_REPEAT: exact at texel centres, the mean of the first and last
// column at u = 0 (wrapping), row 0 at the top.
TEST(BumpsynthBumpMap, IndexTextureIsBilinearBetweenTexelCentresAndWraps) {
    IndexMap m;
    m.width = 4, m.height = 2;
    for (int i = 0; i < 8; ++i) m.u.push_back(vec2(float(i) / 8.f, 1.f - float(i) / 8.f));
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const vec2 uv((float(x) + 0.5f) / 4.f, 1.f - (float(y) + 0.5f) / 2.f);
            EXPECT_NEAR(glm::distance(m.bilinear(uv), m.at(x, y)), 0.f, 1e-6f) << x << ", " << y;
        }
    EXPECT_NEAR(glm::distance(m.bilinear(vec2(0.f, 0.75f)), 0.5f * (m.at(0, 0) + m.at(3, 0))), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(m.bilinear(vec2(1.f, 0.75f)), m.bilinear(vec2(0.f, 0.75f))), 0.f, 1e-6f);
}

// Detail: k = 1 is the map itself; more octaves stay in [0, 1] and within a / (1 - gain) of the
// map (before folding); amplitude 0 adds nothing; the fold is continuous and 2-periodic.
TEST(BumpsynthBumpMap, DetailNoiseStaysInTheTableAndNearTheMap) {
    EXPECT_FLOAT_EQ(reflect_unit(0.25f), 0.25f);
    EXPECT_FLOAT_EQ(reflect_unit(1.25f), 0.75f);
    EXPECT_FLOAT_EQ(reflect_unit(-0.25f), 0.25f);
    EXPECT_FLOAT_EQ(reflect_unit(2.25f), 0.25f);
    IndexMap m;
    m.width = m.height = 16;
    test::Rng rng(5);
    for (int i = 0; i < 256; ++i) m.u.push_back(vec2(float(rng.uniform()), float(rng.uniform())));
    NoiseParams np;
    np.octaves_max = 6;
    const IndexDetail none = index_detail(m, np, 0.f), d = index_detail(m, np, 0.04f);
    EXPECT_EQ(d.noise.base_frequency, 16);
    double moved = 0.0;
    for (int i = 0; i < 2000; ++i) {
        const vec2 uv(float(rng.uniform()), float(rng.uniform()));
        const vec2 base = m.bilinear(uv);
        EXPECT_EQ(index_inputs(m, d, uv, 1), base);
        EXPECT_EQ(index_inputs(m, none, uv, 6), base);
        for (int k = 2; k <= 6; ++k) {
            const vec2 u = index_inputs(m, d, uv, k);
            ASSERT_TRUE(u.x >= 0.f && u.x <= 1.f && u.y >= 0.f && u.y <= 1.f);
            // Folding only brings a value closer to where it started from inside [0, 1].
            EXPECT_LE(std::fabs(u.x - base.x), 0.04f / 0.5f + 1e-5f);
            EXPECT_LE(std::fabs(u.y - base.y), 0.04f / 0.5f + 1e-5f);
            moved += glm::distance(u, base);
        }
    }
    EXPECT_GT(moved / (2000.0 * 5), 0.005);  // the detail is really there
}

// [SECTION] Through the stages and the renderers
// Only what the scene calls for runs: no bump map, no noise CDFs with an index map, no index map
// with noise.
TEST(BumpsynthBumpMap, StagesRunOnlyWhenTheBumpMapIsUsed) {
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    Scene plain = default_scene("bumpsynth");
    apply_set(plain, "geometry.type", "plane");
    const RenderResult a = wb.render(plain, req);
    EXPECT_EQ(a.eval.run(bumpsynth::stages::bump_normals)->status, StageStatus::Skipped);
    EXPECT_EQ(a.eval.run(bumpsynth::stages::index_map)->status, StageStatus::Skipped);
    EXPECT_EQ(a.eval.run(bumpsynth::stages::noise_cdf)->status, StageStatus::Ran);
    const RenderResult b = wb.render(heightfield_scene("bumps", false, false), req);
    EXPECT_EQ(b.eval.run(bumpsynth::stages::bump_normals)->status, StageStatus::Ran);
    EXPECT_EQ(b.eval.run(bumpsynth::stages::index_map)->status, StageStatus::Skipped);
    EXPECT_EQ(b.eval.run(bumpsynth::stages::noise_cdf)->status, StageStatus::Cached);
    // 64² normals over 128² cells: the user is told the histogram is spiky and what to do.
    const auto& warnings = b.eval.run(bumpsynth::stages::ndf)->warnings;
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("bumpsynth.ndf_resolution"), std::string::npos) << warnings[0];
    EXPECT_TRUE(a.eval.run(bumpsynth::stages::ndf)->warnings.empty());
    const RenderResult c = wb.render(heightfield_scene("bumps", true, false), req);
    EXPECT_EQ(c.eval.run(bumpsynth::stages::bump_normals)->status, StageStatus::Cached);
    EXPECT_EQ(c.eval.run(bumpsynth::stages::index_map)->status, StageStatus::Ran);
    EXPECT_EQ(c.eval.run(bumpsynth::stages::noise_cdf)->status, StageStatus::Skipped);
}

// Texture mode with one octave renders the bump map's own normals, one pixel per texel: the
// nearest table entry of each texel's index, within the table's quantisation (1/256 in u).
TEST(BumpsynthBumpMap, TextureModeRendersTheMapsOwnNormals) {
    Scene s = heightfield_scene("gaussian", true);
    apply_set(s, "bumpsynth.octaves_max", "1");
    apply_set(s, "bumpsynth.rms_slope", "0.4");
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const RenderResult r = wb.render(s, req);
    const Image& nrm = r.frame.aov("normal");
    ASSERT_EQ(nrm.width, 64);
    ASSERT_EQ(nrm.height, 64);
    const BumpNormals n = bump_normals_from_material(s, s.objects[0].material);
    const auto lut = r.eval.get(bumpsynth::stages::lut, 0);
    const auto map = r.eval.get(bumpsynth::stages::index_map, 0);
    std::vector<double> err;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const float* q = nrm.at(x, y);
            const vec3 m(q[0], q[1], q[2]);
            ASSERT_NEAR(glm::distance(m, lut->lookup(map->at(x, y)).m), 0.f, 1e-6f) << x << ", " << y;
            err.push_back(glm::distance(m, n.at(x, y)));
        }
    std::sort(err.begin(), err.end());
    std::printf("[          ] rendered vs the map's normals: median %.4f, 99th percentile %.4f, worst %.4f\n", err[err.size() / 2],
                err[err.size() * 99 / 100], err.back());
    EXPECT_LT(err[err.size() / 2], 0.01);
}

// In texture space (uv exact on both backends) the index texture, the detail noise and the shading
// agree as tightly as the noise path. Seen in perspective, the rasterisers' uv differ by ~1e-6, and
// the index texture magnifies that by W |Δu| (W texels, Δu between neighbouring texels up to ~1):
// 256 x 1e-6 moves the inputs by ~1e-4, so ~2% of the inputs, those within that of a table cell's
// edge, take the neighbouring entry. Those are still neighbouring normals: within 2e-2 but for a few
// in a thousand.
TEST(BumpsynthBumpMap, CpuAndGpuAgreeWithAnIndexMapAndDetail) {
    Workbench wb;
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    apply_set(s, "bumpsynth.ndf", "heightfield");
    apply_set(s, "bumpsynth.heightfield", "gaussian");
    apply_set(s, "bumpsynth.rms_slope", "0.4");
    apply_set(s, "bumpsynth.resolution", "256");
    apply_set(s, "bumpsynth.ndf_resolution", "64");
    apply_set(s, "bumpsynth.index_map", "true");
    apply_set(s, "bumpsynth.index_noise", "0.05");
    {
        Scene t = s;
        apply_set(t, "camera.mode", "texture");
        apply_set(t, "bumpsynth.octaves_max", "2");
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, t);
        ASSERT_EQ(cpu.aov("normal").width, 512);
        test::expect_frames_agree(cpu, gpu, {"radiance", "normal", "octaves"}, test::agreement_of("bumpsynth"));
    }
    for (const char* d : {"40", "3", "0.3"}) {
        SCOPED_TRACE(d);
        apply_set(s, "camera.distance", d);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 120);
        if (std::string(d) == "40") {  // beyond the detail distance: no octaves on either
            test::expect_frames_agree(cpu, gpu, {"radiance", "normal"}, test::agreement_of("bumpsynth"));
            test::expect_all_zero(cpu, "octaves");
            test::expect_all_zero(gpu, "octaves");
        } else {
            test::expect_frames_agree(cpu, gpu, {"radiance", "normal", "octaves"}, test::agreement_of("bumpsynth"));
        }
    }
}

// The same surface in both techniques: a heightfield shaded as microgeom's bump map (Lambert, no
// shadows, no scattering) and as bumpsynth's index map with a Lambert term only (ks = 0) give the
// same image in texture space, up to the look-up table's quantisation of the normals.
TEST(BumpsynthBumpMap, IndexMapShowsTheSameSurfaceAsMicrogeomsBumpMap) {
    const auto scene = [](const char* technique) {
        Scene s = default_scene(technique);
        apply_set(s, "geometry.type", "plane");
        apply_set(s, "camera.mode", "texture");
        apply_set(s, "env.color", "0,0,0");
        const std::string t = technique;
        for (const auto& [k, v] : std::vector<std::pair<std::string, std::string>>{{"heightfield", "gaussian"}, {"resolution", "64"}, {"rms_slope", "0.5"}})
            apply_set(s, t + "." + k, v);
        return s;
    };
    Scene g = scene("microgeom");
    apply_set(g, "microgeom.shadows", "none");
    apply_set(g, "microgeom.depth", "0");
    apply_set(g, "microgeom.albedo", "0.8,0.8,0.8");
    apply_set(g, "effects.indirect", "false");
    Scene b = scene("bumpsynth");
    apply_set(b, "bumpsynth.ndf", "heightfield");
    apply_set(b, "bumpsynth.index_map", "true");
    apply_set(b, "bumpsynth.octaves_max", "1");
    apply_set(b, "bumpsynth.lut_size", "1024");
    apply_set(b, "bumpsynth.ks", "0,0,0");
    apply_set(b, "bumpsynth.kd", "0.8,0.8,0.8");
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const Image ig = wb.render(g, req).frame.aov("radiance"), ib = wb.render(b, req).frame.aov("radiance");
    ASSERT_EQ(ig.width, 64);
    ASSERT_EQ(ib.width, 64);
    std::vector<double> rel;
    double mean_g = 0.0, mean_b = 0.0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const double a = ig.at(x, y)[0], c = ib.at(x, y)[0];
            mean_g += a, mean_b += c;
            rel.push_back(std::fabs(a - c) / std::max(1e-3, a));
        }
    std::sort(rel.begin(), rel.end());
    std::printf("[          ] microgeom vs bumpsynth: mean %.4f vs %.4f; relative difference median %.2e, 99th percentile %.2e\n", mean_g / 4096,
                mean_b / 4096, rel[rel.size() / 2], rel[rel.size() * 99 / 100]);
    EXPECT_NEAR(mean_b / mean_g, 1.0, 0.01);
    EXPECT_LT(rel[rel.size() / 2], 0.01);
}
