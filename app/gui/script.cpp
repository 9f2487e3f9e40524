// Scripted GUI runs: parsing script files and stepping through their commands.
#include "app/gui/script.h"
#include "core/error.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace mesolab::gui {
namespace {

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return "";
    const auto e = s.find_last_not_of(" \t\r\n");
    return s.substr(b, e - b + 1);
}

const char* const kScriptVerbs =
    "load PRESET, set KEY=VALUE, save-pack PATH, frames N, wait, screenshot PATH, window-screenshot PATH, size WxH, view real-time|truth|error|frontier [SPP], quit";
}  // namespace

// [SECTION] Parsing
std::vector<ScriptCommand> parse_script(const std::string& path) {
    std::ifstream in(path);
    if (!fs::is_regular_file(path) || !in) throw InputError(path + ": cannot read the script (no such file?)");
    std::vector<ScriptCommand> cmds;
    std::string line;
    for (int no = 1; std::getline(in, line); ++no) {
        line = trim(line);
        if (line.empty() || line[0] == '#') continue;
        ScriptCommand c;
        c.where = path + ":" + std::to_string(no);
        const auto sp = line.find_first_of(" \t");
        c.verb = line.substr(0, sp);
        c.arg = sp == std::string::npos ? "" : trim(line.substr(sp));
        auto bad = [&](const std::string& msg) { return InputError(c.where + ": " + msg); };
        if (c.verb == "load" || c.verb == "screenshot" || c.verb == "window-screenshot" || c.verb == "save-pack") {
            if (c.arg.empty()) throw bad("'" + c.verb + "' needs a path");
        } else if (c.verb == "set") {
            if (c.arg.find('=') == std::string::npos) throw bad("'set' expects KEY=VALUE, got '" + c.arg + "'");
        } else if (c.verb == "frames") {
            size_t used = 0;
            long v = -1;
            try {
                v = std::stol(c.arg, &used);
            } catch (const std::exception&) {
            }
            if (c.arg.empty() || used != c.arg.size() || v < 0 || v > 1000000) throw bad("'frames' expects a count 0..1000000, got '" + c.arg + "'");
            c.n = int(v);
        } else if (c.verb == "size") {
            try {
                parse_size(c.arg, c.w, c.h);
            } catch (const InputError&) {
                throw bad("'size' expects WxH within 1..16384 per side (e.g. 1600x900), got '" + c.arg + "'");
            }
        } else if (c.verb == "view") {
            const auto sp2 = c.arg.find_first_of(" \t");
            const std::string what = c.arg.substr(0, sp2), spp = sp2 == std::string::npos ? "" : trim(c.arg.substr(sp2));
            if (what != "real-time" && what != "truth" && what != "error" && what != "frontier")
                throw bad("'view' expects real-time, truth, error or frontier, got '" + what + "'");
            c.n = 0;
            if (!spp.empty()) {
                size_t used = 0;
                long v = -1;
                try {
                    v = std::stol(spp, &used);
                } catch (const std::exception&) {
                }
                if (used != spp.size() || v < 1 || v > 1000000) throw bad("'view " + what + "' expects a sample count 1..1000000, got '" + spp + "'");
                c.n = int(v);
            }
            c.arg = what;
        } else if (c.verb == "wait" || c.verb == "quit") {
            if (!c.arg.empty()) throw bad("'" + c.verb + "' takes no argument, got '" + c.arg + "'");
        } else {
            throw bad("unknown command '" + c.verb + "' (commands: " + kScriptVerbs + "; '#' starts a comment line)");
        }
        cmds.push_back(std::move(c));
    }
    return cmds;
}

std::vector<ScriptCommand> frames_script(const GuiOptions& o) {
    std::vector<ScriptCommand> cmds;
    auto add = [&](std::string verb, std::string arg, int n = 0) {
        ScriptCommand c;
        c.where = "--frames";
        c.verb = std::move(verb);
        c.arg = std::move(arg);
        c.n = n;
        cmds.push_back(std::move(c));
    };
    add("frames", "", std::max(0, o.frames - 1));
    add("wait", "");
    add("frames", "", 1);  // the last frame counts once the evaluation is done
    if (!o.screenshot.empty()) add("screenshot", o.screenshot);
    if (!o.window_screenshot.empty()) add("window-screenshot", o.window_screenshot);
    add("quit", "");
    return cmds;
}

// [SECTION] Running
ScriptRunner::ScriptRunner(std::vector<ScriptCommand> commands, std::string script_path)
    : commands_(std::move(commands)), script_path_(std::move(script_path)) {}

void ScriptRunner::fail(const std::string& message, bool input_error) {
    if (failure_) return;
    const std::string where = pc_ < commands_.size() ? commands_[pc_].where + ": " : "";
    failure_ = Failure{where + message, input_error};
}

void ScriptRunner::step(ScriptHost& host) {
    while (!finished_ && !failure_ && pc_ < commands_.size()) {
        const ScriptCommand& c = commands_[pc_];
        if (!started_) {
            started_ = true;
            requested_ = false;
            remaining_ = c.n;
            t0_ = Clock::now();
        }
        bool done = false;
        try {
            done = run(c, host);
        } catch (const InputError& e) {
            fail(e.what(), true);
            return;
        } catch (const std::exception& e) {
            fail(e.what(), false);
            return;
        }
        if (!done) {
            const double cap = c.verb == "size" ? kResizeWaitCapS : kScriptWaitCapS;
            if (seconds_since(t0_) > cap)
                fail("'" + c.verb + "' gave up after " + std::to_string(int(cap)) + " s (evaluation or window resize did not finish)", false);
            return;
        }
        if (finished_) return;  // quit: stays on its line
        ++pc_;
        started_ = false;
    }
    if (pc_ >= commands_.size()) finished_ = true;
}

bool ScriptRunner::run(const ScriptCommand& c, ScriptHost& host) {
    if (c.verb == "load") {
        std::string path = c.arg;
        std::error_code ec;
        // Relative to the working directory, else to the script's folder.
        if (fs::path(path).is_relative() && !fs::exists(path, ec) && !script_path_.empty()) {
            const fs::path alt = fs::path(script_path_).parent_path() / path;
            if (fs::exists(alt, ec)) path = alt.string();
        }
        host.load(path);
        return true;
    }
    if (c.verb == "set") {
        host.set(c.arg);
        return true;
    }
    if (c.verb == "save-pack") {
        host.save_pack(c.arg);
        return true;
    }
    if (c.verb == "view") {
        host.view(c.arg, c.n);
        return true;
    }
    if (c.verb == "frames") {
        if (remaining_ <= 0) return true;
        --remaining_;
        return false;
    }
    if (c.verb == "wait") return host.settled();
    if (c.verb == "screenshot") {
        if (!host.settled()) return false;
        host.screenshot(c.arg);
        return true;
    }
    if (c.verb == "window-screenshot") {
        if (!requested_) {
            if (!host.settled()) return false;
            requested_ = true;
            host.request_window_screenshot(c.arg);
            return false;
        }
        const ScriptHost::ShotResult r = host.window_screenshot_result();
        if (!r.error.empty()) throw InputError(r.error);
        return r.done;
    }
    if (c.verb == "size") {
        if (!requested_) {
            requested_ = true;
            host.request_size(c.w, c.h);
            return false;
        }
        return host.has_size(c.w, c.h);
    }
    if (c.verb == "quit") {
        finished_ = true;
        return true;
    }
    throw std::logic_error("script command " + c.verb);
}
}  // namespace mesolab::gui
