#pragma once
// [SECTION] Bilinear look-ups
// Every bilinear look-up of a texel grid in mesolab goes through here (heightfields, scattered
// light, albedo maps, environment maps, the translucency atlas, bumpsynth's noise texture and
// index map): the four texels and two weights at continuous texel coordinates (x, y), where texel
// (i, j) sits at (i, j). A GL texture sampled at uv has x = u w − 1/2 (texel centres at
// (i + 1/2) / w), which `at_uv` computes. Each axis wraps (GL_REPEAT) or clamps
// (GL_CLAMP_TO_EDGE), as the texture it stands for.
//
// Two evaluation orders, both exact for the same weights but rounding differently:
//   blend       (t00 (1 − ax) + t10 ax)(1 − ay) + (t01 (1 − ax) + t11 ax) ay   (glm::mix's order)
//   blend_lerp  a = t00 + ax (t10 − t00), b = t01 + ax (t11 − t01), a + ay (b − a)
// A path whose GPU twin must give the same bits uses the order its shader writes out.
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace mesolab {

enum class Edge { Wrap, Clamp };

struct BilinearTaps {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // the texels: columns x0, x1 and rows y0, y1
    float ax = 0.f, ay = 0.f;            // the weights of x1 and of y1

    BilinearTaps(float x, float y, int w, int h, Edge ex, Edge ey) {
        const float x0f = std::floor(x), y0f = std::floor(y);
        ax = x - x0f, ay = y - y0f;
        x0 = fold(int(x0f), w, ex), x1 = fold(int(x0f) + 1, w, ex);
        y0 = fold(int(y0f), h, ey), y1 = fold(int(y0f) + 1, h, ey);
    }
    // At texture coordinates (u, v) of a w x h texture stored with row 0 at v = 0.
    static BilinearTaps at_uv(vec2 uv, int w, int h, Edge ex, Edge ey) {
        return BilinearTaps(uv.x * float(w) - 0.5f, uv.y * float(h) - 0.5f, w, h, ex, ey);
    }
    static int fold(int i, int n, Edge e) { return e == Edge::Wrap ? ((i % n) + n) % n : std::clamp(i, 0, n - 1); }

    // The blended value of a row-major w-wide grid read by `at(x, y)`.
    template <class At>
    auto blend(At&& at) const {
        return (at(x0, y0) * (1.f - ax) + at(x1, y0) * ax) * (1.f - ay) + (at(x0, y1) * (1.f - ax) + at(x1, y1) * ax) * ay;
    }
    template <class At>
    auto blend_lerp(At&& at) const {
        const auto a = at(x0, y0) + ax * (at(x1, y0) - at(x0, y0)), b = at(x0, y1) + ax * (at(x1, y1) - at(x0, y1));
        return a + ay * (b - a);
    }
    // The same over a row-major grid of T, w texels wide.
    template <class T>
    T blend(const T* grid, int w) const {
        return blend([&](int x, int y) { return grid[size_t(y) * size_t(w) + size_t(x)]; });
    }
};
}  // namespace mesolab
