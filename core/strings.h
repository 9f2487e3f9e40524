#pragma once
// [SECTION] Text: numbers formatted as printf does, byte counts in binary units, fields split,
// "WxH" pairs read.
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mesolab {

// printf into a std::string (any length): strprintf("%.2f MB", bytes / 1048576.0).
std::string strprintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// A byte count with a binary unit: "812 B", "3.5 KiB", "48.0 MiB", "1.50 GiB".
std::string format_bytes(double bytes);

// The fields of `s` between the separators, empty ones included: n separators give n + 1 fields
// ("a,,b," -> "a", "", "b", "").
std::vector<std::string> split(const std::string& s, char sep);

// The parts with `sep` between them: join({"a", "b"}, ", ") -> "a, b".
std::string join(const std::vector<std::string>& parts, const std::string& sep);

// "WxH" (or "WXH"): two decimal integers and nothing else ("512x256" -> {512, 256}); nullopt for
// anything else. Ranges are the caller's to check (frame sizes, goniometer grids).
std::optional<std::pair<int, int>> parse_wxh(const std::string& s);
}  // namespace mesolab
