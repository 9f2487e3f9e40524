#include "app/truth_cache.h"
#include "app/workbench.h"
#include "core/file.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace fs = std::filesystem;

namespace mesolab {
namespace {
struct Fnv {
    uint64_t h = 0xcbf29ce484222325ull;
    void add(const void* p, size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 0x100000001b3ull;
    }
    void add(const std::string& s) {
        const uint64_t n = s.size();
        add(&n, sizeof n);
        add(s.data(), s.size());
    }
};

}  // namespace

TruthCache::TruthCache() {
    if (const char* d = std::getenv("MESOLAB_CACHE_DIR"); d && *d) folder_ = d;
    else if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) folder_ = std::string(x) + "/mesolab/truth";
    else if (const char* home = std::getenv("HOME"); home && *home) folder_ = std::string(home) + "/.cache/mesolab/truth";
}

std::string TruthCache::key(const Scene& s, int width, int height, uint64_t seed) const {
    Fnv f;
    f.add(std::string(version_string()));
    f.add(std::string("sums exact; translucency's exitance gathered, its photons split by power"));  // the truths' format and estimators
    // The developer switch that selects the plain estimators (bumpsynth's without the split of
    // direct light, translucency's photons split evenly over the sources): not the same bytes.
    if (std::getenv("MESOLAB_TRUTH_PLAIN")) f.add(std::string("plain"));
    f.add(truth_description(s));
    const int64_t dims[3] = {width, height, int64_t(seed)};
    f.add(dims, sizeof dims);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(f.h));
    return hex;
}

std::optional<TruthAccumulator> TruthCache::load(const std::string& key) const {
    if (folder_.empty()) return std::nullopt;
    const fs::path path = fs::path(folder_) / (key + ".truth");
    std::error_code ec;
    if (!fs::exists(path, ec)) return std::nullopt;
    try {
        TruthPart p = read_truth_part(path.string());
        if (p.key != key || p.build != truth_build(version_string()) || p.sums.first != 0) return std::nullopt;
        return std::move(p.sums);
    } catch (const std::exception&) {
        return std::nullopt;  // unreadable: rendered again
    }
}

bool TruthCache::store(const std::string& key, const TruthAccumulator& a) const {
    if (folder_.empty() || a.first != 0) return false;
    TruthPart p;
    p.key = key;
    p.build = truth_build(version_string());
    p.sums = a;
    try {
        write_truth_part((fs::path(folder_) / (key + ".truth")).string(), p);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}
}  // namespace mesolab
