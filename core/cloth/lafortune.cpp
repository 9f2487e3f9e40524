// The cloth reflectance model (see lafortune.h).
#include "core/cloth/lafortune.h"
#include "core/cloth/sheen.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace mesolab::cloth {

// [SECTION] Lafortune lobes
dvec3 LafortuneLobe::f(dvec3 l, dvec3 v) const {
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        const double a = Cx[c] * l.x * v.x + Cy[c] * l.y * v.y + Cz[c] * l.z * v.z;
        out[c] = a > 0.0 ? std::pow(a, n[c]) : 0.0;
    }
    return out;
}

dvec3 Lafortune::f(dvec3 l, dvec3 v) const {
    dvec3 out = kd;
    for (const LafortuneLobe& lobe : lobes) out += lobe.f(l, v);
    return out;
}

// [SECTION] View table
dvec4 ViewTable::at(dvec3 w) const {
    if (v.empty()) return dvec4(1.0);
    const double len = glm::length(w);
    if (!(len > 0.0) || !std::isfinite(len)) return T[0];
    w /= len;
    // The four nearest directions by angle (largest cosine; at equal cosines the lower index).
    std::array<int, 4> best{-1, -1, -1, -1};
    std::array<double, 4> cb{-2.0, -2.0, -2.0, -2.0};
    for (size_t i = 0; i < v.size(); ++i) {
        const double c = glm::dot(v[i], w);
        if (c <= cb[3]) continue;
        int k = 3;
        while (k > 0 && c > cb[size_t(k - 1)]) {
            cb[size_t(k)] = cb[size_t(k - 1)], best[size_t(k)] = best[size_t(k - 1)];
            --k;
        }
        cb[size_t(k)] = c, best[size_t(k)] = int(i);
    }
    // The angles from their sines and cosines: exact for nearby directions, where acos is not.
    std::array<double, 4> angle{};
    for (int k = 0; k < 4 && best[size_t(k)] >= 0; ++k) {
        const dvec3& d = v[size_t(best[size_t(k)])];
        angle[size_t(k)] = std::atan2(glm::length(glm::cross(d, w)), glm::dot(d, w));
    }
    if (angle[0] < 1e-9) return T[size_t(best[0])];
    // Weights 1/angle less the fourth nearest's, so that a direction's weight is 0 where it
    // leaves the three nearest: T(v) is continuous (plain inverse-angle weights jump there).
    const double floor_w = best[3] >= 0 ? 1.0 / angle[3] : 0.0;
    dvec4 sum(0.0);
    double wsum = 0.0;
    for (int k = 0; k < 3 && best[size_t(k)] >= 0; ++k) {
        const double wk = std::max(0.0, 1.0 / angle[size_t(k)] - floor_w);
        sum += wk * T[size_t(best[size_t(k)])];
        wsum += wk;
    }
    if (!(wsum > 0.0)) {  // the four nearest at one angle (a set of measure zero): the mean of the three
        sum = dvec4(0.0);
        for (int k = 0; k < 3; ++k) sum += T[size_t(best[size_t(k)])];
        return sum / 3.0;
    }
    return sum / wsum;
}

// [SECTION] The model of a sample point
dvec3 ClothBrdf::f_model(dvec3 l, dvec3 v) const {
    if (sheen) return L.kd + sheen->S * sheen_lobe(l, v, sheen->r);
    return glm::min(L.f(l, v), dvec3(1e300));  // an overflowing lobe stays finite: 0 × it is 0
}

dvec3 ClothBrdf::f(dvec3 l, dvec3 v) const {
    const dvec3 fl = f_model(l, v);
    if (table.empty()) return glm::min(fl, f_max);
    return glm::min(dvec3(table.at(v)) * fl, f_max);
}

double ClothBrdf::alpha(dvec3 v) const { return table.empty() ? 1.0 : table.at(v).w; }
}  // namespace mesolab::cloth
