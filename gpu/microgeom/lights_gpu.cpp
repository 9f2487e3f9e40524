#include "gpu/microgeom/lights_gpu.h"

#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/chunks.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace mesolab::gpu {
namespace {
using namespace mesolab::microgeom;
constexpr int kLocal = 8;
constexpr int kMaxBatch = 64;                       // lights.comp's uniform arrays
constexpr size_t kBatchBytes = size_t(96) << 20;    // the three per-light buffers together, at most

struct TexelGpu {
    vec4 n, albedo, e0, e1;
};

class GpuLightSolver final : public LightSolver {
public:
    // [SECTION] Upload what every light reads
    GpuLightSolver(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s, size_t max_chunk_bytes,
                   const std::string& prelude)
        : dirs_(&dirs), s_(s) {
        if (prelude.empty()) {
            static const Program* compiled = new Program(Program::compute("microgeom/lights.comp"));
            program_ = compiled;
        } else {
            own_program_ = Program::compute("microgeom/lights.comp", {}, prelude);
            program_ = &own_program_;
        }
        W_ = hf.width;
        H_ = hf.height;
        N_ = dirs.size();
        periodic_ = hf.periodic;
        const size_t T = size_t(W_) * size_t(H_);
        const Importance* bent = s.importance && !s.importance->empty() ? s.importance : nullptr;
        has_bent_ = bent != nullptr;
        GLint64 max_block = 0;
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
        if (T * sizeof(TexelGpu) > size_t(max_block))
            throw std::runtime_error("microgeom light images (GPU): " + std::to_string(W_) + "x" + std::to_string(H_) +
                                     " texels exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" + std::to_string(max_block) + " bytes)");
        const size_t per_light = T * sizeof(vec4);
        batch_ = int(std::clamp<size_t>(std::min(kBatchBytes / 3, size_t(max_block)) / per_light, 1, kMaxBatch));

        std::vector<TexelGpu> texels(T);
        for (int y = 0; y < H_; ++y)
            for (int x = 0; x < W_; ++x) {
                TexelGpu& t = texels[hf.index(x, y)];
                t.n = vec4(hf.normal(x, y), 0.f);
                t.albedo = vec4(hf.albedo[hf.index(x, y)], 0.f);
                if (s.ellipses) {
                    const Ellipse& e = s.ellipses->at(x, y);
                    t.e0 = vec4(e.centre, std::cos(e.angle), std::sin(e.angle));
                    t.e1 = vec4(e.a, e.b, 0.f, 0.f);
                }
            }
        std::vector<vec4> d(static_cast<size_t>(N_));
        for (int j = 0; j < N_; ++j) d[size_t(j)] = vec4(dirs.d[size_t(j)], dirs.solid_angle[size_t(j)]);
        subsets_ = scatter_subsets(s, N_);
        chunks_ = upload_direction_chunks(vis, bent, max_chunk_bytes, "microgeom light images (GPU)");
        texels_ = make_storage_buffer(texels.data(), texels.size() * sizeof(TexelGpu));
        dirs_buf_ = make_storage_buffer(d.data(), d.size() * sizeof(vec4));
        direct_ = make_storage_buffer(nullptr, size_t(batch_) * per_light, GL_DYNAMIC_COPY);
        L_ = make_storage_buffer(nullptr, size_t(batch_) * per_light, GL_DYNAMIC_COPY);
        E_ = make_storage_buffer(nullptr, size_t(batch_) * per_light, GL_DYNAMIC_COPY);
        for (const std::vector<int>& J : subsets_) {
            const int none = 0;
            J_.push_back(J.empty() ? make_storage_buffer(&none, sizeof none) : make_storage_buffer(J.data(), J.size() * sizeof(int)));
        }
        check_gl("microgeom light images upload");
    }

    int batch() const override { return batch_; }

    // [SECTION] A batch of lights: direct, K + 1 gathers, compose; read back L and the shadow
    void solve(const std::vector<vec3>& wis, std::vector<std::vector<vec3>>& L, std::vector<std::vector<float>>& shadow) override {
        L.assign(wis.size(), {});
        shadow.assign(wis.size(), {});
        for (size_t b0 = 0; b0 < wis.size(); b0 += size_t(batch_)) {
            const size_t bn = std::min(size_t(batch_), wis.size() - b0);
            solve_batch(&wis[b0], bn, &L[b0], &shadow[b0]);
        }
    }

    ~GpuLightSolver() override = default;

private:
    void solve_batch(const vec3* wis, size_t bn, std::vector<vec3>* L, std::vector<float>* shadow) {
        const size_t T = size_t(W_) * size_t(H_);
        GLint previous = 0;
        glGetIntegerv(GL_CURRENT_PROGRAM, &previous);
        program_->use();
        std::vector<vec4> light(bn), bary(bn);
        std::vector<glm::ivec4> tri(bn);
        for (size_t b = 0; b < bn; ++b) {
            vec3 bc(0.f);
            const auto& t = dirs_->triangles[size_t(dirs_->locate(wis[b], bc))];
            light[b] = vec4(wis[b], 0.f);
            tri[b] = glm::ivec4(t[0], t[1], t[2], 0);
            bary[b] = vec4(bc, 0.f);
        }
        glUniform4fv(program_->uniform("u_light"), GLsizei(bn), &light[0].x);
        glUniform4iv(program_->uniform("u_tri"), GLsizei(bn), &tri[0].x);
        glUniform4fv(program_->uniform("u_bary"), GLsizei(bn), &bary[0].x);
        glUniform2i(program_->uniform("u_size"), W_, H_);
        glUniform1i(program_->uniform("u_periodic"), periodic_ ? 1 : 0);
        glUniform1i(program_->uniform("u_has_bent"), has_bent_ ? 1 : 0);
        glUniform1i(program_->uniform("u_shadows"), s_.shadows ? 1 : 0);
        glUniform1i(program_->uniform("u_ellipses"), s_.ellipses ? 1 : 0);
        glUniform1f(program_->uniform("u_edge"), s_.ellipses ? s_.ellipses->edge : 0.f);
        const GLuint buffers[7] = {0, texels_.get(), dirs_buf_.get(), 0, direct_.get(), L_.get(), E_.get()};
        for (GLuint k = 0; k < 7; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, buffers[k]);
        auto run = [&]() {
            glDispatchCompute(GLuint((W_ + kLocal - 1) / kLocal), GLuint((H_ + kLocal - 1) / kLocal), GLuint(bn));
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        };
        // Direct and gather read S_i: one dispatch per chunk of directions, accumulating.
        auto dispatch = [&](int mode) {
            glUniform1i(program_->uniform("u_mode"), mode);
            if (mode == 2) return run();
            for_each_chunk(chunks_, *program_, 0, 3, run);
        };
        auto gather = [&](size_t k, bool has_prev, bool primary) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, J_[k].get());
            glUniform1i(program_->uniform("u_J_count"), int(subsets_[k].size()));
            glUniform1i(program_->uniform("u_has_prev"), has_prev ? 1 : 0);
            glUniform1i(program_->uniform("u_primary"), primary ? 1 : 0);
            dispatch(1);
        };
        // As scatter(): E^0 without a previous bounce, then L^k = L_d + rho/pi E^k gathered again.
        const size_t K = subsets_.size() - 1;
        dispatch(0);
        gather(0, false, K == 0);
        for (size_t k = 1; k <= K; ++k) {
            dispatch(2);
            gather(k, true, k == K);
        }
        dispatch(2);
        std::vector<vec4> Lb(bn * T), Db(bn * T);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, L_.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(Lb.size() * sizeof(vec4)), Lb.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, direct_.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(Db.size() * sizeof(vec4)), Db.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        for (GLuint k = 0; k < 8; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, 0);
        glUseProgram(GLuint(previous));
        check_gl("microgeom light images");
        for (size_t b = 0; b < bn; ++b) {
            L[b].resize(T);
            shadow[b].resize(T);
            for (size_t p = 0; p < T; ++p) {
                L[b][p] = vec3(Lb[b * T + p]);
                shadow[b][p] = Db[b * T + p].w;
            }
        }
    }

    ComputeScope scope_;  // first: current before the buffers exist, released after they are gone
    Program own_program_;  // with a prelude; else program_ is the shared one
    const Program* program_ = nullptr;
    const DirectionSet* dirs_;
    ScatterSettings s_;
    std::vector<std::vector<int>> subsets_;
    DirectionChunks chunks_;
    Buffer texels_, dirs_buf_, direct_, L_, E_;
    std::vector<Buffer> J_;
    int W_ = 0, H_ = 0, N_ = 0, batch_ = 1;
    bool periodic_ = false, has_bent_ = false;
};
}  // namespace

std::unique_ptr<LightSolver> make_gpu_light_solver(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s,
                                                   size_t max_chunk_bytes, const std::string& shader_prelude) {
    return std::make_unique<GpuLightSolver>(hf, dirs, vis, s, max_chunk_bytes, shader_prelude);
}
}  // namespace mesolab::gpu
