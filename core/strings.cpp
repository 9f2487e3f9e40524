#include "core/strings.h"

#include <charconv>
#include <cstdarg>
#include <cstdio>

namespace mesolab {

std::string strprintf(const char* format, ...) {
    va_list args;
    va_start(args, format);
    va_list again;
    va_copy(again, args);
    char small[256];
    const int n = std::vsnprintf(small, sizeof small, format, args);
    va_end(args);
    std::string out;
    if (n < 0) out.clear();
    else if (size_t(n) < sizeof small) out.assign(small, size_t(n));
    else {
        out.resize(size_t(n) + 1);
        std::vsnprintf(out.data(), out.size(), format, again);
        out.resize(size_t(n));
    }
    va_end(again);
    return out;
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> fields;
    size_t start = 0;
    for (size_t i = s.find(sep); i != std::string::npos; i = s.find(sep, start)) {
        fields.push_back(s.substr(start, i - start));
        start = i + 1;
    }
    fields.push_back(s.substr(start));
    return fields;
}

std::string format_bytes(double bytes) {
    constexpr double KiB = 1024.0, MiB = KiB * 1024.0, GiB = MiB * 1024.0;
    if (bytes >= GiB) return strprintf("%.2f GiB", bytes / GiB);
    if (bytes >= MiB) return strprintf("%.1f MiB", bytes / MiB);
    if (bytes >= KiB) return strprintf("%.1f KiB", bytes / KiB);
    return strprintf("%.0f B", bytes);
}

std::optional<std::pair<int, int>> parse_wxh(const std::string& s) {
    const size_t x = s.find_first_of("xX");
    if (x == std::string::npos || x == 0 || x + 1 >= s.size()) return std::nullopt;
    int w = 0, h = 0;
    const char* end = s.data() + s.size();
    const auto a = std::from_chars(s.data(), s.data() + x, w);
    const auto b = std::from_chars(s.data() + x + 1, end, h);
    if (a.ec != std::errc() || a.ptr != s.data() + x || b.ec != std::errc() || b.ptr != end) return std::nullopt;
    return std::pair{w, h};
}
std::string join(const std::vector<std::string>& parts, const std::string& sep) {
    std::string r;
    for (size_t i = 0; i < parts.size(); ++i) r += (i ? sep : "") + parts[i];
    return r;
}
}  // namespace mesolab
