// Technique translucency: the tables the GPU passes read (gpu_layout.h).
#include "core/translucency/gpu_layout.h"

#include <algorithm>
#include <cstring>

namespace mesolab::translucency {

PaddedFactors pad_factor_rows(const VertexFactors& F) {
    const DirectedFactors D = expand_directed(F);
    constexpr int Q = PaddedFactors::kRowQuantum;
    PaddedFactors P;
    P.outer.assign(D.outer.size(), 0);
    P.entry.reserve(D.entry.size() + size_t(F.n) * (Q / 2) + 2);
    const bool wide = !D.col_hi.empty();
    for (int i = 0; i < F.n; ++i) {
        const int b = D.outer[size_t(i)], e = D.outer[size_t(i) + 1];
        P.outer[size_t(i)] = int(P.entry.size());
        P.entry.insert(P.entry.end(), D.entry.begin() + b, D.entry.begin() + e);
        if (wide) P.col_hi.insert(P.col_hi.end(), D.col_hi.begin() + b, D.col_hi.begin() + e);
        const int pad = (Q - (e - b) % Q) % Q;
        P.entry.insert(P.entry.end(), size_t(pad), 0);
        if (wide) P.col_hi.insert(P.col_hi.end(), size_t(pad), 0);
    }
    P.outer[size_t(F.n)] = int(P.entry.size());
    P.entry.resize(P.entry.size() + 2, 0);
    if (wide) P.col_hi.resize(P.col_hi.size() + 2, 0);
    return P;
}

std::vector<FactorPiece> factor_pieces(const PaddedFactors& P, int64_t max_texels, int64_t align_pairs) {
    align_pairs = std::max<int64_t>(1, align_pairs);
    const int64_t cap = std::max<int64_t>(1024, max_texels - align_pairs);
    const int n = int(P.outer.size()) - 1;
    const int64_t total = P.pairs();
    std::vector<FactorPiece> pieces;
    for (int r0 = 0; r0 < n;) {
        const int64_t base = int64_t(P.outer[size_t(r0)]) / 2 / align_pairs * align_pairs;
        int r1 = r0 + 1;
        while (r1 < n && int64_t(P.outer[size_t(r1) + 1]) / 2 - base <= cap) ++r1;
        const int64_t count = std::max<int64_t>(1, std::min(int64_t(P.outer[size_t(r1)]) / 2 - base, total - base));
        pieces.push_back({r0, r1, base, count});
        r0 = r1;
    }
    return pieces;
}

ShownTexels shown_texels(const AtlasStage& A, const std::vector<uint32_t>& index) {
    const Atlas& a = A.atlas;
    ShownTexels out;
    out.shown.resize(A.nonempty.size());
    out.bary.resize(A.nonempty.size());
    for (size_t k = 0; k < A.nonempty.size(); ++k) {
        const int t = A.nonempty[k];
        const int s = A.fill[size_t(t)] >= 0 ? A.fill[size_t(t)] : t;
        const int f = a.texel_face[size_t(s)];
        out.shown[k] = f >= 0 ? glm::ivec4(t, s, int(index[3 * size_t(f)]), int(index[3 * size_t(f) + 1])) : glm::ivec4(t, s, -1, -1);
        const int32_t v2 = f >= 0 ? int32_t(index[3 * size_t(f) + 2]) : -1;
        float bits;
        std::memcpy(&bits, &v2, sizeof bits);
        out.bary[k] = vec4(f >= 0 ? a.texel_bary[size_t(s)] : vec3(0.f), bits);
    }
    return out;
}
}  // namespace mesolab::translucency
