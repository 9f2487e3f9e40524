// Texel-to-texel kernels (see local.h).
#include "core/translucency/local.h"
#include "core/parallel.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include <tbb/blocked_range.h>

namespace mesolab::translucency {

std::vector<vec3> texel_positions_mm(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index,
                                     double mm_per_unit) {
    std::vector<vec3> x(atlas.texel_kind.size(), vec3(0.f));
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, x.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t)
            if (atlas.texel_face[t] >= 0) x[t] = texel_position(atlas, position, index, t) * float(mm_per_unit);
    });
    return x;
}

LocalKernels build_local_kernels(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                                 double mm_per_unit, int K) {
    if (K < 3 || K > 15 || K % 2 == 0) throw InputError("translucency.kernel: " + std::to_string(K) + " must be odd, in [3, 15]");
    const int h = (K - 1) / 2;
    if (atlas.border < h + 1)
        throw InputError("translucency.kernel: " + std::to_string(K) + " needs an atlas border of " + std::to_string(h + 1) + " texels, the atlas has " +
                         std::to_string(atlas.border));
    if (!(mm_per_unit > 0.0) || !std::isfinite(mm_per_unit))
        throw InputError("translucency.mm_per_unit: " + std::to_string(mm_per_unit) + " must be a positive number of millimetres");
    LocalKernels L;
    L.K = K;
    L.size = atlas.size;
    L.slot.assign(atlas.texel_kind.size(), -1);
    for (size_t t = 0; t < atlas.texel_kind.size(); ++t)
        if (atlas.texel_kind[t] == Atlas::kInner) L.slot[t] = int32_t(L.texel.size()), L.texel.push_back(int32_t(t));
    L.row = LocalKernels::row_floats(K);
    L.w.assign(L.texel.size() * size_t(K) * size_t(L.row), 0.f);

    const std::vector<vec3> x = texel_positions_mm(atlas, position, index, mm_per_unit);
    const double s2 = mm_per_unit * mm_per_unit;
    // Reach of a kernel: its diagonal, in mm, on the most tilted texels (4x margin).
    const double reach = 4.0 * std::sqrt(2.0) * double(h + 1) / double(atlas.scale) * mm_per_unit;
    const RdTable Rd(dipole, reach);
    const int N = atlas.size;
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const int t = L.texel[k], tx = t % N, ty = t / N;
            const vec3 xt = x[size_t(t)];
            for (int dy = -h; dy <= h; ++dy)
                for (int dx = -h; dx <= h; ++dx) {
                    const size_t n = size_t(ty + dy) * size_t(N) + size_t(tx + dx);  // inside the atlas: the border
                    const size_t o = L.at(k, dx, dy);
                    const double area = double(atlas.texel_area[n]) * s2;
                    vec3 w(0.f);
                    if (atlas.texel_kind[n] == Atlas::kClamped) {
                        // A stand-in where the surface ends (a copy of the chunk's nearest point): no surface, no weight.
                    } else if (dx == 0 && dy == 0) {
                        w = vec3(dipole.reflectance_within(std::sqrt(area / 3.14159265358979323846)));
                    } else {
                        const vec3 d = x[n] - xt;
                        w = Rd.at_r2(std::max(glm::dot(d, d), texel_disk_r2(float(area)))) * float(area);
                    }
                    for (int c = 0; c < 3; ++c) L.w[o + size_t(c)] = w[c];
                }
        }
    });
    return L;
}

std::vector<vec3> convolve_local(const LocalKernels& L, const std::vector<vec3>& E) {
    std::vector<vec3> B(L.slot.size(), vec3(0.f));
    const int K = L.K, h = (K - 1) / 2, N = L.size, R = L.row;
    static_assert(sizeof(vec3) == 3 * sizeof(float));
    // A kernel row's R floats against the R / 3 texels from (x − h, y + dy): three accumulators of
    // four lanes, whose lanes hold the channels (r g b r)(g b r g)(b r g b). The texels past x + h
    // meet zero weights; they lie inside the atlas (an inner texel has h + 1 border texels to its
    // right and is not on the last row), so they are finite.
    typedef float f4 __attribute__((vector_size(16)));
    const float* e = reinterpret_cast<const float*>(E.data());
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const int t = L.texel[k], tx = t % N, ty = t / N;
            const float* w = L.w.data() + k * size_t(K) * size_t(R);
            f4 a0 = {0.f, 0.f, 0.f, 0.f}, a1 = a0, a2 = a0;
            for (int dy = -h; dy <= h; ++dy, w += R) {
                const float* x = e + 3 * (size_t(ty + dy) * size_t(N) + size_t(tx - h));
                for (int i = 0; i < R; i += 12) {
                    f4 w0, w1, w2, x0, x1, x2;
                    std::memcpy(&w0, w + i, 16), std::memcpy(&w1, w + i + 4, 16), std::memcpy(&w2, w + i + 8, 16);
                    std::memcpy(&x0, x + i, 16), std::memcpy(&x1, x + i + 4, 16), std::memcpy(&x2, x + i + 8, 16);
                    a0 += w0 * x0, a1 += w1 * x1, a2 += w2 * x2;
                }
            }
            B[size_t(t)] = vec3(a0[0] + a0[3] + a1[2] + a2[1], a0[1] + a1[0] + a1[3] + a2[2], a0[2] + a1[1] + a2[0] + a2[3]);
        }
    });
    return B;
}
}  // namespace mesolab::translucency
