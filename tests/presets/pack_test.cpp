// Packs (core/pack.h): a scene with every file it names renders the same bytes after the pack is
// moved; a bad pack gets an error naming the member and loses nothing.
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/pack.h"
#include "core/scene.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <zip.h>

#include <cstring>
#include <list>
#include <filesystem>
#include <sys/stat.h>

using namespace mesolab;
using namespace mesolab::test;
namespace fs = std::filesystem;

namespace {

// A scene that names four files, one of them twice: the sky (EXR), a mesh (OBJ) and an albedo
// map (PNG) on two objects, all in a folder of its own.
Scene scene_with_files(const TempDir& dir) {
    fs::create_directories(dir / "src/maps");
    fs::copy_file(source_path("presets/basic/maps/sky.exr"), dir / "src/maps/sky.exr");
    fs::copy_file(source_path("presets/translucency/meshes/spot.obj"), dir / "src/spot.obj");
    Image albedo(16, 16, 3);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            float* p = albedo.at(x, y);
            p[0] = float(x) / 15.f;
            p[1] = float(y) / 15.f;
            p[2] = ((x / 4 + y / 4) % 2) ? 0.9f : 0.1f;
        }
    write_png_srgb(dir / "src/maps/albedo.png", albedo);
    write_file(dir / "src/scene.json", R"({
  "schema": 1, "name": "packed",
  "camera": { "mode": "orbit", "distance": 4.5, "orbit": [40, -30], "fov": 40 },
  "lights": [ { "type": "point", "position": [2.5, -2.0, 2.5], "intensity": 12 } ],
  "env": { "map": "maps/sky.exr", "intensity": 1.0 },
  "effects": { "environment": true },
  "objects": [
    { "name": "cow", "geometry": { "type": "mesh", "path": "spot.obj" },
      "material": { "technique": "basic", "albedo_map": "maps/albedo.png" } },
    { "name": "ball", "geometry": { "type": "sphere", "resolution": 24, "scale": 0.5, "position": [1.2, 0, 0] },
      "material": { "technique": "basic", "albedo_map": "maps/albedo.png" } }
  ]
})");
    return load_preset(dir / "src/scene.json");
}

std::vector<float> render_cpu(const Scene& s) {
    Workbench wb;
    RenderRequest r;
    r.renderer = "cpu";
    r.width = 96;
    r.height = 72;
    r.aovs = {"normal"};
    return wb.render(s, r).frame.aov("radiance").data;
}

size_t lit_pixels(const std::vector<float>& rgb) {
    size_t n = 0;
    for (size_t i = 0; i + 2 < rgb.size(); i += 3) n += (rgb[i] + rgb[i + 1] + rgb[i + 2]) > 0.f;
    return n;
}

// A zip written member by member, for packs a writer of ours would never make.
struct RawZip {
    zip_t* za = nullptr;
    std::list<std::string> keep;  // the members' bytes live, where they are, until close
    explicit RawZip(const std::string& path) {
        int err = 0;
        za = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    }
    void add(const std::string& name, const std::string& bytes, bool link = false) {
        keep.push_back(bytes);
        zip_source_t* src = zip_source_buffer(za, keep.back().data(), keep.back().size(), 0);
        const zip_int64_t i = zip_file_add(za, name.c_str(), src, ZIP_FL_ENC_UTF_8);
        ASSERT_GE(i, 0) << zip_strerror(za);
        if (link) zip_file_set_external_attributes(za, zip_uint64_t(i), 0, ZIP_OPSYS_UNIX, zip_uint32_t(S_IFLNK | 0777) << 16);
    }
    void close() { ASSERT_EQ(zip_close(za), 0) << zip_strerror(za); }
};

std::string members_of(const std::string& dir) {
    std::string out;
    for (const auto& e : fs::recursive_directory_iterator(dir)) out += fs::relative(e.path(), dir).generic_string() + "\n";
    return out;
}

void expect_error(const std::function<void()>& f, const std::vector<std::string>& words) {
    try {
        f();
        ADD_FAILURE() << "no error; expected one naming " << words.front();
    } catch (const InputError& e) {
        for (const auto& w : words) EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << "'" << e.what() << "' lacks '" << w << "'";
    }
}
}  // namespace

// [SECTION] Same bytes after a move
TEST(Pack, ZipRendersTheSameBytesAfterItIsMoved) {
    TempDir dir("pack-zip");
    const Scene original = scene_with_files(dir);
    const std::vector<float> want = render_cpu(original);
    ASSERT_GT(lit_pixels(want), want.size() / 3 / 10) << "the scene must show its objects";

    const std::vector<std::string> members = write_pack(original, dir / "out/packed.zip");
    ASSERT_EQ(members.size(), 4u) << "scene.json, the sky, the mesh and the albedo map once (named twice)";
    EXPECT_EQ(members.front(), "scene.json");
    // Moved to another folder, the sources gone: the pack is all there is.
    fs::create_directories(dir / "elsewhere/deeper");
    fs::rename(dir / "out/packed.zip", dir / "elsewhere/deeper/renamed.zip");
    fs::remove_all(dir / "src");
    fs::remove_all(dir / "out");
    const Scene moved = load_preset(dir / "elsewhere/deeper/renamed.zip");
    EXPECT_EQ(moved.name, "packed");
    for (const auto& o : moved.objects) {
        const std::string p = moved.resolve(o.material.get_string("albedo_map"));
        EXPECT_TRUE(fs::is_regular_file(p)) << p;
    }
    const std::vector<float> got = render_cpu(moved);
    ASSERT_EQ(got.size(), want.size());
    EXPECT_EQ(0, std::memcmp(got.data(), want.data(), want.size() * sizeof(float))) << "the moved pack renders other bytes";
}

TEST(Pack, FolderRendersTheSameBytesAfterItIsMoved) {
    TempDir dir("pack-dir");
    const Scene original = scene_with_files(dir);
    const std::vector<float> want = render_cpu(original);
    write_pack(original, dir / "shared/");
    write_pack(original, dir / "first.zip");
    EXPECT_TRUE(is_pack(dir / "shared"));
    fs::rename(dir / "shared", dir / "moved");
    fs::remove_all(dir / "src");
    const Scene moved = load_preset(dir / "moved");
    const std::vector<float> got = render_cpu(moved);
    ASSERT_EQ(got.size(), want.size());
    EXPECT_EQ(0, std::memcmp(got.data(), want.data(), want.size() * sizeof(float)));
    // A pack of the moved pack is the same pack.
    write_pack(moved, dir / "again.zip");
    EXPECT_EQ(slurp(dir / "again.zip"), slurp(dir / "first.zip")) << "the same scene and files must give the same archive bytes";
}

TEST(Pack, BytesRoundTripAndAreDeterministic) {
    TempDir dir("pack-bytes");
    const Scene original = scene_with_files(dir);
    const std::string a = pack_bytes(original), b = pack_bytes(original);
    EXPECT_EQ(a, b);
    const Scene s = load_pack_bytes(a, "sent.zip");
    EXPECT_EQ(scene_to_text(s), scene_to_text(load_pack_bytes(b, "again.zip")));
    // Every file is a member named by its contents' hash.
    for (const auto& o : s.objects) {
        const std::string v = o.material.get_string("albedo_map");
        EXPECT_EQ(v.rfind("files/", 0), 0u) << v;
        EXPECT_EQ(v.substr(6, 16), content_hash(slurp(s.resolve(v))));
    }
}

TEST(Pack, ASceneWithoutFilesPacksToItsPresetAlone) {
    TempDir dir("pack-plain");
    const Scene s = load_preset(source_path("presets/basic/sphere.json"));
    EXPECT_EQ(write_pack(s, dir / "sphere.zip"), std::vector<std::string>{"scene.json"});
    EXPECT_EQ(scene_to_text(load_preset(dir / "sphere.zip")), scene_to_text(s));
}

// [SECTION] Bad packs
TEST(Pack, MissingAndExtraMembersAreNamed) {
    TempDir dir("pack-members");
    write_pack(scene_with_files(dir), dir / "p/");
    std::string mesh;
    for (const auto& e : fs::directory_iterator(dir / "p/files"))
        if (e.path().extension() == ".obj") mesh = "files/" + e.path().filename().string();
    ASSERT_FALSE(mesh.empty());
    const std::string before = members_of(dir / "p");
    fs::rename(dir / "p/" + mesh, dir / "spare.obj");
    expect_error([&] { load_preset(dir / "p"); }, {dir / "p", mesh, "missing", "objects[0].geometry.path"});
    fs::rename(dir / "spare.obj", dir / "p/" + mesh);
    write_file(dir / "p/files/0123456789abcdef.png", "extra");
    expect_error([&] { load_preset(dir / "p"); }, {"files/0123456789abcdef.png", "not named by scene.json"});
    fs::remove(dir / "p/files/0123456789abcdef.png");
    write_file(dir / "p/notes.txt", "hello");
    expect_error([&] { load_preset(dir / "p"); }, {"notes.txt", "not named by scene.json"});
    fs::remove(dir / "p/notes.txt");
    fs::remove(dir / "p/scene.json");
    EXPECT_FALSE(is_pack(dir / "p"));
    expect_error([&] { load_pack(dir / "p"); }, {"no scene.json"});
    (void)before;
}

TEST(Pack, AChangedMemberIsRefused) {
    TempDir dir("pack-hash");
    write_pack(scene_with_files(dir), dir / "p/");
    for (const auto& e : fs::directory_iterator(dir / "p/files")) {
        if (e.path().extension() != ".png") continue;
        std::string bytes = slurp(e.path().string());
        bytes[bytes.size() / 2] ^= 0x01;
        write_file(e.path().string(), bytes);
        expect_error([&] { load_preset(dir / "p"); }, {"files/" + e.path().filename().string(), "changed or damaged"});
    }
}

TEST(Pack, NamesThatLeaveThePackAndLinksAreRefused) {
    TempDir dir("pack-leave");
    const std::string scene = R"({"schema":1,"name":"x","objects":[{"material":{"technique":"basic"}}]})";
    {
        RawZip z(dir / "dotdot.zip");
        z.add("scene.json", scene);
        z.add("../evil.txt", "x");
        z.close();
    }
    expect_error([&] { load_preset(dir / "dotdot.zip"); }, {"dotdot.zip", "../evil.txt", "leaves the pack"});
    EXPECT_FALSE(fs::exists(dir.path.parent_path() / "evil.txt"));
    {
        RawZip z(dir / "absolute.zip");
        z.add("scene.json", scene);
        z.add("/tmp/evil.txt", "x");
        z.close();
    }
    expect_error([&] { load_preset(dir / "absolute.zip"); }, {"/tmp/evil.txt", "leaves the pack"});
    {
        RawZip z(dir / "link.zip");
        z.add("scene.json", scene);
        z.add("files/0123456789abcdef.png", "/etc/passwd", true);
        z.close();
    }
    expect_error([&] { load_preset(dir / "link.zip"); }, {"files/0123456789abcdef.png", "is a link"});
    // The scene naming a file outside the pack.
    write_file(dir / "outside.png", "x");
    {
        RawZip z(dir / "scene-leaves.zip");
        z.add("scene.json", R"({"schema":1,"name":"x","objects":[{"material":{"technique":"basic","albedo_map":"../outside.png"}}]})");
        z.close();
    }
    expect_error([&] { load_preset(dir / "scene-leaves.zip"); }, {"scene.json", "objects[0].material.albedo_map", "leaves the pack"});
    // A folder pack with a link in it.
    write_pack(load_preset(source_path("presets/basic/sphere.json")), dir / "f/");
    fs::create_directories(dir / "f/files");
    fs::create_symlink("/etc/passwd", dir / "f/files/0123456789abcdef.txt");
    expect_error([&] { load_preset(dir / "f"); }, {"files/0123456789abcdef.txt", "is a link"});
}

TEST(Pack, MembersAboveTheMemoryBudgetAreRefused) {
    TempDir dir("pack-budget");
    write_pack(scene_with_files(dir), dir / "p.zip");
    uint64_t biggest = 0, total = 0;
    {
        int err = 0;
        zip_t* za = zip_open((dir / "p.zip").c_str(), ZIP_RDONLY, &err);
        ASSERT_NE(za, nullptr);
        for (zip_int64_t i = 0; i < zip_get_num_entries(za, 0); ++i) {
            zip_stat_t st;
            zip_stat_index(za, zip_uint64_t(i), 0, &st);
            biggest = std::max<uint64_t>(biggest, st.size);
            total += st.size;
        }
        zip_close(za);
    }
    const uint64_t archive = fs::file_size(dir / "p.zip");
    ASSERT_LT(archive, biggest) << "the members compress";
    ASSERT_LT(biggest, total);
    // Fresh folders for the unpacked copies: a pack unpacked before is not unpacked again.
    expect_error([&] { load_pack(dir / "p.zip", PackLimits{biggest - 1}); }, {"member files/", "above the memory budget"});
    expect_error([&] { load_pack(dir / "p.zip", PackLimits{total - 1}); }, {"members total more than the memory budget"});
    expect_error([&] { load_pack(dir / "p.zip", PackLimits{archive - 1}); }, {"p.zip", "above the memory budget"});
    EXPECT_NO_THROW(load_pack(dir / "p.zip", PackLimits{total}));
}

TEST(Pack, ATruncatedArchiveIsRefused) {
    TempDir dir("pack-truncated");
    write_pack(scene_with_files(dir), dir / "p.zip");
    const std::string bytes = slurp(dir / "p.zip");
    for (size_t keep : {bytes.size() - 1, bytes.size() / 2, size_t(100), size_t(0)}) {
        write_file(dir / "cut.zip", bytes.substr(0, keep));
        expect_error([&] { load_preset(dir / "cut.zip"); }, {"cut.zip"});
    }
    // A member whose compressed bytes are damaged (the archive's directory intact).
    std::string damaged = bytes;
    const size_t at = damaged.find("scene.json", 40);  // past the first local header
    ASSERT_NE(at, std::string::npos);
    for (size_t i = 200; i < 260; ++i) damaged[i] ^= 0x5a;
    write_file(dir / "damaged.zip", damaged);
    expect_error([&] { load_preset(dir / "damaged.zip"); }, {"damaged.zip"});
}

TEST(Pack, AFailedWriteLosesNothing) {
    TempDir dir("pack-lose");
    const Scene s = scene_with_files(dir);
    write_pack(s, dir / "p.zip");
    write_pack(s, dir / "f/");
    const std::string zip_before = slurp(dir / "p.zip"), folder_before = members_of(dir / "f");
    Scene broken = s;
    fs::remove(dir / "src/spot.obj");
    expect_error([&] { write_pack(broken, dir / "p.zip"); }, {"objects[0].geometry.path", "spot.obj"});
    expect_error([&] { write_pack(broken, dir / "f/"); }, {"objects[0].geometry.path"});
    EXPECT_EQ(slurp(dir / "p.zip"), zip_before);
    EXPECT_EQ(members_of(dir / "f"), folder_before);
    // A folder that is not a pack is not replaced.
    write_file(dir / "work/thesis.tex", "months of work");
    fs::copy_file(source_path("presets/translucency/meshes/spot.obj"), dir / "src/spot.obj");
    expect_error([&] { write_pack(s, dir / "work"); }, {"work", "other files than a pack"});
    EXPECT_EQ(slurp(dir / "work/thesis.tex"), "months of work");
}

TEST(Pack, ATouchedUnpackedCopyIsUnpackedAgain) {
    TempDir dir("pack-touched");
    Scene s = scene_with_files(dir);
    s.name = "touched";  // a pack of its own: other tests read theirs meanwhile
    const std::string bytes = pack_bytes(s);
    const Scene first = load_pack_bytes(bytes, "p.zip");
    const std::string png = first.resolve(first.objects[0].material.get_string("albedo_map"));
    write_file(png, "touched");
    const Scene again = load_pack_bytes(bytes, "p.zip");
    EXPECT_EQ(content_hash(slurp(again.resolve(again.objects[0].material.get_string("albedo_map")))),
              again.objects[0].material.get_string("albedo_map").substr(6, 16));
}

// [SECTION] The command line
TEST(Pack, CommandLinePacksAndCapturesAPackAsAPreset) {
    TempDir dir("pack-cli");
    scene_with_files(dir);
    const CliResult p = run_mesolab("preset pack '" + dir / "src/scene.json" + "' -o '" + dir / "p.zip" + "'");
    ASSERT_EQ(p.status, 0) << p.err;
    EXPECT_NE(p.out.find("3 files"), std::string::npos) << p.out;
    fs::rename(dir / "p.zip", dir / "moved.zip");
    // sweep, frontier and preset show read it as a preset.
    const CliResult sw = run_mesolab("sweep '" + dir / "moved.zip" + "' --knob objects.1.geometry.resolution=8,16 --size 24x24 --repeat 1 -o '" + dir / "sw" + "'");
    EXPECT_EQ(sw.status, 0) << sw.err;
    const CliResult sp = run_mesolab("preset pack presets/basic/sphere.json -o '" + dir / "sphere.zip" + "'");
    ASSERT_EQ(sp.status, 0) << sp.err;
    const CliResult fr = run_mesolab("frontier '" + dir / "sphere.zip" + "' --size 16x16 --spp 4 --budget 0.05 --repeat 1 -o '" + dir / "fr" + "'");
    EXPECT_EQ(fr.status, 0) << fr.err;
    const CliResult sh = run_mesolab("preset show '" + dir / "moved.zip" + "'");
    EXPECT_EQ(sh.status, 0) << sh.err;
    EXPECT_NE(sh.out.find("\"files/"), std::string::npos) << sh.out;
    const CliResult a = run_mesolab("capture '" + dir / "src/scene.json" + "' --backend cpu --size 64x48 -o '" + dir / "a" + "'");
    const CliResult b = run_mesolab("capture '" + dir / "moved.zip" + "' --backend cpu --size 64x48 -o '" + dir / "b" + "'");
    ASSERT_EQ(a.status, 0) << a.err;
    ASSERT_EQ(b.status, 0) << b.err;
    EXPECT_EQ(slurp(dir / "a/packed.png"), slurp(dir / "b/packed.png"));
    EXPECT_FALSE(slurp(dir / "a/packed.png").empty());
    // A bad pack: exit status 2, the member named, no crash.
    write_file(dir / "bad.zip", "PK\x03\x04 not really");
    const CliResult c = run_mesolab("capture '" + dir / "bad.zip" + "' --backend cpu --size 16x16 -o '" + dir / "c" + "'");
    EXPECT_EQ(c.status, 2);
    EXPECT_NE(c.err.find("bad.zip"), std::string::npos) << c.err;
}
