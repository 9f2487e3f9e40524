// Blending the local and global responses (see blend.h).
#include "core/translucency/blend.h"
#include "core/parallel.h"
#include "core/translucency/surface.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>

namespace mesolab::translucency {

namespace {
// The energy equation's weight against the ring's (and ridge's), the share of each corner's hat
// that the region must see for it to apply, and the share that must lie beyond the kernel (see
// the fit; the last also guards the energy closure's top-up).
constexpr double kEnergyWeight = 10.0;
constexpr double kHatShare = 0.8;
constexpr double kShareBeyond = 0.2;

// s_j = Σ_i R̂_ij A_i / 3 over F0's kept pairs (dimensionless): the share of the power E_j A_j / 3
// that F0 sends to the surface (A source texel's F0 power is A_t Σ_m λ_m s_m). R̂ is symmetric, so
// it is F0's product with E = 1.
std::vector<dvec3> vertex_power(const VertexFactors& F) {
    const std::vector<vec3> s = F.multiply(std::vector<vec3>(size_t(F.n), vec3(1.f)));
    return std::vector<dvec3>(s.begin(), s.end());
}

// P_W(a) = Dipole::reflectance_within_square(a) tabulated over [lo, hi], linear between 256 samples.
class SquarePower {
public:
    SquarePower(const Profile& d, double lo, double hi) : lo_(lo), step_(std::max(hi - lo, 1e-12 * lo) / double(kSamples - 1)), table_(kSamples) {
        for (int k = 0; k < kSamples; ++k) table_[size_t(k)] = d.reflectance_within_square(lo + step_ * double(k));
    }
    dvec3 operator()(double a) const {
        const double u = std::clamp((a - lo_) / step_, 0.0, double(kSamples - 1));
        const int k = std::min(int(u), kSamples - 2);
        const double f = u - double(k);
        return table_[size_t(k)] * (1.0 - f) + table_[size_t(k) + 1] * f;
    }

private:
    static constexpr int kSamples = 256;
    double lo_, step_;
    std::vector<dvec3> table_;
};

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

// The F0 part of the response at receiver p to unit irradiance at source t (projection weights e).
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

// Projection weights of a source texel (project_to_vertices): e_j = A_t (3 / A_j) λ_j.
vec3 source_weights(const TexelRef& t, float area_t, const std::vector<float>& vertex_area) {
    vec3 e;
    for (int k = 0; k < 3; ++k) e[k] = area_t * 3.f / vertex_area[t.v[size_t(k)]] * t.w[k];
    return e;
}
}  // namespace

BlendWeights fit_blending(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                          double mm_per_unit, const VertexFactors& F0, LocalKernels& L) {
    BlendWeights B;
    B.c.assign(L.texel.size(), {vec3(0.f), vec3(0.f), vec3(0.f)});
    const int K = L.K, h = (K - 1) / 2, N = atlas.size;
    const float s2 = float(mm_per_unit * mm_per_unit);
    const std::vector<vec3> x = texel_positions_mm(atlas, position, index, mm_per_unit);
    const std::vector<float>& A = F0.vertex_area;
    const float texel_mm = float(mm_per_unit / double(atlas.scale));

    // The energy region reaches as far as the source triangle's hats can: two mean edges.
    double edge_mm = 0.0;
    for (size_t f = 0; f + 2 < index.size(); f += 3)
        for (int k = 0; k < 3; ++k) edge_mm += double(glm::length(position[index[f + size_t(k)]] - position[index[f + size_t((k + 1) % 3)]]));
    edge_mm *= mm_per_unit / double(std::max<size_t>(1, index.size()));
    const int R = h + 1;
    const int R_energy = std::clamp(int(std::ceil(2.0 * edge_mm / double(texel_mm))), R, R + 12);
    vec3 lo(INFINITY), hi(-INFINITY);
    for (const vec3& v : position) lo = glm::min(lo, v), hi = glm::max(hi, v);
    const RdTable Rd(dipole, std::max(1e-9, double(glm::length(hi - lo)) * mm_per_unit) * 1.0001);
    // The energy closure's tables: the dipole's power over the object's surface, F0's column sums
    // and the dipole's power over a kernel window.
    const SurfaceReflectance surface(position, index, mm_per_unit, dipole);
    const dvec3 R_total = dipole.total_reflectance();
    const std::vector<dvec3> s0 = vertex_power(F0);
    double side_lo = INFINITY, side_hi = 0.0;  // kernel windows' sides, mm
    for (const int32_t t : L.texel) {
        const double side = double(K) * std::sqrt(double(atlas.texel_area[size_t(t)]) * double(s2));
        side_lo = std::min(side_lo, side), side_hi = std::max(side_hi, side);
    }
    const SquarePower window_power(dipole, L.texel.empty() ? 1.0 : side_lo, L.texel.empty() ? 1.0 : side_hi);

    // [SECTION] Fit c per inner texel on the ring just outside its kernel, its energy beyond
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        FactorCache cache(F0);
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t t = size_t(L.texel[k]);
            const int tx = int(t) % N, ty = int(t) / N;
            const TexelRef src = ref(atlas, index, t);
            const float area_t = atlas.texel_area[t] * s2;
            const vec3 e = source_weights(src, area_t, A);
            // Region P can only see 80% of every hat if it is at least that large: on triangles far
            // larger than it, only the kernel and its ring are read.
            bool region = true;
            const double region_area = double(2 * R_energy + 1) * double(2 * R_energy + 1) * double(area_t);
            for (int m = 0; m < 3; ++m) region = region && region_area >= kHatShare * double(A[src.v[size_t(m)]]) / 3.0;
            const int reach = region ? R_energy : R;
            Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
            Eigen::Matrix3d rhs = Eigen::Matrix3d::Zero();  // column = channel
            int samples = 0;
            Eigen::Vector3d aE = Eigen::Vector3d::Zero();  // Σ_P φ_m A_p
            dvec3 bE(0.0);                                  // Σ_P (R_d A_t − F0 response) A_p
            Eigen::Vector3d a_in = Eigen::Vector3d::Zero();  // Σ_kernel φ_m A_p
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dx = -reach; dx <= reach; ++dx) {
                    const int ring = std::max(std::abs(dx), std::abs(dy));
                    if (tx + dx < 0 || ty + dy < 0 || tx + dx >= N || ty + dy >= N) continue;
                    const size_t p = size_t(ty + dy) * size_t(N) + size_t(tx + dx);
                    const bool valid = atlas.texel_face[p] >= 0 && atlas.texel_chunk[p] == atlas.texel_chunk[t] && atlas.texel_kind[p] != Atlas::kClamped;
                    if (ring < R) {
                        if (valid) {
                            const TexelRef rp = ref(atlas, index, p);
                            for (int m = 0; m < 3; ++m) a_in[m] += double(hat(rp, src.v[size_t(m)])) * double(atlas.texel_area[p]) * double(s2);
                        }
                        continue;
                    }
                    if (!valid) continue;
                    // A ring texel must lie beyond the kernel on the surface too: where unfolding
                    // folds a border back near the source, R_d there would demand a huge c.
                    if (glm::length(x[p] - x[t]) < float(h) * texel_mm) continue;
                    const TexelRef rp = ref(atlas, index, p);
                    Eigen::Vector3d a;
                    for (int m = 0; m < 3; ++m) a[m] = hat(rp, src.v[size_t(m)]);
                    const vec3 d = x[p] - x[t];
                    const dvec3 target = dvec3(Rd.at_r2(glm::dot(d, d))) * double(area_t) - dvec3(global_response(cache, rp, src, e));
                    const double Ap = double(atlas.texel_area[p]) * double(s2);
                    aE += a * Ap, bE += target * Ap;
                    if (ring != R) continue;
                    M += a * a.transpose();
                    for (int c = 0; c < 3; ++c) rhs.col(c) += a * target[c];
                    ++samples;
                }
            // The ridge shrinks c towards 0: unregularised least squares overfits where the source
            // triangle's hats barely reach the ring (c grows like 1 / hat: hot spots). 5x the mean
            // diagonal plus 0.1 per ring sample (hat values are in [0, 1]) measured better on a
            // plane, a sphere, Spot and the bunny than a tiny ridge (the tests print the figures).
            const double ridge = 5.0 * M.trace() / 3.0 + 0.1 * double(samples) + 1e-30;
            // The power beyond the kernel, out to where the hats reach (region P: the texels of
            // t's chunk and border within R_energy), as one more equation that outweighs the ring:
            // the ridge alone leaves the first ring of vertices, where the zero diagonal is
            // interpolated, short of power. Only where P sees at least 80% of every corner's hat
            // (kernel included): near a chunk's edge the hats reach surface that P does not see,
            // and c would put power there unchecked (hot spots on Spot, RMSE 0.07 → 0.5). And only
            // where at least 20% of every corner's hat lies beyond the kernel: where a hat barely
            // leaves it, matching the power takes a large c of either sign (negative radiosity,
            // orange dots on the skin bunny of Fig. 6).
            bool hats_inside = region;
            for (int m = 0; m < 3 && hats_inside; ++m)
                hats_inside = aE[m] >= kShareBeyond * double(A[src.v[size_t(m)]]) / 3.0 && aE[m] + a_in[m] >= kHatShare * double(A[src.v[size_t(m)]]) / 3.0;
            if (hats_inside) {
                const double w = kEnergyWeight * (M.trace() + 3.0 * ridge) / aE.squaredNorm();
                M += w * aE * aE.transpose();
                for (int c = 0; c < 3; ++c) rhs.col(c) += w * aE * bE[c];
            }
            Eigen::Matrix3d sol = (M + ridge * Eigen::Matrix3d::Identity()).ldlt().solve(rhs);
            for (int m = 0; m < 3; ++m)
                for (int c = 0; c < 3; ++c)
                    if (!std::isfinite(sol(m, c))) sol(m, c) = 0.0;

            // Energy closure (blend.h), where region P does not hold the hats (triangles larger than
            // it, chunk edges): the power c puts beyond the kernel over its whole hats, Σ_m c_m H_m,
            // must be the dipole's there less F0's, G = A_t (R_total − P_W) − (F0's power from t −
            // F0's inside the window). Above G (or above 0 where F0 alone puts more) c is scaled
            // down; below it, where every hat reaches beyond the kernel, the difference is added
            // along the source's projection weights e. Never negative.
            if (!hats_inside) {
                Eigen::Vector3d hat_in = Eigen::Vector3d::Zero();  // Σ_window, inner texels: φ_m A_p (mm²)
                dvec3 f0_in(0.0);                                   // Σ_window F0 response A_p (mm²)
                dvec3 fold(0.0);                                    // the kernel's border taps in 3D over flat (mm²·mm⁻²)
                for (int dy = -h; dy <= h; ++dy)
                    for (int dx = -h; dx <= h; ++dx) {
                        if (tx + dx < 0 || ty + dy < 0 || tx + dx >= N || ty + dy >= N) continue;
                        const size_t p = size_t(ty + dy) * size_t(N) + size_t(tx + dx);
                        if (atlas.texel_face[p] < 0 || atlas.texel_chunk[p] != atlas.texel_chunk[t] || atlas.texel_kind[p] == Atlas::kClamped) continue;
                        // The corrected kernels keep the kernel's value here: the global part's share
                        // does not count (its direct part only at inner receivers, see blend.h).
                        const TexelRef rp = ref(atlas, index, p);
                        const double Ap = double(atlas.texel_area[p]) * double(s2);
                        if (atlas.texel_kind[p] == Atlas::kInner)
                            for (int m = 0; m < 3; ++m) hat_in[m] += double(hat(rp, src.v[size_t(m)])) * Ap;
                        f0_in += dvec3(global_response(cache, rp, src, e)) * Ap;
                        if (atlas.texel_kind[p] == Atlas::kBorder) {
                            // The kernel reads the surface beyond the chunk's edge at its 3D distance;
                            // flat, it would lie where the atlas puts it.
                            const vec3 d = x[p] - x[t];
                            const float r2_min = texel_disk_r2(float(Ap)), r2_flat = float(dx * dx + dy * dy) * texel_mm * texel_mm;
                            fold += dvec3(Rd.at_r2(std::max(glm::dot(d, d), r2_min)) - Rd.at_r2(std::max(r2_flat, r2_min))) * Ap;
                        }
                    }
                Eigen::Vector3d H, ew;
                bool reaches = true;
                for (int m = 0; m < 3; ++m) {
                    const double third = double(A[src.v[size_t(m)]]) / 3.0;
                    H[m] = std::max(0.0, third - hat_in[m]);
                    ew[m] = double(e[m]);
                    reaches = reaches && H[m] >= kShareBeyond * third;
                }
                const double He = H.dot(ew);
                // The dipole's power on the surface, less the kernel's fold share beyond the flat
                // window (where c can be topped up); R_total where the hats lie within the kernel.
                const dvec3 R = reaches ? surface(x[t]) - fold : R_total;
                const dvec3 P_W = window_power(double(K) * std::sqrt(double(area_t)));
                for (int c = 0; c < 3; ++c) {
                    double f0 = 0.0;
                    for (int m = 0; m < 3; ++m) f0 += double(src.w[m]) * s0[src.v[size_t(m)]][c];
                    const double G = (R[c] - P_W[c] - f0) * double(area_t) + f0_in[c];
                    const double P = H.dot(sol.col(c));
                    if (P > std::max(G, 0.0)) sol.col(c) *= std::max(G, 0.0) / P;
                    else if (reaches && He > 0.0 && G > P) sol.col(c) += (G - P) / He * ew;
                }
            }
            for (int m = 0; m < 3; ++m)
                for (int c = 0; c < 3; ++c) B.c[k][size_t(m)][c] = float(sol(m, c));
        }
    });

    // [SECTION] Correct the kernels: w(t', t) -= the blended global response at t' to t
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, L.texel.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
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
                        D = global_response(cache, recv, src, source_weights(src, atlas.texel_area[ts] * s2, A));
                        const std::array<vec3, 3>& c = B.c[size_t(L.slot[ts])];
                        for (int m = 0; m < 3; ++m) D += hat(recv, src.v[size_t(m)]) * c[size_t(m)];
                    } else {
                        // A border source: only the F0 part (see blend.h); its projection weights as if inner.
                        D = global_response(cache, recv, src, source_weights(src, atlas.texel_area[ts] * s2, A));
                    }
                    const size_t o = L.at(k, dx, dy);
                    for (int c = 0; c < 3; ++c) L.w[o + size_t(c)] -= D[c];
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
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, out.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
