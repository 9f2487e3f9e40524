#include "core/file.h"
#include "core/error.h"

#include <unistd.h>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace mesolab {

void write_file_atomic(const std::string& path, const std::string& what, const std::function<std::string(const std::string& tmp)>& write_to) {
    const auto fail = [&](const std::string& reason) {
        throw InputError(path + ": cannot write " + what + ": " + reason + "; the existing file is unchanged");
    };
    const fs::path target = fs::absolute(path);
    std::error_code ec;
    const fs::path parent = target.parent_path();
    fs::create_directories(parent, ec);
    if (ec || !fs::is_directory(parent))
        fail("cannot create folder " + parent.string() + " (" + (ec ? ec.message() : std::string("not a folder")) + ")");
    const std::string tmp = target.string() + ".tmp-" + std::to_string(long(::getpid()));
    std::string err = write_to(tmp);
    if (err.empty()) {
        fs::rename(tmp, target, ec);
        if (ec) err = "cannot rename " + tmp + " (" + ec.message() + ")";
    }
    if (!err.empty()) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        fail(err);
    }
}

void write_text_atomic(const std::string& path, const std::string& text) {
    write_file_atomic(path, "file", [&](const std::string& tmp) -> std::string {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) return "could not create " + tmp;
        out << text;
        out.flush();
        return out ? std::string() : std::string("write failed");
    });
}
}  // namespace mesolab
