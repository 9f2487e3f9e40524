// Shading with a fitted fabric (see reflectance.h).
#include "core/cloth/reflectance.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>

namespace mesolab::cloth {

MipMode mip_mode_named(const std::string& s) {
    if (s == "off") return MipMode::Off;
    if (s == "nearest") return MipMode::Nearest;
    if (s == "blend") return MipMode::Blend;
    throw InputError("cloth.mip: \"" + s + "\" must be off, nearest or blend");
}

namespace {
struct Eval {
    dvec3 radiance{0.0};
    double alpha = 1.0;
    int index = 0;
};

Eval at_level(const BrdfPyramid& p, int k, dvec2 uv, dvec3 l, dvec3 v, dvec3 E) {
    const int side = p.res >> k;
    const dvec2 w = uv - glm::floor(uv);
    const int x = std::min(side - 1, int(w.x * side)), y = std::min(side - 1, int(w.y * side));
    const size_t at = size_t(y) * size_t(side) + size_t(x);
    const ClothBrdf& b = p.level[size_t(k)][at];
    const glm::dmat3& F = p.frame[size_t(k)][at];
    const dvec3 vh = F * v;
    Eval e;
    e.radiance = entry_reflectance(b, F, l, v) * E;  // foreshortening in the entry's frame (§3)
    e.alpha = b.alpha(vh);
    int offset = 0;
    for (int j = 0; j < k; ++j) offset += int(p.level[size_t(j)].size());
    e.index = offset + int(at);
    return e;
}
}  // namespace

ClothSample shade(const BrdfPyramid& p, dvec2 uv, double footprint, MipMode mode, double bias, dvec3 l, dvec3 v, dvec3 E) {
    ClothSample s;
    if (p.level.empty()) return s;
    const int top = int(p.level.size()) - 1;
    double lambda = std::log2(std::max(footprint, 1e-30) * double(p.res)) + bias;
    lambda = std::clamp(std::isfinite(lambda) ? lambda : 0.0, 0.0, double(top));
    if (mode == MipMode::Off) lambda = 0.0;
    if (mode == MipMode::Nearest) lambda = std::round(lambda);
    const int k0 = int(std::floor(lambda)), k1 = std::min(top, k0 + 1);
    const double t = mode == MipMode::Blend ? lambda - double(k0) : 0.0;
    const Eval a = at_level(p, k0, uv, l, v, E);
    s.index = a.index;
    s.level = mode == MipMode::Blend ? lambda : double(k0);
    if (t > 0.0 && k1 != k0) {
        const Eval b = at_level(p, k1, uv, l, v, E);
        s.radiance = glm::mix(a.radiance, b.radiance, t);
        s.alpha = glm::mix(a.alpha, b.alpha, t);
    } else {
        s.radiance = a.radiance;
        s.alpha = a.alpha;
    }
    return s;
}
}  // namespace mesolab::cloth
