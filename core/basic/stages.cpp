// Technique basic: the stage graph (handles in stages.h).
#include "core/basic/stages.h"
#include "core/basic/technique.h"

namespace mesolab::basic {

void BasicTechnique::declare_stages(StageGraph& g) const {
    // Albedo textures: read once, reused until the file or the path changes.
    g.add(stages::albedo, {
           .help = "Read the object's albedo map",
           .scope = StageScope::Object,
           .technique = "basic",
           .params = {"basic.albedo_map"},
           .run = [](StageContext& ctx) -> std::any {
               auto img = read_albedo_map(ctx.scene, ctx.material());
               return img ? stage_result(stages::albedo, std::move(*img)) : std::any();
           }});
}
}  // namespace mesolab::basic
