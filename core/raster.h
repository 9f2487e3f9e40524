#pragma once
// CPU rasteriser that follows OpenGL's conventions closely enough that the CPU and GPU paths
// agree pixel for pixel away from silhouettes: pixel centres at (x+0.5, y+0.5) in window
// coordinates, perspective-correct attribute interpolation, depth = NDC z interpolated linearly
// in screen space with a LESS test, no face culling, a top-left fill rule. Image row 0 is the
// top of the image (GL window row height-1). Parallel over tiles (TBB).
// Details: triangles are clipped in homogeneous clip space against the near and far planes
// (-w <= z <= w, as GL does without depth clamp), w > 1e-6 and a guard band far outside the
// viewport; window positions snap to 1/256 pixel (8 sub-pixel bits, like GPUs) and coverage uses
// exact integer edge functions, so a pixel centre on an edge shared by two triangles belongs to
// exactly one of them ("top" and "left" as seen in GL's y-up window space). Triangles are drawn
// in submission order (items, then index order): at equal depth the first one drawn stays.
// Like a vertex shader, world normal = normalize(mat3(transpose(inverse(model))) * n) and
// world tangent = normalize(mat3(model) * t) per vertex; both are interpolated and normalised
// again per pixel (0 where they interpolate to 0, e.g. a mesh without tangents). Texture mode
// still fills position/normal/tangent with world-space values through `model`.
// Throws std::invalid_argument for an index out of range or an image over 65536 pixels a side.
#include "core/math.h"
#include "core/mesh.h"
#include <cstdint>
#include <vector>

namespace mesolab {

struct RasterCamera {
    int width = 0, height = 0;
    mat4 view{1.f}, proj{1.f};   // orbit mode: world -> clip is proj*view
    bool texture_space = false;  // texture mode: clip = (2u-1, 2v-1, 0, 1); v=1 at the image top
};

// One object to draw: a mesh and its model matrix (object -> world).
struct DrawItem {
    const TriMesh* mesh = nullptr;
    mat4 model{1.f};
    int object_id = 0;
    bool uv_derivatives = false;  // fill GBuffer::uv_dx, uv_dy at this item's pixels
};

// Per-pixel surface data, world space. Pixels not covered have object == -1.
struct GBuffer {
    int width = 0, height = 0;
    std::vector<float> depth;       // window depth in [0,1], 1 where nothing was drawn
    std::vector<int32_t> object;    // object_id or -1
    std::vector<int32_t> primitive; // the drawn triangle (numbered over every item's triangles after clipping) or -1
    std::vector<vec3> position;     // world position
    std::vector<vec3> normal;       // normalised interpolated world normal
    std::vector<vec3> tangent;      // normalised interpolated world tangent (may be 0 if mesh has none)
    std::vector<vec2> uv;           // interpolated texture coordinate
    // uv's differences across the pixel's 2 x 2 quad, as OpenGL's dFdxFine / dFdyFine give them:
    // quads are aligned to even columns and rows of GL's window (y up, row 0 at the bottom), and
    // every pixel of a quad is evaluated on the pixel's own triangle, extended beyond its edges
    // as GL's helper invocations are: uv_dx = uv(right column) - uv(left column) in the pixel's
    // row, uv_dy = uv(upper row) - uv(lower row) in its column. Filled only when an item asks
    // (DrawItem::uv_derivatives: they add about a fifth to the rasterisation), at its pixels
    // (0 elsewhere); empty when none asks.
    std::vector<vec2> uv_dx, uv_dy;
    size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

// Rasterise all items into `out` (resized and cleared first).
void rasterize(const std::vector<DrawItem>& items, const RasterCamera& cam, GBuffer& out);
}  // namespace mesolab
