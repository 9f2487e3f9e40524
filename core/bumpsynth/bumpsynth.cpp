// Technique bumpsynth: the materials' readers (bumpsynth.h).
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/consistent.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/error.h"
#include "core/heightfield/params.h"
#include "core/image.h"
#include "core/render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mesolab::bumpsynth {

// [SECTION] Materials
BumpNormals bump_normals_from_material(const Scene& s, const ParamTable& m) {
    const std::string& kind = m.get_string("ndf");
    if (kind == "heightfield") return normals_of(heightfield_from_material(s, m));
    if (kind != "normal_map") throw std::logic_error("bumpsynth: ndf " + kind + " has no bump map");
    const std::string path = s.resolve(m.get_string("normal_map"));
    if (path.empty()) throw InputError("bumpsynth.normal_map: ndf is normal_map but no image is given");
    NormalMapFormat f;
    f.encoding = m.get_string("normal_map_encoding") == "signed" ? NormalEncoding::signed_unit : NormalEncoding::unsigned_unit;
    f.y_down = m.get_string("normal_map_y") == "down";
    return read_normal_map(path, f);
}

Ndf ndf_from_material(const Scene& s, const ParamTable& m, const BumpNormals* normals, int resolution) {
    const std::string kind = m.get_string("ndf");
    const int R = resolution > 0 ? resolution : int(m.get_int("ndf_resolution"));
    if (kind == "normal_map" || kind == "heightfield") {
        BumpNormals own;
        if (!normals) own = bump_normals_from_material(s, m), normals = &own;
        return Ndf::from_normals(normals->m, R);
    }
    const vec2 alpha(float(m.get_float("alpha_x")), float(m.get_float("alpha_y")));
    const float rotation = float(m.get_float("rotation"));
    if (kind == "phong") return Ndf::from_lobe(Lobe::blinn_phong(float(m.get_float("exponent"))), R);
    if (kind == "lobes") {
        try {
            return Ndf::from_lobes(parse_lobes(m.get_string("lobes")), R);
        } catch (const InputError& e) {
            throw InputError("bumpsynth.lobes: " + std::string(e.what()));
        }
    }
    if (kind == "image") {
        const std::string path = s.resolve(m.get_string("ndf_image"));
        if (path.empty()) throw InputError("bumpsynth.ndf_image: ndf is image but no image is given");
        const Image img = read_image(path, false, true);
        std::vector<float> px(size_t(img.width) * size_t(img.height));
        const int c = std::min(img.channels, 3);
        for (size_t i = 0; i < px.size(); ++i) {
            float v = 0.f;
            for (int k = 0; k < c; ++k) v += img.data[i * size_t(img.channels) + size_t(k)];
            px[i] = v / float(c);
        }
        try {
            return Ndf::from_image(px, img.width, img.height, R);
        } catch (const InputError& e) {
            throw InputError(path + ": " + e.what());
        }
    }
    LobeKind k = LobeKind::beckmann;
    lobe_kind(kind, k);  // beckmann, ggx or ward: the enum's remaining choices
    return Ndf::from_lobe(Lobe::anisotropic(k, alpha.x, alpha.y, rotation), R);
}

NoiseParams noise_from_material(const ParamTable& m) {
    NoiseParams n;
    n.base_frequency = int(m.get_int("noise_frequency"));
    n.gain = float(m.get_float("noise_gain"));
    n.seed = uint32_t(m.get_int("noise_seed"));
    n.octaves_max = int(m.get_int("octaves_max"));
    n.validate();
    return n;
}

ShadingModel shading_from_material(const ParamTable& m) {
    ShadingModel s;
    s.ks = m.get_vec3("ks");
    s.kd = m.get_vec3("kd");
    s.fresnel = m.get_bool("fresnel");
    s.masking = m.get_bool("masking");
    return s;
}

Synthesis synthesis_for(const Scene& s, const Evaluation& ev, int object) {
    Synthesis syn;
    syn.ndf = ev.get(stages::ndf, object).get();
    syn.lut = ev.get(stages::lut, object).get();
    const SceneObject& o = s.objects[size_t(object)];
    const ParamTable& m = o.material;
    syn.octaves_max = int(m.get_int("octaves_max"));
    syn.detail_distance = float(m.get_float("detail_distance"));
    if (index_mode(o)) {
        syn.index_map = ev.get(stages::index_map, object).get();
        if (syn.index_map) syn.index_detail = index_detail(*syn.index_map, noise_from_material(m), float(m.get_float("index_noise")));
    } else {
        syn.cdfs = ev.get(stages::noise_cdf, object).get();
        if (texture_noise(o)) syn.noise_texture = ev.get(stages::noise_texture, object).get();
    }
    syn.model = shading_from_material(m);
    if (syn.model.masking) syn.smith = ev.get(stages::masking, object).get();
    syn.albedo = ev.get(stages::albedo, object).get();
    if (m.get_string("method") == "kautz-consistent") {
        syn.consistent = ev.get(stages::consistent, object).get();
        if (!syn.consistent) throw std::logic_error("bumpsynth/kautz-consistent: the frame's stages were not evaluated for object " + std::to_string(object));
    }
    return syn;
}

float pixel_octaves(const Synthesis& syn, bool texture_mode, vec3 eye, vec3 p) {
    const int K = syn.octaves_max;
    return texture_mode ? float(K) : octaves_at_distance(glm::length(eye - p), syn.detail_distance, K);
}
}  // namespace mesolab::bumpsynth
