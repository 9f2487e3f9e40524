#include "gpu/microgeom/chunks.h"

#include "gpu/context.h"

#include <algorithm>
#include <climits>
#include <stdexcept>
#include <string>

namespace mesolab::gpu {

std::vector<int> plan_direction_chunks(int width, int height, int N, size_t max_bytes, const char* what) {
    GLint64 limit = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &limit);
    if (max_bytes == 0 || max_bytes > size_t(limit)) max_bytes = size_t(limit);
    const size_t per_direction = size_t(width) * size_t(height) * sizeof(uint32_t);
    if (per_direction > max_bytes)
        throw std::runtime_error(std::string(what) + ": one visibility texture of " + std::to_string(width) + "x" + std::to_string(height) +
                                 " texels exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" + std::to_string(limit) + " bytes)");
    const int per_chunk = int(std::clamp<size_t>(max_bytes / std::max<size_t>(per_direction, 1), 1, INT_MAX));
    std::vector<int> begin;
    for (int j0 = 0; j0 < N; j0 += per_chunk) begin.push_back(j0);
    if (begin.empty()) begin.push_back(0);
    return begin;
}

// [SECTION] S_i kept on the GPU
ResidentHits::ResidentHits(int width, int height, int N, size_t max_bytes) : width_(width), height_(height), N_(N) {
    if (!in_compute_scope()) throw std::logic_error("microgeom visibility (GPU): S_i can be kept on the GPU only on the compute context");
    begin_ = plan_direction_chunks(width, height, N, max_bytes, "microgeom visibility (GPU)");
    const size_t per_direction = size_t(width) * size_t(height) * sizeof(uint32_t);
    buffers_.resize(begin_.size(), 0);
    glGenBuffers(GLsizei(buffers_.size()), buffers_.data());
    for (size_t c = 0; c < begin_.size(); ++c) {
        const int j1 = c + 1 < begin_.size() ? begin_[c + 1] : N;
        const size_t bytes = std::max<size_t>(size_t(j1 - begin_[c]) * per_direction, sizeof(uint32_t));  // an empty field: one word
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffers_[c]);
        glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_STATIC_COPY);
        host_bytes_ += bytes;
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    if (!current_renderer_is_software()) host_bytes_ = 0;
    try {
        check_gl("microgeom.visibility kept buffers");  // GL_OUT_OF_MEMORY
    } catch (...) {
        glDeleteBuffers(GLsizei(buffers_.size()), buffers_.data());
        throw;
    }
}

bool ResidentHits::room_for(size_t bytes) {
    if (!epoxy_has_gl_extension("GL_NVX_gpu_memory_info")) return true;  // a failed allocation still says so
    GLint available_kib = 0;
    glGetIntegerv(GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX, &available_kib);
    return size_t(std::max(available_kib, 0)) * 1024 >= 2 * bytes;
}

ResidentHits::~ResidentHits() { delete_compute_buffers(buffers_); }

void ResidentHits::fill(GLuint source, int d0, int d1) const {
    const size_t per_direction = size_t(width_) * size_t(height_) * sizeof(uint32_t);
    glBindBuffer(GL_COPY_READ_BUFFER, source);
    for (size_t c = 0; c < begin_.size(); ++c) {
        const int j0 = begin_[c], j1 = c + 1 < begin_.size() ? begin_[c + 1] : N_;
        const int a = std::max(d0, j0), b = std::min(d1, j1);
        if (a >= b) continue;
        glBindBuffer(GL_COPY_WRITE_BUFFER, buffers_[c]);
        glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, GLintptr(size_t(a - d0) * per_direction),
                            GLintptr(size_t(a - j0) * per_direction), GLsizeiptr(size_t(b - a) * per_direction));
    }
    glBindBuffer(GL_COPY_READ_BUFFER, 0);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
    check_gl("microgeom.visibility resident copy");
}

std::pair<GLuint, size_t> ResidentHits::direction(int j) const {
    const size_t c = size_t(std::upper_bound(begin_.begin(), begin_.end(), j) - begin_.begin()) - 1;
    return {buffers_[c], size_t(j - begin_[c]) * size_t(width_) * size_t(height_) * sizeof(uint32_t)};
}

// [SECTION] Upload
DirectionChunks upload_direction_chunks(const microgeom::Visibility& vis, const microgeom::Importance* bent, size_t max_bytes, const char* what) {
    const size_t T = size_t(vis.width) * size_t(vis.height), per_direction = T * sizeof(uint32_t);
    const bool has_bent = bent && !bent->empty();
    DirectionChunks c;
    c.N = vis.count;
    c.begin = plan_direction_chunks(vis.width, vis.height, vis.count, max_bytes, what);
    auto resident = std::dynamic_pointer_cast<const ResidentHits>(vis.device);
    if (resident && in_compute_scope() && resident->begin() == c.begin) c.resident = std::move(resident);
    const float zero = 0.f;
    const uint32_t none = 0;
    std::vector<float> w;
    for (size_t k = 0; k < c.begin.size(); ++k) {
        const int j0 = c.begin[k], n = c.end(k) - j0;
        if (!c.resident)
            c.uploaded.push_back(n > 0 ? make_storage_buffer(vis.hit.data() + size_t(j0) * T, size_t(n) * per_direction)
                                       : make_storage_buffer(&none, sizeof none));  // no directions: keeps the shaders' bindings valid
        if (has_bent && n > 0) {
            w.resize(T * size_t(n));
            for (size_t p = 0; p < T; ++p)
                std::copy_n(bent->w.begin() + std::ptrdiff_t(p * size_t(vis.count) + size_t(j0)), n, w.begin() + std::ptrdiff_t(p * size_t(n)));
            c.bent.push_back(make_storage_buffer(w.data(), w.size() * sizeof(float)));
        } else {
            c.bent.push_back(make_storage_buffer(&zero, sizeof zero));
        }
    }
    return c;
}
}  // namespace mesolab::gpu
