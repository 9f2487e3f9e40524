#include "core/scene_stages.h"
#include "core/error.h"

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/parallel_for.h>

namespace mesolab {

mat4 object_to_world(const SceneObject& o) {
    const float s = float(o.geometry.get_float("scale"));
    return glm::scale(glm::translate(mat4(1.f), o.geometry.get_vec3("position")), vec3(s));
}

void declare_scene_stages(StageGraph& g) {
    // Tessellation / mesh files: one mesh per object, object space.
    g.add({.name = "scene.geometry",
           .help = "Tessellate procedural shapes and read mesh files (OpenMesh)",
           .params = {"geometry.type", "geometry.path", "geometry.resolution", "geometry.minor_ratio"},
           .run = [](StageContext& ctx) {
               SceneGeometry out;
               const auto& objs = ctx.scene.objects;
               out.meshes.resize(objs.size());
               for (size_t i = 0; i < objs.size(); ++i) {
                   const ParamTable& g = objs[i].geometry;
                   const std::string& type = g.get_string("type");
                   if (type == "mesh") {
                       const std::string path = ctx.scene.resolve(g.get_string("path"));
                       if (path.empty()) throw InputError("objects[" + std::to_string(i) + "].geometry.path: geometry.type is 'mesh' but no mesh file is given");
                       out.meshes[i] = load_mesh(path);
                   } else {
                       out.meshes[i] = make_primitive(primitive_named(type), int(g.get_int("resolution")), float(g.get_float("minor_ratio")));
                   }
                   ctx.progress(double(i + 1) / double(objs.size()));
               }
               return stage_result(std::move(out));
           }});
    // Environment map: absent when env.map is empty.
    g.add({.name = "env.map",
           .help = "Read the lat-long environment map (EXR)",
           .params = {"env.map"},
           .run = [](StageContext& ctx) -> std::any {
               const std::string path = ctx.scene.resolve(ctx.scene.env.get_string("map"));
               if (path.empty()) return {};
               Image img = read_image(path, false, true);
               if (img.channels < 3) {
                   // Grey maps: replicate the channel.
                   Image rgb(img.width, img.height, 3);
                   for (size_t i = 0; i < size_t(img.width) * size_t(img.height); ++i)
                       for (int c = 0; c < 3; ++c) rgb.data[i * 3 + size_t(c)] = img.data[i * size_t(img.channels)];
                   img = std::move(rgb);
               }
               return stage_result(std::move(img));
           }});
    // Irradiance of the environment map in SH9, only when surfaces are lit by the environment.
    g.add({.name = "env.irradiance",
           .help = "Project the environment map onto order-2 spherical harmonics (diffuse irradiance)",
           .inputs = {"env.map"},
           .effects = {"environment"},
           .run = [](StageContext& ctx) -> std::any {
               auto map = ctx.input<Image>("env.map");
               if (!map) return {};
               Environment env;
               env.map = map;
               return stage_result(project_sh9(env));
           }});
}
}  // namespace mesolab
