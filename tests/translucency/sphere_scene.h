#pragma once
// A small translucent sphere (about 500 vertices, 10 mm per unit), side-lit by a directional light
// and shadowed with 256² maps: the scene several translucency tests start from, each adding its
// own method, material or atlas size. And the largest value of an image.
#include "core/image.h"
#include "core/scene.h"

#include <algorithm>

namespace mesolab::test {

inline Scene side_lit_sphere() {
    Scene s = default_scene("translucency");
    apply_set(s, "geometry.type", "sphere");
    apply_set(s, "geometry.resolution", "32");
    apply_set(s, "translucency.mm_per_unit", "10");
    apply_set(s, "translucency.shadow_map", "256");
    apply_set(s, "light.direction", "70,30");
    apply_set(s, "light.intensity", "3");
    return s;
}

inline double max_value(const Image& img) {
    double m = 0.0;
    for (float v : img.data) m = std::max(m, double(v));
    return m;
}
}  // namespace mesolab::test
