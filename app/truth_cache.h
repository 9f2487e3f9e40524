#pragma once
// [SECTION] The truths on disk: a truth's samples (TruthAccumulator) kept between runs, outside
// the repository, so that asking again costs nothing and asking for more samples continues it.
// Folder: the cache root's truth/ ($MESOLAB_CACHE_DIR/truth, else $XDG_CACHE_HOME/mesolab/truth, else
// ~/.cache/mesolab/truth; core/stage_store.h), evicted with the stage store's entries, least
// recently used first, above the cache's size limit.
// A truth is keyed by a hash of the program version, what the truth reads (truth_description: the
// physical description, with the contents of the files it names, never an accuracy knob, so
// one truth serves a whole sweep), the frame size and the seed; a file that cannot be read back, or
// that another build or instruction set made (truth_build), is ignored and rendered again. The
// files are partial truths of samples [0, spp) (core/truth/truth.h, TruthPart).
#include "core/scene.h"
#include "core/truth/truth.h"

#include <optional>
#include <string>

namespace mesolab {

class TruthCache {
public:
    TruthCache();  // the folder from the environment
    explicit TruthCache(std::string folder) : folder_(std::move(folder)) {}
    const std::string& folder() const { return folder_; }

    std::string key(const Scene& s, int width, int height, uint64_t seed) const;
    std::optional<TruthAccumulator> load(const std::string& key) const;
    // Through a temporary file and a rename; a failure to write is not an error (the truth was
    // rendered), it only costs the next run the time again: returns false.
    bool store(const std::string& key, const TruthAccumulator& a) const;

private:
    std::string folder_;
};
}  // namespace mesolab
