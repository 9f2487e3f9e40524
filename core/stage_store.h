#pragma once
// [SECTION] Stages that outlive the process.
// Expensive stages (fits, visibility, atlases, tables; StageDecl::save and load) are kept on disk,
// so that a second `mesolab capture` of the same scene, the window opened again or a notebook
// restarted reads them back instead of computing them (the timings say "cached (disk)"). An
// entry is addressed by a hash of the program version and the stage's fingerprint with the
// contents of the files it names (StageGraph::fingerprint, FileIdentity::Contents): the values of
// the keys the stage and those upstream read, the contents of their files and its inputs' keys.
// The read contract (core/read_contract.h) is what makes that key trustworthy.
//
// The cache's root is $MESOLAB_CACHE_DIR, else $XDG_CACHE_HOME/mesolab, else ~/.cache/mesolab,
// with a folder per kind: stages/ (this store), truth/ (the truths, core/truth/cache.h) and
// arrays/ (the Python module's array inputs, which presets name and which are never evicted).
//
// Entries are written through a temporary file and a rename, so two processes writing the same
// entry at once leave one complete file; an entry holds its full fingerprint (a hash collision is
// a miss) and a hash of its payload: a corrupt or truncated entry is absent, never data. Above the
// size limit (MESOLAB_CACHE_SIZE, default 8 GiB; stages/ and truth/ together) the least recently
// used entries go first (a read touches an entry's time).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mesolab {

// The cache's root folder ("" when neither MESOLAB_CACHE_DIR, XDG_CACHE_HOME nor HOME is set).
std::string cache_root();
// A kind's folder under the root: "stages", "truth" or "arrays" ("" without a root).
std::string cache_folder(const std::string& kind);
// The size limit of the evictable folders: MESOLAB_CACHE_SIZE ("512M", "20G"...; 0: no limit),
// else 8 GiB. InputError naming the variable for a bad value.
uint64_t cache_size_limit();

class StageStore {
public:
    // The store in `folder` (cache_folder("stages")) for the program `version` (part of every
    // entry's key), evicting within `evict_roots` (the folders that share the limit; empty: the
    // store's own) above `max_bytes` (0: no limit).
    StageStore(std::string folder, std::string version, uint64_t max_bytes, std::vector<std::string> evict_roots = {});
    // The store of the environment's cache root (stages/, sharing the limit with truth/), or null
    // when there is no root.
    static std::shared_ptr<StageStore> from_environment(const std::string& version);

    struct Entry {
        std::string payload;
        std::vector<std::string> warnings;
    };
    // The entry of `stage` whose fingerprint is `fingerprint` (absent, unreadable, corrupt or of
    // another fingerprint: nullopt). Touches the entry's time (least recently used goes first).
    std::optional<Entry> load(const std::string& stage, const std::string& fingerprint) const;
    // Writes the entry atomically, then evicts above the limit; false (nothing kept) when the
    // folder cannot be written: the result was computed, only the next run pays again.
    bool save(const std::string& stage, const std::string& fingerprint, const Entry& e) const;
    // Removes the least recently used files of the evictable folders until they hold at most
    // max_bytes; returns the bytes removed.
    uint64_t evict() const;
    // The entry's file (for tests and messages).
    std::string path(const std::string& stage, const std::string& fingerprint) const;
    const std::string& folder() const { return folder_; }
    uint64_t max_bytes() const { return max_bytes_; }

private:
    std::string folder_, version_;
    uint64_t max_bytes_;
    std::vector<std::string> evict_roots_;
};
}  // namespace mesolab
