// GUI scripts without a window: parsing (errors name FILE:LINE and the bad command) and stepping
// through the commands against a recording stand-in for the window.
#include "app/gui/script.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace mesolab;
using namespace mesolab::gui;

namespace {

class ScriptFiles : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("mesolab_script_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string write(const std::string& name, const std::string& text) {
        const fs::path p = dir_ / name;
        std::ofstream(p) << text;
        return p.string();
    }
    // The InputError message of parsing `text`, or "" when it parses.
    std::string parse_error(const std::string& text) {
        try {
            parse_script(write("bad.txt", text));
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    }

    fs::path dir_;
};

// Records what the commands ask of the window.
struct FakeHost : ScriptHost {
    std::vector<std::string> log;
    bool is_settled = true;
    ShotResult shot;
    int fb_w = 1600, fb_h = 900;

    void load(const std::string& path) override { log.push_back("load " + path); }
    void set(const std::string& a) override {
        if (a == "bad.key=1") throw InputError("--set bad.key: unknown key");
        if (a == "bug=1") throw std::runtime_error("internal trouble");
        log.push_back("set " + a);
    }
    bool settled() const override { return is_settled; }
    void screenshot(const std::string& path) override { log.push_back("screenshot " + path); }
    void request_window_screenshot(const std::string& path) override { log.push_back("window-screenshot " + path); }
    ShotResult window_screenshot_result() const override { return shot; }
    void request_size(int w, int h) override { log.push_back("size " + std::to_string(w) + "x" + std::to_string(h)); }
    bool has_size(int w, int h) const override { return w == fb_w && h == fb_h; }
    void view(const std::string& what, int spp) override { log.push_back("view " + what + " " + std::to_string(spp)); }
};

ScriptCommand cmd(std::string verb, std::string arg = "", int n = 0) {
    ScriptCommand c;
    c.verb = std::move(verb);
    c.arg = std::move(arg);
    c.n = n;
    return c;
}

// A runner for commands as if they were lines 1, 2, ... of "s.txt".
ScriptRunner runner(std::vector<ScriptCommand> cmds) {
    for (size_t i = 0; i < cmds.size(); ++i) cmds[i].where = "s.txt:" + std::to_string(i + 1);
    return ScriptRunner(std::move(cmds), "");
}
}  // namespace

// [SECTION] Parsing
TEST_F(ScriptFiles, ParsesEveryCommandWithItsFileAndLine) {
    const std::string path = write("ok.txt",
                                   "# a comment\n"
                                   "\n"
                                   "load presets/basic/sphere.json\n"
                                   "  set light.direction=80,200  \n"
                                   "frames 3\n"
                                   "wait\n"
                                   "screenshot out/a.png\n"
                                   "window-screenshot out/w.png\n"
                                   "size 1280x720\n"
                                   "quit\n");
    const std::vector<ScriptCommand> c = parse_script(path);
    ASSERT_EQ(c.size(), 8u);
    EXPECT_EQ(c[0].verb, "load");
    EXPECT_EQ(c[0].arg, "presets/basic/sphere.json");
    EXPECT_EQ(c[0].where, path + ":3");
    EXPECT_EQ(c[1].verb, "set");
    EXPECT_EQ(c[1].arg, "light.direction=80,200");
    EXPECT_EQ(c[1].where, path + ":4");
    EXPECT_EQ(c[2].verb, "frames");
    EXPECT_EQ(c[2].n, 3);
    EXPECT_EQ(c[3].verb, "wait");
    EXPECT_EQ(c[4].arg, "out/a.png");
    EXPECT_EQ(c[5].verb, "window-screenshot");
    EXPECT_EQ(c[6].w, 1280);
    EXPECT_EQ(c[6].h, 720);
    EXPECT_EQ(c[7].verb, "quit");
    EXPECT_EQ(c[7].where, path + ":10");
}

TEST_F(ScriptFiles, UnknownCommandNamesFileLineAndTheCommand) {
    const std::string e = parse_error("# comment\n\nload x.json\nframez 3\n");
    EXPECT_NE(e.find("bad.txt:4"), std::string::npos) << e;
    EXPECT_NE(e.find("framez"), std::string::npos) << e;
    EXPECT_NE(e.find("window-screenshot PATH"), std::string::npos) << e;  // lists the commands
}

TEST_F(ScriptFiles, BadArgumentsNameFileLineAndTheValue) {
    struct Case {
        std::string text, where, shows;
    };
    const std::vector<Case> cases{
        {"frames 3x\n", "bad.txt:1", "'3x'"},
        {"frames -1\n", "bad.txt:1", "'-1'"},
        {"frames\n", "bad.txt:1", "'frames' expects a count"},
        {"wait\nsize 16x0\n", "bad.txt:2", "'16x0'"},
        {"set light.direction\n", "bad.txt:1", "'light.direction'"},
        {"\n\nwait now\n", "bad.txt:3", "'now'"},
        {"quit please\n", "bad.txt:1", "'quit' takes no argument"},
        {"load\n", "bad.txt:1", "'load' needs a path"},
        {"screenshot\n", "bad.txt:1", "'screenshot' needs a path"},
        {"view sideways\n", "bad.txt:1", "'sideways'"},
        {"view truth 0\n", "bad.txt:1", "'0'"},
    };
    for (const Case& c : cases) {
        const std::string e = parse_error(c.text);
        EXPECT_NE(e.find(c.where), std::string::npos) << c.text << " -> " << e;
        EXPECT_NE(e.find(c.shows), std::string::npos) << c.text << " -> " << e;
    }
}

TEST_F(ScriptFiles, MissingScriptNamesThePath) {
    const std::string missing = (dir_ / "no_such_script.txt").string();
    try {
        parse_script(missing);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no_such_script.txt"), std::string::npos) << e.what();
    }
}

TEST(FramesScript, FramesThenWaitThenScreenshotsThenQuit) {
    GuiOptions o;
    o.frames = 5;
    o.screenshot = "v.png";
    o.window_screenshot = "w.png";
    const std::vector<ScriptCommand> c = frames_script(o);
    std::vector<std::string> verbs;
    for (const auto& x : c) verbs.push_back(x.verb + (x.arg.empty() ? "" : " " + x.arg));
    EXPECT_EQ(verbs, (std::vector<std::string>{"frames", "wait", "frames", "screenshot v.png", "window-screenshot w.png", "quit"}));
    EXPECT_EQ(c[0].n, 4);
    EXPECT_EQ(c[2].n, 1);
    EXPECT_EQ(c[0].where, "--frames");
}

// [SECTION] Running
TEST(ScriptRunner, FramesCountsFramesThenTheNextCommandsRun) {
    FakeHost host;
    ScriptRunner r = runner({cmd("frames", "", 2), cmd("set", "camera.distance=3")});
    r.step(host);
    r.step(host);
    EXPECT_TRUE(host.log.empty());
    EXPECT_FALSE(r.finished());
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"set camera.distance=3"}));
    EXPECT_TRUE(r.finished());
    EXPECT_FALSE(r.failure());
}

TEST(ScriptRunner, WaitAndScreenshotWaitUntilSettled) {
    FakeHost host;
    host.is_settled = false;
    ScriptRunner r = runner({cmd("wait"), cmd("screenshot", "a.png")});
    r.step(host);
    r.step(host);
    EXPECT_EQ(r.position(), 0u);
    host.is_settled = true;
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"screenshot a.png"}));
    EXPECT_TRUE(r.finished());
}

TEST(ScriptRunner, WindowScreenshotIsRequestedOnceThenAwaited) {
    FakeHost host;
    ScriptRunner r = runner({cmd("window-screenshot", "w.png"), cmd("quit")});
    r.step(host);
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"window-screenshot w.png"}));
    EXPECT_FALSE(r.finished());
    host.shot.done = true;
    r.step(host);
    EXPECT_TRUE(r.finished());
    EXPECT_FALSE(r.failure());
}

TEST(ScriptRunner, FailedWindowScreenshotFailsTheScript) {
    FakeHost host;
    ScriptRunner r = runner({cmd("window-screenshot", "w.png")});
    r.step(host);
    host.shot.error = "window-screenshot w.png: cannot write";
    r.step(host);
    ASSERT_TRUE(r.failure());
    EXPECT_EQ(r.failure()->message, "s.txt:1: window-screenshot w.png: cannot write");
    EXPECT_TRUE(r.failure()->input_error);
}

TEST(ScriptRunner, SizeWaitsForTheFramebuffer) {
    FakeHost host;
    ScriptCommand size = cmd("size", "1280x720");
    size.w = 1280;
    size.h = 720;
    ScriptRunner r = runner({size});
    r.step(host);
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"size 1280x720"}));
    EXPECT_FALSE(r.finished());
    host.fb_w = 1280;
    host.fb_h = 720;
    r.step(host);
    EXPECT_TRUE(r.finished());
}

TEST(ScriptRunner, QuitStopsBeforeTheRest) {
    FakeHost host;
    ScriptRunner r = runner({cmd("set", "a=1"), cmd("quit"), cmd("set", "b=2")});
    r.step(host);
    EXPECT_TRUE(r.finished());
    EXPECT_EQ(host.log, (std::vector<std::string>{"set a=1"}));
    r.step(host);
    EXPECT_EQ(host.log.size(), 1u);
}

TEST(ScriptRunner, FailuresNameTheLineAndKeepTheFirst) {
    FakeHost host;
    ScriptRunner r = runner({cmd("set", "a=1"), cmd("set", "bad.key=1"), cmd("set", "c=1")});
    r.step(host);
    ASSERT_TRUE(r.failure());
    EXPECT_EQ(r.failure()->message, "s.txt:2: --set bad.key: unknown key");
    EXPECT_TRUE(r.failure()->input_error);
    r.fail("later trouble", false);  // e.g. an evaluation failing afterwards: the first one stays
    EXPECT_EQ(r.failure()->message, "s.txt:2: --set bad.key: unknown key");
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"set a=1"}));

    ScriptRunner bug = runner({cmd("set", "bug=1")});
    bug.step(host);
    ASSERT_TRUE(bug.failure());
    EXPECT_FALSE(bug.failure()->input_error);
}

TEST(ScriptRunner, FailureFromOutsideNamesTheRunningCommand) {
    FakeHost host;
    host.is_settled = false;
    ScriptRunner r = runner({cmd("set", "a=1"), cmd("wait")});
    r.step(host);
    r.fail("evaluation failed: bad file", true);
    ASSERT_TRUE(r.failure());
    EXPECT_EQ(r.failure()->message, "s.txt:2: evaluation failed: bad file");
}

TEST_F(ScriptFiles, LoadFallsBackToTheScriptsFolder) {
    const std::string name = "preset_next_to_script_" + std::to_string(::getpid()) + ".json";
    ASSERT_FALSE(fs::exists(name));  // not in the working directory
    write(name, "{}");
    const std::string script = write("s.txt", "load " + name + "\nload /abs/elsewhere.json\nload not_here.json\n");
    FakeHost host;
    ScriptRunner r(parse_script(script), script);
    r.step(host);
    EXPECT_EQ(host.log, (std::vector<std::string>{"load " + (dir_ / name).string(), "load /abs/elsewhere.json", "load not_here.json"}));
    EXPECT_TRUE(r.finished());
}

// `view` switches the Truth view (with a target of samples when given) and completes at once;
// the `wait` after it waits for the truth (the host's settled()).
TEST(ScriptRunner, ViewSwitchesTheTruthView) {
    FakeHost host;
    ScriptCommand truth = cmd("view", "truth", 16), back = cmd("view", "real-time");
    ScriptRunner r = runner({truth, cmd("wait"), back});
    host.is_settled = false;
    r.step(host);
    EXPECT_EQ(host.log, std::vector<std::string>{"view truth 16"});
    host.is_settled = true;
    r.step(host);
    EXPECT_EQ(host.log.back(), "view real-time 0");
    EXPECT_TRUE(r.finished());
}

TEST(ScriptRunner, NoCommandsFinishesAtOnce) {
    FakeHost host;
    ScriptRunner r;
    EXPECT_FALSE(r.finished());
    r.step(host);
    EXPECT_TRUE(r.finished());
    EXPECT_TRUE(host.log.empty());
}
