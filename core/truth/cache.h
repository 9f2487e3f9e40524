#pragma once
// [SECTION] The truths on disk: a truth's samples (TruthAccumulator) kept between runs, outside
// the repository, so that asking again costs nothing and asking for more samples continues it.
// They are entries of the stage store (core/stage_store.h) in the cache root's truth/ folder:
// written atomically, hash-checked (a corrupt or truncated entry is rendered again), evicted with
// the stages' entries, least recently used first, above the cache's size limit.
// A truth is keyed by the program version, what the truth reads (truth_description: the physical
// description, with the contents of the files it names, never an accuracy knob, so one truth
// serves a whole sweep), the frame size and the seed; an entry another build or instruction set
// made (truth_build) is ignored and rendered again. An entry holds samples [0, spp).
#include "core/scene.h"
#include "core/truth/truth.h"

#include <optional>
#include <string>

namespace mesolab {

// The key of the truth of `s` at width x height with `seed`, for the program `version`: 16 hex
// digits (a partial truth's TruthPart::key). InputError as truth_description.
std::string truth_cache_key(const std::string& version, const Scene& s, int width, int height, uint64_t seed);

class TruthCache {
public:
    // The truths in `folder` ("": none kept, nothing read) for the program `version`.
    TruthCache(std::string folder, std::string version) : folder_(std::move(folder)), version_(std::move(version)) {}
    const std::string& folder() const { return folder_; }
    std::optional<TruthAccumulator> load(const std::string& key) const;
    // A failure to write is not an error (the truth was rendered), it only costs the next run the
    // time again: returns false.
    bool store(const std::string& key, const TruthAccumulator& a) const;

private:
    std::string folder_, version_;
};
}  // namespace mesolab
