// Preset round trips (file -> memory -> file is exact), --set addressing, atomic saves.
#include "core/error.h"
#include "core/scene.h"
#include "core/technique.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <filesystem>

using namespace mesolab;
using namespace mesolab::test;
namespace fs = std::filesystem;

TEST(PresetRoundTrip, EveryShippedPresetIsExact) {
    TempDir dir("roundtrip");
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(source_path("presets"))) {
        if (e.path().extension() != ".json") continue;
        ++n;
        const Scene a = load_preset(e.path().string());
        const std::string saved = dir / (e.path().stem().string() + ".json");
        save_preset(a, saved);
        const Scene b = load_preset(saved);
        EXPECT_TRUE(a == b) << e.path();
        // A second save is byte-identical (canonical form).
        const std::string again = dir / (e.path().stem().string() + ".again.json");
        save_preset(b, again);
        EXPECT_EQ(slurp(saved), slurp(again)) << e.path();
    }
    EXPECT_GT(n, 0);
}

TEST(PresetRoundTrip, EditedValuesSurviveExactly) {
    TempDir dir("edited");
    Scene s = default_scene("basic");
    apply_set(s, "camera.distance=0.1");
    apply_set(s, "basic.kd=0.1,0.2,0.30000000000000004");
    apply_set(s, "light.direction=89.9,-123.456789012345");
    apply_set(s, "camera.mode=texture");
    apply_set(s, "geometry.resolution=7");
    s.lights.push_back(Registry::instance().light().defaults());
    apply_set(s, "lights.1.type=point");
    apply_set(s, "lights.1.position=1e-7,2,3");
    save_preset(s, dir / "s.json");
    const Scene t = load_preset(dir / "s.json");
    EXPECT_TRUE(s == t);
    EXPECT_EQ(get_public(t, "camera.distance"), "0.1");
    EXPECT_EQ(get_public(t, "basic.kd"), "0.1,0.2,0.30000000000000004");
    EXPECT_EQ(get_public(t, "lights.1.position"), "1e-07,2,3");
}

TEST(PresetRoundTrip, RelativePathsFollowThePresetFolder) {
    TempDir dir("paths");
    write_file(dir / "maps/albedo.png", "placeholder");  // existence is checked at load, content when used
    write_file(dir / "a/p.json", R"({"schema":1,"objects":[{"material":{"technique":"basic","albedo_map":"../maps/albedo.png"}}]})");
    const Scene s = load_preset(dir / "a/p.json");
    save_preset(s, dir / "b/c/q.json");
    const Scene t = load_preset(dir / "b/c/q.json");
    EXPECT_EQ(t.objects[0].material.get_string("albedo_map"), "../../maps/albedo.png");
    EXPECT_EQ(fs::weakly_canonical(t.resolve(t.objects[0].material.get_string("albedo_map"))), fs::weakly_canonical(dir / "maps/albedo.png"));
}

TEST(SetAddressing, PublicKeysReachTheRightTables) {
    Scene s = default_scene("basic");
    s.objects.push_back(s.objects[0]);
    s.lights.push_back(s.lights[0]);
    apply_set(s, "basic.shininess=10");  // every object using basic
    EXPECT_EQ(s.objects[0].material.get_float("shininess"), 10.0);
    EXPECT_EQ(s.objects[1].material.get_float("shininess"), 10.0);
    apply_set(s, "objects.1.material.shininess=20");
    EXPECT_EQ(s.objects[0].material.get_float("shininess"), 10.0);
    EXPECT_EQ(s.objects[1].material.get_float("shininess"), 20.0);
    apply_set(s, "light.intensity=7");  // the first light
    EXPECT_EQ(s.lights[0].get_float("intensity"), 7.0);
    EXPECT_EQ(s.lights[1].get_float("intensity"), 3.0);
    apply_set(s, "geometry.type=torus");
    EXPECT_EQ(s.objects[0].geometry.get_string("type"), "torus");
    EXPECT_EQ(s.objects[1].geometry.get_string("type"), "sphere");
    EXPECT_THROW(apply_set(s, "lights.5.intensity=1"), InputError);
    EXPECT_THROW(apply_set(s, "nosuch.thing=1"), InputError);
    EXPECT_THROW(apply_set(s, "camera.distance"), InputError);
}

TEST(AtomicSave, FailedSaveLeavesTheOldFileIntact) {
    TempDir dir("atomic");
    const std::string path = dir / "keep.json";
    Scene s = default_scene("basic");
    save_preset(s, path);
    const std::string before = slurp(path);
    // Block the temporary file with a folder of the same name: the write fails half-way.
    fs::create_directories(path + ".tmp-" + std::to_string(::getpid()));
    apply_set(s, "camera.distance=9");
    EXPECT_THROW(save_preset(s, path), InputError);
    EXPECT_EQ(slurp(path), before);
    // A path whose parent is a regular file cannot be written either.
    EXPECT_THROW(save_preset(s, path + "/child.json"), InputError);
    EXPECT_EQ(slurp(path), before);
}

// `bench --update-pages` replaces what lies between whole-line markers, and nothing else: a
// marker quoted inside a line of prose is left alone, and tables not measured keep their text.
TEST(BenchPages, UpdatePagesReplacesOnlyTheMarkedBlocks) {
    using namespace mesolab::test;
    TempDir dir("pages");
    const std::string readme = "# Title\nQuote `<!-- bench basic -->` in prose.\n<!-- bench basic -->\nold table\n<!-- /bench -->\nafter\n";
    const std::string page = "intro\n<!-- bench microgeom -->\nkept\n<!-- /bench -->\n";
    write_file(dir / "README.md", readme);
    write_file(dir / "core/t/README.md", page);
    const CliResult r = run_mesolab("bench basic --repeat 1 --backend cpu --update-pages --pages-root '" + dir.path.string() + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string out = slurp(dir / "README.md");
    EXPECT_EQ(out.find("old table"), std::string::npos) << out;
    EXPECT_NE(out.find("Quote `<!-- bench basic -->` in prose.\n<!-- bench basic -->\n### basic"), std::string::npos) << out;
    EXPECT_NE(out.find("| sphere 64 |"), std::string::npos) << out;
    EXPECT_NE(out.find("<!-- /bench -->\nafter\n"), std::string::npos) << out;
    EXPECT_EQ(slurp(dir / "core/t/README.md"), page) << "a table not measured keeps its text";
    const CliResult none = run_mesolab("bench basic --repeat 1 --backend cpu --update-pages --pages-root '" + (dir / "core") + "'");
    EXPECT_EQ(none.status, 2) << none.err;
}
