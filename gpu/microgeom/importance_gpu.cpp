// Curved-base importance on the GPU (microgeom/importance.comp): host side. Uploads the direction
// table and the triangulation (with the unbent areas, computed here exactly as the CPU does), then
// per batch of rows that batch's S_i and normals, dispatches one invocation per texel and reads
// back the batch's I, w and folded flags.
#include "gpu/microgeom/importance_gpu.h"

#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/chunks.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

constexpr int kLocal = 64;                         // work group: 64 texels
constexpr size_t kBatchBytes = size_t(64) << 20;   // per buffer and dispatch, at most
constexpr GLuint kBindings = 8;

// std430 layout of the shader's Tri.
struct TriData {
    int32_t v[3];
    float area0;
};
static_assert(sizeof(TriData) == 16);

// Restores the current program and clears the storage bindings, however the batches end.
class ProgramGuard {
public:
    ProgramGuard() { glGetIntegerv(GL_CURRENT_PROGRAM, &previous_); }
    ~ProgramGuard() {
        for (GLuint k = 0; k < kBindings; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, 0);
        glUseProgram(GLuint(previous_));
    }
    ProgramGuard(const ProgramGuard&) = delete;
    ProgramGuard& operator=(const ProgramGuard&) = delete;

private:
    GLint previous_ = 0;
};

void check_input(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis) {
    const size_t T = size_t(hf.width) * size_t(hf.height), N = size_t(dirs.size());
    if (vis.width != hf.width || vis.height != hf.height || vis.count != dirs.size() || vis.hit.size() != T * N)
        throw std::invalid_argument("microgeom importance (GPU): visibility of " + std::to_string(vis.width) + "x" + std::to_string(vis.height) +
                                    " texels x " + std::to_string(vis.count) + " directions does not match the " + std::to_string(hf.width) + "x" +
                                    std::to_string(hf.height) + " field and " + std::to_string(N) + " directions");
    if (dirs.solid_angle.size() != N || dirs.fan.size() != N)
        throw std::invalid_argument("microgeom importance (GPU): direction set without solid angles or fans");
}
}  // namespace

Importance compute_importance_gpu(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                                  const std::function<void(double)>& progress) {
    Importance imp = Importance::sized(hf.width, hf.height, dirs.size());
    if (b.zero()) return imp;
    check_input(hf, dirs, vis);
    const int W = hf.width, H = hf.height, N = dirs.size(), M = int(dirs.triangles.size());
    const size_t T = size_t(W) * size_t(H);
    imp.allocate();
    if (T == 0 || N == 0) return imp;

    // [SECTION] Batches of rows within the storage block limit
    ComputeScope scope;  // first: current before the buffers exist, released after they are gone
    GLint64 max_block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    const size_t block = size_t(std::max<GLint64>(max_block, 0));
    const size_t row_bytes = size_t(W) * size_t(N) * sizeof(vec4);  // the largest buffer: bent directions
    if (row_bytes > block || size_t(W) * sizeof(vec4) > block || size_t(M) * sizeof(TriData) > block || size_t(N) * sizeof(vec4) > block)
        throw std::runtime_error("microgeom importance (GPU): a row of " + std::to_string(W) + " texels x " + std::to_string(N) +
                                 " directions exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" + std::to_string(max_block) + " bytes)");
    // At most the CPU's eighth of the field per batch (progress as often), and kBatchBytes per buffer.
    const int rows_per_batch = std::clamp(int(std::min<size_t>(std::min(block, kBatchBytes) / row_bytes, size_t(std::max(1, H / 8)))), 1, H);

    // Compiled once on the compute context, kept with it until exit.
    static const Program* program = new Program(Program::compute("microgeom/importance.comp"));

    // [SECTION] Upload what every batch reads
    std::vector<vec4> dir_data(static_cast<size_t>(N));
    for (int j = 0; j < N; ++j) dir_data[size_t(j)] = vec4(dirs.d[size_t(j)], dirs.solid_angle[size_t(j)]);
    std::vector<TriData> tri_data(size_t(std::max(M, 1)), TriData{{0, 0, 0}, 0.f});
    for (int t = 0; t < M; ++t) {
        const auto& v = dirs.triangles[size_t(t)];
        tri_data[size_t(t)] = {{v[0], v[1], v[2]}, spherical_triangle_area(dirs.d[size_t(v[0])], dirs.d[size_t(v[1])], dirs.d[size_t(v[2])])};
    }
    const size_t batch_texels = size_t(rows_per_batch) * size_t(W);
    const Buffer dir_buf = make_storage_buffer(dir_data.data(), dir_data.size() * sizeof(vec4));
    const Buffer tri_buf = make_storage_buffer(tri_data.data(), tri_data.size() * sizeof(TriData));
    const Buffer vis_buf = make_storage_buffer(nullptr, batch_texels * size_t(N) * sizeof(uint32_t), GL_STREAM_DRAW);
    const Buffer normal_buf = make_storage_buffer(nullptr, batch_texels * sizeof(vec4), GL_STREAM_DRAW);
    const Buffer I_buf = make_storage_buffer(nullptr, batch_texels * size_t(N) * sizeof(float), GL_STREAM_READ);
    const Buffer w_buf = make_storage_buffer(nullptr, batch_texels * size_t(N) * sizeof(float), GL_STREAM_READ);
    const Buffer folded_buf = make_storage_buffer(nullptr, batch_texels * sizeof(uint32_t), GL_STREAM_READ);
    const Buffer bent_buf = make_storage_buffer(nullptr, batch_texels * size_t(N) * sizeof(vec4), GL_DYNAMIC_COPY);  // scratch
    check_gl("microgeom.importance upload");

    const ProgramGuard guard;
    program->use();
    glUniform2i(program->uniform("u_size"), W, H);
    glUniform1i(program->uniform("u_N"), N);
    glUniform1i(program->uniform("u_M"), M);
    glUniform1i(program->uniform("u_periodic"), hf.periodic ? 1 : 0);
    glUniform2f(program->uniform("u_kappa"), b.ku, b.kv);
    const GLint loc_row0 = program->uniform("u_row0"), loc_rows = program->uniform("u_rows");
    const GLuint buffers[kBindings] = {vis_buf.get(), normal_buf.get(), dir_buf.get(), tri_buf.get(), I_buf.get(), w_buf.get(), folded_buf.get(), bent_buf.get()};
    for (GLuint k = 0; k < kBindings; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, buffers[k]);

    // [SECTION] One batch of rows: its S_i and normals, dispatch, read back
    // S_i kept on the GPU since it was computed (chunks.h) is copied there; else it is uploaded.
    const auto kept = std::dynamic_pointer_cast<const ResidentHits>(vis.device);
    std::vector<vec4> normals(batch_texels);
    std::vector<uint32_t> folded(batch_texels);
    for (int y0 = 0; y0 < H; y0 += rows_per_batch) {
        const int y1 = std::min(H, y0 + rows_per_batch), rows = y1 - y0;
        const size_t texels = size_t(rows) * size_t(W), first = size_t(y0) * size_t(W);
        // S_j of rows [y0, y1) for every j, packed as [j][row - y0][column].
        if (kept) {
            glBindBuffer(GL_COPY_WRITE_BUFFER, vis_buf.get());
            for (int j = 0; j < N; ++j) {
                const auto [source, offset] = kept->direction(j);
                glBindBuffer(GL_COPY_READ_BUFFER, source);
                glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, GLintptr(offset + first * sizeof(uint32_t)),
                                    GLintptr(size_t(j) * texels * sizeof(uint32_t)), GLsizeiptr(texels * sizeof(uint32_t)));
            }
            glBindBuffer(GL_COPY_READ_BUFFER, 0);
            glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
        } else {
            glBindBuffer(GL_SHADER_STORAGE_BUFFER, vis_buf.get());
            for (int j = 0; j < N; ++j)
                glBufferSubData(GL_SHADER_STORAGE_BUFFER, GLintptr(size_t(j) * texels * sizeof(uint32_t)), GLsizeiptr(texels * sizeof(uint32_t)),
                                vis.hit.data() + size_t(j) * T + first);
        }
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < W; ++x) normals[size_t(y - y0) * size_t(W) + size_t(x)] = vec4(hf.normal(x, y), 0.f);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, normal_buf.get());
        glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(texels * sizeof(vec4)), normals.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);

        glUniform1i(loc_row0, y0);
        glUniform1i(loc_rows, rows);
        glDispatchCompute(GLuint((texels + kLocal - 1) / kLocal), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);

        const size_t values = texels * size_t(N);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, I_buf.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(values * sizeof(float)), imp.I.data() + first * size_t(N));
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, w_buf.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(values * sizeof(float)), imp.w.data() + first * size_t(N));
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, folded_buf.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(texels * sizeof(uint32_t)), folded.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        check_gl("microgeom.importance batch");
        for (size_t k = 0; k < texels; ++k) imp.folded[first + k] = folded[k] ? 1 : 0;
        if (progress) progress(double(y1) / double(H));
    }
    imp.folded_count = size_t(std::count(imp.folded.begin(), imp.folded.end(), uint8_t(1)));
    return imp;
}
}  // namespace mesolab::gpu
