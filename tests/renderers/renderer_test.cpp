// The renderers behind one interface (core/renderer.h): every registered renderer renders a scene
// through it; a new renderer is one registration and gets the comparison AOV for free;
// truth_error is the difference of two renderers' frames; the truth renders progressively to the
// bytes of one render, keeps its last finished pass when cancelled and continues it; the truths
// of the window and of the command line share one disk cache; the library and the module link no
// window; the command line and Python name no renderer in their code.
#include "app/api.h"
#include "app/gui/truth_view.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/renderer.h"
#include "core/stage_store.h"
#include "support/cli.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>

using namespace mesolab;
using namespace std::chrono_literals;

namespace {
Scene sphere(float kd = 0.6f) {
    Scene s = default_scene("basic");
    apply_set(s, "basic.kd", std::to_string(kd) + ",0.5,0.4");
    return s;
}

RenderRequest request(const std::string& renderer, int size, int spp = 4) {
    RenderRequest r;
    r.renderer = renderer;
    r.width = r.height = size;
    r.truth.spp = spp;
    r.aovs = {"radiance"};
    return r;
}

double mean(const Image& img) {
    double sum = 0;
    for (float v : img.data) sum += v;
    return sum / double(img.data.size());
}

// A renderer a newcomer might add: a flat grey frame of the requested size.
class FlatRenderer final : public Renderer {
public:
    RenderResult render(Session&, const Scene&, const RenderRequest& r) override {
        RenderResult out;
        out.frame = make_frame({{"radiance", 3, "flat grey"}}, r.width, r.height);
        for (float& v : out.frame.aov("radiance").data) v = 0.25f;
        out.renderer = "flat";
        return out;
    }
    std::string device() override { return "flat"; }
};

std::string command_output(const std::string& cmd) {
    std::string out;
    if (FILE* p = ::popen(cmd.c_str(), "r")) {
        std::array<char, 4096> buf;
        while (size_t n = std::fread(buf.data(), 1, buf.size(), p)) out.append(buf.data(), n);
        ::pclose(p);
    }
    return out;
}
}  // namespace

// [SECTION] One interface
TEST(Renderers, EveryRegisteredRendererRendersThroughTheInterface) {
    Workbench wb;
    wb.set_truth_cache("");
    const std::vector<std::string> names = RendererRegistry::instance().names();
    for (const char* expected : {"gpu", "cpu", "truth"}) EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
    const Scene s = sphere();
    for (const std::string& name : names) {
        SCOPED_TRACE(name);
        const RendererDecl& d = RendererRegistry::instance().find(name);
        const RenderResult r = wb.render(s, request(name, 24));
        ASSERT_TRUE(r.frame.has("radiance"));
        EXPECT_EQ(r.frame.width, 24);
        EXPECT_GT(mean(r.frame.aov("radiance")), 0.01) << "content in the frame";
        EXPECT_EQ(r.sampled.has_value(), d.traits.sampled) << "a sampled renderer says what its samples are";
        EXPECT_FALSE(r.renderer.empty());
        EXPECT_EQ(r.renderer, wb.renderer(name).device());
    }
    try {
        wb.render(s, request("raytracer", 8));
        ADD_FAILURE() << "an unknown renderer was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'raytracer' is not one of gpu|cpu|truth"), std::string::npos) << e.what();
    }
}

TEST(Renderers, ANewRendererIsOneRegistrationAndGetsTheComparison) {
    RendererRegistry::instance().add({"flat", "a flat grey frame (a test's renderer)", {false, true, false},
                                      [](const RendererSetup&) { return std::make_unique<FlatRenderer>(); }, [](const Scene&, const RenderRequest&) {}});
    Workbench wb;
    wb.set_truth_cache("");
    const Scene s = sphere();
    RenderRequest req = request("flat", 16, 4);
    req.aovs = {"radiance", "truth_error"};
    check_render_request(s, req);
    const RenderResult r = wb.render(s, req);
    ASSERT_TRUE(r.frame.has("truth_error"));
    ASSERT_TRUE(r.truth && r.truth_frame && r.truth_run);
    const Image& e = r.frame.aov("truth_error");
    const Image& t = r.truth_frame->aov("radiance");
    for (size_t i = 0; i < e.data.size(); ++i) ASSERT_FLOAT_EQ(e.data[i], 0.25f - t.data[i]) << i;
    EXPECT_EQ(r.truth_run->spp, 4);
    // The comparison's reference cannot be compared with itself.
    RenderRequest self = request("truth", 8);
    self.aovs = {"truth_error"};
    EXPECT_THROW(check_render_request(s, self), InputError);
    // A partial render needs a renderer that samples.
    RenderRequest part = request("flat", 8);
    part.partial = true;
    try {
        check_render_request(s, part);
        ADD_FAILURE() << "a partial render of a renderer that does not sample was accepted";
    } catch (const InputError& err) {
        EXPECT_NE(std::string(err.what()).find("needs --backend truth (a renderer that samples), not --backend flat"), std::string::npos) << err.what();
    }
}

// truth_error is the requested renderer's radiance minus the reference renderer's, at the size
// the frame was rendered at: the same numbers as rendering both and subtracting.
TEST(Renderers, TruthErrorIsTheDifferenceOfTwoRenderersFrames) {
    const Scene s = sphere();
    Workbench wb;
    wb.set_truth_cache("");
    RenderRequest req = request("cpu", 20, 6);
    req.aovs = {"truth_error"};
    const RenderResult r = wb.render(s, req);
    const RenderResult cpu = wb.render(s, request("cpu", 20, 6));
    Workbench other;
    other.set_truth_cache("");
    const RenderResult truth = other.render(s, request("truth", 20, 6));
    ASSERT_TRUE(r.frame.has("radiance"));
    const Image& e = r.frame.aov("truth_error");
    for (size_t i = 0; i < e.data.size(); ++i)
        ASSERT_FLOAT_EQ(e.data[i], cpu.frame.aov("radiance").data[i] - truth.frame.aov("radiance").data[i]) << i;
    EXPECT_GT(r.truth->rmse_rel, 0.0);
}

// [SECTION] The truth renderer
TEST(TruthRenderer, PassesGiveTheBytesOfOneRender) {
    const Scene s = sphere();
    Session session;
    Renderers renderers;  // nothing on disk
    std::vector<int> passes;
    RenderRequest req = request("truth", 16, 12);
    req.on_pass = [&](const Frame& f, int spp) {
        passes.push_back(spp);
        EXPECT_TRUE(f.has("truth_stderr"));
    };
    const RenderResult progressive = renderers.get("truth").render(session, s, req);
    EXPECT_EQ(passes, (std::vector<int>{1, 2, 4, 8, 12}));
    Renderers fresh;
    const RenderResult once = fresh.get("truth").render(session, s, request("truth", 16, 12));
    EXPECT_EQ(progressive.frame.aov("radiance").data, once.frame.aov("radiance").data);
    EXPECT_EQ(progressive.sampled->spp, 12);
}

TEST(TruthRenderer, ACancelKeepsTheLastFinishedPassAndTheNextRequestContinuesIt) {
    const Scene s = sphere(0.3f);
    Session session;
    Renderers renderers;
    std::atomic<bool> cancel{false};
    RenderRequest req = request("truth", 16, 64);
    req.cancel = &cancel;
    req.on_pass = [&](const Frame&, int spp) {
        if (spp >= 4) cancel = true;  // stops within the next pass
    };
    EXPECT_THROW(renderers.get("truth").render(session, s, req), Cancelled);
    const RenderResult more = renderers.get("truth").render(session, s, request("truth", 16, 8));
    EXPECT_EQ(more.sampled->cached_spp, 4) << "continued from the last finished pass";
    Renderers fresh;
    EXPECT_EQ(more.frame.aov("radiance").data, fresh.get("truth").render(session, s, request("truth", 16, 8)).frame.aov("radiance").data);
}

// The window's Truth view and `capture`/Python ask the same renderer: a truth the window rendered
// is read back by a workbench from the same cache, and the entries are the stage store's.
TEST(TruthRenderer, TheWindowAndTheWorkbenchShareTheDiskCache) {
    const Scene s = sphere(0.123f);  // a truth no other test renders
    const uint64_t seed = uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());  // not on disk from an earlier run
    {
        gui::TruthRunner window;
        TruthSettings st;
        st.spp = 4;
        st.seed = seed;
        window.want(s, 16, 16, st);
        ASSERT_TRUE(window.wait_idle(60s));
        ASSERT_EQ(window.status().spp, 4) << window.status().error;
    }
    Workbench wb;
    RenderRequest req = request("truth", 16, 4);
    req.truth.seed = seed;
    const RenderResult r = wb.render(s, req);
    EXPECT_EQ(r.sampled->cached_spp, 4) << "the window's truth, from " << cache_folder("truth");
    const std::string entry = StageStore(cache_folder("truth"), version_string(), 0).path("truth", r.sampled->key);
    EXPECT_TRUE(std::filesystem::exists(entry)) << entry;
}

// [SECTION] The library
// The Python module links the library alone: neither GLFW nor ImGui.
TEST(Library, ThePythonModuleLinksNoWindow) {
    const std::filesystem::path build = std::filesystem::path(test::mesolab_binary()).parent_path();
    std::filesystem::path module;
    if (!std::filesystem::is_directory(build / "python")) GTEST_SKIP() << "the Python module is not built in " << build;
    for (const auto& e : std::filesystem::directory_iterator(build / "python"))
        if (e.path().filename().string().rfind("mesolab", 0) == 0 && e.path().extension() == ".so") module = e.path();
    if (module.empty()) GTEST_SKIP() << "the Python module is not built";
    const std::string out = command_output("ldd " + module.string() + " 2>&1");
    EXPECT_NE(out.find("libtbb"), std::string::npos) << out;
    EXPECT_EQ(out.find("glfw"), std::string::npos) << out;
    EXPECT_EQ(out.find("imgui"), std::string::npos) << out;
}

// The command line and the module call renderers by the names users give and by their traits:
// their code neither tests for one renderer nor includes the window's Truth view.
TEST(Library, TheCommandsAndTheModuleNameNoRenderer) {
    const std::filesystem::path root = test::source_dir();
    const std::regex special(R"((Backend::|renderer\s*==\s*"|backend\s*==\s*"truth"|"truth_error"\s*\)|app/gui/truth_view\.h))");
    std::vector<std::filesystem::path> files = {root / "python/mesolab.cpp"};
    for (const auto& e : std::filesystem::directory_iterator(root / "app"))
        if (e.path().extension() == ".cpp" || e.path().extension() == ".h") files.push_back(e.path());
    for (const auto& f : files) {
        const std::string text = test::slurp(f.string());
        std::smatch m;
        EXPECT_FALSE(std::regex_search(text, m, special)) << f << ": " << m.str();
    }
}

// measure_bench gives the cells as values; the JSON the command writes is made from them.
TEST(Library, BenchResultsAreValues) {
    BenchOptions o;
    o.tables = {"basic"};
    o.repeat = 1;
    o.backend = "cpu";
    o.rows = {"sphere 64"};
    o.columns = {"tessellate"};
    o.quiet = true;
    const BenchResult r = measure_bench(o);
    ASSERT_EQ(r.cells.size(), 1u);
    EXPECT_EQ(r.cells[0].row, "sphere 64");
    EXPECT_GT(r.cells[0].median, 0.0);
    EXPECT_EQ(bench_json(r)["cells"][0]["median_ms"].get<double>(), r.cells[0].median);
    o.memory_limit = 1;  // one byte: the first stage does not start
    EXPECT_THROW(measure_bench(o), MemoryBudgetError);
}
