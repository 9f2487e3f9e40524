#pragma once
// [SECTION] Saving without losing: every file mesolab writes (presets, images, sidecars, tables,
// samples, models) goes through a temporary file next to it, renamed over it once complete, so a
// failed or interrupted save leaves the old file as it was.
#include <functional>
#include <string>

namespace mesolab {

// `write_to(tmp)` writes the whole file to the temporary path `tmp` ("<path>.tmp-<pid>") and
// returns an error message, "" on success; then `tmp` is renamed over `path`. The folder is
// created if needed. InputError "<path>: cannot write <what>: <reason>; the existing file is
// unchanged" otherwise, with the temporary file removed.
void write_file_atomic(const std::string& path, const std::string& what, const std::function<std::string(const std::string& tmp)>& write_to);

// `text` (any bytes) as the whole file at `path`, as write_file_atomic.
void write_text_atomic(const std::string& path, const std::string& text);
}  // namespace mesolab
