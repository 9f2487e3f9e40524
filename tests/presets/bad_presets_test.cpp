// Every kind of bad preset gives exit status 2 and one clear message naming the file and key;
// `preset validate` accepts every shipped preset.
#include "support/cli.h"

#include <gtest/gtest.h>

using namespace mesolab::test;

namespace {

struct BadCase {
    const char* name;
    const char* json;        // nullptr: the file is not created
    const char* must_say[3]; // substrings of stderr
};

const BadCase kCases[] = {
    {"unknown_key_suggests", R"({"schema":1,"objects":[{"geometry":{"type":"sphere"},"material":{"technique":"basic","shininnes":10}}]})",
     {"objects[0].material.shininnes", "unknown key", "did you mean 'shininess'"}},
    {"unknown_top_key_suggests", R"({"schema":1,"camra":{},"objects":[{"material":{"technique":"basic"}}]})", {"camra", "did you mean 'camera'", nullptr}},
    {"wrong_type", R"({"schema":1,"camera":{"distance":"far"},"objects":[{"material":{"technique":"basic"}}]})",
     {"camera.distance", "expected a number", "\"far\""}},
    {"wrong_vector_type", R"({"schema":1,"objects":[{"material":{"technique":"basic","kd":[1,2]}}]})", {"objects[0].material.kd", "colour [r, g, b]", nullptr}},
    {"out_of_range", R"({"schema":1,"objects":[{"material":{"technique":"basic","shininess":0.5}}]})",
     {"objects[0].material.shininess", "out of range", "[1, 10000]"}},
    {"bad_enum", R"({"schema":1,"camera":{"mode":"texure"},"objects":[{"material":{"technique":"basic"}}]})",
     {"camera.mode", "orbit|texture", "did you mean 'texture'"}},
    {"truncated_json", R"({"schema":1,"objects":[{"material":{"technique":"basic")", {"invalid JSON", "line 1", nullptr}},
    {"missing_file", nullptr, {"no such file", nullptr, nullptr}},
    {"unknown_technique", R"({"schema":1,"objects":[{"material":{"technique":"basci"}}]})",
     {"objects[0].material.technique", "unknown technique 'basci'", "did you mean 'basic'"}},
    {"missing_schema", R"({"objects":[{"material":{"technique":"basic"}}]})", {"schema", "missing", nullptr}},
    {"future_schema", R"({"schema":7,"objects":[{"material":{"technique":"basic"}}]})", {"unsupported schema 7", nullptr, nullptr}},
    {"unused_key", R"({"schema":1,"objects":[{"geometry":{"type":"sphere","path":"x.obj"},"material":{"technique":"basic"}}]})",
     {"objects[0].geometry.path", "not used when geometry.type is 'sphere'", nullptr}},
    {"missing_referenced_file", R"({"schema":1,"env":{"map":"nowhere.exr"},"objects":[{"material":{"technique":"basic"}}]})",
     {"env.map", "nowhere.exr", "not found"}},
    {"nan_is_not_json", R"({"schema":1,"camera":{"distance":NaN},"objects":[{"material":{"technique":"basic"}}]})", {"invalid JSON", nullptr, nullptr}},
    {"not_an_object", R"([1,2,3])", {"expected a JSON object", nullptr, nullptr}},
    {"no_objects", R"({"schema":1,"objects":[]})", {"objects", "non-empty", nullptr}},
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadPreset : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadPreset, ExitsWithStatus2AndNamesFileAndKey) {
    const BadCase& c = GetParam();
    TempDir dir(std::string("bad-") + c.name);
    const std::string file = dir / (std::string(c.name) + ".json");
    if (c.json) write_file(file, c.json);
    for (const char* cmd : {"preset validate", "capture --backend cpu -o /tmp/mesolab-never", "preset show"}) {
        const CliResult r = run_mesolab(std::string(cmd) + " '" + file + "'");
        EXPECT_EQ(r.status, 2) << cmd << ": " << r.err;
        EXPECT_NE(r.err.find(file), std::string::npos) << cmd << " must name the file: " << r.err;
        for (const char* s : c.must_say)
            if (s) {
                EXPECT_NE(r.err.find(s), std::string::npos) << cmd << " must say '" << s << "': " << r.err;
            }
        EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
    }
}

INSTANTIATE_TEST_SUITE_P(AllKinds, BadPreset, ::testing::ValuesIn(kCases), [](const auto& info) { return std::string(info.param.name); });

TEST(BadInput, SetErrorsNameTheKeyAndSuggest) {
    const std::string preset = source_path("presets/basic/sphere.json");
    CliResult r = run_mesolab("preset show '" + preset + "' --set camera.distnce=3");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("camera.distnce"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("did you mean 'camera.distance'"), std::string::npos) << r.err;
    r = run_mesolab("preset show '" + preset + "' --set basic.shininess=-1");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
    r = run_mesolab("preset show '" + preset + "' --set light.direction=45");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("two numbers"), std::string::npos) << r.err;
    r = run_mesolab("capture '" + preset + "' --backend cpu --aov nope -o /tmp/mesolab-never");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("available: radiance, normal"), std::string::npos) << r.err;
    r = run_mesolab("capture '" + preset + "' --backend vulkan");
    EXPECT_EQ(r.status, 2);
    r = run_mesolab("capture '" + preset + "' --size 0x10");
    EXPECT_EQ(r.status, 2);
    r = run_mesolab("bench nosuchtable");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("unknown table 'nosuchtable'"), std::string::npos) << r.err;
    r = run_mesolab("--no-such-flag");
    EXPECT_EQ(r.status, 2);
}

// A --set of a key the final settings do not use is refused, as the same key in a preset file is;
// the order of the --sets does not matter.
TEST(BadInput, SetOfAnUnusedKeyIsAnErrorWhateverTheOrder) {
    const std::string preset = source_path("presets/microgeom/bricks-texture.json");
    CliResult r = run_mesolab("preset show '" + preset + "' --set microgeom.brdf_resolution=16");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("microgeom.brdf_resolution"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("microgeom.lod"), std::string::npos) << r.err;
    r = run_mesolab("preset show '" + preset + "' --set microgeom.brdf_resolution=16 --set microgeom.lod=brdf");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("\"brdf_resolution\": 16"), std::string::npos) << r.out;
    r = run_mesolab("sweep '" + preset + "' --knob microgeom.brdf_resolution=4,8 -o /tmp/mesolab-never");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("not used"), std::string::npos) << r.err;
}

// An unknown --metric is refused before any rendering, naming the value and listing the known ones.
TEST(BadInput, SweepMetricErrorsNameTheValueAndListTheKnownOnes) {
    const std::string preset = source_path("presets/basic/sphere.json");
    CliResult r = run_mesolab("sweep '" + preset + "' --knob geometry.resolution=8 --metric nosuchmetric -o /tmp/mesolab-never");
    EXPECT_EQ(r.status, 2) << r.err;
    for (const char* s : {"--metric", "unknown metric 'nosuchmetric'", "known: rmse", "bumpsynth.ndf_histogram"})
        EXPECT_NE(r.err.find(s), std::string::npos) << "must say '" << s << "': " << r.err;
    r = run_mesolab("sweep '" + preset + "' --knob geometry.resolution=8 --metric bumpsynth.ndf_histgram -o /tmp/mesolab-never");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("did you mean 'bumpsynth.ndf_histogram'"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
}

TEST(BadInput, BadImageIsAClearErrorNotACrash) {
    TempDir dir("badimage");
    write_file(dir / "fake.png", "this is not a png");
    write_file(dir / "p.json", R"({"schema":1,"objects":[{"material":{"technique":"basic","albedo_map":"fake.png"}}]})");
    const CliResult r = run_mesolab("capture --backend cpu -o '" + (dir / "out") + "' '" + (dir / "p.json") + "'");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("fake.png"), std::string::npos) << r.err;
}

TEST(Presets, EveryShippedPresetValidates) {
    const CliResult r = run_mesolab("preset validate presets");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("ok"), std::string::npos);
}

TEST(Cli, EverySubcommandHasHelp) {
    for (const char* c : {"--help", "gui --help", "capture --help", "bench --help", "sweep --help", "preset --help", "preset validate --help",
                          "preset schema --help", "preset show --help", "info --help"}) {
        const CliResult r = run_mesolab(c);
        EXPECT_EQ(r.status, 0) << c << ": " << r.err;
        EXPECT_NE(r.out.find("Usage"), std::string::npos) << c;
    }
}
}  // namespace
