#include "core/basic/basic.h"
#include "core/sampling.h"
#include "core/error.h"


namespace mesolab::basic {

Material Material::from(const ParamTable& t, const std::string& resolved_map) {
    Material m;
    m.kd = t.get_vec3("kd");
    m.ks = t.get_vec3("ks");
    m.shininess = float(t.get_float("shininess"));
    m.albedo_map = resolved_map;
    return m;
}

// [SECTION] BRDF
vec3 brdf(const Material& m, vec3 n, vec3 wo, vec3 wi, vec3 albedo_tex) {
    const vec3 h = glm::normalize(wo + wi);
    const float nh = std::max(0.f, glm::dot(n, h));
    const float spec = (m.shininess + 8.f) / (8.f * kPi) * std::pow(nh, m.shininess);
    return m.kd * albedo_tex * kInvPi + m.ks * spec;
}

vec3 sample_albedo(const Image& img, vec2 uv) {
    if (img.empty()) return vec3(1.f);
    // Row 0 at v = 1 (the image's top), wrapping.
    const BilinearTaps t(uv.x * float(img.width) - 0.5f, (1.f - uv.y) * float(img.height) - 0.5f, img.width, img.height, Edge::Wrap, Edge::Wrap);
    return t.blend([&](int x, int y) {
        const float* p = img.at(x, y);
        return img.channels >= 3 ? vec3(p[0], p[1], p[2]) : vec3(p[0]);
    });
}

std::optional<Image> read_albedo_map(const Scene& s, const ParamTable& material) {
    const std::string path = s.resolve(material.get_string("albedo_map"));
    if (path.empty()) return std::nullopt;
    return read_image(path, true, true);
}
}  // namespace mesolab::basic
