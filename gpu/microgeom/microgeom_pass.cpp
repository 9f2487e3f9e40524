// GPU pass of technique microgeom: uploads the stages' results (S_i as a texture array, the
// direction set with its triangulation, adjacency and a look-up grid, heightfield normals and
// albedo, scattered irradiance) and shades with microgeom.frag.
#include "core/microgeom/goniometer.h"
#include "core/microgeom/microgeom.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/microgeom/field_textures.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <map>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

constexpr int kGridW = 64, kGridH = 32;

// GL objects made from the stage results (kept in the renderer's resource cache with them).
struct DirectionBuffers {
    Buffer dirs, tris, adj, grid;  // directions, triangles, adjacency (neighbour across the edge opposite corner k), look-up grid
    int tri_count = 0;
};
struct Ellipses {
    Texture t0, t1;
};
struct BrdfTables {
    Texture table, env;
};

// S_i: one R32UI layer per direction.
Texture upload_visibility(const Visibility& vis) {
    return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_R32UI, .width = vis.width, .height = vis.height, .layers = vis.count},
                        {GL_RED_INTEGER, GL_UNSIGNED_INT, vis.hit.data()});
}

DirectionBuffers upload_directions(const DirectionSet& dirs) {
    std::vector<vec4> d;
    for (const vec3& v : dirs.d) d.emplace_back(v, 0.f);
    std::vector<glm::ivec4> tris, adj(dirs.triangles.size(), glm::ivec4(-1));
    std::map<std::pair<int, int>, int> edge;
    for (size_t t = 0; t < dirs.triangles.size(); ++t) {
        const auto& v = dirs.triangles[t];
        tris.emplace_back(v[0], v[1], v[2], 0);
        for (int k = 0; k < 3; ++k) edge[{v[size_t((k + 1) % 3)], v[size_t((k + 2) % 3)]}] = int(t);
    }
    for (size_t t = 0; t < dirs.triangles.size(); ++t) {
        const auto& v = dirs.triangles[t];
        for (int k = 0; k < 3; ++k) {
            auto e = edge.find({v[size_t((k + 2) % 3)], v[size_t((k + 1) % 3)]});
            adj[t][k] = e == edge.end() ? int(t) : e->second;
        }
    }
    std::vector<int> grid(size_t(kGridW) * kGridH);
    for (int gy = 0; gy < kGridH; ++gy)
        for (int gx = 0; gx < kGridW; ++gx) {
            const float theta = (float(gy) + 0.5f) / float(kGridH) * kPi, phi = (float(gx) + 0.5f) / float(kGridW) * 2.f * kPi;
            vec3 bary;
            grid[size_t(gy) * kGridW + size_t(gx)] = dirs.locate({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)}, bary);
        }
    DirectionBuffers b;
    b.dirs = make_storage_buffer(d.data(), d.size() * sizeof(vec4));
    b.tris = make_storage_buffer(tris.data(), tris.size() * sizeof(glm::ivec4));
    b.adj = make_storage_buffer(adj.data(), adj.size() * sizeof(glm::ivec4));
    b.grid = make_storage_buffer(grid.data(), grid.size() * sizeof(int));
    b.tri_count = int(tris.size());
    check_gl("microgeom.upload_directions");
    return b;
}

// All lights' solutions stacked vertically: light i at rows [i H, (i + 1) H).
Texture upload_per_light(const LightsScatter& s, const Heightfield& hf) {
    std::vector<vec3> stacked;
    stacked.reserve(size_t(hf.width) * size_t(hf.height) * std::max<size_t>(1, s.lights.size()));
    for (const LightScatter& one : s.lights) stacked.insert(stacked.end(), one.result.E_indirect.begin(), one.result.E_indirect.end());
    if (stacked.empty()) stacked.assign(size_t(hf.width) * size_t(hf.height), vec3(0.f));
    return rgb_field_texture(stacked, hf.width, int(stacked.size() / size_t(hf.width)));
}

// microgeom.scatter_directions: one RGBA32F layer per direction above the horizon (at least one layer).
Texture upload_per_direction(const DirectionalScatter& s) {
    PROFILE_SCOPE("upload directions");
    const int layers = std::max(1, s.count);
    std::vector<float> rgba(size_t(s.width) * size_t(s.height) * size_t(layers) * 4, 0.f);
    for (size_t k = 0; k < s.E.size(); ++k)
        for (int c = 0; c < 3; ++c) rgba[k * 4 + size_t(c)] = s.E[k][c];
    return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_RGBA32F, .width = s.width, .height = s.height, .layers = layers},
                        {GL_RGBA, GL_FLOAT, rgba.data()});
}

Texture upload_folded(const Importance& imp) {
    std::vector<vec3> mask(imp.folded.size());
    for (size_t k = 0; k < mask.size(); ++k) mask[k] = vec3(float(imp.folded[k]));
    return rgb_field_texture(mask, imp.width, imp.height);
}

Ellipses upload_ellipses(const EllipseMap& em) {
    std::vector<float> rgba0(em.e.size() * 4), rgba1(em.e.size() * 4, 0.f);
    for (size_t k = 0; k < em.e.size(); ++k) {
        const Ellipse& e = em.e[k];
        rgba0[k * 4 + 0] = e.centre.x, rgba0[k * 4 + 1] = e.centre.y, rgba0[k * 4 + 2] = std::cos(e.angle), rgba0[k * 4 + 3] = std::sin(e.angle);
        rgba1[k * 4 + 0] = e.a, rgba1[k * 4 + 1] = e.b;
    }
    Ellipses r;
    r.t0 = rgba_field_texture(rgba0.data(), em.width, em.height);
    r.t1 = rgba_field_texture(rgba1.data(), em.width, em.height);
    return r;
}

// The simulated BRDF: (view node, light node) -> (T, shadow), and the environment row.
BrdfTables upload_brdf(const SimulatedBrdf& b) {
    PROFILE_SCOPE("upload simulated BRDF");
    const int nodes = b.n_theta * b.n_phi;
    std::vector<float> rgba(size_t(nodes) * size_t(nodes) * 4), env(size_t(nodes) * 4, 1.f);
    for (size_t k = 0; k < size_t(nodes) * size_t(nodes); ++k) {
        for (int c = 0; c < 3; ++c) rgba[k * 4 + size_t(c)] = b.table[k][c];
        rgba[k * 4 + 3] = b.shadow.empty() ? 0.f : b.shadow[k];
    }
    for (size_t k = 0; k < size_t(nodes); ++k)
        for (int c = 0; c < 3; ++c) env[k * 4 + size_t(c)] = b.env.empty() ? 0.f : b.env[k][c];
    BrdfTables r;
    r.table = rgba_field_texture(rgba.data(), nodes, nodes);
    r.env = rgba_field_texture(env.data(), nodes, 1);
    check_gl("microgeom.upload_brdf");
    return r;
}

class MicrogeomPass final : public TechniquePass {
public:
    explicit MicrogeomPass(const Technique& t) : program_(Program::graphics("shaders/mesh.vert", "microgeom/microgeom.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.microgeom");
        GpuResources& res = ctx.renderer.resources();
        // The objects' results and materials, parsed once per frame, and their GL objects.
        struct Bound {
            ObjectFrame f;
            GLuint vis = 0, normals = 0, albedo = 0, e_env = 0, e_light = 0, e_dirs = 0, folded = 0;
            const DirectionBuffers* dirs = nullptr;
            const Ellipses* ellipses = nullptr;
            const BrdfTables* brdf = nullptr;
        };
        std::map<int, Bound> bound;
        for (int i : ctx.objects) {
            Bound b{ObjectFrame::from(ctx.scene, ctx.eval, i)};
            const ObjectFrame& f = b.f;
            const Heightfield& hf = *f.hf;
            b.vis = res.get<Texture>(f.vis, "vis", [&] { return upload_visibility(*f.vis); }).get();
            b.normals = res.get<Texture>(f.hf, "normals", [&] { return field_normals_texture(hf); }).get();
            b.albedo = res.get<Texture>(f.hf, "albedo", [&] { return rgb_field_texture(hf.albedo, hf.width, hf.height); }).get();
            b.dirs = &res.get<DirectionBuffers>(f.dirs, "directions", [&] { return upload_directions(*f.dirs); });
            if (f.env) b.e_env = res.get<Texture>(f.env, "E_env", [&] { return rgb_field_texture(f.env->result.E_indirect, hf.width, hf.height); }).get();
            if (f.lights) b.e_light = res.get<Texture>(f.lights, "E_light", [&] { return upload_per_light(*f.lights, hf); }).get();
            if (f.table) b.e_dirs = res.get<Texture>(f.table, "E_dirs", [&] { return upload_per_direction(*f.table); }).get();
            if (f.imp && !f.imp->folded.empty()) b.folded = res.get<Texture>(f.imp, "folded", [&] { return upload_folded(*f.imp); }).get();
            if (f.ell) b.ellipses = &res.get<Ellipses>(f.ell, "ellipses", [&] { return upload_ellipses(*f.ell); });
            if (f.brdf) b.brdf = &res.get<BrdfTables>(f.brdf, "brdf", [&] { return upload_brdf(*f.brdf); });
            bound.emplace(i, std::move(b));
        }
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const Bound& b = bound.at(i);
            const ObjectFrame& f = b.f;
            const Material& m = f.material;
            const Heightfield& hf = *f.hf;
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, b.dirs->dirs.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, b.dirs->tris.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, b.dirs->adj.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, b.dirs->grid.get());
            const int light_scatters = f.lights ? int(std::min(f.lights->lights.size(), ctx.lighting.lights.size())) : 0;
            program_.bind_texture(1, GL_TEXTURE_2D_ARRAY, b.vis, "u_vis");
            program_.bind_texture(2, GL_TEXTURE_2D, b.normals, "u_normals");
            program_.bind_texture(3, GL_TEXTURE_2D, b.albedo, "u_albedo");
            program_.bind_texture(4, GL_TEXTURE_2D, b.e_env, "u_E_env");
            program_.bind_texture(5, GL_TEXTURE_2D, b.e_light, "u_E_light");
            program_.bind_texture(6, GL_TEXTURE_2D, b.folded, "u_folded");
            glUniform1i(program_.uniform("u_has_folded"), b.folded ? 1 : 0);
            program_.bind_texture(7, GL_TEXTURE_2D, b.ellipses ? b.ellipses->t0.get() : 0, "u_ellipse0");
            program_.bind_texture(8, GL_TEXTURE_2D, b.ellipses ? b.ellipses->t1.get() : 0, "u_ellipse1");
            glUniform1i(program_.uniform("u_use_ellipse"), f.ell ? 1 : 0);
            glUniform1f(program_.uniform("u_ellipse_edge"), f.ell ? f.ell->edge : 0.f);
            glUniform2i(program_.uniform("u_size"), hf.width, hf.height);
            glUniform2i(program_.uniform("u_grid"), kGridW, kGridH);
            glUniform1i(program_.uniform("u_tri_count"), b.dirs->tri_count);
            glUniform1f(program_.uniform("u_tiling"), m.tiling);
            glUniform1i(program_.uniform("u_has_env"), f.env ? 1 : 0);
            glUniform1i(program_.uniform("u_light_scatters"), light_scatters);
            program_.bind_texture(11, GL_TEXTURE_2D_ARRAY, b.e_dirs, "u_E_dirs");
            glUniform1i(program_.uniform("u_dir_scatters"), f.table ? f.table->count : 0);
            glUniform1i(program_.uniform("u_shadows"), m.shadows ? 1 : 0);
            glUniform1i(program_.uniform("u_phong"), m.phong ? 1 : 0);
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(m.ks));
            glUniform1f(program_.uniform("u_shininess"), m.shininess);
            program_.bind_texture(9, GL_TEXTURE_2D, b.brdf ? b.brdf->table.get() : 0, "u_brdf");
            program_.bind_texture(10, GL_TEXTURE_2D, b.brdf ? b.brdf->env.get() : 0, "u_brdf_env");
            glUniform1i(program_.uniform("u_lod_brdf"), f.brdf ? 1 : 0);
            glUniform2i(program_.uniform("u_brdf_nodes"), f.brdf ? f.brdf->n_theta : 2, f.brdf ? f.brdf->n_phi : 1);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
        check_gl("microgeom.draw");
    }

private:
    Program program_;
};
}  // namespace

void register_microgeom_gpu(std::map<std::string, PassFactory>& out) {
    out["microgeom"] = [](const Technique& t) { return std::make_unique<MicrogeomPass>(t); };
}
}  // namespace mesolab::gpu
