#include "core/scene_stages.h"
#include "core/error.h"

#include <glm/gtc/matrix_transform.hpp>

namespace mesolab {

mat4 object_to_world(const SceneObject& o) {
    const float s = float(o.geometry.get_float("scale"));
    return glm::scale(glm::translate(mat4(1.f), o.geometry.get_vec3("position")), vec3(s));
}

void declare_scene_stages(StageGraph& g) {
    // Tessellation / mesh files: one mesh per object, object space.
    g.add(stages::geometry, {
           .help = "Tessellate procedural shapes and read mesh files (OpenMesh)",
           .scope = StageScope::Object,
           .params = {"geometry.type", "geometry.path", "geometry.resolution", "geometry.minor_ratio"},
           .memory = [](const StageContext& ctx) {
               MemoryEstimate e;
               const ParamTable& g = ctx.obj().geometry;
               if (g.get_string("type") == "mesh") return e;  // the file's size bounds it
               const double n = double(g.get_int("resolution"));
               // Tessellations have about n x n/2 (sphere) to n x n (torus, plane) vertices; the teapot 32 x (n/8)^2.
               const double vertices = g.get_string("type") == "teapot" ? 32.0 * (n / 8.0 + 1.0) * (n / 8.0 + 1.0) : (n + 1.0) * (n + 1.0);
               constexpr double kVertexBytes = 3 * sizeof(vec3) + sizeof(vec2), kTriangleBytes = 3 * sizeof(uint32_t);
               e.bytes = vertices * (kVertexBytes + 2.0 * kTriangleBytes);
               e.what = "about " + std::to_string(int64_t(vertices)) + " vertices";
               e.lower = {"geometry.resolution"};
               return e;
           },
           .run = [](StageContext& ctx) {
               const ParamTable& g = ctx.obj().geometry;
               const std::string& type = g.get_string("type");
               if (type == "mesh") {
                   const std::string path = ctx.scene.resolve(g.get_string("path"));
                   if (path.empty()) throw InputError("objects[" + std::to_string(ctx.object) + "].geometry.path: geometry.type is 'mesh' but no mesh file is given");
                   return stage_result(stages::geometry, load_mesh(path));
               }
               return stage_result(stages::geometry, make_primitive(primitive_named(type), int(g.get_int("resolution")), float(g.get_float("minor_ratio"))));
           }});
    // Environment map: absent when env.map is empty.
    g.add(stages::env_map, {
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
               return stage_result(stages::env_map, std::move(img));
           }});
    // Irradiance of the environment map in SH9, only when surfaces are lit by the environment.
    g.add(stages::env_irradiance, {
           .help = "Project the environment map onto order-2 spherical harmonics (diffuse irradiance)",
           .inputs = {stages::env_map},
           .effects = {"environment"},
           .run = [](StageContext& ctx) -> std::any {
               auto map = ctx.input(stages::env_map);
               if (!map) return {};
               Environment env;
               env.map = map;
               return stage_result(stages::env_irradiance, project_sh9(env));
           }});
}
}  // namespace mesolab
