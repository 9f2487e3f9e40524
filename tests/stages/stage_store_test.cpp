// Stages that outlive the process (core/stage_store.h): a stage declared with a codec is read back
// from disk by a later session (status "cached (disk)"), the same bytes as computing it; a corrupt,
// truncated or foreign entry is absent, never data; a result the CPU computed because the GPU
// could not is not kept; the least recently used entries go first above the size limit; two
// processes writing one entry at once leave a complete one; `capture` twice takes cloth's fit from
// disk the second time, with the same output bytes, and `--no-cache` computes everything.
#include "core/blob.h"
#include "core/error.h"
#include "core/session.h"
#include "core/stage.h"
#include "core/stage_store.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

using namespace mesolab;
using namespace mesolab::test;
namespace fs = std::filesystem;

namespace {
constexpr Stage<std::vector<float>> kTable{"t.table"};

void write_table(BlobWriter& w, const std::vector<float>& v) { w.put_vector(v); }
std::vector<float> read_table(BlobReader& r) { return r.get_vector<float>(); }

// A stage computing a table from camera.fov, kept on disk; `fall_back` says the CPU computed it
// in place of the GPU.
struct Graph {
    StageGraph g;
    int runs = 0;
    bool fall_back = false;
    Graph() {
        g.add(kTable, {.params = {"camera.fov"},
                       .run = [this](StageContext& ctx) {
                           ++runs;
                           if (fall_back) ctx.fell_back_to_cpu();
                           std::vector<float> v(1000);
                           for (size_t i = 0; i < v.size(); ++i) v[i] = float(ctx.scene.camera.get_float("fov")) * 0.001f * float(i) + 1e-7f * float(i * i);
                           ctx.warn("a warning kept with the result");
                           return stage_result(kTable, std::move(v));
                       },
                       .disk = stage_codec(kTable, write_table, read_table)});
    }
    // Evaluates in a fresh session over `store`: the table and the stage's status.
    std::pair<std::vector<float>, const char*> eval(const std::shared_ptr<StageStore>& store, const Scene& s) {
        Session session(g);
        session.set_store(store);
        const Evaluation e = session.evaluate(s, {kTable});
        return {*e.get(kTable), to_string(e.run(kTable)->status)};
    }
};

std::shared_ptr<StageStore> store_in(const TempDir& dir, uint64_t max_bytes = 0) {
    return std::make_shared<StageStore>(dir / "stages", "test-version", max_bytes);
}

std::string entry_path(const StageStore& store, const Scene& s, const StageGraph& g) {
    StageGraph::Memo memo;
    return store.path("t.table", g.fingerprint(s, g.at("t.table"), -1, memo, FileIdentity::Contents));
}
}  // namespace

TEST(StageStore, ALaterSessionReadsTheStageBackAsTheSameBytes) {
    TempDir dir("store-roundtrip");
    Graph g;
    const Scene s = default_scene("basic");
    const auto store = store_in(dir);
    const auto [first, st1] = g.eval(store, s);
    EXPECT_STREQ(st1, "ran");
    const auto [second, st2] = g.eval(store, s);
    EXPECT_STREQ(st2, "cached (disk)");
    EXPECT_EQ(g.runs, 1);
    ASSERT_EQ(first.size(), second.size());
    EXPECT_EQ(0, std::memcmp(first.data(), second.data(), first.size() * sizeof(float))) << "the same bytes";
    {
        Session session(g.g);
        session.set_store(store);
        const Evaluation e = session.evaluate(s, {kTable});
        ASSERT_EQ(e.run(kTable)->warnings.size(), 1u) << "warnings are kept with the result";
    }
    Scene other = s;
    apply_set(other, "camera.fov=30");
    EXPECT_STREQ(g.eval(store, other).second, "ran") << "another value of a declared key is another entry";
    EXPECT_STREQ(g.eval(nullptr, s).second, "ran") << "without a store nothing is read";
    // Another program version reads nothing of this one's.
    StageStore other_version(dir / "stages", "another-version", 0);
    Session session(g.g);
    session.set_store(std::make_shared<StageStore>(other_version));
    EXPECT_EQ(session.evaluate(s, {kTable}).run(kTable)->status, StageStatus::Ran);
}

TEST(StageStore, ACorruptTruncatedOrForeignEntryIsAbsent) {
    TempDir dir("store-corrupt");
    Graph g;
    const Scene s = default_scene("basic");
    const auto store = store_in(dir);
    g.eval(store, s);
    const std::string path = entry_path(*store, s, g.g);
    ASSERT_TRUE(fs::exists(path)) << path;
    const std::string good = slurp(path);
    std::string flipped = good;
    flipped[flipped.size() - 7] ^= 0x10;  // one bit of the payload
    for (const std::string& bad : {flipped, good.substr(0, good.size() / 2), std::string("not an entry at all"), std::string()}) {
        write_file(path, bad);
        const int before = g.runs;
        const auto [v, status] = g.eval(store, s);
        EXPECT_STREQ(status, "ran") << bad.size() << " bytes";
        EXPECT_EQ(g.runs, before + 1);
        EXPECT_EQ(slurp(path), good) << "computed again and kept, whole";
    }
}

TEST(StageStore, AResultTheCpuComputedForTheGpuIsNotKept) {
    TempDir dir("store-fallback");
    Graph g;
    g.fall_back = true;
    const Scene s = default_scene("basic");
    const auto store = store_in(dir);
    g.eval(store, s);
    EXPECT_FALSE(fs::exists(entry_path(*store, s, g.g)));
    EXPECT_STREQ(g.eval(store, s).second, "ran");
}

TEST(StageStore, TheLeastRecentlyUsedEntriesGoFirst) {
    TempDir dir("store-lru");
    Graph g;
    Scene a = default_scene("basic"), b = a, c = a;
    apply_set(b, "camera.fov=31");
    apply_set(c, "camera.fov=32");
    auto big = store_in(dir);
    g.eval(big, a);
    const uint64_t entry = fs::file_size(entry_path(*big, a, g.g));
    g.eval(big, b);
    // a is older than b, then a is read (used) again: b is now the least recently used.
    const auto now = fs::file_time_type::clock::now();
    fs::last_write_time(entry_path(*big, a, g.g), now - std::chrono::hours(2));
    fs::last_write_time(entry_path(*big, b, g.g), now - std::chrono::hours(1));
    EXPECT_STREQ(g.eval(big, a).second, "cached (disk)");
    // Room for two entries: writing c evicts b.
    const auto limited = std::make_shared<StageStore>(dir / "stages", "test-version", 2 * entry + entry / 2);
    g.eval(limited, c);
    EXPECT_TRUE(fs::exists(entry_path(*big, a, g.g)));
    EXPECT_FALSE(fs::exists(entry_path(*big, b, g.g)));
    EXPECT_TRUE(fs::exists(entry_path(*big, c, g.g)));
}

TEST(StageStore, TwoProcessesWritingOneEntryLeaveItWhole) {
    TempDir dir("store-race");
    Graph g;
    const Scene s = default_scene("basic");
    const auto store = store_in(dir);
    g.eval(store, s);
    const std::string path = entry_path(*store, s, g.g);
    const std::string good = slurp(path);
    StageGraph::Memo memo;
    const std::string fp = g.g.fingerprint(s, g.g.at("t.table"), -1, memo, FileIdentity::Contents);
    const std::optional<StageStore::Entry> entry = store->load("t.table", fp);
    ASSERT_TRUE(entry);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {  // the other process: writes the entry again and again
        for (int i = 0; i < 200; ++i) store->save("t.table", fp, *entry);
        _exit(0);
    }
    int complete = 0;
    for (int i = 0; i < 200; ++i) {
        store->save("t.table", fp, *entry);
        const std::optional<StageStore::Entry> e = store->load("t.table", fp);
        ASSERT_TRUE(e) << "a reader never sees a torn entry";
        complete += e->payload == entry->payload;
    }
    int status = 0;
    waitpid(child, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    EXPECT_EQ(complete, 200);
    EXPECT_EQ(slurp(path), good);
    for (const auto& f : fs::directory_iterator(fs::path(path).parent_path()))
        EXPECT_EQ(f.path().string().find(".tmp-"), std::string::npos) << "no temporary file left: " << f.path();
}

TEST(StageStore, CaptureTwiceTakesTheFitFromDiskWithTheSameBytes) {
    TempDir dir("store-capture");
    const std::string env = "MESOLAB_CACHE_DIR='" + (dir / "cache") + "'";
    const std::string args = "capture presets/cloth/stitch-knit.json --backend cpu --size 48x48 --aov normal --set cloth.spatial=4 "
                             "--set cloth.directions=6 ";
    const CliResult first = run_mesolab(args + "-o '" + (dir / "a") + "'", env);
    ASSERT_EQ(first.status, 0) << first.err;
    EXPECT_NE(first.out.find(", 0 cached (disk)"), std::string::npos) << first.out;
    const CliResult second = run_mesolab(args + "-o '" + (dir / "b") + "'", env);
    ASSERT_EQ(second.status, 0) << second.err;
    EXPECT_NE(second.out.find(", 2 cached (disk)"), std::string::npos) << "cloth.acquire and cloth.fit: " << second.out;
    for (const char* f : {"stitch-knit.png", "stitch-knit.radiance.exr", "stitch-knit.normal.exr"})
        EXPECT_EQ(slurp(dir / (std::string("a/") + f)), slurp(dir / (std::string("b/") + f))) << f;
    const CliResult none = run_mesolab(args + "--no-cache -o '" + (dir / "c") + "'", env);
    ASSERT_EQ(none.status, 0) << none.err;
    EXPECT_NE(none.out.find(", 0 cached (disk)"), std::string::npos) << none.out;
    EXPECT_EQ(slurp(dir / "a/stitch-knit.png"), slurp(dir / "c/stitch-knit.png"));
    EXPECT_TRUE(fs::is_directory(dir / "cache/stages/cloth.fit"));
}

TEST(StageStore, TheCacheRootHoldsAFolderPerKind) {
    const char* was = std::getenv("MESOLAB_CACHE_DIR");
    const std::string before = was ? was : "";
    setenv("MESOLAB_CACHE_DIR", "/tmp/mesolab-root-test", 1);
    EXPECT_EQ(cache_root(), "/tmp/mesolab-root-test");
    EXPECT_EQ(cache_folder("stages"), "/tmp/mesolab-root-test/stages");
    EXPECT_EQ(cache_folder("truth"), "/tmp/mesolab-root-test/truth");
    setenv("MESOLAB_CACHE_SIZE", "20G", 1);
    EXPECT_EQ(cache_size_limit(), uint64_t(20) << 30);
    setenv("MESOLAB_CACHE_SIZE", "lots", 1);
    EXPECT_THROW(cache_size_limit(), InputError);
    unsetenv("MESOLAB_CACHE_SIZE");
    EXPECT_EQ(cache_size_limit(), uint64_t(8) << 30);
    if (was) setenv("MESOLAB_CACHE_DIR", before.c_str(), 1);
    else unsetenv("MESOLAB_CACHE_DIR");
}
