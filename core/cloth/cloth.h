#pragma once
// [SECTION] Technique cloth (Daubert et al. 2001): an object's settings, read in one place, and
// what the CPU shading and the GPU pass share.
//
// Stages (per object): cloth.stitch (the stitch mesh) → cloth.acquire (the sample grid, or the
// file cloth.samples names) → cloth.fit (the BRDF pyramid); cloth.garment (the drawn mesh). A
// frame reads the pyramid: per pixel the garment's uv times cloth.repeat gives the pattern
// coordinates, the screen-space uv derivatives the footprint (tiles per pixel) and so the mip
// level (reflectance.h); the entry's model in its own frame gives the radiance per light, and the
// table's alpha mixes it with the background seen through holes (the environment along the
// pixel's ray; objects behind the garment do not show through).
#include "core/cloth/acquire.h"
#include "core/cloth/reflectance.h"
#include "core/cloth/stitch.h"
#include "core/raster.h"
#include "core/scene.h"

#include <string>
#include <vector>

namespace mesolab::cloth {

struct Settings {
    StitchParams stitch;
    int stitch_resolution = 48;  // marching-cubes cells per tile side
    AcquireParams acquire;
    std::string samples;         // resolved path of acquired samples to read instead of acquiring ("" = acquire)
    FitOptions fit;
    double repeat = 8.0;         // pattern tiles across the garment's uv square
    MipMode mip = MipMode::Blend;
    double mip_bias = 0.0;
    std::string garment = "curtain";  // curtain, sleeve or geometry (the object's own mesh)
    // The keys are read by part, so that a stage reads only those it declares (the session checks
    // it, core/session.h); the fields of the parts not read keep their defaults.
    enum Part : unsigned {
        Stitch = 1,    // stitch, yarn_radius, loop_height, color_a, color_b, stitch_resolution
        Acquire = 2,   // spatial, directions, visibility_rays, samples
        Fit = 4,       // method, lobes (daubert), lookup_table, tolerance
        Shading = 8,   // repeat, mip, mip_bias, garment
        All = 15,
    };
    static Settings from(const Scene& s, const SceneObject& o, unsigned parts = All);
};

// The pyramid as the GPU reads it: one record of `stride` vec4s per entry, entries level by
// level (level_first[k] = the first entry of level k), each record:
//   [0]   k_d (rgb), lobe count (−1: the sheen model, its S (rgb) and r in the first lobe's first vec4)
//   [1-3] the entry's frame rows x, y, z (xyz); [1].w = table size
//   [4]   f_max (rgb; ClothBrdf::f_max, the bound on f_r, at most 3e38)
//   then per lobe 4 vec4: C_x, C_y, C_z, n (rgb); then per table direction 2 vec4: v (xyz), T (rgba).
struct PackedPyramid {
    int res = 0, stride = 0;
    int lobes = 0, dirs = 0;  // of the widest entry: the table starts at vec4 5 + 4 lobes
    std::vector<int> level_first;
    std::vector<vec4> data;
    // When every entry's table holds the same directions in its own frame (the acquisition's
    // views, rotated by the entry's frame: the pyramid's case), those directions in the pattern
    // frame, so that the three nearest are found once per pixel for every entry (angles do not
    // change under the rotation); empty otherwise.
    std::vector<vec4> shared_views;
};
PackedPyramid pack_pyramid(const BrdfPyramid& p);

// Screen-space size of a pixel in uv units: max(|∂uv/∂x|, |∂uv/∂y|), each the difference across
// the pixel's 2 × 2 quad on its own triangle (GBuffer::uv_dx, uv_dy), as the GPU pass takes it
// from dFdxFine and dFdyFine; 0 where the pixel shows nothing.
double uv_footprint(const GBuffer& gb, size_t pixel);
}  // namespace mesolab::cloth
