// Headless capture of the basic technique: deterministic bytes, CPU and GPU agree, AOV EXRs
// hold the analytic values, the sidecar says what ran, and --backend cpu works without GL.
#include "app/workbench.h"
#include "core/scene_stages.h"
#include "core/basic/stages.h"
#include "core/image.h"
#include "core/scene.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <cmath>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::test;

namespace {

// A plane seen in texture mode from straight above, one directional light: every texel has the
// same analytic radiance.
const char* kPlane = R"({
  "schema": 1, "name": "plane-analytic",
  "camera": {"mode": "texture", "orbit": [0, 0]},
  "lights": [{"type": "directional", "direction": [30, 0], "intensity": 2, "color": [1, 0.5, 0.25]}],
  "env": {"color": [0.1, 0.2, 0.3], "intensity": 1.5},
  "objects": [{"geometry": {"type": "plane", "resolution": 8},
               "material": {"technique": "basic", "kd": [0.5, 0.4, 0.3], "ks": [0.2, 0.2, 0.2], "shininess": 20}}]
})";

// Written out from basic.h's model, not through basic::brdf: n = wo = +z, wi at 30 degrees from n
// in the xz plane, so n.wi = cos 30 and n.h = cos 15 (h halves the angle between wo and wi);
//   L = (kd/pi + ks (s + 8)/(8 pi) cos^s 15deg) E cos 30deg + kd/pi * (pi L_env).
vec3 analytic_plane() {
    const double pi = 3.14159265358979323846, deg = pi / 180.0, s = 20.0;
    const double kd[3] = {0.5, 0.4, 0.3}, ks = 0.2, E[3] = {2.0 * 1.0, 2.0 * 0.5, 2.0 * 0.25}, env[3] = {0.1 * 1.5, 0.2 * 1.5, 0.3 * 1.5};
    const double lobe = ks * (s + 8.0) / (8.0 * pi) * std::pow(std::cos(15.0 * deg), s);
    vec3 L;
    for (int c = 0; c < 3; ++c) L[c] = float((kd[c] / pi + lobe) * E[c] * std::cos(30.0 * deg) + kd[c] * env[c]);
    return L;
}

}  // namespace

TEST(Capture, AovExrsHoldTheAnalyticValuesOnBothBackends) {
    TempDir dir("analytic");
    write_file(dir / "plane.json", kPlane);
    const vec3 want = analytic_plane();
    for (const char* backend : {"cpu", "gpu"}) {
        SCOPED_TRACE(backend);
        const std::string out = dir / backend;
        const CliResult r = run_mesolab(std::string("capture --backend ") + backend + " --size 64x48 --aov radiance --aov normal -o '" + out + "' '" +
                                        (dir / "plane.json") + "'");
        ASSERT_EQ(r.status, 0) << r.err;
        const Image rad = read_image(out + "/plane-analytic.radiance.exr");
        const Image nrm = read_image(out + "/plane-analytic.normal.exr");
        ASSERT_EQ(rad.width, 64);
        ASSERT_EQ(rad.height, 48);
        ASSERT_EQ(rad.channels, 3);
        for (int y = 0; y < rad.height; ++y)
            for (int x = 0; x < rad.width; ++x) {
                for (int c = 0; c < 3; ++c) ASSERT_NEAR(rad.at(x, y)[c], want[c], 2e-5 * want[c] + 1e-6) << x << "," << y;
                ASSERT_NEAR(nrm.at(x, y)[2], 1.0, 1e-6);
            }
    }
}

// Two captures of one preset, the second pinned to one CPU (one TBB thread, one llvmpipe thread)
// while the first uses every core: the work splits differently, the files must not differ.
TEST(Capture, SamePresetOnAllCoresAndOnOneGivesIdenticalBytes) {
    TempDir dir("determinism");
    const std::string preset = source_path("presets/basic/sphere.json");
    for (const char* backend : {"gpu", "cpu"}) {
        for (const char* run : {"a", "b"}) {
            const std::string prefix = std::string(run) == "b" ? "taskset -c 0 env LP_NUM_THREADS=1" : "";
            const CliResult r = run_mesolab(std::string("capture --backend ") + backend + " --size 160x120 --aov radiance -o '" + (dir / (std::string(backend) + run)) +
                                                "' '" + preset + "'",
                                            prefix);
            ASSERT_EQ(r.status, 0) << r.err;
        }
        for (const char* f : {"/basic-sphere.png", "/basic-sphere.radiance.exr"}) {
            const std::string a = slurp(dir / (std::string(backend) + "a") + f), b = slurp(dir / (std::string(backend) + "b") + f);
            EXPECT_FALSE(a.empty());
            EXPECT_EQ(a, b) << backend << f;
        }
    }
}

// Tolerance: interiors agree to float rounding (< 2e-3 absolute on radiance of order 1);
// silhouette pixels may differ where the two rasterisers' coverage differs: at most 0.5% of pixels.
TEST(Capture, CpuAndGpuAgree) {
    Workbench wb;
    for (const char* setup : {"geometry.type=sphere", "geometry.type=torus", "camera.mode=texture"}) {
        SCOPED_TRACE(setup);
        Scene s = load_preset(source_path("presets/basic/sphere.json"));
        apply_set(s, setup);
        const auto [cpu, gpu] = render_cpu_and_gpu(wb, s, 200, 150);
        for (const char* aov : {"radiance", "normal"}) {
            ASSERT_TRUE(cpu.has(aov) && gpu.has(aov)) << aov;
            const Image &a = cpu.aov(aov), &b = gpu.aov(aov);
            ASSERT_EQ(a.width, 200);
            ASSERT_EQ(a.height, 150);
            ASSERT_EQ(a.data.size(), b.data.size());
            ASSERT_EQ(a.data.size(), size_t(200 * 150 * 3));
            size_t off = 0, drawn = 0;
            for (size_t p = 0; p < size_t(a.width) * size_t(a.height); ++p) {
                float d = 0;
                bool nonzero = false;
                for (int c = 0; c < 3; ++c) {
                    d = std::max(d, std::fabs(a.data[p * 3 + size_t(c)] - b.data[p * 3 + size_t(c)]));
                    nonzero = nonzero || a.data[p * 3 + size_t(c)] != 0.f;
                }
                off += d > 2e-3f;
                drawn += nonzero;
            }
            EXPECT_GT(double(drawn), 0.05 * a.width * a.height) << aov << ": the object covers too few pixels to compare";
            EXPECT_LE(double(off), 0.005 * a.width * a.height) << aov << ": " << off << " pixels differ by more than 2e-3";
        }
    }
}

namespace {
// The sidecar's entries for stage `name` (object stages: one per object they ran for).
std::vector<nlohmann::json> stage_entries(const nlohmann::json& sidecar, const std::string& name) {
    std::vector<nlohmann::json> found;
    for (const auto& st : sidecar.at("stages"))
        if (st.at("name") == name) found.push_back(st);
    return found;
}

// The single entry of an object stage for object 0, the preset's "sphere".
void expect_object_stage(const nlohmann::json& sidecar, const std::string& name, const std::string& status) {
    const std::vector<nlohmann::json> e = stage_entries(sidecar, name);
    ASSERT_EQ(e.size(), 1u) << name << ": one entry per object, and the preset has one";
    EXPECT_EQ(e[0].value("status", ""), status) << name;
    EXPECT_EQ(e[0].value("object", -1), 0) << name;
    EXPECT_EQ(e[0].value("object_name", ""), "sphere") << name;
}
}  // namespace

TEST(Capture, SidecarSaysWhatRanWithWhichRenderer) {
    TempDir dir("sidecar");
    const std::string preset = source_path("presets/basic/sphere.json");
    const CliResult r = run_mesolab("capture --backend cpu --size 32x32 -o '" + dir.path.string() + "' '" + preset + "' --set light.intensity=5");
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(dir / "basic-sphere.json"));
    EXPECT_EQ(j["renderer"], "cpu");
    EXPECT_FALSE(j["version"].get<std::string>().empty());
    EXPECT_EQ(j["parameters"]["lights"][0]["intensity"], 5.0);
    ASSERT_TRUE(j["stages"].is_array());
    ASSERT_FALSE(j["stages"].empty());
    for (const auto& st : j["stages"]) {
        const std::string status = st.value("status", "");
        EXPECT_TRUE(status == "ran" || status == "cached" || status == "skipped") << st.dump();
    }
    // Object stages: once per object, named; scene stages: once, without an object.
    expect_object_stage(j, "scene.geometry", "ran");
    expect_object_stage(j, "basic.albedo", "ran");
    const std::vector<nlohmann::json> irradiance = stage_entries(j, mesolab::stages::env_irradiance);
    ASSERT_EQ(irradiance.size(), 1u);
    EXPECT_EQ(irradiance[0].value("status", ""), "ran");
    EXPECT_FALSE(irradiance[0].contains("object"));
    // basic has no frame steps; without --aov the frame holds the radiance only (AOVs on demand),
    // while every AOV the scene could render is listed.
    ASSERT_TRUE(j["frame_steps"].is_array());
    EXPECT_TRUE(j["frame_steps"].empty()) << j["frame_steps"].dump();
    EXPECT_EQ(j["aovs_rendered"], nlohmann::json::array({"radiance"}));
    EXPECT_EQ(j["aovs_available"], nlohmann::json::array({"radiance", "normal"}));
    EXPECT_TRUE(j["timings"].contains("render_ms"));
    // The same capture with the environment effect off skips its stage, and says why.
    const CliResult r2 = run_mesolab("capture --backend cpu --size 32x32 -o '" + dir.path.string() + "' '" + preset + "' --set effects.environment=false");
    ASSERT_EQ(r2.status, 0) << r2.err;
    const auto j2 = nlohmann::json::parse(slurp(dir / "basic-sphere.json"));
    const std::vector<nlohmann::json> skipped = stage_entries(j2, mesolab::stages::env_irradiance);
    ASSERT_EQ(skipped.size(), 1u) << "a skipped stage is still listed";
    EXPECT_EQ(skipped[0].value("status", ""), "skipped");
    EXPECT_NE(skipped[0].value("reason", "").find("effects.environment is off"), std::string::npos) << skipped[0].dump();
    expect_object_stage(j2, "basic.albedo", "ran");
}

TEST(Capture, SecondRenderReusesEveryStage) {
    Workbench wb;
    Scene s = load_preset(source_path("presets/basic/sphere.json"));
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    const RenderResult first = wb.render(s, req);
    ASSERT_NE(first.eval.run(mesolab::stages::geometry), nullptr);
    EXPECT_EQ(first.eval.run(mesolab::stages::geometry)->status, StageStatus::Ran);
    apply_set(s, "light.direction=70,200");
    const RenderResult r = wb.render(s, req);
    ASSERT_EQ(r.eval.runs.size(), first.eval.runs.size());
    for (const StageName& stage : std::vector<StageName>{mesolab::stages::geometry, basic::stages::albedo, mesolab::stages::env_irradiance}) {
        ASSERT_NE(r.eval.run(stage), nullptr) << stage;
        EXPECT_EQ(r.eval.run(stage)->status, StageStatus::Cached) << stage;
    }
    for (const auto& run : r.eval.runs) EXPECT_NE(run.status, StageStatus::Ran) << run.name;
}

TEST(Capture, CpuBackendWorksWithoutGl) {
    TempDir dir("nogl");
    const std::string preset = source_path("presets/basic/sphere.json");
    const std::string no_gl = "env EGL_PLATFORM=none __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json __EGL_VENDOR_LIBRARY_DIRS=/nonexistent";
    const CliResult gpu = run_mesolab("capture --backend gpu --size 32x32 -o '" + dir.path.string() + "' '" + preset + "'", no_gl);
    EXPECT_EQ(gpu.status, 1) << gpu.err;
    EXPECT_NE(gpu.err.find("--backend cpu"), std::string::npos) << gpu.err;
    const CliResult cpu = run_mesolab("capture --backend cpu --size 32x32 -o '" + dir.path.string() + "' '" + preset + "'", no_gl);
    EXPECT_EQ(cpu.status, 0) << cpu.err;
}
