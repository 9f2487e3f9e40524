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
constexpr char kMagic[8] = {'M', 'L', 'T', 'R', 'U', 'T', 'H', '2'};

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
    f.add(truth_description(s));
    const int64_t dims[3] = {width, height, int64_t(seed)};
    f.add(dims, sizeof dims);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(f.h));
    return hex;
}

std::optional<TruthAccumulator> TruthCache::load(const std::string& key) const {
    if (folder_.empty()) return std::nullopt;
    std::ifstream in(fs::path(folder_) / (key + ".truth"), std::ios::binary);
    if (!in) return std::nullopt;
    char magic[8];
    TruthAccumulator a;
    int32_t dims[3];
    if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) return std::nullopt;
    if (!in.read(reinterpret_cast<char*>(dims), sizeof dims) || !in.read(reinterpret_cast<char*>(&a.seed), sizeof a.seed)) return std::nullopt;
    a.width = dims[0], a.height = dims[1], a.spp = dims[2];
    if (a.width < 1 || a.height < 1 || a.width > 16384 || a.height > 16384 || a.spp < 1) return std::nullopt;
    const size_t n = size_t(a.width) * size_t(a.height) * 3;
    a.sum.resize(n), a.sum2.resize(n), a.exitance.resize(n), a.normal.resize(n);
    if (!in.read(reinterpret_cast<char*>(a.sum.data()), std::streamsize(n * sizeof(double))) ||
        !in.read(reinterpret_cast<char*>(a.sum2.data()), std::streamsize(n * sizeof(double))) ||
        !in.read(reinterpret_cast<char*>(a.exitance.data()), std::streamsize(n * sizeof(double))) ||
        !in.read(reinterpret_cast<char*>(a.normal.data()), std::streamsize(n * sizeof(float))))
        return std::nullopt;
    return a;
}

bool TruthCache::store(const std::string& key, const TruthAccumulator& a) const {
    if (folder_.empty()) return false;
    std::string bytes(kMagic, 8);
    const int32_t dims[3] = {a.width, a.height, a.spp};
    bytes.append(reinterpret_cast<const char*>(dims), sizeof dims);
    bytes.append(reinterpret_cast<const char*>(&a.seed), sizeof a.seed);
    bytes.append(reinterpret_cast<const char*>(a.sum.data()), a.sum.size() * sizeof(double));
    bytes.append(reinterpret_cast<const char*>(a.sum2.data()), a.sum2.size() * sizeof(double));
    bytes.append(reinterpret_cast<const char*>(a.exitance.data()), a.exitance.size() * sizeof(double));
    bytes.append(reinterpret_cast<const char*>(a.normal.data()), a.normal.size() * sizeof(float));
    try {
        write_text_atomic((fs::path(folder_) / (key + ".truth")).string(), bytes);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}
}  // namespace mesolab
