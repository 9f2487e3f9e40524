#include "core/truth/cache.h"
#include "core/hash.h"
#include "core/stage_store.h"

#include <cstdio>
#include <cstdlib>

namespace mesolab {
namespace {
// What an entry is of, in full (the store compares it, so a hash collision is a miss).
std::string key_text(const std::string& version, const Scene& s, int width, int height, uint64_t seed) {
    std::string t = version + "\nsums exact; translucency's exitance gathered, its photons split by power and sent where the camera sees the object, two distances a direction, 64 photons a point seen, a guide of 64x64 cells, ballistic exits kept as expected\n";  // the truths' format and estimators
    // The developer switch that selects the plain estimators (bumpsynth's without the split of
    // direct light, translucency's photons split evenly over the sources), and the one that sends
    // translucency's photons without the camera's importance: not the same bytes.
    if (std::getenv("MESOLAB_TRUTH_PLAIN")) t += "plain\n";
    if (std::getenv("MESOLAB_TRUTH_NO_IMPORTANCE")) t += "no importance\n";
    return t + truth_description(s) + "\n" + std::to_string(width) + "x" + std::to_string(height) + " seed " + std::to_string(seed);
}

StageStore store_of(const std::string& folder, const std::string& version) {
    // The truths share the cache's size limit with the stages (least recently used first).
    std::vector<std::string> roots = {folder};
    if (folder == cache_folder("truth")) roots.push_back(cache_folder("stages"));
    return StageStore(folder, version, cache_size_limit(), roots);
}
}  // namespace

std::string truth_cache_key(const std::string& version, const Scene& s, int width, int height, uint64_t seed) {
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a(key_text(version, s, width, height, seed))));
    return hex;
}

std::optional<TruthAccumulator> TruthCache::load(const std::string& key) const {
    if (folder_.empty()) return std::nullopt;
    try {
        const auto e = store_of(folder_, version_).load("truth", key);
        if (!e) return std::nullopt;
        TruthPart p = truth_part_from_bytes(e->payload, key);
        if (p.key != key || p.build != truth_build(version_) || p.sums.first != 0) return std::nullopt;
        return std::move(p.sums);
    } catch (const std::exception&) {
        return std::nullopt;  // unreadable: rendered again
    }
}

bool TruthCache::store(const std::string& key, const TruthAccumulator& a) const {
    if (folder_.empty() || a.first != 0) return false;
    TruthPart p;
    p.key = key;
    p.build = truth_build(version_);
    p.sums = a;
    try {
        return store_of(folder_, version_).save("truth", key, {truth_part_bytes(p), {}});
    } catch (const std::exception&) {
        return false;
    }
}
}  // namespace mesolab
