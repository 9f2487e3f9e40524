// Vertex-to-vertex throughput factors (see global.h).
#include "core/translucency/global.h"
#include "core/translucency/atlas.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
            E[v] += e * (3.0 / double(vertex_area[v]) * (4.0 * double(w[j]) - 1.0));
        }
    }
    return std::vector<vec3>(E.begin(), E.end());
}

Eigen::Map<const Eigen::SparseMatrix<float, Eigen::RowMajor>> VertexFactors::channel(int c) const {
    return {n, n, Eigen::Index(inner.size()), outer.data(), inner.data(), value[size_t(c)].data()};
}

std::vector<vec3> VertexFactors::multiply(const std::vector<vec3>& E) const {
    std::vector<vec3> B(size_t(n), vec3(0.f));
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& rows) {
        for (int i = rows.begin(); i != rows.end(); ++i) {
            vec3 sum(0.f);
            for (int k = outer[size_t(i)]; k < outer[size_t(i) + 1]; ++k) {
                const vec3 e = E[size_t(inner[size_t(k)])];
                sum += vec3(value[0][size_t(k)] * e.x, value[1][size_t(k)] * e.y, value[2][size_t(k)] * e.z);
            }
            B[size_t(i)] = sum;
        }
    });
    return B;
}

VertexFactors build_vertex_factors(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Dipole& dipole,
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

    // Positions in mm; R_d tabulated over the diameter.
    std::vector<vec3> x(position.size());
    vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] = position[i] * float(p.mm_per_unit);
        lo = glm::min(lo, x[i]), hi = glm::max(hi, x[i]);
    }
    const double diameter = std::max(1e-9, double(glm::length(hi - lo)));
    const RdTable Rd(dipole, diameter * 1.0001);
    std::vector<float> third(F.vertex_area.size());
    for (size_t j = 0; j < third.size(); ++j) third[j] = F.vertex_area[j] / 3.f;

    // Rows in parallel, each into its own buffers, then concatenated.
    struct Row {
        std::vector<int> col;
        std::vector<vec3> val;
    };
    std::vector<Row> rows(size_t(F.n));
    const float thr = p.threshold;
    tbb::parallel_for(tbb::blocked_range<int>(0, F.n, 64), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) {
            Row& row = rows[size_t(i)];
            const vec3 xi = x[size_t(i)];
            for (int j = 0; j < F.n; ++j) {
                if (j == i && p.zero_diagonal) continue;
                const vec3 d = x[size_t(j)] - xi;
                const vec3 f = Rd.at_r2(glm::dot(d, d)) * third[size_t(j)];
                if (std::max(f.x, std::max(f.y, f.z)) < thr || !(f.x > 0.f || f.y > 0.f || f.z > 0.f)) continue;
                row.col.push_back(j);
                row.val.push_back(f);
            }
        }
    });
    for (int i = 0; i < F.n; ++i) F.outer[size_t(i) + 1] = F.outer[size_t(i)] + int(rows[size_t(i)].col.size());
    const size_t nnz = size_t(F.outer[size_t(F.n)]);
    F.inner.resize(nnz);
    for (auto& v : F.value) v.resize(nnz);
    tbb::parallel_for(tbb::blocked_range<int>(0, F.n, 256), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) {
            Row& row = rows[size_t(i)];
            size_t k = size_t(F.outer[size_t(i)]);
            for (size_t m = 0; m < row.col.size(); ++m, ++k) {
                F.inner[k] = row.col[m];
                for (int c = 0; c < 3; ++c) F.value[size_t(c)][k] = row.val[m][c];
            }
            row = Row{};
        }
    });
    return F;
}
}  // namespace mesolab::translucency
