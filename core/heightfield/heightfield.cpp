// Heightfields: queries, bilinear look-ups, procedural fields, images and albedo maps (see heightfield.h).
#include "core/heightfield/heightfield.h"
#include "core/parallel.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>


namespace mesolab {

// [SECTION] Heightfield queries
float Heightfield::at_outside(int x, int y) const {
    if (periodic) {
        x = ((x % width) + width) % width;
        y = ((y % height) + height) % height;
    } else {
        x = std::clamp(x, 0, width - 1);
        y = std::clamp(y, 0, height - 1);
    }
    return h[index(x, y)];
}

vec3 Heightfield::normal(int x, int y) const {
    if (x > 0 && y > 0 && x < width - 1 && y < height - 1) {
        // Inside the field: central differences, the same operations as below without the wrap.
        const float* c = h.data() + index(x, y);
        const float dhdx = (c[1] - c[-1]) / (2.f * texel_size);
        const float dhdy = (c[-ptrdiff_t(width)] - c[width]) / (2.f * texel_size);
        return glm::normalize(vec3(-dhdx, -dhdy, 1.f));
    }
    // Slope along one axis at texel i of n: central difference, or one-sided at a non-periodic
    // border (zero for a single texel). `h_prev`/`h_next` are the neighbours at i-1 and i+1.
    auto slope = [&](int i, int n, float h_prev, float h_here, float h_next) {
        if (periodic) return (h_next - h_prev) / (2.f * texel_size);
        if (n < 2) return 0.f;
        if (i <= 0) return (h_next - h_here) / texel_size;
        if (i >= n - 1) return (h_here - h_prev) / texel_size;
        return (h_next - h_prev) / (2.f * texel_size);
    };
    const float here = at(x, y);
    const float dhdx = slope(x, width, at(x - 1, y), here, at(x + 1, y));
    // Local +y runs towards the top row, i.e. towards row y - 1.
    const float dhdy = slope(height - 1 - y, height, at(x, y + 1), here, at(x, y - 1));
    return glm::normalize(vec3(-dhdx, -dhdy, 1.f));
}

float Heightfield::min_height() const { return h.empty() ? 0.f : *std::min_element(h.begin(), h.end()); }
float Heightfield::max_height() const { return h.empty() ? 0.f : *std::max_element(h.begin(), h.end()); }

// [SECTION] Procedural fields
namespace {

std::string to_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Fractional part in [0, 1).
double frac(double v) { return v - std::floor(v); }

// Deterministic hash of two integers to [-1, 1] (per-brick colour variation).
double hash_signed(int a, int b) {
    uint32_t v = uint32_t(a) * 0x9E3779B1u ^ (uint32_t(b) + 0x7F4A7C15u) * 0x85EBCA77u;
    v ^= v >> 16;
    v *= 0x7FEB352Du;
    v ^= v >> 15;
    v *= 0x846CA68Bu;
    v ^= v >> 16;
    return double(v) / double(0xFFFFFFFFu) * 2.0 - 1.0;
}

// Continuous coordinates of texel (x, y)'s centre in [0, 1)^2 (u along x, v along the rows).
// Every pattern below is a function of (u, v) with period 1, so the fields tile at any resolution.
double cu(int x, int n) { return (double(x) + 0.5) / double(n); }

// Symmetric triangle wave of period 1: 0 at integers, 1/2 at half-integers.
double tri(double t) { return 0.5 - std::abs(frac(t) - 0.5); }

// Paper Fig. 2: ridges along y, 4 periods across, 45-degree faces (peak = half the period).
void make_triangles(Heightfield& f, int n) {
    const double period = double(n) / 4.0;  // texels
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) f.h[f.index(x, y)] = float(period * tri(4.0 * cu(x, n)));
}

// Running-bond bricks: 4 courses, 2 bricks per course (2:1 aspect), alternate courses shifted by
// half a brick; mortar joints 1/8 of the course height wide at height 0; bricks raised by 1/6 of
// the course height with a linear bevel 1/12 of the course height wide (slope 2).
void make_bricks(Heightfield& f, int n, vec3 albedo) {
    const double course = double(n) / 4.0;  // course height in texels (brick + one joint)
    const double length = 2.0 * course;     // brick length in texels (brick + one joint)
    const double half_joint = course / 16.0;
    const double raise = course / 6.0, bevel = course / 12.0;
    const vec3 brick_colour = albedo * vec3(0.75f, 0.3f, 0.2f) / 0.8f;
    const vec3 mortar_colour(0.6f, 0.6f, 0.58f);
    for (int y = 0; y < n; ++y) {
        const double v = 4.0 * cu(y, n);
        const int row = int(std::floor(v));
        const double fy = frac(v) * course;
        for (int x = 0; x < n; ++x) {
            const double s = 2.0 * cu(x, n) + ((row & 1) ? 0.5 : 0.0);  // in bricks
            const int column = int(std::floor(s)) % 2;
            const double fx = frac(s) * length;
            const double inside = std::min(std::min(fx, length - fx), std::min(fy, course - fy)) - half_joint;
            const size_t i = f.index(x, y);
            if (inside <= 0.0) {
                f.h[i] = 0.f;
                f.albedo[i] = mortar_colour;
            } else {
                f.h[i] = float(raise * std::min(1.0, inside / bevel));
                f.albedo[i] = brick_colour * float(1.0 + 0.1 * hash_signed(row, column));
            }
        }
    }
}

// 4x4 bumps: h = r0 cos^2(pi/2 d/r0) within radius r0 = 0.4 cell of the cell centre.
void make_bumps(Heightfield& f, int n) {
    const double cell = double(n) / 4.0, r0 = 0.4 * cell;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double dx = (frac(4.0 * cu(x, n)) - 0.5) * cell, dy = (frac(4.0 * cu(y, n)) - 0.5) * cell;
            const double d = std::sqrt(dx * dx + dy * dy);
            const double c = d < r0 ? std::cos(0.5 * 3.14159265358979323846 * d / r0) : 0.0;
            f.h[f.index(x, y)] = float(r0 * c * c);
        }
}

// 4 V grooves along y: each groove spans its period P with the bottom (height 0) at the centre and
// walls of slope tan(90 - angle/2), so the ridges between grooves are at P/2 tan(90 - angle/2).
void make_vgrooves(Heightfield& f, int n, float angle_deg) {
    const double period = double(n) / 4.0;
    const double slope = std::tan((90.0 - 0.5 * double(angle_deg)) * 3.14159265358979323846 / 180.0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double t = frac(4.0 * cu(x, n));
            f.h[f.index(x, y)] = float(slope * period * std::abs(t - 0.5));
        }
}

// Periodic Gaussian random surface: white noise (own Box-Muller on std::mt19937, so the values are
// identical on every standard library) convolved periodically with a separable Gaussian of
// std dev `sigma` texels (truncated at 4 sigma), mean removed, scaled to the RMS slope.
void make_gaussian(Heightfield& f, int n, double sigma, double rms_slope, uint32_t seed) {
    std::mt19937 rng(seed);
    auto uniform = [&] { return (double(rng()) + 0.5) / 4294967296.0; };  // (0, 1)
    std::vector<double> noise(size_t(n) * size_t(n));
    for (size_t i = 0; i < noise.size(); i += 2) {
        const double r = std::sqrt(-2.0 * std::log(uniform())), phi = 2.0 * 3.14159265358979323846 * uniform();
        noise[i] = r * std::cos(phi);
        if (i + 1 < noise.size()) noise[i + 1] = r * std::sin(phi);
    }

    // Kernel taps (offset, weight), truncated at 4 sigma; a kernel longer than the period is
    // folded onto it (offsets 0..n-1), which is the same periodic convolution.
    const int radius = std::max(1, int(std::ceil(4.0 * sigma)));
    std::vector<int> offset;
    std::vector<double> weight;
    if (2 * radius + 1 <= n) {
        for (int k = -radius; k <= radius; ++k) {
            offset.push_back(k);
            weight.push_back(std::exp(-0.5 * double(k) * double(k) / (sigma * sigma)));
        }
    } else {
        weight.assign(size_t(n), 0.0);
        for (int k = -radius; k <= radius; ++k)
            weight[size_t(((k % n) + n) % n)] += std::exp(-0.5 * double(k) * double(k) / (sigma * sigma));
        for (int k = 0; k < n; ++k) offset.push_back(k);
    }
    // Convolves every row of `in` (one fixed-order sum per output, so the result does not depend
    // on the parallel split) and writes the result transposed; applied twice it convolves along x
    // and then along y, and leaves the field in its original layout.
    auto convolve_rows_transposed = [&](const std::vector<double>& in, std::vector<double>& out) {
        constexpr int kBlock = 32;  // rows per task: the transposed writes then come in runs
        mesolab::parallel_for(0, (n + kBlock - 1) / kBlock, [&](int block) {
            const int y0 = block * kBlock, rows = std::min(kBlock, n - y0);
            std::vector<double> result(size_t(rows) * size_t(n));
            for (int r = 0; r < rows; ++r) {
                const double* row = in.data() + size_t(y0 + r) * size_t(n);
                for (int x = 0; x < n; ++x) {
                    double sum = 0.0;
                    for (size_t k = 0; k < offset.size(); ++k) {
                        int j = x + offset[k];
                        j = j < 0 ? j + n : (j >= n ? j - n : j);
                        sum += weight[k] * row[j];
                    }
                    result[size_t(r) * size_t(n) + size_t(x)] = sum;
                }
            }
            for (int x = 0; x < n; ++x)
                for (int r = 0; r < rows; ++r) out[size_t(x) * size_t(n) + size_t(y0 + r)] = result[size_t(r) * size_t(n) + size_t(x)];
        });
    };
    std::vector<double> tmp(noise.size()), field(noise.size());
    convolve_rows_transposed(noise, tmp);
    convolve_rows_transposed(tmp, field);

    double mean = 0.0;
    for (double v : field) mean += v;
    mean /= double(field.size());
    auto wrap = [n](int i) { return ((i % n) + n) % n; };
    double slope2 = 0.0;  // mean of |grad h|^2, central differences in texel units
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double gx = 0.5 * (field[size_t(y) * size_t(n) + size_t(wrap(x + 1))] - field[size_t(y) * size_t(n) + size_t(wrap(x - 1))]);
            const double gy = 0.5 * (field[size_t(wrap(y + 1)) * size_t(n) + size_t(x)] - field[size_t(wrap(y - 1)) * size_t(n) + size_t(x)]);
            slope2 += gx * gx + gy * gy;
        }
    const double rms = std::sqrt(slope2 / double(field.size()));
    const double scale = rms > 0.0 ? rms_slope / rms : 0.0;
    for (size_t i = 0; i < field.size(); ++i) f.h[i] = float((field[i] - mean) * scale);
}
}  // namespace

const std::vector<std::string>& procedural_names() {
    static const std::vector<std::string> names = {"triangles", "bricks", "bumps", "vgrooves", "gaussian", "flat"};
    return names;
}

Heightfield make_procedural(const ProceduralParams& p) {
    const auto& names = procedural_names();
    if (std::find(names.begin(), names.end(), p.name) == names.end()) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        const std::string hint = nearest_key(p.name, names);
        throw InputError(p.group + ".heightfield: '" + p.name + "' is not one of " + list +
                         (hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
    }
    if (p.resolution < 8 || p.resolution > 4096)
        throw InputError(p.group + ".resolution: value " + std::to_string(p.resolution) + " is out of range [8, 4096]");
    if (!std::isfinite(p.height_scale))
        throw InputError(p.group + ".height_scale: value " + to_text(p.height_scale) + " is not finite");
    if (!(p.texel_size > 0.f) || !std::isfinite(p.texel_size))
        throw InputError(p.group + ".texel_size: value " + to_text(p.texel_size) + " must be positive and finite");

    const int n = p.resolution;
    Heightfield f;
    f.width = f.height = n;
    f.texel_size = p.texel_size;
    f.periodic = p.periodic;
    f.h.assign(size_t(n) * size_t(n), 0.f);
    f.albedo.assign(f.h.size(), p.albedo);

    if (p.name == "triangles") {
        make_triangles(f, n);
    } else if (p.name == "bricks") {
        make_bricks(f, n, p.albedo);
    } else if (p.name == "bumps") {
        make_bumps(f, n);
    } else if (p.name == "vgrooves") {
        if (!(p.vgroove_angle >= 1.f && p.vgroove_angle <= 179.f))
            throw InputError(p.group + ".vgroove_angle: value " + to_text(p.vgroove_angle) +
                             " is out of range [1, 179] (opening angle of the V, degrees)");
        make_vgrooves(f, n, p.vgroove_angle);
    } else if (p.name == "gaussian") {
        if (!(p.rms_slope >= 0.f) || !std::isfinite(p.rms_slope))
            throw InputError(p.group + ".rms_slope: value " + to_text(p.rms_slope) + " must be finite and >= 0");
        // Beyond the resolution the periodic kernel is flat to within rounding (the field would be
        // rounding noise); beyond 64 texels the direct convolution gets slow.
        if (!(p.correlation > 0.f && p.correlation <= float(std::min(n, 64))))
            throw InputError(p.group + ".correlation: value " + to_text(p.correlation) + " is out of range (0, " +
                             std::to_string(std::min(n, 64)) + "] (texels, at most the resolution and 64)");
        make_gaussian(f, n, double(p.correlation), double(p.rms_slope), p.seed);
    }  // "flat": zero

    const float scale = p.height_scale * p.texel_size;
    for (float& v : f.h) v *= scale;

    // Triangles (Fig. 2): red exactly where dh/dx > 0 (the sign of the central difference, i.e. of
    // -normal.x), white elsewhere.
    if (p.name == "triangles")
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                f.albedo[f.index(x, y)] = f.at(x + 1, y) - f.at(x - 1, y) > 0.f ? vec3(0.8f, 0.08f, 0.08f) : vec3(0.8f);
    return f;
}

// [SECTION] Heightfields from images
Heightfield load_heightfield(const std::string& path, float height_scale, float texel_size, bool periodic, vec3 albedo) {
    if (!std::isfinite(height_scale))
        throw InputError(path + ": height scale " + to_text(height_scale) + " is not finite");
    if (!(texel_size > 0.f) || !std::isfinite(texel_size))
        throw InputError(path + ": texel size " + to_text(texel_size) + " must be positive and finite");
    const Image img = read_image(path, false, true);  // InputError naming the file (and a NaN/Inf texel)
    if (img.empty() || img.channels < 1) throw InputError(path + ": empty image (a heightfield needs at least 2x2 texels)");
    if (img.width < 2 || img.height < 2 || img.width > 4096 || img.height > 4096)
        throw InputError(path + ": heightfield size " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                         " is out of range (2 to 4096 texels a side)");

    Heightfield f;
    f.width = img.width;
    f.height = img.height;
    f.texel_size = texel_size;
    f.periodic = periodic;
    f.h.resize(size_t(f.width) * size_t(f.height));
    f.albedo.assign(f.h.size(), albedo);
    const float scale = height_scale * texel_size;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) f.h[f.index(x, y)] = img.at(x, y)[0] * scale;
    return f;
}

// [SECTION] Albedo maps
void apply_albedo_map(Heightfield& hf, const std::string& path, vec3 tint, const std::string& key) {
    const Image img = read_image(path, /*srgb_to_linear_8bit=*/true, /*reject_nonfinite=*/true);
    std::vector<vec3> rgb(size_t(img.width) * size_t(img.height));
    for (size_t i = 0; i < rgb.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[i][c] = img.data[i * size_t(img.channels) + size_t(img.channels >= 3 ? c : 0)];
    for (int y = 0; y < hf.height; ++y)
        for (int x = 0; x < hf.width; ++x) {
            const float c = (float(x) + 0.5f) * float(img.width) / float(hf.width) - 0.5f, r = (float(y) + 0.5f) * float(img.height) / float(hf.height) - 0.5f;
            const vec3 a = sample_bilinear(rgb, img.width, img.height, true, c, r) * tint;
            if (!(a.x >= 0.f && a.y >= 0.f && a.z >= 0.f)) throw InputError(path + ": " + key + " has a negative or non-finite albedo");
            hf.albedo[hf.index(x, y)] = glm::min(a, vec3(1.f));
        }
}
}  // namespace mesolab
