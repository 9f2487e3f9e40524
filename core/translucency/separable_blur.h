#pragma once
// Method separable of technique translucency: one pixel of one of the two 1D blurs (separable.h),
// the CPU twin of gpu/translucency/separable_blur.comp.
#include "core/math.h"
#include "core/translucency/separable.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

// What a blur reads per pixel (row-major, width x height).
struct BlurImage {
    int width = 0, height = 0;
    std::vector<vec3> value;     // what is blurred (the irradiance, then the first pass's result)
    std::vector<int32_t> object; // the object the pixel shows (-1: none of the method's)
    std::vector<float> depth_mm; // view depth of its surface point
    std::vector<float> pixel_mm; // the size of a pixel there
};

// Pixel (x, y) of the pass along rows (vertical = false) or columns, with its object's kernel.
// A tap x_i mm away lies x_i / pixel_mm pixels away, read linearly from the two pixels around it;
// a pixel of another object, of none or outside the image gives the centre's value, a pixel of
// the object mix(its value, the centre's, min(1, |Δdepth| / |x_i|)) (following the surface).
inline vec3 blur_pixel(const BlurImage& in, const SeparableKernel& k, int x, int y, bool vertical) {
    const size_t c = size_t(y) * size_t(in.width) + size_t(x);
    const vec3 centre = in.value[c];
    const int object = in.object[c];
    const float z = in.depth_mm[c], inv_pixel = 1.f / in.pixel_mm[c];
    const int along = vertical ? y : x, n = vertical ? in.height : in.width;
    const auto tap = [&](int i, float offset) {
        if (i < 0 || i >= n) return centre;
        const size_t j = vertical ? size_t(i) * size_t(in.width) + size_t(x) : size_t(y) * size_t(in.width) + size_t(i);
        if (in.object[j] != object) return centre;
        const float s = std::min(1.f, std::abs(in.depth_mm[j] - z) / std::abs(offset));
        return glm::mix(in.value[j], centre, s);
    };
    vec3 sum(0.f);
    for (size_t i = 0; i < k.offset_mm.size(); ++i) {
        const float offset = k.offset_mm[i];
        if (offset == 0.f) {
            sum += k.weight[i] * centre;
            continue;
        }
        const float u = float(along) + offset * inv_pixel;
        if (!(u > -1.f && u < float(n))) {  // both pixels outside the image (and no overflow below)
            sum += k.weight[i] * centre;
            continue;
        }
        const float f0 = std::floor(u);
        const int i0 = int(f0);
        const float f = u - f0;
        sum += k.weight[i] * glm::mix(tap(i0, offset), tap(i0 + 1, offset), f);
    }
    return sum;
}

// One pass over every pixel whose object has a kernel (kernels by object id; null: not blurred).
void separable_blur_pass(const BlurImage& in, const std::vector<const SeparableKernel*>& kernels, bool vertical, std::vector<vec3>& out);
}  // namespace mesolab::translucency
