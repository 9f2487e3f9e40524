// The heightfield's parameters, shared by the techniques (see params.h).
#include "core/heightfield/params.h"

namespace mesolab {

// [SECTION] Declarations
const std::vector<std::string>& heightfield_keys() {
    static const std::vector<std::string> keys{"heightfield", "resolution", "height_scale", "texel_size", "periodic",
                                               "vgroove_angle", "rms_slope", "correlation", "seed"};
    return keys;
}

void declare_heightfield_params(ParamGroup& p, const std::function<void(ParamDecl&)>& each) {
    const auto add = [&](ParamDecl& d) {
        if (each) each(d);
    };
    add(p.add_path("heightfield", "bricks").builtins(procedural_names())
            .doc("Procedural heightfield (triangles: the paper's Fig. 2 ridge, bricks, bumps, vgrooves, gaussian, flat) or an image "
                 "(8/16-bit, float EXR/TIFF; first channel = height in texels before height_scale)"));
    add(p.add_int("resolution", 128).range(8, 4096).in("texels").doc("Size of a procedural heightfield (texels per side)"));
    add(p.add_float("height_scale", 1.0).range(0.0, 1e4).doc("Multiplies the heights (procedural heights are in texels)"));
    add(p.add_float("texel_size", 1.0).range(1e-6, 1e6).log()
            .doc("Image heightfields: the grid spacing in the unit of the image's heights (e.g. 0.1 for heights in mm sampled every 0.1 mm); "
                 "height in texels = value * height_scale / texel_size. Procedural heights are already in texels"));
    add(p.add_bool("periodic", true).doc("Wrap-around visibility across the borders (tileable fields)"));
    add(p.add_float("vgroove_angle", 90.0).range(1.0, 179.0).in("degrees").doc("vgrooves: opening angle of the V"));
    add(p.add_float("rms_slope", 0.5).range(0.0, 10.0).doc("gaussian: RMS slope"));
    add(p.add_float("correlation", 4.0).range(0.5, 64.0).in("texels").doc("gaussian: correlation length"));
    add(p.add_int("seed", 1).range(0, 2147483647).doc("gaussian: random seed"));
}

// [SECTION] Heightfields from materials
ProceduralParams procedural_params(const ParamTable& m) {
    ProceduralParams p;
    p.name = m.get_string("heightfield");
    p.resolution = int(m.get_int("resolution"));
    p.height_scale = float(m.get_float("height_scale"));
    p.periodic = m.get_bool("periodic");
    p.vgroove_angle = float(m.get_float("vgroove_angle"));
    p.rms_slope = float(m.get_float("rms_slope"));
    p.correlation = float(m.get_float("correlation"));
    p.seed = uint32_t(m.get_int("seed"));
    if (m.group().find("albedo")) p.albedo = m.get_vec3("albedo");
    return p;
}

Heightfield heightfield_from_material(const Scene& s, const ParamTable& m) {
    ProceduralParams p = procedural_params(m);
    p.group = m.group().name();
    if (!m.group().find("heightfield")->is_file(m.get("heightfield"))) return make_procedural(p);
    return load_heightfield(s.resolve(p.name), p.height_scale / float(m.get_float("texel_size")), 1.f, p.periodic, p.albedo);
}
}  // namespace mesolab
