#pragma once
// S_i (and a curved base's gather weights) split into ranges of directions, one storage buffer
// each, so that no buffer exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE: llvmpipe allows 128 MB, and
// 1024^2 texels x 100 directions of S_i are 400 MB. The gather shaders (scatter.comp,
// lights.comp) run once per chunk and accumulate (sum w L, sum w) per texel; with one chunk the
// sums are exactly the single-pass ones.
#include "core/microgeom/curvature.h"
#include "core/microgeom/visibility.h"
#include "gpu/gl.h"
#include <vector>

namespace mesolab::gpu {

struct DirectionChunks {
    int N = 0;
    std::vector<int> begin;    // first direction of each chunk (ascending; chunk c ends at begin[c + 1] or N)
    std::vector<Buffer> S;     // per chunk: [direction - begin][row][column], as Visibility::hit
    std::vector<Buffer> bent;  // per chunk: [texel][direction - begin] (curved base), or one float 0
    size_t size() const { return begin.size(); }
    int end(size_t c) const { return c + 1 < begin.size() ? begin[c + 1] : N; }
};

// For each chunk: binds its S_i and weights at s_binding and bent_binding, sets the program's
// u_j0, u_j1 (the chunk's directions) and u_first, u_last (which chunk), then dispatch().
template <class F>
void for_each_chunk(const DirectionChunks& c, const Program& program, GLuint s_binding, GLuint bent_binding, F&& dispatch) {
    for (size_t k = 0; k < c.size(); ++k) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, s_binding, c.S[k].get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, bent_binding, c.bent[k].get());
        glUniform1i(program.uniform("u_j0"), c.begin[k]);
        glUniform1i(program.uniform("u_j1"), c.end(k));
        glUniform1i(program.uniform("u_first"), k == 0 ? 1 : 0);
        glUniform1i(program.uniform("u_last"), k + 1 == c.size() ? 1 : 0);
        dispatch();
    }
}

// Uploads vis (and bent's weights, when not null or empty) in chunks of at most max_bytes per
// buffer (0: GL_MAX_SHADER_STORAGE_BLOCK_SIZE). Needs a current context. Throws
// std::runtime_error (naming `what`) when one direction's texture alone exceeds the limit.
DirectionChunks upload_direction_chunks(const microgeom::Visibility& vis, const microgeom::Importance* bent, size_t max_bytes, const char* what);
}  // namespace mesolab::gpu
