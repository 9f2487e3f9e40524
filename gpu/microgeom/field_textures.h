#pragma once
// Textures of a heightfield shared by microgeom's passes (the paper's and pom): RGBA32F, nearest
// filtering (the shaders fetch texels and blend with the CPU's bilinear weights), one texel per
// heightfield texel.
#include "core/heightfield/heightfield.h"
#include "core/param.h"
#include "gpu/gl.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <memory>

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
// For the counterparts' passes (pom, horizon): binds the heightfield's normals and albedo
// (u_normals, u_albedo on texture units `unit` and `unit + 1`, made once per heightfield) and
// sets the bump level's uniforms u_size, u_tiling, u_phong, u_ks and u_shininess from `m`.
inline void bind_field_material(Program& program, GpuResources& res, const std::shared_ptr<const Heightfield>& hf, const ParamTable& m, int unit) {
    const GLuint normals = res.get<Texture>(hf, "normals", [&] { return field_normals_texture(*hf); }).get();
    const GLuint albedo = res.get<Texture>(hf, "albedo", [&] { return rgb_field_texture(hf->albedo, hf->width, hf->height); }).get();
    program.bind_texture(unit, GL_TEXTURE_2D, normals, "u_normals");
    program.bind_texture(unit + 1, GL_TEXTURE_2D, albedo, "u_albedo");
    glUniform2i(program.uniform("u_size"), hf->width, hf->height);
    glUniform1f(program.uniform("u_tiling"), float(m.get_float("tiling")));
    const bool phong = m.get_string("brdf") == "blinn-phong";
    const vec3 ks = phong ? m.get_vec3("ks") : vec3(0.f);
    glUniform1i(program.uniform("u_phong"), phong ? 1 : 0);
    glUniform3fv(program.uniform("u_ks"), 1, glm::value_ptr(ks));
    glUniform1f(program.uniform("u_shininess"), float(m.get_float("shininess")));
}
}  // namespace mesolab::gpu
