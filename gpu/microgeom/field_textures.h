#pragma once
// Textures of a heightfield shared by microgeom's passes (the paper's and pom): RGBA32F, nearest
// filtering (the shaders fetch texels and blend with the CPU's bilinear weights), one texel per
// heightfield texel.
#include "core/heightfield/heightfield.h"
#include "gpu/gl.h"

#include <vector>

namespace mesolab::gpu {

// RGBA32F texture from w x h RGBA floats.
inline Texture rgba_field_texture(const float* rgba, int w, int h) {
    return make_texture({.format = GL_RGBA32F, .width = w, .height = h}, {GL_RGBA, GL_FLOAT, rgba});
}

// RGBA32F texture from per-texel vec3 (alpha 1).
inline Texture rgb_field_texture(const std::vector<vec3>& v, int w, int h) {
    std::vector<float> rgba(size_t(w) * size_t(h) * 4, 1.f);
    for (size_t i = 0; i < v.size(); ++i)
        for (int c = 0; c < 3; ++c) rgba[i * 4 + size_t(c)] = v[i][c];
    return rgba_field_texture(rgba.data(), w, h);
}

// The heightfield's normals (local frame: x along +c, y along -r, z up), rgb.
inline Texture field_normals_texture(const Heightfield& hf) {
    std::vector<vec3> normals(hf.h.size());
    for (int y = 0; y < hf.height; ++y)
        for (int x = 0; x < hf.width; ++x) normals[hf.index(x, y)] = hf.normal(x, y);
    return rgb_field_texture(normals, hf.width, hf.height);
}
}  // namespace mesolab::gpu
