// Texel-to-texel kernels (see local.h).
#include "core/translucency/local.h"
#include "core/error.h"

#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mesolab::translucency {

std::vector<vec3> texel_positions_mm(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index,
                                     double mm_per_unit) {
    std::vector<vec3> x(atlas.texel_kind.size(), vec3(0.f));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, x.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t)
            if (atlas.texel_face[t] >= 0) x[t] = texel_position(atlas, position, index, t) * float(mm_per_unit);
    });
    return x;
}

LocalKernels build_local_kernels(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Dipole& dipole,
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
    const size_t KK = size_t(K) * size_t(K);
    for (auto& w : L.w) w.assign(L.texel.size() * KK, 0.f);

    const std::vector<vec3> x = texel_positions_mm(atlas, position, index, mm_per_unit);
    const double s2 = mm_per_unit * mm_per_unit;
    // Reach of a kernel: its diagonal, in mm, on the most tilted texels (4x margin).
    const double reach = 4.0 * std::sqrt(2.0) * double(h + 1) / double(atlas.scale) * mm_per_unit;
    const RdTable Rd(dipole, reach);
    const int N = atlas.size;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const int t = L.texel[k], tx = t % N, ty = t / N;
            const vec3 xt = x[size_t(t)];
            for (int dy = -h; dy <= h; ++dy)
                for (int dx = -h; dx <= h; ++dx) {
                    const size_t n = size_t(ty + dy) * size_t(N) + size_t(tx + dx);  // inside the atlas: the border
                    const size_t o = k * KK + size_t(dy + h) * size_t(K) + size_t(dx + h);
                    const double area = double(atlas.texel_area[n]) * s2;
                    vec3 w(0.f);
                    if (atlas.texel_kind[n] == Atlas::kClamped) {
                        // A stand-in where the surface ends (a copy of the chunk's nearest point): no surface, no weight.
                    } else if (dx == 0 && dy == 0) {
                        w = vec3(dipole.reflectance_within(std::sqrt(area / 3.14159265358979323846)));
                    } else {
                        const vec3 d = x[n] - xt;
                        w = Rd.at_r2(glm::dot(d, d)) * float(area);
                    }
                    for (int c = 0; c < 3; ++c) L.w[size_t(c)][o] = w[c];
                }
        }
    });
    return L;
}

std::vector<vec3> convolve_local(const LocalKernels& L, const std::vector<vec3>& E) {
    std::vector<vec3> B(L.slot.size(), vec3(0.f));
    const int K = L.K, h = (K - 1) / 2, N = L.size;
    const size_t KK = size_t(K) * size_t(K);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const int t = L.texel[k], tx = t % N, ty = t / N;
            const float* w0 = L.w[0].data() + k * KK;
            const float* w1 = L.w[1].data() + k * KK;
            const float* w2 = L.w[2].data() + k * KK;
            vec3 sum(0.f);
            for (int dy = -h, o = 0; dy <= h; ++dy) {
                const vec3* row = E.data() + size_t(ty + dy) * size_t(N) + size_t(tx - h);
                for (int i = 0; i < K; ++i, ++o) sum += vec3(w0[o] * row[i].x, w1[o] * row[i].y, w2[o] * row[i].z);
            }
            B[size_t(t)] = sum;
        }
    });
    return B;
}
}  // namespace mesolab::translucency
