#pragma once
// [SECTION] Scripted GUI runs
//  - ScriptCommand, parse_script: a script file, one command per line ('#' starts a comment):
//      load PRESET, set KEY=VALUE, frames N, wait, screenshot PATH, window-screenshot PATH,
//      size WxH, view real-time|truth|error [SPP], quit. Bad lines throw InputError naming
//      FILE:LINE and the command.
//  - frames_script: `--frames N [--screenshot P] [--window-screenshot P]` as the same commands.
//  - ScriptRunner: steps through the commands once per frame against a ScriptHost (the window),
//    waiting where a command needs later frames, and keeps the first failure with its FILE:LINE.
// Nothing here needs a window: the host is an interface, so tests can stand in for it.
#include "app/commands.h"
#include "app/gui/clock.h"

#include <optional>
#include <string>
#include <vector>

namespace mesolab::gui {

// [SECTION] Parsing
struct ScriptCommand {
    std::string where;  // "FILE:LINE" for messages ("--frames" for frames_script)
    std::string verb, arg;
    int n = 0, w = 0, h = 0;  // frames N; size WxH
};

std::vector<ScriptCommand> parse_script(const std::string& path);
std::vector<ScriptCommand> frames_script(const GuiOptions& o);

// [SECTION] Running
// What the commands act on.
class ScriptHost {
public:
    virtual ~ScriptHost() = default;
    virtual void load(const std::string& path) = 0;          // load (the path already resolved)
    virtual void set(const std::string& assignment) = 0;     // set KEY=VALUE
    virtual void save_pack(const std::string& /*path*/) {}   // save-pack PATH: File > Save as shareable
    virtual bool settled() const = 0;                        // evaluated, rendered, nothing pending
    virtual void screenshot(const std::string& path) = 0;    // the viewport's frame, now
    // The whole window, taken after a later frame was drawn: request, then ask for the result.
    virtual void request_window_screenshot(const std::string& path) = 0;
    struct ShotResult {
        bool done = false;
        std::string error;  // not empty: it failed
    };
    virtual ShotResult window_screenshot_result() const = 0;
    virtual void request_size(int w, int h) = 0;             // the window's framebuffer size
    virtual bool has_size(int w, int h) const = 0;
    // What the viewport shows: "real-time", "truth" or "error" (the Truth view), refining the
    // truth to `spp` samples (0: as it is); `wait` then also waits for the truth.
    virtual void view(const std::string& what, int spp) = 0;
};

// Longest a command waits for one evaluation (or a window resize) before giving up.
constexpr double kScriptWaitCapS = 600.0;
constexpr double kResizeWaitCapS = 10.0;

class ScriptRunner {
public:
    struct Failure {
        std::string message;  // "FILE:LINE: message" while a command runs
        bool input_error = false;
    };

    ScriptRunner() = default;  // no commands: finished at the first step
    // `script_path` (may be empty): relative `load` paths not found from the working directory
    // are looked up next to it.
    ScriptRunner(std::vector<ScriptCommand> commands, std::string script_path);

    // Runs commands until one has to wait for a later frame, the script ends (or quits) or a
    // command fails (recorded with fail()).
    void step(ScriptHost& host);
    bool finished() const { return finished_; }
    // Records the first failure, prefixed with the running command's FILE:LINE.
    void fail(const std::string& message, bool input_error);
    const std::optional<Failure>& failure() const { return failure_; }
    const std::vector<ScriptCommand>& commands() const { return commands_; }
    size_t position() const { return pc_; }

private:
    bool run(const ScriptCommand& c, ScriptHost& host);  // true: the command is complete

    std::vector<ScriptCommand> commands_;
    std::string script_path_;
    size_t pc_ = 0;
    // The running command's progress.
    bool started_ = false, requested_ = false;
    int remaining_ = 0;
    Clock::time_point t0_{};
    bool finished_ = false;
    std::optional<Failure> failure_;
};
}  // namespace mesolab::gui
