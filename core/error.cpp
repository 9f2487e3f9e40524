#include "core/error.h"

#include <algorithm>
#include <cctype>

namespace mesolab {

// [SECTION] "Did you mean" suggestions
namespace {

char lower(char c) { return char(std::tolower(static_cast<unsigned char>(c))); }

// Levenshtein distance (unit insert/delete/substitute costs), case-insensitive, two rows.
size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t substitute = prev[j - 1] + (lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, substitute});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}
}  // namespace

std::string nearest_key(const std::string& key, const std::vector<std::string>& candidates) {
    const size_t threshold = std::max<size_t>(2, key.size() / 3);
    const std::string* best = nullptr;
    size_t best_distance = threshold + 1;
    for (const std::string& c : candidates) {
        const size_t d = edit_distance(key, c);
        if (d < best_distance) {  // strict: ties keep the first candidate
            best_distance = d;
            best = &c;
        }
    }
    return best ? *best : std::string();
}
}  // namespace mesolab
