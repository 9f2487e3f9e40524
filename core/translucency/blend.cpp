// Blending the local and global responses (see blend.h).
#include "core/translucency/blend.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mesolab::translucency {

namespace {
// F0(i, j) per channel (0 where the factor was dropped), through a small direct-mapped cache:
// a texel's fit and correction ask for the same few vertex pairs hundreds of times (every texel
// of a triangle shares its corners), and a look-up is a binary search plus three half floats.
class FactorCache {
public:
    explicit FactorCache(const VertexFactors& F) : F_(F), slot_(kSlots) {}
    vec3 operator()(uint32_t i, uint32_t j) {
        const uint64_t key = uint64_t(i) << 32 | j;
        Slot& s = slot_[size_t((key * 0x9e3779b97f4a7c15ull) >> (64 - kBits))];
        if (s.key != key) s.key = key, s.value = F_.factor(int(i), int(j));
        return s.value;
    }

private:
    static constexpr int kBits = 12;
    static constexpr size_t kSlots = size_t(1) << kBits;
    struct Slot {
        uint64_t key = ~uint64_t(0);
        vec3 value{0.f};
    };
    const VertexFactors& F_;
    std::vector<Slot> slot_;
};

struct TexelRef {
    std::array<uint32_t, 3> v{};  // corners of its triangle
    vec3 w{0.f};                  // barycentrics
};

TexelRef ref(const Atlas& a, const std::vector<uint32_t>& index, size_t t) {
    TexelRef r;
    const size_t f = size_t(a.texel_face[t]);
    for (int k = 0; k < 3; ++k) r.v[size_t(k)] = index[3 * f + size_t(k)];
    r.w = a.texel_bary[t];
    return r;
}

// φ_v at a texel: its barycentric of v when v is a corner of its triangle.
float hat(const TexelRef& p, uint32_t v) {
    for (int k = 0; k < 3; ++k)
        if (p.v[size_t(k)] == v) return p.w[k];
    return 0.f;
}

// The F0 part of the response at receiver p to unit irradiance at source t (dual-basis weights e).
vec3 global_response(FactorCache& F0, const TexelRef& p, const TexelRef& t, const vec3& e) {
    vec3 sum(0.f);
    for (int m = 0; m < 3; ++m) {
        if (p.w[m] == 0.f) continue;
        vec3 row(0.f);
        for (int k = 0; k < 3; ++k) row += F0(p.v[size_t(m)], t.v[size_t(k)]) * e[k];
        sum += p.w[m] * row;
    }
    return sum;
}

// Dual-basis weights of a source texel: e_j = A_t (3 / A_j) (4 λ_j - 1).
vec3 dual_weights(const TexelRef& t, float area_t, const std::vector<float>& vertex_area) {
    vec3 e;
    for (int k = 0; k < 3; ++k) e[k] = area_t * 3.f / vertex_area[t.v[size_t(k)]] * (4.f * t.w[k] - 1.f);
    return e;
}
}  // namespace

BlendWeights fit_blending(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Dipole& dipole,
                          double mm_per_unit, const VertexFactors& F0, LocalKernels& L) {
    BlendWeights B;
    B.c.assign(L.texel.size(), {vec3(0.f), vec3(0.f), vec3(0.f)});
    const int K = L.K, h = (K - 1) / 2, N = atlas.size;
    const float s2 = float(mm_per_unit * mm_per_unit);
    const std::vector<vec3> x = texel_positions_mm(atlas, position, index, mm_per_unit);
    const std::vector<float>& A = F0.vertex_area;
    const float texel_mm = float(mm_per_unit / double(atlas.scale));

    // [SECTION] Fit c per inner texel on the ring just outside its kernel
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        FactorCache cache(F0);
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t t = size_t(L.texel[k]);
            const int tx = int(t) % N, ty = int(t) / N;
            const TexelRef src = ref(atlas, index, t);
            const float area_t = atlas.texel_area[t] * s2;
            const vec3 e = dual_weights(src, area_t, A);
            Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
            Eigen::Matrix3d rhs = Eigen::Matrix3d::Zero();  // column = channel
            const int R = h + 1;
            int samples = 0;
            for (int dy = -R; dy <= R; ++dy)
                for (int dx = -R; dx <= R; ++dx) {
                    if (std::max(std::abs(dx), std::abs(dy)) != R) continue;
                    const size_t p = size_t(ty + dy) * size_t(N) + size_t(tx + dx);
                    if (atlas.texel_face[p] < 0 || atlas.texel_chunk[p] != atlas.texel_chunk[t] || atlas.texel_kind[p] == Atlas::kClamped) continue;
                    // A ring texel must lie beyond the kernel on the surface too: where unfolding
                    // folds a border back near the source, R_d there would demand a huge c.
                    if (glm::length(x[p] - x[t]) < float(h) * texel_mm) continue;
                    const TexelRef rp = ref(atlas, index, p);
                    Eigen::Vector3d a;
                    for (int m = 0; m < 3; ++m) a[m] = hat(rp, src.v[size_t(m)]);
                    const vec3 d = x[p] - x[t];
                    const dvec3 target = dipole.Rd(double(glm::length(d))) * double(area_t) - dvec3(global_response(cache, rp, src, e));
                    M += a * a.transpose();
                    for (int c = 0; c < 3; ++c) rhs.col(c) += a * target[c];
                    ++samples;
                }
            // The ridge shrinks c towards 0: unregularised least squares overfits where the source
            // triangle's hats barely reach the ring (c grows like 1 / hat: hot spots). 5x the mean
            // diagonal plus 0.1 per ring sample (hat values are in [0, 1]) measured better on a
            // plane, a sphere, Spot and the bunny than a tiny ridge (the tests print the figures).
            const double ridge = 5.0 * M.trace() / 3.0 + 0.1 * double(samples) + 1e-30;
            const Eigen::Matrix3d sol = (M + ridge * Eigen::Matrix3d::Identity()).ldlt().solve(rhs);
            for (int m = 0; m < 3; ++m)
                for (int c = 0; c < 3; ++c) B.c[k][size_t(m)][c] = std::isfinite(sol(m, c)) ? float(sol(m, c)) : 0.f;
        }
    });

    // [SECTION] Correct the kernels: w(t', t) -= the blended global response at t' to t
    const size_t KK = size_t(K) * size_t(K);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        FactorCache cache(F0);
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t tr = size_t(L.texel[k]);
            const int tx = int(tr) % N, ty = int(tr) / N;
            const TexelRef recv = ref(atlas, index, tr);
            for (int dy = -h; dy <= h; ++dy)
                for (int dx = -h; dx <= h; ++dx) {
                    const size_t ts = size_t(ty + dy) * size_t(N) + size_t(tx + dx);
                    if (atlas.texel_face[ts] < 0 || atlas.texel_kind[ts] == Atlas::kClamped) continue;  // no weight to correct
                    const TexelRef src = ref(atlas, index, ts);
                    vec3 D(0.f);
                    if (atlas.texel_kind[ts] == Atlas::kInner) {
                        D = global_response(cache, recv, src, dual_weights(src, atlas.texel_area[ts] * s2, A));
                        const std::array<vec3, 3>& c = B.c[size_t(L.slot[ts])];
                        for (int m = 0; m < 3; ++m) D += hat(recv, src.v[size_t(m)]) * c[size_t(m)];
                    } else {
                        // A border source: only the F0 part (see blend.h); its projection weights as if inner.
                        D = global_response(cache, recv, src, dual_weights(src, atlas.texel_area[ts] * s2, A));
                    }
                    const size_t o = k * KK + size_t(dy + h) * size_t(K) + size_t(dx + h);
                    for (int c = 0; c < 3; ++c) L.w[size_t(c)][o] -= D[c];
                }
        }
    });
    return B;
}

std::vector<vec3> direct_vertex_radiosity(const BlendWeights& b, const LocalKernels& L, const Atlas& atlas, const std::vector<uint32_t>& index,
                                          size_t vertex_count, const std::vector<vec3>& E) {
    std::vector<vec3> out(vertex_count, vec3(0.f));
    for (size_t k = 0; k < L.texel.size(); ++k) {
        const size_t t = size_t(L.texel[k]);
        const size_t f = size_t(atlas.texel_face[t]);
        for (int m = 0; m < 3; ++m) out[index[3 * f + size_t(m)]] += b.c[k][size_t(m)] * E[t];
    }
    return out;
}

std::vector<vec3> interpolate_to_texels(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& value) {
    std::vector<vec3> out(atlas.texel_kind.size(), vec3(0.f));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            if (atlas.texel_face[t] < 0) continue;
            const size_t f = size_t(atlas.texel_face[t]);
            const vec3 w = atlas.texel_bary[t];
            out[t] = w.x * value[index[3 * f]] + w.y * value[index[3 * f + 1]] + w.z * value[index[3 * f + 2]];
        }
    });
    return out;
}
}  // namespace mesolab::translucency
