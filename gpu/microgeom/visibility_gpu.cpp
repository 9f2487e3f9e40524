// Visibility textures S_i on the GPU (microgeom/visibility.comp): host side. Prepares, in double
// exactly as core/microgeom/visibility.cpp does, everything the walk reads (texel-space cell
// heights, the min/max pyramid, lifted origins, normalised directions), uploads it as SSBOs and
// dispatches one invocation per (texel, direction) in batches of directions.
#include "gpu/microgeom/visibility_gpu.h"
#include "core/parallel.h"

#include "gpu/microgeom/chunks.h"
#include "core/profile.h"
#include "gpu/dispatch_timer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

constexpr float kLift = 1e-3f;        // origin lift along n, texel sizes (as the CPU)
constexpr double kPeriodicReach = 4;  // periodic reach, units of (W + H) texels (as the CPU)
constexpr float kBig = 3.0e38f;       // "infinity" for the shader (never multiplied by 0 there)
constexpr int kLocal = 8;             // work group: 8 x 8 texels of one direction
constexpr int kMaxLevels = 16;        // pyramid levels the shader's uniform arrays hold

// std430 layouts of the shader's structs.
struct TexelData {
    float n[4];  // normal, w: 1 = origin not finite (no trace)
    float o[4];  // c0 - x, r0 - y, z0 - hs, hs
};
struct DirData {
    float d[4];    // direction as given, w: valid
    float ray[4];  // dc, dr, dz, tcap
    float inv[4];  // 1/dc, 1/dr, 1/ed, ed
};
static_assert(sizeof(TexelData) == 32 && sizeof(DirData) == 48);

struct Prepared {
    int W = 0, H = 0, N = 0;
    int Wc = 0, Hc = 0, top = 0;
    bool periodic = true;
    float gmin = 0, gmax = 0;
    int steps = 0;
    std::array<int, kMaxLevels> loff{}, lw{};
    std::vector<TexelData> texels;
    std::vector<DirData> dirs;
    std::vector<float> cells;  // 4 per cell: h00, h10, h01, h11 (texels)
    std::vector<float> mm;     // 2 per block: min, max
};

// Validates like compute_visibility; false when there is nothing to compute (W, H or N is 0).
bool check_input(const Heightfield& hf, const DirectionSet& dirs) {
    if (hf.width <= 0 || hf.height <= 0 || dirs.size() <= 0) return false;
    if (hf.h.size() != size_t(hf.width) * size_t(hf.height))
        throw std::invalid_argument("microgeom visibility (GPU): heightfield has " + std::to_string(hf.h.size()) + " heights for " +
                                    std::to_string(hf.width) + "x" + std::to_string(hf.height) + " texels");
    return true;
}

// The field in texel units and its pyramid (as build_field in core/microgeom/visibility.cpp).
void prepare_field(const Heightfield& hf, Prepared& P) {
    const int W = P.W, H = P.H;
    const double s = double(hf.texel_size);
    P.Wc = P.Hc = 0;
    if (s > 0) {
        P.Wc = P.periodic ? W : W - 1;
        P.Hc = P.periodic ? H : H - 1;
        if (P.Wc <= 0 || P.Hc <= 0) P.Wc = P.Hc = 0;
    }
    if (P.Wc == 0) {
        P.cells.assign(4, 0.f);  // dummies: the shader never reads them
        P.mm.assign(2, 0.f);
        P.steps = 1;
        return;
    }
    // Heights in texel units, each converted once (a cell reads four), on every core.
    std::vector<float> hs(size_t(W) * size_t(H));
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, hs.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) hs[k] = float(double(hf.h[k]) / s);
    });
    auto h = [&](int x, int y) {
        if (x >= W) x -= W;
        if (y >= H) y -= H;
        return hs[size_t(y) * size_t(W) + size_t(x)];
    };
    const int Wc = P.Wc, Hc = P.Hc;
    std::array<size_t, 64> off{};
    std::array<int, 64> lw{}, lh{};
    lw[0] = Wc;
    lh[0] = Hc;
    size_t total = 0;
    for (int L = 0;; ++L) {
        off[size_t(L)] = total;
        total += size_t(lw[size_t(L)]) * size_t(lh[size_t(L)]);
        if (lw[size_t(L)] == 1 && lh[size_t(L)] == 1) {
            P.top = L;
            break;
        }
        lw[size_t(L) + 1] = (lw[size_t(L)] + 1) / 2;
        lh[size_t(L) + 1] = (lh[size_t(L)] + 1) / 2;
    }
    if (P.top >= kMaxLevels) throw std::runtime_error("microgeom visibility (GPU): heightfield too large (" + std::to_string(W) + "x" + std::to_string(H) + ")");
    if (total * 2 > size_t(INT_MAX)) throw std::runtime_error("microgeom visibility (GPU): heightfield too large");
    for (int L = 0; L <= P.top; ++L) {
        P.loff[size_t(L)] = int(off[size_t(L)]);
        P.lw[size_t(L)] = lw[size_t(L)];
    }
    P.cells.resize(size_t(Wc) * size_t(Hc) * 4);
    P.mm.resize(total * 2);
    // Level 0 and each level above it, row by row on every core; the field's range from the rows'.
    std::vector<float> row_min(static_cast<size_t>(Hc)), row_max(static_cast<size_t>(Hc));
    mesolab::parallel_for(0, Hc, [&](int y) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int x = 0; x < Wc; ++x) {
            const float c[4] = {h(x, y), h(x + 1, y), h(x, y + 1), h(x + 1, y + 1)};
            const size_t k = size_t(y) * size_t(Wc) + size_t(x);
            std::copy(c, c + 4, P.cells.begin() + std::ptrdiff_t(k * 4));
            P.mm[2 * k] = std::min(std::min(c[0], c[1]), std::min(c[2], c[3]));
            P.mm[2 * k + 1] = std::max(std::max(c[0], c[1]), std::max(c[2], c[3]));
            lo = std::min(lo, P.mm[2 * k]);
            hi = std::max(hi, P.mm[2 * k + 1]);
        }
        row_min[size_t(y)] = lo;
        row_max[size_t(y)] = hi;
    });
    P.gmin = *std::min_element(row_min.begin(), row_min.end());
    P.gmax = *std::max_element(row_max.begin(), row_max.end());
    for (int L = 1; L <= P.top; ++L) {
        const float* p = P.mm.data() + 2 * off[size_t(L) - 1];
        float* q = P.mm.data() + 2 * off[size_t(L)];
        const int pw = lw[size_t(L) - 1], ph = lh[size_t(L) - 1], w = lw[size_t(L)], hh = lh[size_t(L)];
        mesolab::parallel_for(0, hh, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float lo = std::numeric_limits<float>::infinity(), hi = -lo;
                for (int py = 2 * y; py < std::min(2 * y + 2, ph); ++py)
                    for (int px = 2 * x; px < std::min(2 * x + 2, pw); ++px) {
                        const size_t e = size_t(py) * size_t(pw) + size_t(px);
                        lo = std::min(lo, p[2 * e]);
                        hi = std::max(hi, p[2 * e + 1]);
                    }
                const size_t e = size_t(y) * size_t(w) + size_t(x);
                q[2 * e] = lo;
                q[2 * e + 1] = hi;
            }
        });
    }
    const double reach = kPeriodicReach * double(W + H);
    const double cells = P.periodic ? 1.5 * reach + 4 : double(Wc + Hc) + 4;
    P.steps = int(std::min(cells * double(P.top + 2) + 64, double(INT_MAX)));
}

Prepared prepare(const Heightfield& hf, const DirectionSet& dirs) {
    Prepared P;
    P.W = hf.width;
    P.H = hf.height;
    P.N = dirs.size();
    P.periodic = hf.periodic;
    prepare_field(hf, P);
    const int W = P.W, H = P.H;
    const double s = double(hf.texel_size);

    // Per texel: normal and lifted origin (texel space, as compute_visibility), relative to the
    // texel: c0 - x, r0 - y and z0 - hs, with hs the texel's height as the cells store it.
    P.texels.resize(size_t(W) * size_t(H));
    mesolab::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t k = size_t(y) * size_t(W) + size_t(x);
            const vec3 n = hf.normal(x, y);
            TexelData& T = P.texels[k];
            T = {{n.x, n.y, n.z, 0.f}, {0.f, 0.f, 0.f, 0.f}};
            if (P.Wc == 0) continue;  // never traced
            const vec3 p = hf.position(x, y) + (kLift * hf.texel_size) * n;
            const double c0 = double(p.x) / s - 0.5, r0 = double(H) - 0.5 - double(p.y) / s, z0 = double(p.z) / s;
            const float hs = float(double(hf.h[k]) / s);
            T.o[0] = float(c0 - x);
            T.o[1] = float(r0 - y);
            T.o[2] = float(z0 - double(hs));
            T.o[3] = hs;
            if (!std::isfinite(T.o[0]) || !std::isfinite(T.o[1]) || !std::isfinite(T.o[2]) || !std::isfinite(hs)) {
                T.n[3] = 1.f;
                T.o[0] = T.o[1] = T.o[2] = T.o[3] = 0.f;
            }
        }
    });

    // Per direction (as make_ray_dir): normalised, components below 1e-12 snapped to 0.
    const double reach = kPeriodicReach * double(W + H);
    P.dirs.resize(size_t(P.N));
    for (int i = 0; i < P.N; ++i) {
        const vec3 d = dirs.d[size_t(i)];
        DirData& D = P.dirs[size_t(i)];
        D = {{d.x, d.y, d.z, 0.f}, {0.f, 0.f, 0.f, kBig}, {kBig, kBig, kBig, 0.f}};
        double dc = double(d.x), dr = -double(d.y), dz = double(d.z);
        const double len = std::sqrt(dc * dc + dr * dr + dz * dz);
        if (!(len > 0) || !std::isfinite(len)) continue;
        auto snap = [](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; };
        dc = snap(dc / len);
        dr = snap(dr / len);
        dz = snap(dz / len);
        const double ed = dc - dr, hl = std::sqrt(dc * dc + dr * dr);
        const double tcap = P.periodic && hl > 0 ? reach / hl : HUGE_VAL;
        D.d[3] = 1.f;
        D.ray[0] = float(dc);
        D.ray[1] = float(dr);
        D.ray[2] = float(dz);
        D.ray[3] = tcap < double(kBig) ? float(tcap) : kBig;
        D.inv[0] = dc != 0 ? float(1.0 / dc) : kBig;
        D.inv[1] = dr != 0 ? float(1.0 / dr) : kBig;
        D.inv[2] = ed != 0 ? float(1.0 / ed) : kBig;
        D.inv[3] = float(ed);
    }
    return P;
}

// Uploads, then dispatches batches of directions [d0, d1), each into an output SSBO ([d - d0][row][col]),
// and calls sink(d0, d1, buffer) for each batch, in order. Up to Batching::in_flight_bytes of batches are
// dispatched before the first sink, each into a buffer of its own, so that a read-back waits only
// for its own batch while the GPU goes on with the later ones (a buffer is reused once its batch
// is sunk). Restores the current program.
template <class Sink>
void run(const Program& program, const VisibilityProgram::Batching& batching, const Prepared& P, Sink&& sink, DispatchTimer& timer) {
    const size_t per_dir = size_t(P.W) * size_t(P.H);
    GLint64 max_block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    const size_t limit = std::min(batching.batch_bytes, size_t(std::max<GLint64>(max_block, 0)));
    if (per_dir * sizeof(uint32_t) > size_t(std::max<GLint64>(max_block, 0)) ||
        P.texels.size() * sizeof(TexelData) > size_t(std::max<GLint64>(max_block, 0)))
        throw std::runtime_error("microgeom visibility (GPU): " + std::to_string(P.W) + "x" + std::to_string(P.H) +
                                 " texels exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" + std::to_string(max_block) + " bytes)");
    const int batch = int(std::clamp<size_t>(std::min(limit / (per_dir * sizeof(uint32_t)), batching.invocations / per_dir), 1, 65535));

    GLint previous = 0;
    glGetIntegerv(GL_CURRENT_PROGRAM, &previous);
    const Buffer texels = make_storage_buffer(P.texels.data(), P.texels.size() * sizeof(TexelData), GL_STATIC_DRAW);
    const Buffer dirs = make_storage_buffer(P.dirs.data(), P.dirs.size() * sizeof(DirData), GL_STATIC_DRAW);
    const Buffer cells = make_storage_buffer(P.cells.data(), P.cells.size() * sizeof(float), GL_STATIC_DRAW);
    const Buffer mm = make_storage_buffer(P.mm.data(), P.mm.size() * sizeof(float), GL_STATIC_DRAW);
    const size_t batch_bytes = size_t(std::min(batch, P.N)) * per_dir * sizeof(uint32_t);
    const int batches = (P.N + batch - 1) / batch;
    std::vector<Buffer> outs(size_t(std::clamp<size_t>(batching.in_flight_bytes / batch_bytes, 1, size_t(batches))));
    for (Buffer& b : outs) b = make_storage_buffer(nullptr, batch_bytes, GL_STREAM_READ);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl("microgeom.visibility upload");

    program.use();
    const GLuint id = program.id();
    glUniform2i(program.uniform("u_size"), P.W, P.H);
    glUniform2i(program.uniform("u_cells"), P.Wc, P.Hc);
    glUniform1i(program.uniform("u_periodic"), P.periodic ? 1 : 0);
    glUniform1i(program.uniform("u_top"), P.top);
    glUniform1iv(glGetUniformLocation(id, "u_loff"), kMaxLevels, P.loff.data());
    glUniform1iv(glGetUniformLocation(id, "u_lw"), kMaxLevels, P.lw.data());
    glUniform1f(program.uniform("u_gmin"), P.gmin);
    glUniform1f(program.uniform("u_gmax"), P.gmax);
    glUniform1i(program.uniform("u_steps"), P.steps);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, texels.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, dirs.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, cells.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, mm.get());
    const GLint loc_dir0 = program.uniform("u_dir0"), loc_count = program.uniform("u_dir_count");
    const GLuint gx = GLuint((P.W + kLocal - 1) / kLocal), gy = GLuint((P.H + kLocal - 1) / kLocal);
    const auto sink_batch = [&](int b) {
        const int d0 = b * batch, d1 = std::min(P.N, d0 + batch);
        sink(d0, d1, outs[size_t(b) % outs.size()].get());
    };
    try {
        for (int b = 0; b < batches; ++b) {
            if (b >= int(outs.size())) sink_batch(b - int(outs.size()));  // frees the buffer this batch writes
            const int d0 = b * batch, d1 = std::min(P.N, d0 + batch);
            glUseProgram(id);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, outs[size_t(b) % outs.size()].get());
            glUniform1i(loc_dir0, d0);
            glUniform1i(loc_count, d1 - d0);
            timer.begin();
            glDispatchCompute(gx, gy, GLuint(d1 - d0));
            timer.end();
            check_gl("microgeom.visibility dispatch");
        }
        for (int b = std::max(0, batches - int(outs.size())); b < batches; ++b) sink_batch(b);
    } catch (...) {
        glUseProgram(GLuint(previous));
        throw;
    }
    glUseProgram(GLuint(previous));
}

// Copies the first `bytes` of buffer b into dst through a read mapping, in blocks on every core:
// the copy is also the first touch of dst's fresh pages, which costs more than the copy (a
// driver's glGetBufferSubData copies on one thread, and the pages had to be touched before).
void read_back(GLuint b, size_t bytes, void* dst) {
    read_storage_buffer(b, bytes, [&](const void* src) {
        constexpr size_t kBlock = size_t(4) << 20;
        mesolab::parallel_for(size_t(0), (bytes + kBlock - 1) / kBlock, [&](size_t k) {
            const size_t at = k * kBlock;
            std::memcpy(static_cast<char*>(dst) + at, static_cast<const char*>(src) + at, std::min(kBlock, bytes - at));
        });
    }, "microgeom visibility (GPU) read-back");
}
}  // namespace

VisibilityProgram::VisibilityProgram() : program_(Program::compute("microgeom/visibility.comp")) {}

Visibility VisibilityProgram::compute(const Heightfield& hf, const DirectionSet& dirs, bool keep_on_gpu) const {
    Visibility vis;
    vis.width = hf.width;
    vis.height = hf.height;
    vis.count = dirs.size();
    if (!check_input(hf, dirs)) return vis;
    // Scopes: the host's preparation, then the dispatches with their read-backs (on llvmpipe the
    // dispatches are the CPU's work; on a GPU the read-backs' waits).
    DispatchTimer timer("dispatch");  // each batch's GPU time: microgeom.visibility/dispatch (GPU)
    std::optional<ProfileScope> scope(std::in_place, "gpu.prepare");
    const Prepared P = prepare(hf, dirs);
    const size_t per_dir = size_t(P.W) * size_t(P.H);
    // The result's memory (4 bytes per texel and direction), left uninitialised: each batch's
    // read-back is the first to touch its pages, on every core (read_back).
    scope.emplace("gpu.allocate");
    vis.hit.resize(size_t(P.N) * per_dir);
    std::shared_ptr<ResidentHits> resident;  // the copy kept on the GPU, filled batch by batch there
    if (keep_on_gpu && P.N > 0 && per_dir > 0 && ResidentHits::room_for(size_t(P.N) * per_dir * sizeof(uint32_t))) {
        scope.emplace("gpu.allocate_kept");
        try {
            resident = std::make_shared<ResidentHits>(P.W, P.H, P.N, batching_.kept_chunk_bytes);
        } catch (const std::runtime_error&) {
            // No room on the GPU: S_i is not kept, and the passes that read it upload it.
        }
    }
    scope.emplace("gpu.dispatch_and_read_back");
    run(program_, batching_, P, [&](int d0, int d1, GLuint out) {
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        if (resident) resident->fill(out, d0, d1);  // queued before the read-back waits
        read_back(out, size_t(d1 - d0) * per_dir * sizeof(uint32_t), vis.hit.data() + size_t(d0) * per_dir);
    }, timer);
    timer.finish();
    vis.device = std::move(resident);
    return vis;
}

Texture VisibilityProgram::compute_texture(const Heightfield& hf, const DirectionSet& dirs) const {
    if (!check_input(hf, dirs)) return Texture();
    GLint max_layers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (dirs.size() > max_layers)
        throw std::runtime_error("microgeom visibility (GPU): " + std::to_string(dirs.size()) +
                                 " directions exceed GL_MAX_ARRAY_TEXTURE_LAYERS (" + std::to_string(max_layers) + ")");
    DispatchTimer texture_timer("dispatch");
    const Prepared P = prepare(hf, dirs);
    GLint previous_unpack = 0, previous_align = 4;
    glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &previous_unpack);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &previous_align);
    Texture tex = make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_R32UI, .width = P.W, .height = P.H, .layers = P.N});
    auto restore = [&] {
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, GLuint(previous_unpack));
        glPixelStorei(GL_UNPACK_ALIGNMENT, previous_align);
    };
    try {
        // Each batch of directions goes from the storage buffer the shader wrote into its layers,
        // on the GPU (the buffer is the pixel-unpack source).
        run(program_, batching_, P, [&](int d0, int d1, GLuint out) {
            glMemoryBarrier(GL_PIXEL_BUFFER_BARRIER_BIT);
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, out);
            glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
            glTextureSubImage3D(tex.get(), 0, 0, 0, d0, P.W, P.H, d1 - d0, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
            check_gl("microgeom.visibility texture");
        }, texture_timer);
    } catch (...) {
        restore();
        throw;
    }
    restore();
    check_gl("microgeom.visibility texture");
    return tex;
}

namespace {
std::atomic<KeepOnGpu> g_keep{KeepOnGpu::Automatic};
}
void set_keep_visibility_on_gpu(KeepOnGpu k) { g_keep = k; }
KeepOnGpu keep_visibility_on_gpu() { return g_keep; }

Visibility compute_visibility_gpu(const Heightfield& hf, const DirectionSet& dirs) { return VisibilityProgram().compute(hf, dirs); }
}  // namespace mesolab::gpu
