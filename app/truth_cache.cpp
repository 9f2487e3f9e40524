#include "app/truth_cache.h"
#include "app/workbench.h"
#include "core/file.h"
#include "core/hash.h"
#include "core/stage_store.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace fs = std::filesystem;

namespace mesolab {

TruthCache::TruthCache() : folder_(cache_folder("truth")) {}

std::string TruthCache::key(const Scene& s, int width, int height, uint64_t seed) const {
    Fnv1a f;
    f.add_sized(std::string(version_string()));
    f.add_sized(std::string("sums exact; translucency's exitance gathered, its photons split by power"));  // the truths' format and estimators
    // The developer switch that selects the plain estimators (bumpsynth's without the split of
    // direct light, translucency's photons split evenly over the sources): not the same bytes.
    if (std::getenv("MESOLAB_TRUTH_PLAIN")) f.add_sized(std::string("plain"));
    f.add_sized(truth_description(s));
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
        fs::last_write_time(path, fs::file_time_type::clock::now(), ec);  // recently used: evicted last
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
        // The truths share the cache's size limit with the stage store (least recently used first).
        std::vector<std::string> roots = {folder_};
        if (folder_ == cache_folder("truth")) roots.push_back(cache_folder("stages"));
        StageStore(folder_, version_string(), cache_size_limit(), roots).evict();
        return true;
    } catch (const std::exception&) {
        return false;
    }
}
}  // namespace mesolab
