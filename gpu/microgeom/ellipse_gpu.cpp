// Per-texel shadow ellipses on the GPU (microgeom/ellipse_fit.comp): host side. Prepares each
// batch's points and lit bits (ellipse_gpu.h, [SECTION] Points), dispatches one work group per
// texel and reads the ellipses straight into the map (the shader writes Ellipse's layout).
#include "gpu/microgeom/ellipse_gpu.h"
#include "core/parallel.h"
#include "core/profile.h"
#include "gpu/dispatch_timer.h"

#include "gpu/context.h"
#include "gpu/gl.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

// [SECTION] Group size
// Invocations per group (ellipse_fit.comp LOCAL_SIZE, a power of two): at least 64 on a hardware
// GPU; at least 8 on a software rasterizer, which runs a group as coroutines of one SIMD vector
// (8 lanes on llvmpipe) and switches between them at every barrier (bricks 128x128, N = 100 takes
// 2.5 s there with 8, 5.0 s with 32 and 8.8 s with 64). Larger where llvmpipe's loop limiter
// requires it: gallivm counts every loop back-edge of an invocation against one counter of
// 65535 (LP_MAX_TGSI_LOOP_ITERATIONS) and, once it runs out, leaves every loop after one pass,
// so a group would stop without writing its ellipse. loop_iterations() bounds one invocation's
// back-edges from the shader's loop structure; the size is doubled until that bound is within
// kLoopBudget (8 up to 128 points, 32 up to 256, 64 up to 512, 128 up to 1024).
constexpr int kLocalHardware = 64, kLocalSoftware = 8, kLocalMax = 512;
constexpr long kLoopBudget = 50000;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kMaxPoints = 1024;  // points per texel the shader's shared memory holds
constexpr int kMaxGroups = 65535;  // glDispatchCompute's guaranteed x count
// Work per dispatch, in units of M log2(M)^2 per texel (M: the points padded to a power of two,
// the bitonic sort's compare-exchanges): about 0.1 s on llvmpipe (2 cores).
constexpr double kBatchWork = 1.5e6;

static_assert(sizeof(Ellipse) == 5 * sizeof(float) && offsetof(Ellipse, angle) == 2 * sizeof(float) &&
                  offsetof(Ellipse, a) == 3 * sizeof(float) && offsetof(Ellipse, b) == 4 * sizeof(float),
              "ellipse_fit.comp writes an Ellipse as 5 floats: cx, cy, angle, a, b");

// As the CPU's check in core/microgeom/ellipse.cpp.
void check_visibility(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis) {
    const int W = hf.width, H = hf.height;
    if (vis.width != W || vis.height != H || vis.count != dirs.size() ||
        vis.hit.size() != size_t(std::max(0, W)) * size_t(std::max(0, H)) * size_t(std::max(0, vis.count)))
        throw std::invalid_argument("microgeom ellipses (GPU): visibility is " + std::to_string(vis.width) + "x" +
                                    std::to_string(vis.height) + " with " + std::to_string(vis.count) +
                                    " directions, expected " + std::to_string(W) + "x" + std::to_string(H) + " with " +
                                    std::to_string(dirs.size()));
}

std::runtime_error too_many_points(int n) {
    return std::runtime_error("microgeom ellipses (GPU): " + std::to_string(n) + " points in one texel exceed the shader's " +
                              std::to_string(kMaxPoints) + " (fewer directions, or the CPU fit)");
}

// [SECTION] Batch inputs
// What one dispatch reads: points (shared by every texel when stride is 0), lit bits and counts.
struct Batch {
    int stride = 0, words = 1;  // points and lit uints per texel
    std::vector<vec2> points;
    std::vector<uint32_t> lit, count;
};

// Flat base: lit bits of the upper directions `up` for texels [t0, t1). Direction by direction
// over blocks of texels: each S_i plane is read contiguously (texel by texel within a direction
// would stride 4 bytes per texel across every plane), and a block's bits stay in cache.
void flat_batch(const Visibility& vis, const std::vector<int>& up, int t0, int t1, Batch& B) {
    constexpr int kBlock = 4096;  // texels: 4096 x words x 4 B of bits
    const size_t T = size_t(t1 - t0), plane = size_t(vis.width) * size_t(vis.height);
    const size_t words = size_t(B.words);
    B.lit.assign(T * words, 0u);
    B.count.assign(T, uint32_t(up.size()));
    mesolab::parallel_for(tbb::blocked_range<int>(t0, t1, kBlock), [&](const tbb::blocked_range<int>& r) {
        uint32_t* bits = B.lit.data() + size_t(r.begin() - t0) * words;
        for (size_t j = 0; j < up.size(); ++j) {
            const uint32_t* hit = vis.hit.data() + size_t(up[j]) * plane + size_t(r.begin());
            const uint32_t bit = 1u << (j & 31u);
            uint32_t* word = bits + (j >> 5);
            const size_t n = r.size();
            for (size_t k = 0; k < n; ++k)
                if (hit[k] == Visibility::kNoHit) word[k * words] |= bit;
        }
    });
}

// Curved base: the points of the CPU's bent_points (core/microgeom/ellipse.cpp), in direction
// order: no-hit upper directions lit and unbent, every other direction shadowed at its bent
// direction when that is above the base plane. Returns the largest count.
int bent_batch(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int t0, int t1, Batch& B) {
    const int W = hf.width, N = dirs.size();
    const size_t T = size_t(t1 - t0);
    B.points.assign(T * size_t(B.stride), vec2(0.f));
    B.lit.assign(T * size_t(B.words), 0u);
    B.count.assign(T, 0u);
    mesolab::parallel_for(tbb::blocked_range<int>(t0, t1, std::max(1, W)), [&](const tbb::blocked_range<int>& r) {
        for (int t = r.begin(); t < r.end(); ++t) {
            const int x = t % W, y = t / W;
            const size_t k = size_t(t - t0);
            vec2* P = B.points.data() + k * size_t(B.stride);
            uint32_t* bits = B.lit.data() + k * size_t(B.words);
            uint32_t n = 0;
            for (int j = 0; j < N; ++j) {
                const vec3 d = dirs.d[size_t(j)];
                if (vis.at(j, x, y) == Visibility::kNoHit) {
                    if (d.z > 0.f) {
                        bits[n >> 5] |= 1u << (n & 31u);
                        P[n++] = vec2(d);
                    }
                    continue;
                }
                const vec3 w = bent_direction(hf, dirs, vis, b, x, y, j);
                if (w.z > 0.f) P[n++] = vec2(w);
            }
            B.count[k] = n;
        }
    });
    return int(*std::max_element(B.count.begin(), B.count.end()));
}

// Texels per dispatch for up to n points per texel: about 0.1 s of work on a software renderer
// (progress and cancellation stay responsive); on a hardware GPU as many groups as one dispatch
// takes (kMaxGroups), since a few hundred groups of 64 would leave most of its cores idle and
// every batch costs a round trip.
int batch_texels(int n, bool software) {
    if (!software) return kMaxGroups;
    int M = 2, log_m = 1;
    while (M < n) M <<= 1, ++log_m;
    const double per_texel = double(M) * double(log_m) * double(log_m);
    return int(std::clamp(kBatchWork / per_texel, 1.0, double(kMaxGroups)));
}

// Upper bound on the loop back-edges one invocation of ellipse_fit.comp runs for n points and L
// invocations per group (each loop entered counts its passes + 1).
long loop_iterations(int n, int L) {
    long M = 2, log_m = 1, log_l = 0;
    while (M < n) M <<= 1, ++log_m;
    while ((1 << log_l) < L) ++log_l;
    const long stages = log_m * (log_m + 1) / 2, pairs = (M / 2 + L - 1) / L, per = (M + L - 1) / L;
    const long sort = stages * (pairs + 1) + stages + log_m + 1;
    const long evaluation = sort + 3 * (per + 1) + 2 * (log_l + 1) + 8;  // keys, chunk sum, sweep; scan, argmax
    // kMaxEvaluations evaluations; loading the points; the start's sums; the search and the rest.
    return 120 * evaluation + 2 * (per + 1) + 2 * (long(n) + 1) + log_m + 120 + 16;
}


int local_size(int n, bool software) {
    int L = software ? kLocalSoftware : kLocalHardware;
    while (L < kLocalMax && loop_iterations(n, L) > kLoopBudget) L *= 2;
    return L;
}

// The program for L invocations per group, compiled on first use on the compute context and
// kept with it until exit (one per size; callers hold the ComputeScope, which serialises this).
const Program& program_for(int L) {
    static const Program* compiled[16] = {};
    int k = 0;
    while ((1 << k) < L) ++k;
    if (!compiled[k]) compiled[k] = new Program(Program::compute("microgeom/ellipse_fit.comp", {"LOCAL_SIZE " + std::to_string(L)}));
    return *compiled[k];
}

// Restores the previous program and clears the storage bindings, also when progress throws.
struct BindingGuard {
    GLint previous = 0;
    BindingGuard() { glGetIntegerv(GL_CURRENT_PROGRAM, &previous); }
    ~BindingGuard() {
        for (GLuint b = 0; b < 4; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
        glUseProgram(GLuint(previous));
    }
    BindingGuard(const BindingGuard&) = delete;
    BindingGuard& operator=(const BindingGuard&) = delete;
};

void upload(const Buffer& buffer, const void* data, size_t bytes) {
    if (bytes == 0) return;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer.get());
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), data);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}
}  // namespace

// [SECTION] API
EllipseMap fit_ellipses_gpu(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                            const std::function<void(double)>& progress) {
    check_visibility(hf, dirs, vis);
    ComputeScope scope;  // first: current before the buffers exist, released after they are gone
    const bool software = !tuned_for_hardware();

    const int W = hf.width, H = hf.height, N = dirs.size();
    EllipseMap map;
    map.width = W;
    map.height = H;
    map.edge = ellipse_edge(N);
    map.e.assign(size_t(std::max(0, W)) * size_t(std::max(0, H)), kEmptyEllipse);
    if (progress) progress(0.0);
    if (map.e.empty()) {
        if (progress) progress(1.0);
        return map;
    }
    const int T = int(map.e.size());
    const bool flat = b.zero();

    // Flat base: the upper directions' projections, once for every texel.
    std::vector<int> up;
    Batch B;
    int max_points = N;
    if (flat) {
        for (int i = 0; i < N; ++i)
            if (dirs.d[size_t(i)].z > 0.f) {
                up.push_back(i);
                B.points.push_back(vec2(dirs.d[size_t(i)]));
            }
        if (int(up.size()) > kMaxPoints) throw too_many_points(int(up.size()));
        max_points = int(up.size());
        B.stride = 0;
        B.words = std::max(1, (max_points + 31) / 32);
    } else {
        B.stride = std::max(1, N);
        B.words = std::max(1, (N + 31) / 32);
    }
    const int batch = batch_texels(std::min(max_points, kMaxPoints), software);

    // [SECTION] Buffers, sized for the largest batch: two sets, so that the CPU prepares and
    // uploads batch i + 1 while the GPU fits batch i, and a read-back waits for its own batch only.
    const size_t max_batch = size_t(std::min(batch, T));
    const vec2 zero(0.f);
    struct Set {
        Buffer points, lit, counts, out;
        int t0 = 0, t1 = 0, n = 0;
    };
    Set sets[2];
    for (Set& set : sets) {
        set.points = flat ? Buffer() : make_storage_buffer(nullptr, max_batch * size_t(B.stride) * sizeof(vec2), GL_DYNAMIC_DRAW);
        set.lit = make_storage_buffer(nullptr, max_batch * size_t(B.words) * sizeof(uint32_t), GL_DYNAMIC_DRAW);
        set.counts = make_storage_buffer(nullptr, max_batch * sizeof(uint32_t), GL_DYNAMIC_DRAW);
        set.out = make_storage_buffer(nullptr, max_batch * sizeof(Ellipse), GL_STREAM_READ);
    }
    const Buffer shared_points = flat ? make_storage_buffer(B.points.empty() ? &zero : B.points.data(), std::max<size_t>(1, B.points.size()) * sizeof(vec2)) : Buffer();
    check_gl("microgeom.ellipses upload");

    const BindingGuard guard;
    DispatchTimer timer("dispatch");  // each batch's fit: microgeom.ellipses/dispatch (GPU)
    // Reads batch `set` back and checks that every texel of it was written.
    const auto finish = [&](const Set& set) {
        const size_t bytes = size_t(set.t1 - set.t0) * sizeof(Ellipse);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, set.out.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), map.e.data() + set.t0);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        check_gl("microgeom.ellipses dispatch");
        for (int t = set.t0; t < set.t1; ++t)
            if (const Ellipse& e = map.e[size_t(t)]; !(std::isfinite(e.a) && std::isfinite(e.b) && std::isfinite(e.angle) &&
                                                      std::isfinite(e.centre.x) && std::isfinite(e.centre.y)))
                throw std::runtime_error("microgeom ellipses (GPU): texel " + std::to_string(t % W) + ", " + std::to_string(t / W) +
                                         " came back unfinished (" + std::to_string(set.n) + " points)");
        if (progress) progress(double(set.t1) / double(T));
    };

    // [SECTION] Batches
    int i = 0;
    for (int t0 = 0; t0 < T; t0 += batch, ++i) {
        Set& set = sets[i % 2];
        set.t0 = t0, set.t1 = std::min(T, t0 + batch);
        set.n = max_points;
        std::optional<ProfileScope> prep(std::in_place, "gpu.prepare_batch");  // the lit bits (and bent points) on the CPU
        if (flat) {
            flat_batch(vis, up, set.t0, set.t1, B);
        } else {
            set.n = bent_batch(hf, dirs, vis, b, set.t0, set.t1, B);
            if (set.n > kMaxPoints) throw too_many_points(set.n);
            upload(set.points, B.points.data(), B.points.size() * sizeof(vec2));
        }
        upload(set.lit, B.lit.data(), B.lit.size() * sizeof(uint32_t));
        upload(set.counts, B.count.data(), B.count.size() * sizeof(uint32_t));
        prep.reset();
        const Program& program = program_for(local_size(set.n, software));
        program.use();
        glUniform1i(program.uniform("u_point_stride"), B.stride);
        glUniform1i(program.uniform("u_lit_words"), B.words);
        glUniform1f(program.uniform("u_edge"), map.edge);
        // NaN first: a group that stops without writing (a driver's loop limit) cannot pass unseen.
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, set.out.get());
        glClearBufferSubData(GL_SHADER_STORAGE_BUFFER, GL_R32F, 0, GLsizeiptr(size_t(set.t1 - set.t0) * sizeof(Ellipse)), GL_RED, GL_FLOAT, &kNaN);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        const GLuint buffers[4] = {flat ? shared_points.get() : set.points.get(), set.lit.get(), set.counts.get(), set.out.get()};
        for (GLuint k = 0; k < 4; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, buffers[k]);
        std::optional<ProfileScope> fit(std::in_place, "gpu.dispatch");
        timer.begin();
        glDispatchCompute(GLuint(set.t1 - set.t0), 1, 1);
        timer.end();
        fit.reset();
        PROFILE_SCOPE("gpu.read_back");  // waits for the previous batch's fit (on llvmpipe: runs it)
        if (i > 0) finish(sets[(i - 1) % 2]);  // the GPU goes on with this batch meanwhile
    }
    PROFILE_SCOPE("gpu.read_back");
    finish(sets[(i - 1) % 2]);
    timer.finish();
    return map;
}
}  // namespace mesolab::gpu
