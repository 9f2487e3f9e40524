#pragma once
// S_i (and a curved base's gather weights) split into ranges of directions, one storage buffer
// each, so that no buffer exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE: llvmpipe allows 128 MB, and
// 1024^2 texels x 100 directions of S_i are 400 MB. The gather shaders (scatter.comp,
// lights.comp) run once per chunk and accumulate (sum w L, sum w) per texel; with one chunk the
// sums are exactly the single-pass ones.
//
// S_i computed on the compute context can stay there (ResidentHits, Visibility::device): the
// passes that read it next on that context (the scattering's bounces, the light images) then bind
// those buffers instead of uploading S_i again (400 MB at 1024², ~16 ms over a PCIe link).
#include "core/microgeom/curvature.h"
#include "core/microgeom/visibility.h"
#include "gpu/gl.h"
#include <memory>
#include <utility>
#include <vector>

namespace mesolab::gpu {

// The first direction of each chunk of a width x height x N field's S_i, with at most max_bytes
// per chunk (0, or more than the limit: GL_MAX_SHADER_STORAGE_BLOCK_SIZE). One chunk starting at
// 0 when N is 0. Needs a current context. Throws std::runtime_error (naming `what`) when one
// direction's texture alone exceeds the limit.
std::vector<int> plan_direction_chunks(int width, int height, int N, size_t max_bytes, const char* what);

// S_i kept in the compute context's buffers (gpu/context.h ComputeScope), chunked as
// plan_direction_chunks chunks it. Made by the GPU's S_i stage, owned by
// the Visibility it returned (Visibility::device); the buffers are deleted on the compute
// context when the last copy goes, from whichever thread that happens on.
class ResidentHits final : public microgeom::Visibility::DeviceCopy {
public:
    // Empty chunk buffers for the field (chunks of at most max_bytes, as plan_direction_chunks),
    // to be filled on the GPU (fill). Throws std::logic_error unless the calling thread holds
    // the compute scope (the buffers belong to the compute context), std::runtime_error when the
    // GPU cannot hold them.
    ResidentHits(int width, int height, int N, size_t max_bytes = 0);
    ~ResidentHits() override;
    ResidentHits(const ResidentHits&) = delete;
    ResidentHits& operator=(const ResidentHits&) = delete;

    // Whether the GPU has room for a copy of `bytes` and as much again for what reads it (NVIDIA
    // reports its free memory, GL_NVX_gpu_memory_info; elsewhere true, and a failed allocation
    // makes the constructor throw). Needs a current context.
    static bool room_for(size_t bytes);

    // Copies directions [d0, d1) from `source` (laid out [d - d0][row][column]) into the chunks,
    // on the GPU. Call after the barrier that makes the shader's writes to `source` visible.
    void fill(GLuint source, int d0, int d1) const;

    // The buffer that holds direction j and the byte offset where j's texture starts in it.
    std::pair<GLuint, size_t> direction(int j) const;

    const std::vector<int>& begin() const { return begin_; }
    GLuint buffer(size_t chunk) const { return buffers_[chunk]; }
    size_t host_bytes() const override { return host_bytes_; }

private:
    int width_ = 0, height_ = 0, N_ = 0;
    std::vector<int> begin_;
    std::vector<GLuint> buffers_;
    size_t host_bytes_ = 0;  // the buffers' bytes on a renderer that keeps them in the host's memory
};

struct DirectionChunks {
    int N = 0;
    std::vector<int> begin;                        // first direction of each chunk (ascending; chunk c ends at begin[c + 1] or N)
    std::vector<Buffer> uploaded;                  // per chunk: [direction - begin][row][column], as Visibility::hit ...
    std::shared_ptr<const ResidentHits> resident;  // ... or the same, kept on the GPU since S_i was computed
    std::vector<Buffer> bent;                      // per chunk: [texel][direction - begin] (curved base), or one float 0
    size_t size() const { return begin.size(); }
    int end(size_t c) const { return c + 1 < begin.size() ? begin[c + 1] : N; }
    GLuint S(size_t c) const { return resident ? resident->buffer(c) : uploaded[c].get(); }
};

// For each chunk: binds its S_i and weights at s_binding and bent_binding, sets the program's
// u_j0, u_j1 (the chunk's directions) and u_first, u_last (which chunk), then dispatch().
template <class F>
void for_each_chunk(const DirectionChunks& c, const Program& program, GLuint s_binding, GLuint bent_binding, F&& dispatch) {
    for (size_t k = 0; k < c.size(); ++k) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, s_binding, c.S(k));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, bent_binding, c.bent[k].get());
        glUniform1i(program.uniform("u_j0"), c.begin[k]);
        glUniform1i(program.uniform("u_j1"), c.end(k));
        glUniform1i(program.uniform("u_first"), k == 0 ? 1 : 0);
        glUniform1i(program.uniform("u_last"), k + 1 == c.size() ? 1 : 0);
        dispatch();
    }
}

// S_i (and bent's weights, when not null or empty) in chunks of at most max_bytes per buffer (0:
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE). S_i is not uploaded when vis holds a ResidentHits chunked
// alike and the calling thread holds the compute scope it was made in: its buffers are bound.
// Needs a current context. Throws std::runtime_error (naming `what`) when one direction's
// texture alone exceeds the limit.
DirectionChunks upload_direction_chunks(const microgeom::Visibility& vis, const microgeom::Importance* bent, size_t max_bytes, const char* what);
}  // namespace mesolab::gpu
