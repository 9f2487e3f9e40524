// Technique basic: its timing table.
#include "core/basic/technique.h"
#include "core/scene_stages.h"

namespace mesolab::basic {

// Our own table (no paper behind this technique): tessellation and frame times.
std::vector<BenchTable> BasicTechnique::bench_tables() const {
    auto scene = [](const char* type, int res) {
        return [=] {
            Scene s = default_scene("basic");
            s.name = std::string(type) + std::to_string(res);
            s.objects[0].geometry.set("type", std::string(type));
            s.objects[0].geometry.set("resolution", int64_t(res));
            return s;
        };
    };
    BenchTable t;
    t.name = "basic";
    t.title = "basic: tessellation and frame time (no paper figures: this technique carries the pipeline)";
    t.columns = {{"tessellate", mesolab::stages::geometry},
                 {"frame 512x512", {}, 512, 512, true, true},
                 {"frame 1280x720", {}, 1280, 720, true, true}};
    t.rows = {{"sphere 64", scene("sphere", 64), {}},
              {"sphere 512", scene("sphere", 512), {}},
              {"torus 256", scene("torus", 256), {}}};
    return {t};
}
}  // namespace mesolab::basic
