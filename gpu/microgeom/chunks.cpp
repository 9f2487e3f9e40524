#include "gpu/microgeom/chunks.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace mesolab::gpu {

DirectionChunks upload_direction_chunks(const microgeom::Visibility& vis, const microgeom::Importance* bent, size_t max_bytes, const char* what) {
    GLint64 limit = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &limit);
    if (max_bytes == 0 || max_bytes > size_t(limit)) max_bytes = size_t(limit);
    const size_t T = size_t(vis.width) * size_t(vis.height), per_direction = T * sizeof(uint32_t);
    if (per_direction > max_bytes)
        throw std::runtime_error(std::string(what) + ": one visibility texture of " + std::to_string(vis.width) + "x" + std::to_string(vis.height) +
                                 " texels exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" + std::to_string(limit) + " bytes)");
    const bool has_bent = bent && !bent->empty();
    DirectionChunks c;
    c.N = vis.count;
    const int per_chunk = int(std::max<size_t>(1, max_bytes / per_direction));
    const float zero = 0.f;
    std::vector<float> w;
    for (int j0 = 0; j0 < vis.count; j0 += per_chunk) {
        const int j1 = std::min(vis.count, j0 + per_chunk), n = j1 - j0;
        c.begin.push_back(j0);
        c.S.push_back(make_storage_buffer(vis.hit.data() + size_t(j0) * T, size_t(n) * per_direction));
        if (has_bent) {
            w.resize(T * size_t(n));
            for (size_t p = 0; p < T; ++p)
                std::copy_n(bent->w.begin() + std::ptrdiff_t(p * size_t(vis.count) + size_t(j0)), n, w.begin() + std::ptrdiff_t(p * size_t(n)));
            c.bent.push_back(make_storage_buffer(w.data(), w.size() * sizeof(float)));
        } else {
            c.bent.push_back(make_storage_buffer(&zero, sizeof zero));
        }
    }
    if (c.begin.empty()) {  // no directions: one empty chunk keeps the shaders' bindings valid
        const uint32_t none = 0;
        c.begin.push_back(0);
        c.S.push_back(make_storage_buffer(&none, sizeof none));
        c.bent.push_back(make_storage_buffer(&zero, sizeof zero));
    }
    return c;
}
}  // namespace mesolab::gpu
