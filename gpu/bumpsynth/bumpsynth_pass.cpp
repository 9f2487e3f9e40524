// GPU pass of technique bumpsynth: uploads the NDF, the look-up table, the resampled input CDFs, the
// noise texture and the Smith table (each once per stage result), draws a depth pre-pass and shades
// with bumpsynth.frag.
#include "core/bumpsynth/bumpsynth.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <map>

namespace mesolab::gpu {
namespace {

using namespace mesolab::bumpsynth;

GLuint make_texture(GLenum target) {
    GLuint id = 0;
    glGenTextures(1, &id);
    glBindTexture(target, id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return id;
}

// GPU resources made from one stage result, kept while the result is cached elsewhere.
template <class T>
class Uploads {
public:
    template <class Make>
    auto& get(const std::shared_ptr<const T>& r, const Make& make) {
        auto it = items_.find(r.get());
        if (it == items_.end()) it = items_.emplace(r.get(), Item{r, make(*r)}).first;
        return it->second.gl;
    }
    void prune() {
        for (auto it = items_.begin(); it != items_.end();) it = it->second.keep.use_count() == 1 ? items_.erase(it) : std::next(it);
    }

private:
    struct Item {
        std::shared_ptr<const T> keep;
        Texture gl;
    };
    std::map<const void*, Item> items_;
};

struct CdfBuffer {
    std::shared_ptr<const NoiseCdfs> keep;
    Buffer table;
};

class BumpsynthPass final : public TechniquePass {
public:
    BumpsynthPass()
        : program_(Program::graphics("shaders/mesh.vert", "bumpsynth/bumpsynth.frag")),
          depth_(Program::graphics("shaders/mesh.vert", "bumpsynth/depth.frag")) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("bumpsynth.draw");
        auto ndfs = ctx.eval.get<PerObject<Ndf>>("bumpsynth.ndf");
        auto luts = ctx.eval.get<PerObject<Lut>>("bumpsynth.lut");
        auto cdfss = ctx.eval.get<PerObject<NoiseCdfs>>("bumpsynth.noise_cdf");
        auto texs = ctx.eval.get<PerObject<NoiseTexture>>("bumpsynth.noise_texture");
        auto smiths = ctx.eval.get<PerObject<SmithTable>>("bumpsynth.masking");
        auto indexes = ctx.eval.get<PerObject<IndexMap>>("bumpsynth.index_map");
        auto maps = ctx.eval.get<basic::AlbedoMaps>("bumpsynth.albedo");
        ndf_.prune(), lut_.prune(), noise_.prune(), smith_.prune(), index_.prune();
        for (auto it = cdfs_.begin(); it != cdfs_.end();) it = it->second.keep.use_count() == 1 ? cdfs_.erase(it) : std::next(it);
        // Upload first: creating a texture binds it to the active unit.
        struct Bound { GLuint ndf, lut, noise, smith, albedo, index; const CdfBuffer* cdf; };
        std::map<int, Bound> bound;
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            Bound b{};
            b.ndf = ndf_.get(ndfs->items[size_t(i)], upload_ndf).get();
            b.lut = lut_.get(luts->items[size_t(i)], upload_lut).get();
            const bool index = indexes && indexes->get(i);
            b.index = index ? index_.get(indexes->items[size_t(i)], upload_index).get() : 0;
            b.cdf = !index && cdfss && cdfss->get(i) ? &cdf_buffer(cdfss->items[size_t(i)]) : nullptr;
            const bool tex = o.material.get_string("noise") == "texture" && texs && texs->get(i);
            b.noise = tex ? noise_.get(texs->items[size_t(i)], upload_noise).get() : 0;
            const bool masking = o.material.get_bool("masking") && smiths && smiths->get(i);
            b.smith = masking ? smith_.get(smiths->items[size_t(i)], upload_smith).get() : 0;
            const std::string path = ctx.scene.resolve(o.material.get_string("albedo_map"));
            b.albedo = !path.empty() && maps && maps->count(path) ? ctx.renderer.texture(maps->at(path), &maps->at(path)) : 0;
            bound[i] = b;
        }
        // Depth pre-pass: the shading pass (noise, look-ups, BRDF) then runs once per visible pixel,
        // not for every hidden fragment drawn before the nearest one (the teapot's back, its handle).
        // Texture mode draws everything at depth 0 in uv: nothing is hidden there.
        const bool prepass = !ctx.camera.texture_mode;
        if (prepass) {
            depth_.use();
            glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            for (int i : ctx.objects) {
                ctx.renderer.set_camera_uniforms(depth_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
                ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
            }
            glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            glDepthFunc(GL_LEQUAL);
        }
        program_.use();
        ctx.renderer.draw_buffers({"radiance", "normal", "octaves"});
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const ParamTable& m = o.material;
            const Bound& b = bound.at(i);
            const Synthesis syn = synthesis_for(ctx.scene, ctx.eval, i);
            if (!syn.index_map && !syn.cdfs) throw std::logic_error("bumpsynth: neither an index map nor noise CDFs were evaluated");
            const NoiseParams np = syn.index_map ? syn.index_detail.noise : syn.cdfs->params;
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            program_.bind_texture(1, GL_TEXTURE_2D, b.ndf, "u_ndf");
            program_.bind_texture(2, GL_TEXTURE_2D_ARRAY, b.lut, "u_lut");
            program_.bind_texture(3, GL_TEXTURE_2D, b.noise, "u_noise");
            program_.bind_texture(4, GL_TEXTURE_2D, b.smith, "u_smith");
            program_.bind_texture(5, GL_TEXTURE_2D, b.albedo, "u_albedo");
            program_.bind_texture(6, GL_TEXTURE_2D, b.index, "u_index");
            glUniform1i(program_.uniform("u_index_map"), syn.index_map ? 1 : 0);
            glUniform2i(program_.uniform("u_index_size"), syn.index_map ? syn.index_map->width : 1, syn.index_map ? syn.index_map->height : 1);
            glUniform1f(program_.uniform("u_index_noise"), syn.index_map ? syn.index_detail.amplitude : 0.f);
            if (b.cdf) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, b.cdf->table.get());
            glUniform1i(program_.uniform("u_ndf_res"), ndfs->get(i)->resolution());
            glUniform1i(program_.uniform("u_lut_size"), luts->get(i)->size());
            glUniform1i(program_.uniform("u_cdf_nodes"), NoiseCdfs::kCdfNodes);
            glUniform1i(program_.uniform("u_octaves_max"), np.octaves_max);
            // The octaves of the noise, or of the index map's detail noise (one lattice cell per texel).
            const NoiseOctaves oc = syn.index_map ? NoiseOctaves(np) : syn.cdfs->octaves;
            std::vector<GLint> periods;
            std::vector<GLuint> seeds;
            std::vector<float> offsets;
            for (int oct = 0; oct < oc.count; ++oct)
                for (int c = 0; c < 2; ++c) {
                    periods.push_back(oc.period[oct][c]);
                    seeds.push_back(oc.seed[oct][c]);
                    offsets.push_back(oc.offset[oct][c].x), offsets.push_back(oc.offset[oct][c].y);
                }
            glUniform1iv(program_.uniform("u_octave_period"), GLsizei(periods.size()), periods.data());
            glUniform1uiv(program_.uniform("u_octave_seed"), GLsizei(seeds.size()), seeds.data());
            glUniform2fv(program_.uniform("u_octave_offset"), GLsizei(offsets.size() / 2), offsets.data());
            glUniform1fv(program_.uniform("u_octave_gain"), GLsizei(oc.count), oc.gain);
            glUniform1i(program_.uniform("u_noise_texture"), b.noise ? 1 : 0);
            glUniform1i(program_.uniform("u_noise_levels"), b.noise ? int(texs->get(i)->levels.size()) : 1);
            glUniform1i(program_.uniform("u_masking"), b.smith ? 1 : 0);
            glUniform1i(program_.uniform("u_fresnel"), m.get_bool("fresnel") ? 1 : 0);
            const ShadingModel sm = shading_from_material(m);
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(sm.ks));
            glUniform3fv(program_.uniform("u_kd"), 1, glm::value_ptr(sm.kd));
            glUniform1f(program_.uniform("u_detail_distance"), float(m.get_float("detail_distance")));
            glUniform1i(program_.uniform("u_has_albedo"), b.albedo ? 1 : 0);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glDepthFunc(GL_LESS);
        glBindVertexArray(0);
        check_gl("bumpsynth.draw");
    }

private:

    // NDF: (value, 1 where the cell meets the disk), cell (i, j) at texel (i + 1, j + 1) inside a
    // border of (0, 0) (bumpsynth.frag ndf_eval).
    static Texture upload_ndf(const Ndf& ndf) {
        const int R = ndf.resolution(), W = R + 2;
        std::vector<float> rg(size_t(W) * size_t(W) * 2, 0.f);
        for (int j = 0; j < R; ++j)
            for (int i = 0; i < R; ++i) {
                const size_t k = size_t(j + 1) * size_t(W) + size_t(i + 1);
                rg[k * 2] = ndf.value(i, j);
                rg[k * 2 + 1] = ndf.cell_area(i, j) > 0.0 ? 1.f : 0.f;
            }
        Texture t(make_texture(GL_TEXTURE_2D));
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, W, W, 0, GL_RG, GL_FLOAT, rg.data());
        return t;
    }

    // Look-up table: layers m, t, b.
    static Texture upload_lut(const Lut& lut) {
        const int S = lut.size();
        std::vector<float> rgba(size_t(S) * size_t(S) * 4 * 3, 0.f);
        const size_t layer = size_t(S) * size_t(S) * 4;
        for (size_t k = 0; k < lut.entries().size(); ++k) {
            const LutEntry& e = lut.entries()[k];
            for (int c = 0; c < 3; ++c) {
                rgba[k * 4 + size_t(c)] = e.m[c];
                rgba[layer + k * 4 + size_t(c)] = e.t[c];
                rgba[2 * layer + k * 4 + size_t(c)] = e.b[c];
            }
        }
        Texture t(make_texture(GL_TEXTURE_2D_ARRAY));
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, S, S, 3, 0, GL_RGBA, GL_FLOAT, rgba.data());
        return t;
    }

    // Noise texture: RG32F mip chain, bilinear within a level, wrapping.
    static Texture upload_noise(const NoiseTexture& n) {
        Texture t(make_texture(GL_TEXTURE_2D));
        const int levels = int(n.levels.size());
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, levels - 1);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
        for (int l = 0; l < levels; ++l) {
            const int s = std::max(1, n.size >> l);
            glTexImage2D(GL_TEXTURE_2D, l, GL_RG32F, s, s, 0, GL_RG, GL_FLOAT, n.levels[size_t(l)].data());
        }
        return t;
    }

    // Index texture: RG32F, fetched texel by texel (bilinear in the shader, as on the CPU).
    static Texture upload_index(const IndexMap& m) {
        Texture t(make_texture(GL_TEXTURE_2D));
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, m.width, m.height, 0, GL_RG, GL_FLOAT, m.u.data());
        return t;
    }

    static Texture upload_smith(const SmithTable& s) {
        Texture t(make_texture(GL_TEXTURE_2D));
        glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, SmithTable::kPhi, SmithTable::kTheta, 0, GL_RED, GL_FLOAT, s.values().data());
        return t;
    }

    const CdfBuffer& cdf_buffer(const std::shared_ptr<const NoiseCdfs>& c) {
        auto it = cdfs_.find(c.get());
        if (it != cdfs_.end()) return it->second;
        CdfBuffer b;
        b.keep = c;
        b.table = make_storage_buffer(c->table.data(), c->table.size() * sizeof(float));
        return cdfs_.emplace(c.get(), std::move(b)).first->second;
    }

    Program program_, depth_;
    Uploads<Ndf> ndf_;
    Uploads<Lut> lut_;
    Uploads<NoiseTexture> noise_;
    Uploads<SmithTable> smith_;
    Uploads<IndexMap> index_;
    std::map<const void*, CdfBuffer> cdfs_;
};
}  // namespace

void register_bumpsynth_gpu(std::map<std::string, PassFactory>& out) {
    out["bumpsynth"] = [] { return std::make_unique<BumpsynthPass>(); };
}
}  // namespace mesolab::gpu
