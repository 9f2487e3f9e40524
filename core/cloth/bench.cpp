// Technique cloth: the timing table (mesolab bench cloth) beside the paper's §7 figures.
#include "core/cloth/paper.h"
#include "core/cloth/stages.h"
#include "core/cloth/technique.h"
#include "core/strings.h"

#include <algorithm>
#include <string>
#include <vector>

namespace mesolab::cloth {
// [SECTION] Timing table
std::vector<BenchTable> ClothTechnique::bench_tables() const {
    BenchTable t;
    t.name = "cloth";
    t.title = "Daubert et al. 2001: acquisition, fitting (32 x 32 points, 32 x 32 directions, 1365 BRDFs), memory and frames";
    t.paper_machine = paper::kMachine;
    BenchColumn brdfs{"BRDFs"}, memory{"memory (fitted)"}, error{"fit rel. RMS (level 0, median)"};
    brdfs.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        return p ? std::to_string(p->count()) + " in " + std::to_string(p->level.size()) + " levels" : std::string("—");
    };
    memory.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        return p ? format_bytes(double(p->bytes())) + " (paper " + paper::kMemory + ")" : std::string("—");
    };
    error.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        if (!p || p->report.empty()) return std::string("—");
        std::vector<double> r;
        for (const FitReport& f : p->report[0]) r.push_back(f.rel_rms);
        std::sort(r.begin(), r.end());
        return strprintf("%.2f", r[r.size() / 2]);
    };
    t.columns = {brdfs,
                 memory,
                 error,
                 {"stitch mesh", stages::stitch},
                 {"acquisition", stages::acquire},
                 {"fitting", stages::fit},
                 {"frame " + std::to_string(paper::kFrameWidth) + "x" + std::to_string(paper::kFrameHeight), {}, paper::kFrameWidth, paper::kFrameHeight, true, true},
                 {"frame 1920x1080", {}, 1920, 1080, true, true}};
    auto row = [](const std::string& stitch) {
        BenchRow r;
        r.name = stitch + " curtain";
        r.scene = [=] {
            Scene s = default_scene("cloth");
            s.name = "cloth-" + stitch;
            apply_set(s, "cloth.stitch", stitch);
            apply_set(s, "light.direction", "50,-60");
            apply_set(s, "light.intensity", "3");
            return s;
        };
        r.paper_ms = {std::nullopt, std::nullopt, std::nullopt, std::nullopt, paper::kAcquireMs, paper::kFitMs, paper::kFrameMs, std::nullopt};
        return r;
    };
    t.rows = {row("knit"), row("weave")};
    return {t};
}
}  // namespace mesolab::cloth
