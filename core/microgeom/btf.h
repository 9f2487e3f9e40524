#pragma once
// Light field / BTF export (Heidrich et al. 2000, §6): a view x light grid of texture-space images
// of the heightfield, each the goniometer image (goniometer.h) before averaging: per texel the
// radiance towards the view, with shadows, K bounces of scattering and masking, 0 where masked.
// "A light field of 32 x 32 images of a heightfield including scattering terms in about 6-8
// minutes" in the paper; here one scattering solve per light and one masking texture per view.
#include "core/image.h"
#include "core/microgeom/goniometer.h"
#include <functional>
#include <vector>

namespace mesolab::microgeom {

// Directions of a grid of n_theta x n_phi: theta_i = (i + 1/2) 90 / n_theta degrees from the
// macro normal, phi_j = j 360 / n_phi degrees from +u (index i * n_phi + j).
std::vector<vec3> btf_directions(int n_theta, int n_phi);

// Mosaic: tile (row = light index, column = view index) of hf.width x hf.height texels, RGB,
// tile row 0 at the top like Heightfield. Equal to goniometer_image(l, v) tile by tile.
// Throws InputError naming `grid` when the mosaic would exceed 16384 pixels per side.
Image btf_mosaic(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& s,
                 const std::vector<vec3>& lights, const std::vector<vec3>& views, const std::function<void(double)>& progress = {});
}  // namespace mesolab::microgeom
