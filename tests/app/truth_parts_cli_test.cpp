// `mesolab capture --backend truth --samples A:B` writes partial truths and `mesolab truth merge`
// joins them into the truth rendered at once (its PNG and EXRs the same bytes, its sidecar saying
// what it holds); `--noise` stops a truth at its noise and the sidecar says so; bad requests exit 2
// with a message naming the option or the file.
#include "core/image.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

using namespace mesolab;

namespace {
nlohmann::json sidecar(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}
std::string bytes_of(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}
const char* kPreset = "presets/basic/sphere.json";
}  // namespace

TEST(TruthPartsCli, PartsMergeIntoTheTruthRenderedAtOnce) {
    test::TempDir dir("truth-parts-cli");
    const std::string env = "MESOLAB_CACHE_DIR='" + (dir / "cache") + "'";
    const std::string common = std::string("capture ") + kPreset + " --backend truth --size 24x24 --seed 3 ";
    auto run = [&](const std::string& args) {
        const test::CliResult r = test::run_mesolab(args, env);
        EXPECT_EQ(r.status, 0) << args << "\n" << r.err;
        return r;
    };
    run(common + "--spp 10 --aov truth_stderr -o '" + (dir / "whole") + "'");
    run(common + "--samples 6:10 -o '" + (dir / "parts") + "'");
    run(common + "--samples 0:6 -o '" + (dir / "parts") + "'");
    const test::CliResult m = run("truth merge '" + (dir / "parts/basic-sphere.samples-6-10.truth") + "' '" + (dir / "parts/basic-sphere.samples-0-6.truth") +
                                  "' --aov truth_stderr -o '" + (dir / "merged") + "'");
    EXPECT_NE(m.out.find("samples 0:10"), std::string::npos) << m.out;
    EXPECT_EQ(bytes_of(dir / "merged/basic-sphere.png"), bytes_of(dir / "whole/basic-sphere.png"));
    const Image a = read_image(dir / "merged/basic-sphere.truth_stderr.exr", false, false), b = read_image(dir / "whole/basic-sphere.truth_stderr.exr", false, false);
    EXPECT_EQ(a.data, b.data);
    const nlohmann::json j = sidecar(dir / "merged/basic-sphere.json");
    EXPECT_EQ(j["truth"]["spp"], 10);
    EXPECT_EQ(j["truth"]["seed"], 3);
    EXPECT_EQ(j["truth"]["parts"].size(), 2u);
    EXPECT_TRUE(std::filesystem::exists(dir / "merged/basic-sphere.samples-0-10.truth"));
    // Kept in the truth cache: a capture of the same scene, size and seed reads it.
    const test::CliResult again = run(common + "--spp 10 -o '" + (dir / "again") + "'");
    EXPECT_EQ(sidecar(dir / "again/basic-sphere.json")["truth"]["cached_spp"], 10);
    // Bad input names what is wrong, with exit status 2.
    const test::CliResult bad = test::run_mesolab(common + "--samples 4:2 -o '" + (dir / "x") + "'", env);
    EXPECT_NE(bad.err.find("--samples 4:2"), std::string::npos) << bad.err;
    const test::CliResult cpu = test::run_mesolab(std::string("capture ") + kPreset + " --backend cpu --samples 0:4 -o '" + (dir / "x") + "'", env);
    EXPECT_EQ(cpu.status, 2);
    EXPECT_NE(cpu.err.find("needs --backend truth"), std::string::npos) << cpu.err;
    std::ofstream(dir / "junk.truth") << "not a truth";
    const test::CliResult junk = test::run_mesolab("truth merge '" + (dir / "junk.truth") + "' -o '" + (dir / "x") + "'", env);
    EXPECT_EQ(junk.status, 2);
    EXPECT_NE(junk.err.find("junk.truth: not a partial truth"), std::string::npos) << junk.err;
}

TEST(TruthPartsCli, ANoiseTargetEndsTheTruthThereAndTheSidecarSaysSo) {
    test::TempDir dir("truth-noise-cli");
    const std::string env = "MESOLAB_CACHE_DIR='" + (dir / "cache") + "'";
    const test::CliResult r = test::run_mesolab(std::string("capture ") + kPreset + " --backend truth --size 24x24 --noise 0.05 --time-limit 10m -o '" + (dir / "out") + "'", env);
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json t = sidecar(dir / "out/basic-sphere.json")["truth"];
    EXPECT_EQ(t["ended"], "noise");
    EXPECT_LE(t["noise_rel"].get<double>(), 0.05);
    EXPECT_GE(t["spp"].get<int>(), 16);
    EXPECT_EQ(t["noise_target"], 0.05);
    EXPECT_EQ(t["time_limit_s"], 600.0);
    const test::CliResult bad = test::run_mesolab(std::string("capture ") + kPreset + " --backend truth --time-limit soon -o '" + (dir / "out") + "'", env);
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("--time-limit soon"), std::string::npos) << bad.err;
    const test::CliResult noise = test::run_mesolab(std::string("capture ") + kPreset + " --backend truth --noise 5 -o '" + (dir / "out") + "'", env);
    EXPECT_EQ(noise.status, 2);
    EXPECT_NE(noise.err.find("--noise 5"), std::string::npos) << noise.err;
}
