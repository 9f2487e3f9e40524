#pragma once
// [SECTION] The read contract.
// Wherever a result is kept and reused under a key made of declared parameter values, everything
// that result reads must be among them: a stage's cached result (its StageDecl::params and those
// of the stages upstream), a frame step's output kept from the previous frame (FrameStepDecl), a
// truth kept on disk (TruthDecl, core/truth/truth.h). A key read but not declared would not be
// part of the key, and the kept result would silently go stale when that key changes.
//
// DeclaredReads is the one check for all three: installed as the ParamReadWatch of the work (and
// carried into its parallel tasks, core/parallel.h), it throws std::logic_error naming the work and
// the key at the first read of an undeclared key. Sessions, the frame-step scheduler and the truth
// install it where the environment has MESOLAB_CHECK_STAGE_READS=1 (every test run sets it).
#include "core/param.h"
#include "core/scene.h"

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace mesolab {

// Whether a declared pattern ("group.*" or "group.name") covers a read of `group`.`name`; a read
// of "*" (every key: ParamTable::values(), ==) is covered by "group.*" only.
bool pattern_covers(std::string_view pattern, std::string_view group, std::string_view name);

class DeclaredReads final : public ParamReadWatch {
public:
    // `who` names the work ("stage microgeom.visibility", "frame step translucency.illumination",
    // "the truth of bumpsynth"); `patterns` are every key it may read; `object` >= 0 refuses the
    // material and geometry of every other object of `scene` (object stages); `remedy` ends the
    // message (where to declare the key).
    DeclaredReads(std::string who, const Scene& scene, std::vector<std::string> patterns, int object = -1, std::string remedy = {});
    void read(const ParamTable& table, std::string_view name) override;
    const std::vector<std::string>& patterns() const { return patterns_; }

private:
    std::string who_, remedy_;
    const Scene& scene_;
    std::vector<std::string> patterns_;
    int object_;
};

// Throws std::logic_error naming `who` and the pattern when a declared pattern is not "group.*" or
// "group.name" of an existing group and key (`group` finds a group by name, null when there is
// none). The registry checks every stage, frame step and truth when it is built, so a misspelt key
// stops the program at start-up instead of leaving a key out of a cache key.
void check_key_patterns(const std::string& who, const std::vector<std::string>& patterns,
                        const std::function<const ParamGroup*(std::string_view)>& group);

// Whether the read contract is checked (MESOLAB_CHECK_STAGE_READS=1 in the environment).
bool check_reads_by_default();
}  // namespace mesolab
