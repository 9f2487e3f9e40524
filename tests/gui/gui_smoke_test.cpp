// GUI smoke tests: run the real window under a virtual X display (xvfb-run) in scripted mode and
// check the exit status, the screenshots it writes and its error messages.
#include "core/image.h"
#include "support/cli.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

// Single-quoted for sh.
std::string q(const std::string& s) {
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Result {
    int status = -1;
    std::string err;
};

class GuiSmoke : public ::testing::Test {
protected:
    void SetUp() override {
        ASSERT_EQ(std::system("command -v xvfb-run >/dev/null 2>&1"), 0)
            << "xvfb-run is required by the GUI smoke tests (Debian: apt-get install xvfb xauth); CI installs it";
        dir_ = fs::temp_directory_path() / ("mesolab_gui_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        preset_ = fs::path(mesolab::test::source_dir()) / "presets/basic/sphere.json";
        if (!fs::exists(preset_)) {
            preset_ = dir_ / "sphere.json";
            std::ofstream(preset_) << R"({"schema":1,"objects":[{"geometry":{"type":"sphere"},"material":{"technique":"basic"}}]})";
        }
    }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(dir_);
    }

    // `mesolab gui ARGS` under xvfb-run, from the temporary folder (so screenshots/ lands there).
    // The exit status is mesolab's own, written by the inner shell: xvfb-run's status also
    // reflects its own clean-up, which can fail now and then.
    Result gui(const std::string& args) {
        const fs::path err = dir_ / "stderr.txt", status = dir_ / "status.txt";
        fs::remove(status);
        const std::string inner = q(mesolab::test::mesolab_binary()) + " gui " + args + " >/dev/null 2>" + q(err.string()) + "; echo $? >" + q(status.string());
        const std::string cmd = "cd " + q(dir_.string()) + " && timeout 600 xvfb-run -a -s " + q("-screen 0 1600x1000x24") + " sh -c " + q(inner) +
                                " >" + q((dir_ / "xvfb.txt").string()) + " 2>&1";
        // `xvfb-run -a` instances started at the same moment (ctest -j) may race for a display
        // number; one of them then fails before running anything. Try again in that case.
        int rc = 0;
        for (int attempt = 0; attempt < 3; ++attempt) {
            rc = std::system(cmd.c_str());
            if (fs::exists(status)) break;
            ::sleep(1);
        }
        Result r;
        r.err = slurp(err);
        const std::string st = slurp(status);
        if (st.empty()) {
            r.status = -1;
            r.err += "\n(no exit status: xvfb-run exited with " + std::to_string(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1) + ": " + slurp(dir_ / "xvfb.txt") + ")";
        } else {
            r.status = std::stoi(st);
        }
        return r;
    }

    fs::path dir_, preset_;
};

// Not one colour everywhere: the largest per-channel spread of the image.
float spread(const mesolab::Image& img) {
    float lo = 1e30f, hi = -1e30f;
    for (float v : img.data) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    return hi - lo;
}

// Fraction of texels that differ from the first one by more than `eps` in some channel.
double varied_fraction(const mesolab::Image& img, float eps = 0.02f) {
    size_t n = 0;
    const size_t count = size_t(img.width) * size_t(img.height), c = size_t(img.channels);
    for (size_t i = 0; i < count; ++i)
        for (size_t k = 0; k < std::min<size_t>(c, 3); ++k)
            if (std::abs(img.data[i * c + k] - img.data[k]) > eps) {
                ++n;
                break;
            }
    return double(n) / double(count);
}

double mean_abs_diff(const mesolab::Image& a, const mesolab::Image& b) {
    if (a.width != b.width || a.height != b.height || a.channels != b.channels) return 1e30;
    double s = 0;
    for (size_t i = 0; i < a.data.size(); ++i) s += std::abs(a.data[i] - b.data[i]);
    return s / double(a.data.size());
}
}  // namespace

TEST_F(GuiSmoke, FramesWithScreenshots) {
    const fs::path v = dir_ / "v.png", w = dir_ / "w.png";
    const Result r = gui(q(preset_.string()) + " --size 1600x900 --frames 5 --screenshot " + q(v.string()) + " --window-screenshot " + q(w.string()));
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_TRUE(fs::exists(v)) << r.err;
    ASSERT_TRUE(fs::exists(w)) << r.err;

    const mesolab::Image vi = mesolab::read_image(v.string());
    const mesolab::Image wi = mesolab::read_image(w.string());
    // The whole window; the viewport is most of its width left of the panels.
    EXPECT_EQ(wi.width, 1600);
    EXPECT_EQ(wi.height, 900);
    EXPECT_GE(vi.width, 600);
    EXPECT_LT(vi.width, 1600);
    EXPECT_GE(vi.height, 300);
    EXPECT_LT(vi.height, 900);
    // The object is on screen: a good part of the viewport differs from the background corner.
    EXPECT_GT(spread(vi), 0.2f);
    EXPECT_GT(varied_fraction(vi), 0.1);
    // The window shows panels (text, widgets) around the viewport.
    EXPECT_GT(spread(wi), 0.5f);
    EXPECT_GT(varied_fraction(wi), 0.3);
}

TEST_F(GuiSmoke, ScriptLoadsSetsAndScreenshots) {
    const fs::path a = dir_ / "a.png", b = dir_ / "b.png", w = dir_ / "w.png", script = dir_ / "script.txt";
    std::ofstream(script) << "# smoke test script\n"
                          << "load " << preset_.string() << "\n"
                          << "frames 3\n"
                          << "screenshot " << a.string() << "\n"
                          << "set light.direction=80,200\n"
                          << "set camera.distance=4.5\n"
                          << "frames 2\n"
                          << "wait\n"
                          << "screenshot " << b.string() << "\n"
                          << "size 1280x720\n"
                          << "window-screenshot " << w.string() << "\n"
                          << "quit\n"
                          << "frames 1000000\n";  // never reached
    const Result r = gui("--script " + q(script.string()));
    ASSERT_EQ(r.status, 0) << r.err;
    const mesolab::Image ai = mesolab::read_image(a.string()), bi = mesolab::read_image(b.string()), wi = mesolab::read_image(w.string());
    EXPECT_GT(varied_fraction(ai), 0.1);
    EXPECT_GT(varied_fraction(bi), 0.1);
    // The light and the camera moved: the frames differ.
    EXPECT_GT(mean_abs_diff(ai, bi), 0.01);
    EXPECT_EQ(wi.width, 1280);
    EXPECT_EQ(wi.height, 720);
}

// File > Save as shareable writes a pack (here of a scene with an environment map); the window
// opens the pack as it opens a preset and shows the same frame.
TEST_F(GuiSmoke, SavesAsShareableAndOpensThePack) {
    const fs::path sky = fs::path(mesolab::test::source_dir()) / "presets/basic/torus-sky.json";
    const fs::path a = dir_ / "a.png", b = dir_ / "b.png", pack = dir_ / "shared/torus.zip", script = dir_ / "pack.txt";
    std::ofstream(script) << "load " << sky.string() << "\n"
                          << "frames 2\nwait\nscreenshot " << a.string() << "\n"
                          << "save-pack " << pack.string() << "\n"
                          << "load " << pack.string() << "\n"
                          << "frames 2\nwait\nscreenshot " << b.string() << "\n"
                          << "quit\n";
    const Result r = gui("--script " + q(script.string()));
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_TRUE(fs::is_regular_file(pack));
    const mesolab::Image ai = mesolab::read_image(a.string()), bi = mesolab::read_image(b.string());
    EXPECT_GT(varied_fraction(ai), 0.1);
    EXPECT_LT(mean_abs_diff(ai, bi), 1e-6) << "the pack shows another frame than its preset";
    // A bad pack: status 2, naming it; the window does not crash.
    const fs::path bad = dir_ / "bad.zip";
    std::ofstream(bad) << "PK not a zip";
    const Result rb = gui(q(bad.string()) + " --frames 1");
    EXPECT_EQ(rb.status, 2) << rb.err;
    EXPECT_NE(rb.err.find("bad.zip"), std::string::npos) << rb.err;
}

TEST_F(GuiSmoke, BadPresetExitsWithStatus2NamingTheFile) {
    const fs::path bad = dir_ / "broken_preset.json";
    std::ofstream(bad) << R"({"schema":1,"objects":[{"geometry":{"type":"sphere"},"material":{"technique":"basic","kd":[0.5,0.5]}}]})";
    const Result r = gui(q(bad.string()) + " --frames 3 --screenshot " + q((dir_ / "never.png").string()));
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("broken_preset.json"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "never.png"));

    const Result missing = gui(q((dir_ / "no_such_preset.json").string()) + " --frames 1");
    EXPECT_EQ(missing.status, 2) << missing.err;
    EXPECT_NE(missing.err.find("no_such_preset.json"), std::string::npos) << missing.err;
}

TEST_F(GuiSmoke, BadScriptLineExitsWithStatus2NamingFileAndLine) {
    const fs::path script = dir_ / "typo.txt";
    std::ofstream(script) << "# comment\n\nload " << preset_.string() << "\nframez 3\n";
    const Result r = gui("--script " + q(script.string()));
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("typo.txt:4"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("framez"), std::string::npos) << r.err;

    // A bad key at run time names the line too.
    const fs::path script2 = dir_ / "badkey.txt";
    std::ofstream(script2) << "load " << preset_.string() << "\nframes 1\nset light.directoin=10,10\n";
    const Result r2 = gui("--script " + q(script2.string()));
    EXPECT_EQ(r2.status, 2) << r2.err;
    EXPECT_NE(r2.err.find("badkey.txt:3"), std::string::npos) << r2.err;
    EXPECT_NE(r2.err.find("light.direction"), std::string::npos) << r2.err;  // the suggestion
}

// The Truth view: the viewport shows the truth refined to the samples asked for, then the error
// against it (colours, mostly white where the two agree); the screenshot is what is shown. A
// technique without a truth says so and the window keeps running.
TEST_F(GuiSmoke, TruthViewShowsTheTruthAndTheErrorAndSurvivesATechniqueWithoutOne) {
    const fs::path rt = dir_ / "rt.png", truth = dir_ / "truth.png", error = dir_ / "error.png", back = dir_ / "back.png", script = dir_ / "truth.txt";
    std::ofstream(script) << "load " << preset_.string() << "\n"
                          << "size 1280x720\n"
                          << "wait\n"
                          << "screenshot " << rt.string() << "\n"
                          << "view truth 4\n"
                          << "wait\n"
                          << "screenshot " << truth.string() << "\n"
                          << "view error\n"
                          << "wait\n"
                          << "screenshot " << error.string() << "\n"
                          << "load " << (fs::path(mesolab::test::source_dir()) / "presets/bumpsynth/fig1-sphere-distances.json").string() << "\n"
                          << "wait\n"
                          << "view real-time\n"
                          << "wait\n"
                          << "screenshot " << back.string() << "\n"
                          << "quit\n";
    const Result r = gui("--script " + q(script.string()));
    ASSERT_EQ(r.status, 0) << r.err;
    const mesolab::Image a = mesolab::read_image(rt.string()), t = mesolab::read_image(truth.string()), e = mesolab::read_image(error.string());
    EXPECT_GT(varied_fraction(t), 0.1);
    EXPECT_GT(mean_abs_diff(a, t), 0.001);  // the truth is not the real-time frame (noise, shadows; 0.004-0.006 measured)
    EXPECT_LT(mean_abs_diff(a, t), 0.2);    // but the same scene
    EXPECT_GT(mean_abs_diff(t, e), 0.05);   // the error's colours
    EXPECT_GT(varied_fraction(mesolab::read_image(back.string())), 0.1);
}
