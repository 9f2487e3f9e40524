// Existing bump maps: normals from heightfields and normal maps, index textures, detail (see bump_map.h).
#include "core/bumpsynth/bump_map.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/error.h"
#include "core/heightfield/heightfield.h"
#include "core/image.h"

#include <cmath>

namespace mesolab::bumpsynth {
namespace {
constexpr float kS = 0.70710678f;  // √½: the bound of 2D gradient noise (noise.h)

std::string texel_name(int x, int y) { return "texel (" + std::to_string(x) + ", " + std::to_string(y) + ")"; }
}  // namespace

// [SECTION] Sources
BumpNormals normals_of(const Heightfield& f) {
    BumpNormals n;
    n.width = f.width;
    n.height = f.height;
    n.m.resize(size_t(f.width) * size_t(f.height));
    mesolab::parallel_for(0, f.height, [&](int y) {
        for (int x = 0; x < f.width; ++x) n.m[size_t(y) * size_t(f.width) + size_t(x)] = f.normal(x, y);
    });
    return n;
}

BumpNormals decode_normal_map(const std::vector<float>& pixels, int width, int height, int channels, NormalMapFormat f,
                              const std::string& where) {
    if (channels < 3)
        throw InputError(where + ": a normal map needs 3 channels (x, y, z), this image has " + std::to_string(channels));
    if (width < 1 || height < 1 || pixels.size() != size_t(width) * size_t(height) * size_t(channels))
        throw InputError(where + ": empty normal map");
    BumpNormals n;
    n.width = width;
    n.height = height;
    n.m.resize(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float* p = pixels.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels);
            vec3 v(p[0], p[1], p[2]);
            if (f.encoding == NormalEncoding::unsigned_unit) v = v * 2.f - 1.f;
            if (f.y_down) v.y = -v.y;
            const float len = glm::length(v);
            if (!std::isfinite(len) || !(len > 1e-6f))
                throw InputError(where + ": " + texel_name(x, y) + " holds no direction (" + std::to_string(p[0]) + ", " +
                                 std::to_string(p[1]) + ", " + std::to_string(p[2]) + ")");
            v /= len;
            if (v.z < 0.f)
                throw InputError(where + ": " + texel_name(x, y) + " points below the surface (z = " + std::to_string(v.z) +
                                 "); is bumpsynth.normal_map_encoding right?");
            n.m[size_t(y) * size_t(width) + size_t(x)] = v;
        }
    return n;
}

BumpNormals read_normal_map(const std::string& path, NormalMapFormat f) {
    const Image img = read_image(path, false, true);  // InputError naming the file (and a NaN/Inf texel)
    return decode_normal_map(img.data, img.width, img.height, img.channels, f, path);
}

// [SECTION] Index texture
IndexMap make_index_map(const BumpNormals& n, const Lut& lut) {
    IndexMap map;
    map.width = n.width;
    map.height = n.height;
    map.u.resize(n.m.size());
    mesolab::parallel_for(0, n.height, [&](int y) {
        for (int x = 0; x < n.width; ++x) {
            const size_t i = size_t(y) * size_t(n.width) + size_t(x);
            map.u[i] = lut.index(n.m[i]);
        }
    });
    return map;
}

vec2 IndexMap::bilinear(vec2 uv) const {
    // Row 0 at v = 1; a + t (b - a), as the GLSL writes it (synthesis.glsl).
    const BilinearTaps taps(uv.x * float(width) - 0.5f, (1.f - uv.y) * float(height) - 0.5f, width, height, Edge::Wrap, Edge::Wrap);
    return taps.blend_lerp([&](int x, int y) { return at(x, y); });
}

// [SECTION] Detail
IndexDetail index_detail(const IndexMap& map, const NoiseParams& n, float amplitude) {
    IndexDetail d;
    d.noise = n;
    d.noise.base_frequency = map.width;
    d.octaves = NoiseOctaves(d.noise);
    d.amplitude = amplitude;
    d.scale = amplitude / kS;
    return d;
}

float reflect_unit(float r) {
    r -= 2.f * std::floor(r * 0.5f);  // [0, 2)
    return r > 1.f ? 2.f - r : r;
}

vec2 index_inputs(const IndexMap& map, const IndexDetail& d, vec2 uv, int k) {
    vec2 u = map.bilinear(uv);
    if (k < 2 || !(d.amplitude > 0.f)) return u;
    uv -= glm::floor(uv);  // the periodic square (the GLSL noise needs it; the same noise either way)
    vec2 T(0.f);
    for (int o = 0; o < k - 1; ++o) T += noise_octave_pair(d.octaves, uv, o);
    u += d.scale * T;
    return {reflect_unit(u.x), reflect_unit(u.y)};
}
}  // namespace mesolab::bumpsynth
