#pragma once
// Test helpers: run the mesolab executable, capture its output and exit status; temp folders.
#include <sys/wait.h>
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace mesolab::test {

// The repository's folder and the mesolab binary (tests/CMakeLists.txt generates them).
const char* source_dir();
const char* mesolab_binary();

struct CliResult {
    int status = -1;
    std::string out, err;
};

inline std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

inline void write_file(const std::string& path, const std::string& text) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    std::ofstream(path, std::ios::binary) << text;
}

// A fresh folder under the system temp dir, removed by the destructor.
struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& tag) {
        path = std::filesystem::temp_directory_path() / ("mesolab-" + tag + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// Runs `mesolab ARGS` in the source folder (so presets/ resolves); ARGS is shell-quoted by the caller.
inline CliResult run_mesolab(const std::string& args, const std::string& prefix = "") {
    static int counter = 0;
    const auto dir = std::filesystem::temp_directory_path();
    const std::string tag = std::to_string(::getpid()) + "-" + std::to_string(counter++);
    const std::string out = (dir / ("mesolab-out-" + tag)).string(), err = (dir / ("mesolab-err-" + tag)).string();
    const std::string cmd = "cd '" + std::string(source_dir()) + "' && " + prefix + " '" + mesolab_binary() + "' " + args + " >'" + out + "' 2>'" + err + "' </dev/null";
    const int raw = std::system(cmd.c_str());
    CliResult r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + (WIFSIGNALED(raw) ? WTERMSIG(raw) : 0);
    r.out = slurp(out);
    r.err = slurp(err);
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
}

inline std::string source_path(const std::string& rel) { return std::string(source_dir()) + "/" + rel; }
}  // namespace mesolab::test
