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

// Uploads vis (and bent's weights, when not null or empty) in chunks of at most max_bytes per
// buffer (0: GL_MAX_SHADER_STORAGE_BLOCK_SIZE). Needs a current context. Throws
// std::runtime_error (naming `what`) when one direction's texture alone exceeds the limit.
DirectionChunks upload_direction_chunks(const microgeom::Visibility& vis, const microgeom::Importance* bent, size_t max_bytes, const char* what);
}  // namespace mesolab::gpu
