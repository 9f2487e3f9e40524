#pragma once
// Technique translucency on the GPU: the lights' shadow maps of one object (ShadowMap,
// core/translucency/translucency.h), drawn as the layers of one texture, and the uniforms of
// shadow.glsl that read them. Shared by the paper's pass and the separable method's.
#include "core/translucency/translucency.h"
#include "gpu/renderer.h"

#include <vector>

namespace mesolab::gpu {

// One shadow map per light as the layers of one texture (a single fetch in the shader, whatever
// the light), with one depth buffer they share in turn.
struct ShadowLayers {
    int res = 0, layers = 0;
    Texture color, depth;
    Framebuffer fbo;
    void resize(int r, int n);
    // Binds layer i as the target, cleared: no surface (3e38) at the far plane.
    void begin(int i) const;
};

// The shadow maps of object `o` for the first kMaxShadowMaps lights, in the frame the CPU uses
// (shadow_frame over the world bounds of `mesh`, the object's drawn triangles), drawn with
// `program` (shadow.vert / shadow.frag) into `layers`. Leaves the default framebuffer bound.
std::vector<translucency::ShadowMap> draw_shadow_maps(DrawContext& ctx, int o, const TriMesh& mesh, int res, const Program& program,
                                                      ShadowLayers& layers);

// The uniforms of shadow.glsl for `frames` (none: every point lit), the maps bound to `unit`.
void set_shadow_uniforms(const Program& p, const std::vector<translucency::ShadowMap>& frames, const ShadowLayers& layers, int res, int unit);
}  // namespace mesolab::gpu
