// Coarse meshes: triangles far larger than the diffusion length, lit through the technique's own
// illumination step.
#include "core/mesh.h"
#include "core/render.h"
#include "core/translucency/translucency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
struct Shape {
    std::vector<vec3> position;
    std::vector<uint32_t> index;
};

// 12 triangles, 8 vertices, half extents `half`.
Shape box(vec3 half) {
    Shape s;
    for (int k = 0; k < 8; ++k) s.position.push_back(vec3(k & 1 ? half.x : -half.x, k & 2 ? half.y : -half.y, k & 4 ? half.z : -half.z));
    const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) s.index.insert(s.index.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    return s;
}

Light point_light(vec3 p) {
    Light l;
    l.point = true;
    l.position = p;
    l.radiance = vec3(1.f);
    return l;
}

}  // namespace

// A point light 0.033 units above the centre of a 2 x 2 face lights all of it: cos θ at its
// corners is 0.033 / 1.414 > 0. Normals averaged across the box's 90° edges leaned 8-24°
// outwards at the corners and cut the light beyond 84-87° from the light's axis; the normals now
// keep the two sides of an edge sharper than kCreaseDegrees apart. (No shadow map: the light is
// inside the object's bounding sphere, see ShadowMap::valid.)
TEST(CloseLight, APointLightGrazingAFlatFaceLightsAllOfIt) {
    const Shape b = box(vec3(1.f, 1.f, 0.2f));
    const PreparedMesh m = prepare_mesh(b.position, b.index, 0);
    const AtlasStage a = make_atlas_stage(m, {128, 4, 30.f});
    const Light l = point_light(vec3(0.f, 0.f, 0.233f));
    Lighting L;
    L.lights = {l};
    L.env_lighting = false;
    const std::vector<ShadowMap> shadows = {make_shadow_map(*a.display, mat4(1.f), l, 256)};
    EXPECT_FALSE(shadows[0].valid);
    const std::vector<vec3> E = illuminate(a, mat4(1.f), L, 1.3, shadows);
    int top = 0;
    for (size_t t = 0; t < E.size(); ++t) {
        if (a.atlas.texel_kind[t] != Atlas::kInner) continue;
        const vec3 p = a.texel_position[t], n = a.texel_normal[t];
        if (p.z > 0.199f) {
            ++top;
            EXPECT_NEAR(n.z, 1.f, 1e-6f) << "texel " << t;
            EXPECT_GT(E[t].x, 0.f) << "texel " << t << " at " << p.x << ", " << p.y;
        } else {
            EXPECT_EQ(E[t], vec3(0.f)) << "texel " << t;  // the sides and the bottom face away
        }
    }
    EXPECT_GT(top, 1000);
}
