// GPU pass of technique microgeom: uploads the stages' results (S_i as a texture array, the
// direction set with its triangulation, adjacency and a look-up grid, heightfield normals and
// albedo, scattered irradiance) and shades with microgeom.frag.
#include "core/microgeom/goniometer.h"
#include "core/microgeom/microgeom.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <map>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

constexpr int kGridW = 64, kGridH = 32;

// RGBA32F texture, nearest filtering (the shader fetches texels).
GLuint make_rgba_texture(const float* rgba, int w, int h) {
    GLuint id = 0;
    glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, rgba);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return id;
}

// RGBA32F texture from per-texel vec3 (alpha 1).
GLuint make_rgb_texture(const std::vector<vec3>& v, int w, int h) {
    std::vector<float> rgba(size_t(w) * size_t(h) * 4, 1.f);
    for (size_t i = 0; i < v.size(); ++i)
        for (int c = 0; c < 3; ++c) rgba[i * 4 + size_t(c)] = v[i][c];
    return make_rgba_texture(rgba.data(), w, h);
}

// Resources of one (heightfield, directions, visibility) triple.
struct Geometry {
    std::shared_ptr<const void> keep_hf, keep_dirs, keep_vis;
    Texture vis, normals, albedo;
    Buffer dirs, tris, adj, grid;
    int tri_count = 0;
};

struct Ellipses {
    std::shared_ptr<const void> keep;
    Texture t0, t1;
};

struct BrdfTables {
    std::shared_ptr<const void> keep;
    Texture table, env;
};

struct Irradiance {
    std::shared_ptr<const void> keep;
    Texture tex;
};

class MicrogeomPass final : public TechniquePass {
public:
    explicit MicrogeomPass(const Technique& t) : program_(Program::graphics("shaders/mesh.vert", "microgeom/microgeom.frag", {}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("microgeom.draw");
        auto hfs = ctx.eval.get<PerObject<Heightfield>>("microgeom.heightfield");
        auto dirss = ctx.eval.get<PerObject<DirectionSet>>("microgeom.directions");
        auto viss = ctx.eval.get<PerObject<Visibility>>("microgeom.visibility");
        auto envs = ctx.eval.get<PerObject<LightScatter>>("microgeom.scatter_env");
        auto lights = ctx.eval.get<PerObject<LightsScatter>>("microgeom.scatter");
        auto tables = ctx.eval.get<PerObject<DirectionalScatter>>("microgeom.scatter_directions");
        auto imps = ctx.eval.get<PerObject<Importance>>("microgeom.importance");
        auto ells = ctx.eval.get<PerObject<EllipseMap>>("microgeom.ellipses");
        auto brdfs = ctx.eval.get<PerObject<SimulatedBrdf>>("microgeom.brdf");
        prune();
        // Upload first: creating a texture binds it to the active unit, which must not disturb
        // the units bound below.
        for (int i : ctx.objects) {
            geometry(hfs->items[size_t(i)], dirss->items[size_t(i)], viss->items[size_t(i)]);
            if (envs && envs->get(i)) irradiance(envs->items[size_t(i)], *hfs->get(i));
            if (lights && lights->get(i)) irradiance_per_light(lights->items[size_t(i)], *hfs->get(i));
            if (tables && tables->get(i)) irradiance_per_direction(tables->items[size_t(i)]);
            if (imps && imps->get(i)) folded(imps->items[size_t(i)]);
            if (ells && ells->get(i)) ellipses(ells->items[size_t(i)]);
            if (brdfs && brdfs->get(i)) brdf_tables(brdfs->items[size_t(i)]);
        }
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const ParamTable& m = o.material;
            const Heightfield& hf = *hfs->get(i);
            Geometry& g = geometry(hfs->items[size_t(i)], dirss->items[size_t(i)], viss->items[size_t(i)]);
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g.dirs.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, g.tris.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.adj.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, g.grid.get());
            const LightScatter* es = envs ? envs->get(i) : nullptr;
            const LightsScatter* ls = lights ? lights->get(i) : nullptr;
            const int light_scatters = ls ? int(std::min(ls->lights.size(), ctx.lighting.lights.size())) : 0;
            const GLuint e_env = es ? irradiance(envs->items[size_t(i)], hf) : 0, e_light = ls ? irradiance_per_light(lights->items[size_t(i)], hf) : 0;
            program_.bind_texture(1, GL_TEXTURE_2D_ARRAY, g.vis.get(), "u_vis");
            program_.bind_texture(2, GL_TEXTURE_2D, g.normals.get(), "u_normals");
            program_.bind_texture(3, GL_TEXTURE_2D, g.albedo.get(), "u_albedo");
            program_.bind_texture(4, GL_TEXTURE_2D, e_env, "u_E_env");
            program_.bind_texture(5, GL_TEXTURE_2D, e_light, "u_E_light");
            const Importance* imp = imps ? imps->get(i) : nullptr;
            const bool has_folded = imp && !imp->folded.empty();
            program_.bind_texture(6, GL_TEXTURE_2D, has_folded ? folded(imps->items[size_t(i)]) : 0, "u_folded");
            glUniform1i(program_.uniform("u_has_folded"), has_folded ? 1 : 0);
            const EllipseMap* em = ells ? ells->get(i) : nullptr;
            const Ellipses* et = em ? &ellipses(ells->items[size_t(i)]) : nullptr;
            program_.bind_texture(7, GL_TEXTURE_2D, et ? et->t0.get() : 0, "u_ellipse0");
            program_.bind_texture(8, GL_TEXTURE_2D, et ? et->t1.get() : 0, "u_ellipse1");
            glUniform1i(program_.uniform("u_use_ellipse"), em ? 1 : 0);
            glUniform1f(program_.uniform("u_ellipse_edge"), em ? em->edge : 0.f);
            glUniform2i(program_.uniform("u_size"), hf.width, hf.height);
            glUniform2i(program_.uniform("u_grid"), kGridW, kGridH);
            glUniform1i(program_.uniform("u_tri_count"), g.tri_count);
            glUniform1f(program_.uniform("u_tiling"), float(m.get_float("tiling")));
            glUniform1i(program_.uniform("u_has_env"), es ? 1 : 0);
            glUniform1i(program_.uniform("u_light_scatters"), light_scatters);
            const DirectionalScatter* table = tables ? tables->get(i) : nullptr;
            program_.bind_texture(11, GL_TEXTURE_2D_ARRAY, table ? irradiance_per_direction(tables->items[size_t(i)]) : 0, "u_E_dirs");
            glUniform1i(program_.uniform("u_dir_scatters"), table ? table->count : 0);
            glUniform1i(program_.uniform("u_shadows"), m.get_string("shadows") != "none" ? 1 : 0);
            const bool phong = m.get_string("brdf") == "blinn-phong";
            glUniform1i(program_.uniform("u_phong"), phong ? 1 : 0);
            const vec3 ks = m.get_vec3("ks");
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(ks));
            glUniform1f(program_.uniform("u_shininess"), float(m.get_float("shininess")));
            const SimulatedBrdf* brdf = brdfs ? brdfs->get(i) : nullptr;
            const BrdfTables* bt = brdf ? &brdf_tables(brdfs->items[size_t(i)]) : nullptr;
            program_.bind_texture(9, GL_TEXTURE_2D, bt ? bt->table.get() : 0, "u_brdf");
            program_.bind_texture(10, GL_TEXTURE_2D, bt ? bt->env.get() : 0, "u_brdf_env");
            glUniform1i(program_.uniform("u_lod_brdf"), brdf ? 1 : 0);
            glUniform2i(program_.uniform("u_brdf_nodes"), brdf ? brdf->n_theta : 2, brdf ? brdf->n_phi : 1);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
        check_gl("microgeom.draw");
    }

private:

    // Drop resources whose stage results are no longer cached anywhere but here.
    void prune() {
        for (auto it = geometry_.begin(); it != geometry_.end();)
            it = it->second.keep_vis.use_count() == 1 ? geometry_.erase(it) : std::next(it);
        for (auto it = irradiance_.begin(); it != irradiance_.end();)
            it = it->second.keep.use_count() == 1 ? irradiance_.erase(it) : std::next(it);
        for (auto it = ellipses_.begin(); it != ellipses_.end();)
            it = it->second.keep.use_count() == 1 ? ellipses_.erase(it) : std::next(it);
        for (auto it = brdfs_.begin(); it != brdfs_.end();)
            it = it->second.keep.use_count() == 1 ? brdfs_.erase(it) : std::next(it);
    }

    // The simulated BRDF: (view node, light node) -> (T, shadow), and the environment row.
    const BrdfTables& brdf_tables(const std::shared_ptr<const SimulatedBrdf>& b) {
        auto it = brdfs_.find(b.get());
        if (it != brdfs_.end()) return it->second;
        PROFILE_SCOPE("microgeom.upload_brdf");
        const int nodes = b->n_theta * b->n_phi;
        std::vector<float> rgba(size_t(nodes) * size_t(nodes) * 4), env(size_t(nodes) * 4, 1.f);
        for (size_t k = 0; k < size_t(nodes) * size_t(nodes); ++k) {
            for (int c = 0; c < 3; ++c) rgba[k * 4 + size_t(c)] = b->table[k][c];
            rgba[k * 4 + 3] = b->shadow.empty() ? 0.f : b->shadow[k];
        }
        for (size_t k = 0; k < size_t(nodes); ++k)
            for (int c = 0; c < 3; ++c) env[k * 4 + size_t(c)] = b->env.empty() ? 0.f : b->env[k][c];
        BrdfTables r;
        r.keep = b;
        r.table = Texture(make_rgba_texture(rgba.data(), nodes, nodes));
        r.env = Texture(make_rgba_texture(env.data(), nodes, 1));
        check_gl("microgeom.upload_brdf");
        return brdfs_[b.get()] = std::move(r);
    }

    Geometry& geometry(const std::shared_ptr<const Heightfield>& hf, const std::shared_ptr<const DirectionSet>& dirs,
                       const std::shared_ptr<const Visibility>& vis) {
        auto it = geometry_.find(vis.get());
        if (it != geometry_.end() && it->second.keep_hf == hf && it->second.keep_dirs == dirs) return it->second;
        PROFILE_SCOPE("microgeom.upload");
        Geometry g;
        g.keep_hf = hf;
        g.keep_dirs = dirs;
        g.keep_vis = vis;
        // S_i: one R32UI layer per direction.
        GLuint id = 0;
        glGenTextures(1, &id);
        glBindTexture(GL_TEXTURE_2D_ARRAY, id);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R32UI, vis->width, vis->height, vis->count, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, vis->hit.data());
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        g.vis = Texture(id);
        std::vector<vec3> normals(hf->h.size());
        for (int y = 0; y < hf->height; ++y)
            for (int x = 0; x < hf->width; ++x) normals[hf->index(x, y)] = hf->normal(x, y);
        g.normals = Texture(make_rgb_texture(normals, hf->width, hf->height));
        g.albedo = Texture(make_rgb_texture(hf->albedo, hf->width, hf->height));
        // Directions, triangles, adjacency (neighbour across the edge opposite corner k), grid.
        std::vector<vec4> d;
        for (const vec3& v : dirs->d) d.emplace_back(v, 0.f);
        std::vector<glm::ivec4> tris, adj(dirs->triangles.size(), glm::ivec4(-1));
        std::map<std::pair<int, int>, int> edge;
        for (size_t t = 0; t < dirs->triangles.size(); ++t) {
            const auto& v = dirs->triangles[t];
            tris.emplace_back(v[0], v[1], v[2], 0);
            for (int k = 0; k < 3; ++k) edge[{v[size_t((k + 1) % 3)], v[size_t((k + 2) % 3)]}] = int(t);
        }
        for (size_t t = 0; t < dirs->triangles.size(); ++t) {
            const auto& v = dirs->triangles[t];
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
                grid[size_t(gy) * kGridW + size_t(gx)] = dirs->locate({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)}, bary);
            }
        g.dirs = make_storage_buffer(d.data(), d.size() * sizeof(vec4));
        g.tris = make_storage_buffer(tris.data(), tris.size() * sizeof(glm::ivec4));
        g.adj = make_storage_buffer(adj.data(), adj.size() * sizeof(glm::ivec4));
        g.grid = make_storage_buffer(grid.data(), grid.size() * sizeof(int));
        g.tri_count = int(tris.size());
        check_gl("microgeom.upload");
        return geometry_[vis.get()] = std::move(g);
    }

    GLuint irradiance(const std::shared_ptr<const LightScatter>& s, const Heightfield& hf) {
        auto it = irradiance_.find(s.get());
        if (it != irradiance_.end()) return it->second.tex.get();
        Irradiance r;
        r.keep = s;
        r.tex = Texture(make_rgb_texture(s->result.E_indirect, hf.width, hf.height));
        return (irradiance_[s.get()] = std::move(r)).tex.get();
    }

    // All lights' solutions stacked vertically: light i at rows [i H, (i + 1) H).
    GLuint irradiance_per_light(const std::shared_ptr<const LightsScatter>& s, const Heightfield& hf) {
        auto it = irradiance_.find(s.get());
        if (it != irradiance_.end()) return it->second.tex.get();
        std::vector<vec3> stacked;
        stacked.reserve(size_t(hf.width) * size_t(hf.height) * std::max<size_t>(1, s->lights.size()));
        for (const LightScatter& one : s->lights) stacked.insert(stacked.end(), one.result.E_indirect.begin(), one.result.E_indirect.end());
        if (stacked.empty()) stacked.assign(size_t(hf.width) * size_t(hf.height), vec3(0.f));
        Irradiance r;
        r.keep = s;
        r.tex = Texture(make_rgb_texture(stacked, hf.width, int(stacked.size() / size_t(hf.width))));
        return (irradiance_[s.get()] = std::move(r)).tex.get();
    }

    // microgeom.scatter_directions: one RGBA32F layer per direction above the horizon (at least one layer).
    GLuint irradiance_per_direction(const std::shared_ptr<const DirectionalScatter>& s) {
        auto it = irradiance_.find(s.get());
        if (it != irradiance_.end()) return it->second.tex.get();
        PROFILE_SCOPE("microgeom.upload_directions");
        const int layers = std::max(1, s->count);
        std::vector<float> rgba(size_t(s->width) * size_t(s->height) * size_t(layers) * 4, 0.f);
        for (size_t k = 0; k < s->E.size(); ++k)
            for (int c = 0; c < 3; ++c) rgba[k * 4 + size_t(c)] = s->E[k][c];
        GLuint id = 0;
        glGenTextures(1, &id);
        glBindTexture(GL_TEXTURE_2D_ARRAY, id);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, s->width, s->height, layers, 0, GL_RGBA, GL_FLOAT, rgba.data());
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        check_gl("microgeom.upload_directions");
        Irradiance r;
        r.keep = s;
        r.tex = Texture(id);
        return (irradiance_[s.get()] = std::move(r)).tex.get();
    }

    GLuint folded(const std::shared_ptr<const Importance>& imp) {
        auto it = irradiance_.find(imp.get());
        if (it != irradiance_.end()) return it->second.tex.get();
        std::vector<vec3> mask(imp->folded.size());
        for (size_t k = 0; k < mask.size(); ++k) mask[k] = vec3(float(imp->folded[k]));
        Irradiance r;
        r.keep = imp;
        r.tex = Texture(make_rgb_texture(mask, imp->width, imp->height));
        return (irradiance_[imp.get()] = std::move(r)).tex.get();
    }

    const Ellipses& ellipses(const std::shared_ptr<const EllipseMap>& em) {
        auto it = ellipses_.find(em.get());
        if (it != ellipses_.end()) return it->second;
        std::vector<float> rgba0(em->e.size() * 4), rgba1(em->e.size() * 4, 0.f);
        for (size_t k = 0; k < em->e.size(); ++k) {
            const Ellipse& e = em->e[k];
            rgba0[k * 4 + 0] = e.centre.x, rgba0[k * 4 + 1] = e.centre.y, rgba0[k * 4 + 2] = std::cos(e.angle), rgba0[k * 4 + 3] = std::sin(e.angle);
            rgba1[k * 4 + 0] = e.a, rgba1[k * 4 + 1] = e.b;
        }
        Ellipses r;
        r.keep = em;
        r.t0 = Texture(make_rgba_texture(rgba0.data(), em->width, em->height));
        r.t1 = Texture(make_rgba_texture(rgba1.data(), em->width, em->height));
        return ellipses_[em.get()] = std::move(r);
    }

    Program program_;
    std::map<const void*, Ellipses> ellipses_;
    std::map<const void*, BrdfTables> brdfs_;
    std::map<const void*, Geometry> geometry_;
    std::map<const void*, Irradiance> irradiance_;
};
}  // namespace

void register_microgeom_gpu(std::map<std::string, PassFactory>& out) {
    out["microgeom"] = [](const Technique& t) { return std::make_unique<MicrogeomPass>(t); };
}
}  // namespace mesolab::gpu
