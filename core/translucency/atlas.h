#pragma once
// [SECTION] The texture atlas of Lensch et al. 2002, §5.1.
// The local response works on texels: the surface is cut into chunks, each projected
// orthographically into the plane of its average normal, and the chunks are packed into one
// square texture with a single global scale, so a texel spans the same length (1/scale scene
// units) in every chunk's plane. Around each chunk a border of `border` texels holds the surface
// just beyond the chunk's edge, so a K x K filter kernel centred on any texel of the chunk reads
// real neighbours (border >= (K - 1)/2 + 1).
//
//   chunks   grown from the largest unassigned triangle over shared edges while a triangle's
//            normal deviates less than `chunk_angle` from the chunk's (area-weighted) average
//            normal; a triangle that deviates more from the final average, or whose projection
//            overlaps the chunk's, is left for another chunk, so no chunk folds over itself.
//   frame    each chunk's projected points are rotated to their minimum-area bounding rectangle
//            (rotating calipers over the convex hull) and placed at integer texel offsets.
//   packing  rectangles padded by the border on every side, packed on shelves (tallest first)
//            into the atlas; the scale is the largest that fits (bisection), so the fill ratio
//            (texels covered by triangles / all texels) is what the packing achieves.
//   texels   a texel belongs to the chunk triangle covering its centre; a border texel to the
//            neighbouring triangle that covers it once that triangle is unfolded about the
//            chunk's edge into the chunk's plane (rings of neighbours, nearest first); where the
//            surface ends (holes, boundaries) a border texel takes the nearest point of the chunk.
//            Unfolding is exact on developable surfaces; around a vertex whose angles do not sum
//            to 360° two unfolding paths disagree, by up to the border's width far from the edge.
// Texel area on the surface: 1/scale² in the chunk's plane, 1/(scale² cos θ) on a triangle
// tilted by θ from the chunk's normal (`texel_area`).
//
// Degenerate triangles (zero area, non-finite corners) are skipped and counted; non-manifold
// edges (three or more triangles) join the chunk growth like any shared edge and are counted.
#include "core/math.h"

#include <cstdint>
#include <string>
#include <vector>

namespace mesolab::translucency {

struct AtlasParams {
    int size = 512;              // atlas side, texels (translucency.atlas_size, 128..2048)
    int border = 4;              // texels around each chunk (>= (kernel - 1)/2 + 1)
    float chunk_angle = 30.f;    // degrees (translucency.chunk_angle)
};

struct AtlasChunk {
    std::vector<uint32_t> faces;  // triangle indices
    vec3 normal{0.f};             // projection direction (unit, average normal)
    vec3 origin{0.f};             // 3D point mapped to the rectangle's (0, 0)
    vec3 axis_u{0.f}, axis_v{0.f};  // unit in-plane axes along the rectangle's sides
    ivec2 offset{0};              // texel of the rectangle's (0, 0) in the atlas (inside the border)
    ivec2 extent{0};              // rectangle size in texels (without the border)
};

struct Atlas {
    int size = 0;
    int border = 0;
    float scale = 0.f;            // texels per scene unit (the same in every chunk)
    std::vector<AtlasChunk> chunks;
    // Per triangle corner (3 per triangle): atlas coordinates in texels (texel (x, y) spans
    // [x, x+1) x [y, y+1)); NaN for skipped triangles.
    std::vector<vec2> corner_uv;
    std::vector<int32_t> face_chunk;  // per triangle: its chunk, -1 when skipped

    // Per texel (row-major, size x size):
    std::vector<int32_t> texel_chunk;  // owning chunk (inner or border texel), -1 empty
    std::vector<int32_t> texel_face;   // surface triangle the texel samples, -1 empty
    std::vector<vec3> texel_bary;      // barycentrics of the sampled point in texel_face
    std::vector<uint8_t> texel_kind;   // kEmpty, kInner (a chunk triangle covers the centre), kBorder, kClamped
    std::vector<float> texel_area;     // surface area of the texel (inner texels; border texels: the same rule)

    static constexpr uint8_t kEmpty = 0, kInner = 1, kBorder = 2, kClamped = 3;

    // Report.
    double fill_ratio = 0.0;        // inner texels / all texels
    int skipped_degenerate = 0;     // triangles without area or with non-finite corners
    int non_manifold_edges = 0;     // edges shared by three or more triangles
    int unfolded_border_texels = 0, clamped_border_texels = 0;
    std::vector<std::string> warnings;

    size_t texel(int x, int y) const { return size_t(y) * size_t(size) + size_t(x); }
};

// Builds the atlas of a triangle mesh (positions, 3 indices per triangle). InputError naming
// translucency.atlas_size / chunk_angle for values out of range, or the mesh when no triangle
// has area; a border too wide for the atlas is an InputError naming translucency.kernel.
Atlas build_atlas(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const AtlasParams& p);

// The surface point a texel samples (barycentric interpolation of its triangle).
vec3 texel_position(const Atlas& a, const std::vector<vec3>& position, const std::vector<uint32_t>& index, size_t texel);
}  // namespace mesolab::translucency
