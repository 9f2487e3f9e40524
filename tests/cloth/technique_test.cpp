// Technique cloth as users run it: CPU and GPU (llvmpipe) frames of a garment agree on every
// AOV; moving the light or changing the mip settings recomputes no stage, a fit setting refits
// without acquiring again; exported samples read back fit as well as the acquisition; holes show the
// background; the fit and eval commands work on measured samples and name bad input.
#include "app/workbench.h"
#include "core/cloth/stages.h"
#include "core/cloth/samples.h"
#include "core/cloth/cloth.h"
#include "core/error.h"
#include "core/scene.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <string>

using namespace mesolab;
using glm::dvec3;

namespace {

// A small fabric (8 x 8 points, 12 x 12 directions, a coarse stitch mesh) on a curtain lit from the front.
Scene small_curtain(const std::string& stitch = "knit") {
    Scene s = default_scene("cloth");
    apply_set(s, "cloth.stitch", stitch);
    apply_set(s, "cloth.stitch_resolution", "24");
    apply_set(s, "cloth.spatial", "8");
    apply_set(s, "cloth.directions", "12");
    apply_set(s, "cloth.visibility_rays", "8");
    apply_set(s, "cloth.garment_resolution", "32");
    apply_set(s, "cloth.repeat", "4");
    apply_set(s, "camera.orbit", "80,-90");
    apply_set(s, "light.direction", "50,-60");
    apply_set(s, "light.intensity", "3");
    return s;
}

bool all_finite(const Frame& f) {
    for (const auto& [name, img] : f.aovs)
        for (float v : img.data)
            if (!std::isfinite(v)) return false;
    return true;
}

RenderRequest cpu_request(int w, int h) {
    RenderRequest r;
    r.renderer = "cpu";
    r.width = w;
    r.height = h;
    return r;
}
}  // namespace

// [SECTION] CPU and GPU
// Radiance, normal and alpha to the technique's tolerances (ClothTechnique::agreement: the paths
// evaluate the same continuous functions of attributes the two rasterisers interpolate slightly
// differently; only a pixel within that difference of a border between two sample points reads
// another entry). The index read is that entry: equal at all but 0.1% of the pixels, and off
// edges but for the same allowance. The mip level comes from uv's differences across the pixel's
// quad on both: the relative difference of the footprints is about the attributes' (up to 3e-3
// pixel of their gradients, at each end of a one-pixel difference), so levels agree to 1e-2
// (log2 of 1 + 6e-3 is 9e-3) but where the two paths show another triangle (silhouettes).
TEST(ClothCpuGpu, AgreeOnEveryAovOfAGarment) {
    Workbench wb;
    const FrameAgreement cloth = test::agreement_of("cloth");
    for (const char* mip : {"blend", "off"}) {
        Scene s = small_curtain();
        apply_set(s, "cloth.mip", mip);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 200, 140);
        ASSERT_TRUE(all_finite(cpu) && all_finite(gpu)) << mip;
        test::expect_frames_agree(cpu, gpu, {"radiance", "normal", "alpha"}, cloth);
        test::expect_frames_agree(cpu, gpu, {"brdf_index"},
                                  {.tight = 0.5, .frac_tight = 0.999, .loose = 0.5, .frac_loose = 0.999, .interior_max = 0.5,
                                   .interior_outliers = cloth.interior_outliers});
        if (std::string(mip) == "blend")
            test::expect_frames_agree(cpu, gpu, {"mip_level"}, {.tight = 1e-2, .frac_tight = 0.999, .loose = 0.05, .frac_loose = 0.999, .interior_max = 1e-2});
    }
}

TEST(ClothCpuGpu, AgreeInTextureModeOnASleeve) {
    Workbench wb;
    Scene s = small_curtain("weave");
    apply_set(s, "cloth.garment", "sleeve");
    apply_set(s, "camera.mode", "texture");
    apply_set(s, "camera.orbit", "20,-90");
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 128, 128);
    test::expect_frames_agree(cpu, gpu, {"radiance", "alpha"}, test::agreement_of("cloth"));
}

// [SECTION] What a change reruns
TEST(ClothStages, LightAndMipChangesRecomputeNothingAndAFitSettingDoesNotAcquireAgain) {
    Workbench wb;
    Scene s = small_curtain();
    const RenderResult first = wb.render(s, cpu_request(64, 48));
    for (const StageName& st : std::vector<StageName>{cloth::stages::stitch, cloth::stages::acquire, cloth::stages::fit, cloth::stages::garment}) ASSERT_EQ(first.eval.run(st)->status, StageStatus::Ran) << st;
    apply_set(s, "light.direction", "30,-120");
    apply_set(s, "cloth.mip", "nearest");
    apply_set(s, "cloth.mip_bias", "1");
    apply_set(s, "cloth.repeat", "9");
    const RenderResult moved = wb.render(s, cpu_request(64, 48));
    for (const StageName& st : std::vector<StageName>{cloth::stages::stitch, cloth::stages::acquire, cloth::stages::fit, cloth::stages::garment}) EXPECT_EQ(moved.eval.run(st)->status, StageStatus::Cached) << st;
    apply_set(s, "cloth.lobes", "1");
    const RenderResult refit = wb.render(s, cpu_request(64, 48));
    EXPECT_EQ(refit.eval.run(cloth::stages::acquire)->status, StageStatus::Cached);
    EXPECT_EQ(refit.eval.run(cloth::stages::fit)->status, StageStatus::Ran);
}

// Acquire once: the exported samples, read back through cloth.samples, skip the stitch and the
// acquisition and fit as well as the acquisition itself.
TEST(ClothStages, ExportedSamplesReadBackSkipTheAcquisitionAndFitAsWell) {
    test::TempDir dir("cloth-samples");
    Workbench wb;
    Scene s = small_curtain("weave");
    const Evaluation a = wb.evaluate(s, Registry::instance().frame_stages(s));
    const auto grid = a.get(cloth::stages::acquire, 0);
    ASSERT_TRUE(grid);
    cloth::write_sample_grid(dir / "weave.samples", *grid);
    apply_set(s, "cloth.samples", dir / "weave.samples");
    apply_set(s, "cloth.stitch", "knit");  // ignored: the samples are read
    const Evaluation b = wb.evaluate(s, Registry::instance().frame_stages(s));
    EXPECT_EQ(b.run(cloth::stages::stitch)->status, StageStatus::Skipped);
    const auto pa = a.get(cloth::stages::fit, 0), pb = b.get(cloth::stages::fit, 0);
    ASSERT_TRUE(pa && pb);
    ASSERT_EQ(pa->count(), pb->count());
    // The file holds f_r in float: the fits start from values rounded to 7 digits, so an entry may
    // settle in another local minimum of equal quality; the fit errors agree on average.
    double ea = 0.0, eb = 0.0;
    for (size_t k = 0; k < pa->level.size(); ++k)
        for (size_t i = 0; i < pa->level[k].size(); ++i) ea += pa->report[k][i].rel_rms, eb += pb->report[k][i].rel_rms;
    EXPECT_NEAR(ea / double(pa->count()), eb / double(pb->count()), 0.01 * ea / double(pa->count()));
    // A bad file is an error naming it, not a crash.
    test::write_file(dir / "bad.samples", "not samples");
    apply_set(s, "cloth.samples", dir / "bad.samples");
    try {
        wb.evaluate(s, Registry::instance().frame_stages(s));
        FAIL() << "a bad samples file was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.samples"), std::string::npos) << e.what();
    }
}

// [SECTION] Holes
// Looking straight at a weave with wide gaps, the background shows through where alpha < 1:
// radiance there is the mix of the fabric and the environment, and the frame has both kinds of pixel.
TEST(ClothFrames, HolesShowTheBackground) {
    Workbench wb;
    Scene s = small_curtain("weave");
    apply_set(s, "cloth.yarn_radius", "0.2");
    apply_set(s, "cloth.spatial", "16");
    apply_set(s, "cloth.garment", "geometry");
    apply_set(s, "geometry.type", "plane");
    apply_set(s, "camera.orbit", "0,-90");
    apply_set(s, "cloth.mip", "off");
    apply_set(s, "cloth.repeat", "2");
    apply_set(s, "env.color", "0,0,1");
    const Frame f = wb.render(s, cpu_request(96, 96)).frame;
    size_t holes = 0, yarn = 0;
    for (float a : f.aov("alpha").data) holes += a < 0.01f, yarn += a > 0.99f;
    EXPECT_GT(holes, 100u);
    EXPECT_GT(yarn, 100u);
    // Through a hole the pixel is the environment's blue.
    for (size_t p = 0; p < f.aov("alpha").data.size(); ++p)
        if (f.aov("alpha").data[p] < 0.01f) {
            const float* L = &f.aov("radiance").data[p * 3];
            EXPECT_NEAR(L[2], 1.f, 0.02f);
            EXPECT_LT(L[0], 0.02f);
        }
}

// [SECTION] Commands on measured samples
TEST(ClothCommands, FitAndEvalMeasuredSamples) {
    test::TempDir dir("cloth-cmd");
    // Samples of k_d = (0.1, 0.2, 0.3) plus one lobe, two points.
    std::string csv = "point,lx,ly,lz,vx,vy,vz,r,g,b\n";
    const auto dirs = cloth::hemisphere_directions(10);
    for (const char* pt : {"a", "b"})
        for (const auto& l : dirs)
            for (const auto& v : dirs) {
                const double lobe = std::pow(std::max(0.0, -l.x * v.x - l.y * v.y + l.z * v.z), 8.0);
                char row[256];
                std::snprintf(row, sizeof row, "%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", pt, l.x, l.y, l.z, v.x, v.y, v.z, 0.1 + lobe,
                              0.2 + lobe, 0.3 + lobe);
                csv += row;
            }
    test::write_file(dir / "s.csv", csv);
    auto fit = test::run_mesolab("cloth fit '" + dir / "s.csv" + "' -o '" + dir / "m.json" + "' --lobes 1 --lookup-table off");
    ASSERT_EQ(fit.status, 0) << fit.err;
    EXPECT_NE(fit.out.find("fitted 2 point(s)"), std::string::npos) << fit.out;
    test::write_file(dir / "d.csv", "point,lx,ly,lz,vx,vy,vz\nb,0,0,1,0,0,1\na,0.6,0,0.8,-0.6,0,0.8\n");
    auto ev = test::run_mesolab("cloth eval '" + dir / "m.json" + "' '" + dir / "d.csv" + "' -o '" + dir / "v.csv" + "'");
    ASSERT_EQ(ev.status, 0) << ev.err;
    double r[2][3];
    ASSERT_EQ(std::sscanf(test::slurp(dir / "v.csv").c_str(), "%lf,%lf,%lf\n%lf,%lf,%lf", &r[0][0], &r[0][1], &r[0][2], &r[1][0], &r[1][1], &r[1][2]), 6);
    EXPECT_NEAR(r[0][0], 1.1, 1e-3);  // the lobe's peak: 0.1 + 1
    EXPECT_NEAR(r[0][2], 1.3, 1e-3);
    EXPECT_NEAR(r[1][1], 1.2, 1e-3);
    // Bad input: exit status 2 naming the line or the option; the model file is not clobbered.
    test::write_file(dir / "bad.csv", "lx,ly,lz,vx,vy,vz,r,g,b\n0,0,1,0,0,1,0.1,0.1,0.1\n0,0,1,0,0,-1,0.1,0.1,0.1\n");
    auto bad = test::run_mesolab("cloth fit '" + dir / "bad.csv" + "' -o '" + dir / "m.json" + "'");
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("bad.csv:3"), std::string::npos) << bad.err;
    auto lobes = test::run_mesolab("cloth fit '" + dir / "s.csv" + "' -o '" + dir / "m.json" + "' --lobes 7");
    EXPECT_EQ(lobes.status, 2);
    EXPECT_NE(lobes.err.find("--lobes"), std::string::npos) << lobes.err;
    auto again = test::run_mesolab("cloth eval '" + dir / "m.json" + "' '" + dir / "d.csv" + "' -o '" + dir / "v2.csv" + "'");
    EXPECT_EQ(again.status, 0) << again.err;
}

// [SECTION] Hard cases
TEST(ClothFrames, NoLightAGrazingViewAndTheObjectsOwnMeshStayFinite) {
    Workbench wb;
    Scene s = small_curtain();
    s.lights.clear();
    apply_set(s, "camera.orbit", "89.5,-90");
    EXPECT_TRUE(all_finite(wb.render(s, cpu_request(64, 48)).frame));
    s = small_curtain();
    apply_set(s, "cloth.garment", "geometry");
    apply_set(s, "geometry.type", "sphere");
    const Frame f = wb.render(s, cpu_request(64, 48)).frame;
    EXPECT_TRUE(all_finite(f));
    double sum = 0.0;
    for (float v : f.aov("radiance").data) sum += v;
    EXPECT_GT(sum, 0.0);
}

// The pyramid's tables share the acquisition's views (rotated into each entry's frame), so the GPU
// finds the three nearest once per pixel; the packed views are those directions.
TEST(ClothPacking, ThePyramidsTablesShareTheAcquisitionsViews) {
    Workbench wb;
    const Scene s = small_curtain("weave");
    const Evaluation ev = wb.evaluate(s, Registry::instance().frame_stages(s));
    const auto g = ev.get(cloth::stages::acquire, 0);
    const auto p = ev.get(cloth::stages::fit, 0);
    ASSERT_TRUE(g && p);
    const cloth::PackedPyramid packed = cloth::pack_pyramid(*p);
    ASSERT_EQ(packed.shared_views.size(), g->views.size());
    for (size_t i = 0; i < g->views.size(); ++i) EXPECT_LT(glm::length(dvec3(vec3(packed.shared_views[i])) - g->views[i]), 1e-6) << i;
    EXPECT_EQ(packed.data.size(), p->count() * size_t(packed.stride));
    EXPECT_EQ(packed.stride, 5 + 4 * 2 + 2 * int(g->views.size()));
}

// With few directions the lobes are barely constrained between samples (a base above 1 to a large
// exponent, which the table can even cancel at the samples): evaluated at many unseen directions,
// every entry stays finite and within twice its brightest sample (ClothBrdf::f_max).
TEST(ClothHardCases, SparseDirectionsStayBoundedBetweenSamples) {
    Workbench wb;
    Scene s = small_curtain("weave");
    apply_set(s, "cloth.directions", "6");
    const Evaluation ev = wb.evaluate(s, Registry::instance().frame_stages(s));
    const auto g = ev.get(cloth::stages::acquire, 0);
    const auto p = ev.get(cloth::stages::fit, 0);
    ASSERT_TRUE(g && p);
    const auto dense = cloth::hemisphere_directions(40, 0.0);
    size_t checked = 0;
    for (size_t k = 0; k < p->level.size(); ++k)
        for (size_t e = 0; e < p->level[k].size(); ++e) {
            const cloth::ClothBrdf& b = p->level[k][e];
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(b.f_max[c])) << k << " " << e;
            for (const dvec3& l : dense)
                for (const dvec3& v : dense) {
                    const dvec3 r = cloth::entry_reflectance(b, p->frame[k][e], l, v);
                    for (int c = 0; c < 3; ++c) {
                        ASSERT_TRUE(std::isfinite(r[c]) && r[c] >= 0.0) << k << " " << e;
                        ASSERT_LE(r[c], b.f_max[c] + 1e-12) << k << " " << e;
                    }
                    ++checked;
                }
        }
    double brightest = 0.0;
    for (const auto& point : g->f)
        for (const dvec3& f : point) brightest = std::max({brightest, f.x, f.y, f.z});
    for (const auto& level : p->level)
        for (const cloth::ClothBrdf& b : level)  // an entry's samples carry cos θ_l / cos θ̂_l <= 1 / 0.05 (pyramid.h)
            EXPECT_LE(std::max({b.f_max.x, b.f_max.y, b.f_max.z}), 2.0 * brightest / cloth::kFittedLightZ + 1e-9);
    EXPECT_EQ(checked, p->count() * dense.size() * dense.size());
}
