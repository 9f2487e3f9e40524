// Technique basic: its parameters, what a frame needs and how closely the GPU follows the CPU.
#include "core/basic/technique.h"
#include "core/basic/stages.h"

namespace mesolab::basic {

BasicTechnique::BasicTechnique() : Technique("basic", "Basic (Lambert + Blinn-Phong)") {
    params_.add_color("kd", {0.8, 0.8, 0.8}).doc("Diffuse albedo (linear RGB)");
    params_.add_color("ks", {0.04, 0.04, 0.04}).doc("Specular albedo (linear RGB) of the normalised Blinn-Phong lobe");
    params_.add_float("shininess", 64.0).range(1.0, 10000.0).log().doc("Blinn-Phong exponent s");
    params_.add_path("albedo_map", "")
        .doc("Image multiplying kd, looked up at the surface's (u,v) (8-bit images are sRGB); relative to the preset's folder");
}

std::vector<StageName> BasicTechnique::frame_stages() const { return {stages::albedo}; }

// The same arithmetic on both paths; float evaluation order and the GPU's pow and normalize
// leave differences of about 1e-5 of the radiance. Only silhouettes, where a pixel centre
// lies within sub-pixel rounding of an edge, can differ by a whole value.
FrameAgreement BasicTechnique::agreement() const {
    return {.tight = 1e-4, .frac_tight = 0.99, .loose = 1e-3, .frac_loose = 0.998, .interior_max = 1e-3, .interior_outliers = 0,
            .why = "float evaluation order and the GPU's transcendentals; silhouettes"};
}
}  // namespace mesolab::basic

namespace mesolab {
void register_basic(Registry& r) { r.add(std::make_unique<basic::BasicTechnique>()); }
}  // namespace mesolab
