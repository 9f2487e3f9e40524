#include "app/truth_figures.h"
#include "app/plot.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace mesolab {

// [SECTION] Error colours
namespace {
float mean_abs(const float* e) { return (std::fabs(e[0]) + std::fabs(e[1]) + std::fabs(e[2])) / 3.f; }
bool object_pixel(const Frame& truth, int x, int y) {
    const float* n = truth.aov("normal").at(x, y);
    return n[0] != 0.f || n[1] != 0.f || n[2] != 0.f;
}
}  // namespace

Image error_colors(const Image& error, const Frame& truth, float scale) {
    Image out(error.width, error.height, 3);
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x) {
            float* o = out.at(x, y);
            if (!object_pixel(truth, x, y)) {
                o[0] = o[1] = o[2] = 0.01f;
                continue;
            }
            const float* e = error.at(x, y);
            const float t = std::clamp((e[0] + e[1] + e[2]) / (3.f * scale), -1.f, 1.f);
            // White at 0; towards blue (0.05, 0.25, 1) below the truth, red (1, 0.1, 0.05) above.
            const vec3 end = t < 0.f ? vec3(0.05f, 0.25f, 1.f) : vec3(1.f, 0.1f, 0.05f);
            const vec3 c = glm::mix(vec3(1.f), end, std::fabs(t));
            o[0] = c.x, o[1] = c.y, o[2] = c.z;
        }
    return out;
}

Image error_figure(const Image& error, const Frame& truth) {
    const float scale = error_scale(error, truth);
    const Image colours = error_colors(error, truth, scale);
    const int text = text_height(1), strip = 3 * text + 16;
    Image out(error.width, error.height + strip, 3);
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, y)[c] = colours.at(x, y)[c];
    for (int y = error.height; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) out.at(x, y)[0] = 0.005f, out.at(x, y)[1] = 0.0055f, out.at(x, y)[2] = 0.0065f;
    // The ramp, as error_colors draws it, across the middle of the strip's width.
    const int w = std::max(16, std::min(out.width - 16, 200)), x0 = (out.width - w) / 2, y0 = error.height + text + 8, h = std::max(4, text / 2);
    for (int x = 0; x < w; ++x) {
        const float t = 2.f * (float(x) + 0.5f) / float(w) - 1.f;
        const vec3 end = t < 0.f ? vec3(0.05f, 0.25f, 1.f) : vec3(1.f, 0.1f, 0.05f);
        const vec3 c = glm::mix(vec3(1.f), end, std::fabs(t));
        for (int y = y0; y < y0 + h; ++y)
            for (int k = 0; k < 3; ++k) out.at(x0 + x, y)[k] = c[k];
    }
    const float grey = 0.6f;
    // The longest caption that fits the width.
    std::string caption;
    for (const char* c : {"real-time - truth (radiance, mean of RGB)", "real-time - truth", "rt - truth"}) {
        caption = c;
        if (text_width(caption) <= out.width - 4) break;
    }
    draw_text(out, std::max(2, (out.width - text_width(caption)) / 2), error.height + 4, caption, grey, grey, grey);
    char lo[32], hi[32];
    std::snprintf(lo, sizeof lo, "%+.3g", -double(scale));
    std::snprintf(hi, sizeof hi, "%+.3g", double(scale));
    draw_text(out, x0, y0 + h + 3, lo, grey, grey, grey);
    draw_text(out, x0 + w / 2 - text_width("0") / 2, y0 + h + 3, "0", grey, grey, grey);
    draw_text(out, x0 + w - text_width(hi), y0 + h + 3, hi, grey, grey, grey);
    return out;
}

float error_scale(const Image& error, const Frame& truth) {
    std::vector<float> v;
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x)
            if (object_pixel(truth, x, y)) v.push_back(mean_abs(error.at(x, y)));
    if (v.empty()) return 1.f;
    const size_t k = std::min(v.size() - 1, size_t(0.99 * double(v.size())));
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
    const double p = std::max(1e-6, double(v[k]));
    const double decade = std::pow(10.0, std::floor(std::log10(p)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade >= p) return float(m * decade);
    return float(10.0 * decade);
}
}  // namespace mesolab
