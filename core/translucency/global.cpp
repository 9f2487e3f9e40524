// Vertex-to-vertex throughput factors (see global.h).
#include "core/translucency/global.h"
#include "core/parallel.h"
#include "core/translucency/atlas.h"
#include "core/error.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>

#include <cstring>
#include <limits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace mesolab::translucency {

std::vector<float> vertex_areas(const std::vector<vec3>& position, const std::vector<uint32_t>& index, double mm_per_unit) {
    std::vector<double> a(position.size(), 0.0);
    const double s2 = mm_per_unit * mm_per_unit;
    for (size_t f = 0; f + 2 < index.size(); f += 3) {
        const vec3 p0 = position[index[f]], p1 = position[index[f + 1]], p2 = position[index[f + 2]];
        const double area = 0.5 * double(glm::length(glm::cross(p1 - p0, p2 - p0))) * s2;
        for (int j = 0; j < 3; ++j) a[index[f + size_t(j)]] += area;
    }
    return std::vector<float>(a.begin(), a.end());
}

std::vector<vec3> project_to_vertices(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& texel_irradiance,
                                      const std::vector<float>& vertex_area, double mm_per_unit) {
    std::vector<glm::dvec3> E(vertex_area.size(), glm::dvec3(0.0));
    const double s2 = mm_per_unit * mm_per_unit;
    for (size_t t = 0; t < atlas.texel_kind.size(); ++t) {
        if (atlas.texel_kind[t] != Atlas::kInner) continue;
        const size_t f = size_t(atlas.texel_face[t]);
        const vec3 w = atlas.texel_bary[t];
        const glm::dvec3 e = glm::dvec3(texel_irradiance[t]) * (double(atlas.texel_area[t]) * s2);
        for (int j = 0; j < 3; ++j) {
            const uint32_t v = index[3 * f + size_t(j)];
            E[v] += e * (3.0 / double(vertex_area[v]) * double(w[j]));
        }
    }
    return std::vector<vec3>(E.begin(), E.end());
}

namespace {
// The factor that undoes one side's linear interpolation, for a first-order excess x = q ∇²R_d / R_d:
// along an exponential e^(−k s) sampled every h, the interpolant's mean over a step exceeds the
// function's by ρ(a) = (a / 2) coth(a / 2), a = k h (1 + a² / 12 for small a, a / 2 for large);
// with a² / 12 = x, 1 / ρ = tanh(b) / b, b = sqrt(3 x). Tabulated over x in [0, 64], linear
// between samples (relative error below 1e-4), 1 / b beyond.
class SideFactor {
public:
    SideFactor() : table_(kSamples + 1) {
        for (int k = 0; k <= kSamples; ++k) table_[size_t(k)] = exact(kMax * float(k) / float(kSamples));
    }
    float operator()(float x) const {
        if (!(x > 0.f)) return 1.f;
        const float u = x * (float(kSamples) / kMax);
        if (u >= float(kSamples)) return exact(x);
        const int k = int(u);
        const float t = u - float(k);
        return table_[size_t(k)] * (1.f - t) + table_[size_t(k) + 1] * t;
    }
    static float exact(float x) {
        const double b = std::sqrt(3.0 * double(x));
        return b < 1e-4 ? float(1.0 - b * b / 3.0) : float(std::tanh(b) / b);
    }

private:
    static constexpr int kSamples = 4096;
    static constexpr float kMax = 64.f;
    std::vector<float> table_;
};

// [SECTION] Hat-pair means (see global.h): R̄_ij = 9 / (A_i A_j) ∫∫ φ_i(x) φ_j(y) R_d(|x − y|) dA dA
// Every triangle of the two supports split into n² equal sub-triangles (n from its longest edge
// against the dipole's shortest virtual-source depth z_v, at most kMaxSplit), each sampled at its
// centroid (exact for the linear φ), the pair of a sub-triangle with itself as a disk of its
// area (Dipole::reflectance_within, as the local kernels and the reference treat a texel).
struct SubSamples {
    std::vector<int> first;        // per face: its first sample; first[faces] = total
    std::vector<vec3> x, bary;     // mm, barycentrics of the face's corners
    std::vector<float> area;       // mm²
    std::vector<int> face;         // per sample
    std::vector<vec3> disk;        // per face: ∫ R_d over a disk of one sample's area (dimensionless)
};

constexpr int kMaxSplit = 8;

SubSamples sub_samples(const std::vector<vec3>& x, const std::vector<uint32_t>& index, const Profile& dipole, int max_split) {
    SubSamples S;
    const size_t faces = index.size() / 3;
    const double z = dipole.length_scale();
    std::vector<int> split(faces, 0);
    S.first.assign(faces + 1, 0);
    for (size_t f = 0; f < faces; ++f) {
        const vec3 a = x[index[3 * f]], b = x[index[3 * f + 1]], c = x[index[3 * f + 2]];
        const double e = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
        split[f] = std::isfinite(e) ? std::clamp(int(std::ceil(e / z)), 1, max_split) : 1;
        S.first[f + 1] = split[f] * split[f];
    }
    for (size_t f = 0; f < faces; ++f) S.first[f + 1] += S.first[f];
    const size_t total = size_t(S.first[faces]);
    S.x.resize(total), S.bary.resize(total), S.area.resize(total), S.face.resize(total), S.disk.assign(faces, vec3(0.f));
    mesolab::parallel_for(size_t(0), faces, [&](size_t f) {
        const int n = split[f];
        const vec3 a = x[index[3 * f]], b = x[index[3 * f + 1]], c = x[index[3 * f + 2]];
        const float sub = 0.5f * glm::length(glm::cross(b - a, c - a)) / float(n * n);
        S.disk[f] = vec3(dipole.reflectance_within(std::sqrt(double(sub) / 3.14159265358979323846)));
        size_t k = size_t(S.first[f]);
        auto put = [&](float u, float v) {
            const vec3 w(1.f - u - v, u, v);
            S.bary[k] = w, S.x[k] = w.x * a + w.y * b + w.z * c, S.area[k] = sub, S.face[k] = int(f), ++k;
        };
        for (int i = 0; i < n; ++i)
            for (int j = 0; i + j < n; ++j) {
                put((float(i) + 1.f / 3.f) / float(n), (float(j) + 1.f / 3.f) / float(n));
                if (i + j < n - 1) put((float(i) + 2.f / 3.f) / float(n), (float(j) + 2.f / 3.f) / float(n));
            }
    });
    return S;
}

// (sample, φ_v × its area) over the support of vertex v.
void hat_samples(const SubSamples& S, const std::vector<uint32_t>& index, const std::vector<uint32_t>& faces, uint32_t v,
                 std::vector<std::pair<int, float>>& out) {
    out.clear();
    for (const uint32_t f : faces) {
        int corner = 0;
        while (corner < 3 && index[3 * size_t(f) + size_t(corner)] != v) ++corner;
        if (corner == 3) continue;
        for (int k = S.first[f]; k < S.first[size_t(f) + 1]; ++k) out.emplace_back(k, S.bary[size_t(k)][corner] * S.area[size_t(k)]);
    }
}

// 9 G_ij / (A_i A_j) from the two supports' samples.
vec3 hat_pair_mean(const SubSamples& S, const RdTable& Rd, const std::vector<std::pair<int, float>>& si,
                   const std::vector<std::pair<int, float>>& sj) {
    dvec3 G(0.0);
    double wi = 0.0, wj = 0.0;
    for (const auto& [b, w] : sj) wj += double(w);
    for (const auto& [a, wa] : si) {
        wi += double(wa);
        const vec3 xa = S.x[size_t(a)];
        vec3 row(0.f);
        for (const auto& [b, wb] : sj) {
            if (a == b) {
                row += S.disk[size_t(S.face[size_t(a)])] / S.area[size_t(a)] * wb;
                continue;
            }
            const vec3 d = S.x[size_t(b)] - xa;
            row += Rd.at_r2(glm::dot(d, d)) * wb;
        }
        G += dvec3(row) * double(wa);
    }
    return wi > 0.0 && wj > 0.0 ? vec3(G / (wi * wj)) : vec3(0.f);
}
}  // namespace

// [SECTION] Half floats
// Imath's conversions (OpenEXR's half): round to nearest even, F16C instructions where the build has them.
uint16_t half_bits(float f) { return imath_float_to_half(f); }
float half_value(uint16_t h) { return imath_half_to_float(h); }

namespace {
vec3 decode(uint64_t p) { return {half_value(uint16_t(p)), half_value(uint16_t(p >> 16)), half_value(uint16_t(p >> 32))}; }
uint64_t encode(vec3 v, int column) {
    return uint64_t(half_bits(v.x)) | uint64_t(half_bits(v.y)) << 16 | uint64_t(half_bits(v.z)) << 32 | uint64_t(uint32_t(column) & 0xffffu) << 48;
}

// E'_j = E_j A_j / 3 × scale, as 4 floats (the fourth 0).
std::vector<vec4> weighted(const VertexFactors& F, const std::vector<vec3>& E) {
    std::vector<vec4> Ew(size_t(F.n));
    for (int j = 0; j < F.n; ++j) Ew[size_t(j)] = vec4(E[size_t(j)] * F.weight(j), 0.f);
    return Ew;
}

// [SECTION] The symmetric product: rows [r0, r1) into B (one thread's sums)
void rows_portable(const VertexFactors& F, const vec4* Ew, vec4* B, int r0, int r1) {
    const bool wide = !F.col_hi.empty();
    for (int i = r0; i < r1; ++i) {
        const vec4 ei = Ew[i];
        vec4 sum(0.f);
        for (int k = F.outer[size_t(i)]; k < F.outer[size_t(i) + 1]; ++k) {
            const uint64_t p = F.pair[size_t(k)];
            const int j = int(p >> 48) | (wide ? int(F.col_hi[size_t(k)]) << 16 : 0);
            const vec4 f(decode(p), 0.f);
            sum += f * Ew[j];
            if (j != i) B[j] += f * ei;
        }
        B[i] += sum;
    }
}

#if defined(__x86_64__)
// The same with F16C's half conversion and FMA: 4 lanes per pair (the fourth masked off).
__attribute__((target("avx,f16c,fma"))) inline void scatter_f16c(float* b, int j, __m128 f, __m128 ei) {
    float* bj = b + 4 * size_t(j);
    _mm_storeu_ps(bj, _mm_fmadd_ps(f, ei, _mm_loadu_ps(bj)));
}

template <bool Wide>
__attribute__((target("avx,f16c,fma"))) void rows_f16c(const VertexFactors& F, const vec4* Ew, vec4* B, int r0, int r1) {
    const __m128 mask = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    const uint64_t* pair = F.pair.data();
    const float* e = &Ew[0].x;
    float* b = &B[0].x;
#define MESOLAB_HALF3(p) _mm_and_ps(_mm_cvtph_ps(_mm_cvtsi64_si128(int64_t(p))), mask)
    auto column = [&](int k, uint64_t p) { return int(p >> 48) | (Wide ? int(F.col_hi[size_t(k)]) << 16 : 0); };
    for (int i = r0; i < r1; ++i) {
        const __m128 ei = _mm_loadu_ps(e + 4 * size_t(i));
        int k = F.outer[size_t(i)];
        const int end = F.outer[size_t(i) + 1];
        __m128 s0 = _mm_setzero_ps(), s1 = _mm_setzero_ps(), s2 = _mm_setzero_ps(), s3 = _mm_setzero_ps();
        // The diagonal, when kept, is the row's first pair: it adds to row i once.
        if (k < end && column(k, pair[k]) == i) s0 = _mm_mul_ps(MESOLAB_HALF3(pair[k]), ei), ++k;
        // Four independent sums: the FMA's latency, not the loads, would set the pace of one.
        for (; k + 4 <= end; k += 4) {
            const uint64_t p0 = pair[k], p1 = pair[k + 1], p2 = pair[k + 2], p3 = pair[k + 3];
            const int j0 = column(k, p0), j1 = column(k + 1, p1), j2 = column(k + 2, p2), j3 = column(k + 3, p3);
            const __m128 f0 = MESOLAB_HALF3(p0), f1 = MESOLAB_HALF3(p1), f2 = MESOLAB_HALF3(p2), f3 = MESOLAB_HALF3(p3);
            s0 = _mm_fmadd_ps(f0, _mm_loadu_ps(e + 4 * size_t(j0)), s0);
            s1 = _mm_fmadd_ps(f1, _mm_loadu_ps(e + 4 * size_t(j1)), s1);
            s2 = _mm_fmadd_ps(f2, _mm_loadu_ps(e + 4 * size_t(j2)), s2);
            s3 = _mm_fmadd_ps(f3, _mm_loadu_ps(e + 4 * size_t(j3)), s3);
            scatter_f16c(b, j0, f0, ei), scatter_f16c(b, j1, f1, ei), scatter_f16c(b, j2, f2, ei), scatter_f16c(b, j3, f3, ei);
        }
        for (; k < end; ++k) {
            const uint64_t p = pair[k];
            const int j = column(k, p);
            const __m128 f = MESOLAB_HALF3(p);
            s0 = _mm_fmadd_ps(f, _mm_loadu_ps(e + 4 * size_t(j)), s0);
            scatter_f16c(b, j, f, ei);
        }
        const __m128 sum = _mm_add_ps(_mm_add_ps(s0, s1), _mm_add_ps(s2, s3));
        _mm_storeu_ps(b + 4 * size_t(i), _mm_add_ps(_mm_loadu_ps(b + 4 * size_t(i)), sum));
    }
#undef MESOLAB_HALF3
}
bool has_f16c() {
    static const bool yes = __builtin_cpu_supports("avx") && __builtin_cpu_supports("f16c") && __builtin_cpu_supports("fma");
    return yes;
}
#endif

void rows(const VertexFactors& F, const vec4* Ew, vec4* B, int r0, int r1, bool simd) {
#if defined(__x86_64__)
    if (simd && has_f16c()) return F.col_hi.empty() ? rows_f16c<false>(F, Ew, B, r0, r1) : rows_f16c<true>(F, Ew, B, r0, r1);
#else
    (void)simd;
#endif
    rows_portable(F, Ew, B, r0, r1);
}
}  // namespace

// [SECTION] Look-ups
vec3 VertexFactors::rd(size_t k) const { return decode(pair[k]) * scale; }

vec3 VertexFactors::factor(int i, int j) const {
    const int a = std::min(i, j), b = std::max(i, j);
    int lo = outer[size_t(a)], hi = outer[size_t(a) + 1];
    while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (column(size_t(mid)) < b) lo = mid + 1;
        else hi = mid;
    }
    if (lo == outer[size_t(a) + 1] || column(size_t(lo)) != b) return vec3(0.f);
    return rd(size_t(lo)) * (vertex_area[size_t(j)] / 3.f);
}

Eigen::SparseMatrix<float, Eigen::RowMajor> VertexFactors::upper(int c) const {
    std::vector<Eigen::Triplet<float>> t;
    t.reserve(pair.size());
    for (int i = 0; i < n; ++i)
        for (int k = outer[size_t(i)]; k < outer[size_t(i) + 1]; ++k) t.emplace_back(i, column(size_t(k)), rd(size_t(k))[c]);
    Eigen::SparseMatrix<float, Eigen::RowMajor> m(n, n);
    m.setFromTriplets(t.begin(), t.end());
    return m;
}

// [SECTION] Products
std::vector<vec3> VertexFactors::multiply(const std::vector<vec3>& E, bool simd) const {
    const std::vector<vec4> Ew = weighted(*this, E);
    tbb::enumerable_thread_specific<std::vector<vec4>> sums([&] { return std::vector<vec4>(size_t(n), vec4(0.f)); });
    mesolab::parallel_for(tbb::blocked_range<int>(0, n, 128), [&](const tbb::blocked_range<int>& r) {
        rows(*this, Ew.data(), sums.local().data(), r.begin(), r.end(), simd);
    });
    std::vector<vec3> B(size_t(n), vec3(0.f));
    for (const std::vector<vec4>& s : sums)
        for (size_t i = 0; i < B.size(); ++i) B[i] += vec3(s[i]);
    return B;
}

DirectedFactors expand_directed(const VertexFactors& F) {
    DirectedFactors D;
    const size_t n = size_t(F.n);
    std::vector<int64_t> start(n + 1, 0);
    for (size_t i = 0; i < n; ++i) {
        start[i + 1] += F.outer[i + 1] - F.outer[i];
        for (int k = F.outer[i]; k < F.outer[i + 1]; ++k)
            if (const int j = F.column(size_t(k)); size_t(j) != i) ++start[size_t(j) + 1];
    }
    for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    if (start[n] > std::numeric_limits<int>::max()) throw std::length_error("translucency: more than 2^31 factors to expand");
    D.outer.assign(start.begin(), start.end());
    D.entry.resize(size_t(start[n]));
    const bool wide = !F.col_hi.empty();
    if (wide) D.col_hi.resize(D.entry.size());
    std::vector<int64_t> next(start.begin(), start.end() - 1);
    for (size_t i = 0; i < n; ++i)
        for (int k = F.outer[i]; k < F.outer[i + 1]; ++k) {
            const uint64_t p = F.pair[size_t(k)];
            const int j = F.column(size_t(k));
            const size_t a = size_t(next[i]++);
            D.entry[a] = p;
            if (wide) D.col_hi[a] = F.col_hi[size_t(k)];
            if (size_t(j) == i) continue;
            const size_t b = size_t(next[size_t(j)]++);
            D.entry[b] = (p & 0xffffffffffffull) | uint64_t(i & 0xffffu) << 48;
            if (wide) D.col_hi[b] = uint16_t(i >> 16);
        }
    return D;
}

std::vector<vec3> multiply_directed(const VertexFactors& F, const DirectedFactors& D, const std::vector<vec3>& E) {
    const std::vector<vec4> Ew = weighted(F, E);
    std::vector<vec3> B(size_t(F.n), vec3(0.f));
    mesolab::parallel_for(tbb::blocked_range<int>(0, F.n, 256), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) {
            vec4 sum(0.f);
            for (int k = D.outer[size_t(i)]; k < D.outer[size_t(i) + 1]; ++k) {
                const uint64_t p = D.entry[size_t(k)];
                const int j = int(p >> 48) | (D.col_hi.empty() ? 0 : int(D.col_hi[size_t(k)]) << 16);
                sum += vec4(decode(p), 0.f) * Ew[size_t(j)];
            }
            B[size_t(i)] = vec3(sum);
        }
    });
    return B;
}

// [SECTION] Building
VertexFactors build_vertex_factors(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                                   const FactorParams& p) {
    if (!(p.mm_per_unit > 0.0) || !std::isfinite(p.mm_per_unit))
        throw InputError("translucency.mm_per_unit: " + std::to_string(p.mm_per_unit) + " must be a positive number of millimetres");
    if (!(p.threshold >= 0.f) || !std::isfinite(p.threshold))
        throw InputError("translucency.threshold: " + std::to_string(p.threshold) + " must be >= 0");
    VertexFactors F;
    F.n = int(position.size());
    F.threshold = p.threshold;
    F.zero_diagonal = p.zero_diagonal;
    F.vertex_area = vertex_areas(position, index, p.mm_per_unit);
    F.outer.assign(size_t(F.n) + 1, 0);
    if (F.n == 0) return F;

    // Positions in mm; R_d tabulated over the diameter; halves relative to R_d(0) / 2^15.
    std::vector<vec3> x(position.size());
    vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] = position[i] * float(p.mm_per_unit);
        lo = glm::min(lo, x[i]), hi = glm::max(hi, x[i]);
    }
    const double diameter = std::max(1e-9, double(glm::length(hi - lo)));
    const RdTable Rd(dipole, diameter * 1.0001);
    const vec3 Rd0 = Rd.at_r2(0.f);
    for (int c = 0; c < 3; ++c) F.scale[c] = Rd0[c] > 0.f && std::isfinite(Rd0[c]) ? Rd0[c] / 32768.f : 1.f;
    const vec3 inv_scale = 1.f / F.scale;
    std::vector<float> third(F.vertex_area.size());
    for (size_t j = 0; j < third.size(); ++j) third[j] = F.vertex_area[j] / 3.f;
    const bool wide = F.n > 65536 || p.wide_columns;

    // Interpolation correction (see global.h): q_i per vertex, ∇²R_d / R_d tabulated like R_d.
    std::vector<float> q(size_t(F.n), 0.f);
    if (p.interpolation_correction) {
        std::vector<float> area(size_t(F.n), 0.f);
        for (size_t f = 0; f + 2 < index.size(); f += 3) {
            const vec3 a = x[index[f]], b = x[index[f + 1]], c = x[index[f + 2]];
            const float e2 = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
            const float at = 0.5f * glm::length(glm::cross(b - a, c - a));
            if (!(at > 0.f) || !std::isfinite(e2)) continue;
            for (int k = 0; k < 3; ++k) q[index[f + size_t(k)]] += at * e2 / 48.f, area[index[f + size_t(k)]] += at;
        }
        for (size_t i = 0; i < q.size(); ++i) q[i] = area[i] > 0.f ? q[i] / area[i] : 0.f;
    }
    // Pairs that share an edge are not shrunk: with blending they keep R_d (the zero diagonal
    // sits inside both their stencils, so interpolation there pulls towards 0 instead of
    // smoothing R_d, and the blending fit closes the energy); without, they and the diagonal are
    // the hat-pair means R̄ (see global.h).
    std::vector<std::vector<uint32_t>> ring(p.interpolation_correction ? size_t(F.n) : 0);
    std::vector<float> reach2(ring.size(), 0.f);  // i's longest edge, squared (mm²)
    if (p.interpolation_correction) {
        for (size_t f = 0; f + 2 < index.size(); f += 3)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = index[f + size_t(k)], b = index[f + size_t((k + 1) % 3)];
                ring[a].push_back(b), ring[b].push_back(a);
                const vec3 e = x[a] - x[b];
                const float e2 = glm::dot(e, e) * 1.0001f;
                reach2[a] = std::max(reach2[a], e2), reach2[b] = std::max(reach2[b], e2);
            }
        for (auto& r : ring) {
            std::sort(r.begin(), r.end());
            r.erase(std::unique(r.begin(), r.end()), r.end());
        }
    }
    // Without blending, the diagonal and the pairs that share an edge (whose hats overlap) are
    // the hat-pair means R̄_ij (see global.h); diag[i], and edge[i][k] for ring[i][k] > i. With
    // blending, an edge keeps R_d(r_ij) up to twice R̄_ij, sampled once per triangle.
    std::vector<vec3> diag;
    std::vector<std::vector<vec3>> edge;
    if (p.interpolation_correction) {
        std::vector<std::vector<uint32_t>> faces(size_t(F.n));
        for (size_t f = 0; f + 2 < index.size(); f += 3)
            for (int k = 0; k < 3; ++k) faces[index[f + size_t(k)]].push_back(uint32_t(f / 3));
        const SubSamples S = sub_samples(x, index, dipole, p.zero_diagonal ? 1 : kMaxSplit);
        diag.assign(size_t(F.n), vec3(0.f));
        edge.resize(size_t(F.n));
        mesolab::parallel_for(tbb::blocked_range<int>(0, F.n, 16), [&](const tbb::blocked_range<int>& r) {
            std::vector<std::pair<int, float>> si, sj;
            for (int i = r.begin(); i != r.end(); ++i) {
                hat_samples(S, index, faces[size_t(i)], uint32_t(i), si);
                if (!p.zero_diagonal) diag[size_t(i)] = hat_pair_mean(S, Rd, si, si);
                edge[size_t(i)].assign(ring[size_t(i)].size(), vec3(0.f));
                for (size_t k = 0; k < ring[size_t(i)].size(); ++k) {
                    const uint32_t j = ring[size_t(i)][k];
                    if (j <= uint32_t(i)) continue;
                    hat_samples(S, index, faces[j], j, sj);
                    edge[size_t(i)][k] = hat_pair_mean(S, Rd, si, sj);
                }
            }
        });
    }
    constexpr int kLaplacianSamples = 4096;
    std::vector<vec3> laplacian;
    if (p.interpolation_correction) {
        laplacian.resize(kLaplacianSamples);
        for (int k = 0; k < kLaplacianSamples; ++k) {
            const double u = double(k) / double(kLaplacianSamples - 1);
            laplacian[size_t(k)] = vec3(dipole.laplacian_ratio(u * u * diameter * 1.0001));
        }
    }
    const float inv_diameter = float(1.0 / (diameter * 1.0001));
    // 1 / (ρ_i ρ_j) (see global.h), only ever shrinking R_d.
    const SideFactor side;
    const auto correction = [&](float r2, float qi, float qj) {
        const float u = std::min(1.f, std::sqrt(std::sqrt(r2) * inv_diameter)) * float(kLaplacianSamples - 1);
        const int k = std::min(int(u), kLaplacianSamples - 2);
        const float t = u - float(k);
        const vec3 L = laplacian[size_t(k)] * (1.f - t) + laplacian[size_t(k) + 1] * t;
        vec3 out;
        for (int c = 0; c < 3; ++c) out[c] = side(qi * L[c]) * side(qj * L[c]);
        return out;
    };

    // Rows of the upper triangle in parallel, each into its own buffers, then concatenated.
    struct Row {
        std::vector<uint64_t> pair;
        std::vector<uint16_t> hi;
    };
    std::vector<Row> rows(size_t(F.n));
    const float thr = p.threshold;
    mesolab::parallel_for(tbb::blocked_range<int>(0, F.n, 64), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) {
            Row& row = rows[size_t(i)];
            const vec3 xi = x[size_t(i)];
            const float ai = third[size_t(i)];
            for (int j = p.zero_diagonal ? i + 1 : i; j < F.n; ++j) {
                const vec3 d = x[size_t(j)] - xi;
                const float r2 = glm::dot(d, d);
                vec3 rd = Rd.at_r2(r2);
                // j == i or an edge (looked up only within i's longest edge)
                bool neighbour = j == i;
                if (!laplacian.empty() && !neighbour && r2 <= reach2[size_t(i)]) {
                    const auto& ri = ring[size_t(i)];
                    const auto it = std::lower_bound(ri.begin(), ri.end(), uint32_t(j));
                    if (it != ri.end() && *it == uint32_t(j)) {
                        neighbour = true;
                        const vec3 mean = edge[size_t(i)][size_t(it - ri.begin())];
                        rd = p.zero_diagonal ? glm::min(rd, 2.f * mean) : mean;
                    }
                }
                if (!diag.empty() && j == i) rd = diag[size_t(i)];
                const float mean_area = 0.5f * (ai + third[size_t(j)]);
                float largest = std::max(rd.x, std::max(rd.y, rd.z));
                if (!(largest > 0.f) || largest * mean_area < thr) continue;  // the correction only shrinks
                if (!laplacian.empty() && !neighbour) {
                    rd *= correction(r2, q[size_t(i)], q[size_t(j)]);
                    largest = std::max(rd.x, std::max(rd.y, rd.z));
                    if (!(largest > 0.f) || largest * mean_area < thr) continue;
                }
                row.pair.push_back(encode(rd * inv_scale, j));
                if (wide) row.hi.push_back(uint16_t(j >> 16));
            }
        }
    });
    size_t total = 0;
    for (int i = 0; i < F.n; ++i) total += rows[size_t(i)].pair.size();
    if (total > size_t(std::numeric_limits<int>::max()))
        throw InputError("translucency.threshold: " + std::to_string(p.threshold) + " keeps " + std::to_string(total) +
                         " vertex pairs, more than 2^31; raise it or lower translucency.vertices");
    for (int i = 0; i < F.n; ++i) F.outer[size_t(i) + 1] = F.outer[size_t(i)] + int(rows[size_t(i)].pair.size());
    F.pair.resize(total);
    if (wide) F.col_hi.resize(total);
    mesolab::parallel_for(tbb::blocked_range<int>(0, F.n, 256), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) {
            Row& row = rows[size_t(i)];
            std::copy(row.pair.begin(), row.pair.end(), F.pair.begin() + F.outer[size_t(i)]);
            if (wide) std::copy(row.hi.begin(), row.hi.end(), F.col_hi.begin() + F.outer[size_t(i)]);
            row = Row{};
        }
    });
    for (int i = 0; i < F.n; ++i)
        if (F.outer[size_t(i)] < F.outer[size_t(i) + 1] && F.column(size_t(F.outer[size_t(i)])) == i) ++F.diagonal;
    return F;
}
}  // namespace mesolab::translucency
