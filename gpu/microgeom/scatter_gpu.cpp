#include "gpu/microgeom/scatter_gpu.h"
#include "core/parallel.h"

#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/chunks.h"
#include "core/profile.h"
#include "gpu/dispatch_timer.h"


#include <stdexcept>
#include <string>

namespace mesolab::gpu {
namespace {
using namespace mesolab::microgeom;
constexpr int kLocal = 8;

// A storage buffer of one vec4 per texel, (v[p], 0), written in place on every core.
Buffer upload_vec4(const std::vector<vec3>& v, GLenum usage, const char* what) {
    return make_storage_buffer_filled(v.size() * sizeof(vec4), [&](void* dst) {
        vec4* out = static_cast<vec4*>(dst);
        mesolab::parallel_for(tbb::blocked_range<size_t>(0, v.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t p = r.begin(); p < r.end(); ++p) out[p] = vec4(v[p], 0.f);
        });
    }, what, usage);
}

// The xyz of T vec4 in buffer b, on every core.
std::vector<vec3> read_vec3(GLuint b, size_t T, const char* what) {
    std::vector<vec3> out(T);
    read_storage_buffer(b, T * sizeof(vec4), [&](const void* src) {
        const vec4* in = static_cast<const vec4*>(src);
        mesolab::parallel_for(tbb::blocked_range<size_t>(0, T, 16384), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t p = r.begin(); p < r.end(); ++p) out[p] = vec3(in[p]);
        });
    }, what);
    return out;
}

class GpuGatherer final : public Gatherer {
public:
    explicit GpuGatherer(size_t max_chunk_bytes) : max_chunk_bytes_(max_chunk_bytes) {
        // Compiled once on the compute context, kept with it until exit.
        static const Program* compiled = new Program(Program::compute("microgeom/scatter.comp"));
        program_ = compiled;
    }

    ~GpuGatherer() override = default;  // buffers go first, then the scope (declared first)

    // [SECTION] Upload what every bounce reads
    void begin(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const Importance* bent, const std::vector<vec3>& L_env) override {
        PROFILE_SCOPE("gpu.upload");  // normals, directions and S_i (the largest: 4 bytes per texel and direction)
        W_ = hf.width;
        H_ = hf.height;
        N_ = dirs.size();
        periodic_ = hf.periodic;
        has_bent_ = bent && !bent->empty();
        const size_t T = size_t(W_) * size_t(H_);
        std::vector<vec4> d(static_cast<size_t>(N_)), env(static_cast<size_t>(N_));
        for (int j = 0; j < N_; ++j) {
            d[size_t(j)] = vec4(dirs.d[size_t(j)], dirs.solid_angle[size_t(j)]);
            env[size_t(j)] = vec4(L_env[size_t(j)], 0.f);
        }
        chunks_ = upload_direction_chunks(vis, has_bent_ ? bent : nullptr, max_chunk_bytes_, "microgeom scattering (GPU)");
        normals_ = make_storage_buffer_filled(T * sizeof(vec4), [&](void* dst) {
            vec4* n = static_cast<vec4*>(dst);
            mesolab::parallel_for(0, H_, [&](int y) {
                for (int x = 0; x < W_; ++x) n[hf.index(x, y)] = vec4(hf.normal(x, y), 0.f);
            });
        }, "microgeom scattering (GPU): normals");
        dirs_ = make_storage_buffer(d.data(), d.size() * sizeof(vec4));
        env_ = make_storage_buffer(env.data(), env.size() * sizeof(vec4));
        prev_ = make_storage_buffer(nullptr, T * sizeof(vec4), GL_DYNAMIC_DRAW);
        out_ = make_storage_buffer(nullptr, T * sizeof(vec4), GL_STREAM_READ);
        check_gl("microgeom.scatter upload");
    }

    // [SECTION] One bounce
    std::vector<vec3> gather(const std::vector<vec3>* L_prev, const std::vector<int>& J, bool primary) override {
        const size_t T = size_t(W_) * size_t(H_);
        if (L_prev) prev_ = upload_vec4(*L_prev, GL_DYNAMIC_DRAW, "microgeom scattering (GPU): L");
        const int none = 0;
        const Buffer subset = J.empty() ? make_storage_buffer(&none, sizeof none) : make_storage_buffer(J.data(), J.size() * sizeof(int));
        GLint previous = 0;
        glGetIntegerv(GL_CURRENT_PROGRAM, &previous);
        program_->use();
        glUniform2i(program_->uniform("u_size"), W_, H_);
        glUniform1i(program_->uniform("u_J_count"), int(J.size()));
        glUniform1i(program_->uniform("u_periodic"), periodic_ ? 1 : 0);
        glUniform1i(program_->uniform("u_has_bent"), has_bent_ ? 1 : 0);
        glUniform1i(program_->uniform("u_has_prev"), L_prev ? 1 : 0);
        glUniform1i(program_->uniform("u_primary"), primary ? 1 : 0);
        glUniform1i(program_->uniform("u_form_next"), 0);
        const GLuint buffers[8] = {0, normals_.get(), dirs_.get(), 0, env_.get(), prev_.get(), subset.get(), out_.get()};
        for (GLuint b = 0; b < 8; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, buffers[b]);
        // One dispatch per chunk of directions, accumulating; the last divides.
        for_each_chunk(chunks_, *program_, 0, 3, [&] {
            glDispatchCompute(GLuint((W_ + kLocal - 1) / kLocal), GLuint((H_ + kLocal - 1) / kLocal), 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        });
        for (GLuint b = 0; b < 8; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
        glUseProgram(GLuint(previous));
        check_gl("microgeom.scatter gather");
        return read_vec3(out_.get(), T, "microgeom scattering (GPU): E");
    }

    // [SECTION] Every bounce on the GPU
    // E and L stay in GPU buffers from one bounce to the next: each bounce's last dispatch forms
    // the next bounce's L (scatter.comp, u_form_next), and only E^K is read back.
    std::vector<vec3> bounces(const std::vector<vec3>& direct, const std::vector<vec3>& albedo, bool env, const std::vector<std::vector<int>>& J, int K,
                              const std::function<void(double)>& progress) override {
        DispatchTimer timer("dispatch");  // each chunk's gather: microgeom.scatter/dispatch (GPU)
        PROFILE_SCOPE("gpu.bounces");  // every dispatch, and E^K read back
        const size_t T = size_t(W_) * size_t(H_);
        const Buffer direct_buf = upload_vec4(direct, GL_STATIC_DRAW, "microgeom scattering (GPU): direct light");
        const Buffer albedo_buf = upload_vec4(albedo, GL_STATIC_DRAW, "microgeom scattering (GPU): albedo");
        // L^{k-1} is read from `prev`, L^k written to `next`; they swap after each bounce.
        Buffer next = make_storage_buffer(nullptr, T * sizeof(vec4), GL_DYNAMIC_COPY);
        Buffer prev = std::move(prev_);
        if (!prev) prev = make_storage_buffer(nullptr, T * sizeof(vec4), GL_DYNAMIC_COPY);
        GLint previous = 0;
        glGetIntegerv(GL_CURRENT_PROGRAM, &previous);
        program_->use();
        glUniform2i(program_->uniform("u_size"), W_, H_);
        glUniform1i(program_->uniform("u_periodic"), periodic_ ? 1 : 0);
        glUniform1i(program_->uniform("u_has_bent"), has_bent_ ? 1 : 0);
        for (GLuint b : {1u, 2u, 4u, 7u, 8u, 9u})
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, b == 1 ? normals_.get() : b == 2 ? dirs_.get() : b == 4 ? env_.get() : b == 7 ? out_.get() : b == 8 ? direct_buf.get() : albedo_buf.get());
        const int none = 0;
        const auto run = [&](const std::vector<int>& subset_J, bool has_prev, bool primary, bool form_next) {
            const Buffer subset = subset_J.empty() ? make_storage_buffer(&none, sizeof none) : make_storage_buffer(subset_J.data(), subset_J.size() * sizeof(int));
            glUniform1i(program_->uniform("u_J_count"), int(subset_J.size()));
            glUniform1i(program_->uniform("u_has_prev"), has_prev ? 1 : 0);
            glUniform1i(program_->uniform("u_primary"), primary ? 1 : 0);
            glUniform1i(program_->uniform("u_form_next"), form_next ? 1 : 0);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, prev.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, subset.get());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, next.get());
            for_each_chunk(chunks_, *program_, 0, 3, [&] {
                timer.begin();
                glDispatchCompute(GLuint((W_ + kLocal - 1) / kLocal), GLuint((H_ + kLocal - 1) / kLocal), 1);
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                timer.end();
            });
            std::swap(prev, next);  // L^k becomes the next bounce's input
        };
        if (env) {
            run(J[0], false, K == 0, K > 0);
        } else if (K > 0) {
            // E^0 = 0: L^0 is the direct light.
            glBindBuffer(GL_COPY_READ_BUFFER, direct_buf.get());
            glBindBuffer(GL_COPY_WRITE_BUFFER, prev.get());
            glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, GLsizeiptr(T * sizeof(vec4)));
            glBindBuffer(GL_COPY_READ_BUFFER, 0);
            glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        for (int k = 1; k <= K; ++k) {
            run(J[size_t(k)], true, k == K, k < K);
            if (progress) progress(double(k) / double(K));
        }
        for (GLuint b = 0; b < 11; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
        std::vector<vec3> E = env || K > 0 ? read_vec3(out_.get(), T, "microgeom scattering (GPU): E") : std::vector<vec3>(T, vec3(0.f));
        glUseProgram(GLuint(previous));
        prev_ = std::move(prev);
        timer.finish();
        check_gl("microgeom.scatter bounces");
        return E;
    }

private:
    ComputeScope scope_;  // first: current before the buffers exist, released after they are gone
    const Program* program_ = nullptr;
    DirectionChunks chunks_;
    Buffer normals_, dirs_, env_, prev_, out_;
    size_t max_chunk_bytes_ = 0;
    int W_ = 0, H_ = 0, N_ = 0;
    bool periodic_ = false, has_bent_ = false;
};
}  // namespace

std::unique_ptr<Gatherer> make_gpu_gatherer(size_t max_chunk_bytes) { return std::make_unique<GpuGatherer>(max_chunk_bytes); }
}  // namespace mesolab::gpu
