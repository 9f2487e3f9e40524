#pragma once
// Helpers for tests of the truth (core/truth/truth.h): which pixels show an object, and the mean
// radiance over them with its standard error.
#include "core/render.h"

#include <cmath>

namespace mesolab::test {

// Whether the truth's pixel (x, y) shows an object (a first hit's normal; 0 for the background).
inline bool shows_object(const Frame& f, int x, int y) {
    const float* n = f.aov("normal").at(x, y);
    return n[0] != 0.f || n[1] != 0.f || n[2] != 0.f;
}

// The mean of channel `c` of the truth's radiance over the pixels that show an object, and its
// standard error (from truth_stderr: the pixels' estimates are independent).
struct ObjectMean {
    double mean = 0, stderr_mean = 0;
    int pixels = 0;
};
inline ObjectMean object_mean(const Frame& f, int c = 1) {
    const Image& L = f.aov("radiance");
    double sum = 0.0, var = 0.0;
    ObjectMean m;
    for (int y = 0; y < L.height; ++y)
        for (int x = 0; x < L.width; ++x)
            if (shows_object(f, x, y)) {
                sum += L.at(x, y)[c];
                const double se = f.aov("truth_stderr").at(x, y)[c];
                var += se * se, ++m.pixels;
            }
    if (m.pixels) m.mean = sum / m.pixels, m.stderr_mean = std::sqrt(var) / m.pixels;
    return m;
}
}  // namespace mesolab::test
