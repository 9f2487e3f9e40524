#pragma once
// [SECTION] The mip levels of a fabric's BRDF array (Daubert et al. 2001, §5.1).
// Level 0 holds one model per sample point of the res × res grid; level k one per 2^k × 2^k
// block, fitted to the block's samples with the block's averaged normal and tangent, down to a
// single model: res = 32 gives 6 levels and 1365 models.
//
// Every point is sampled at the same (light, view) pairs, given in the pattern's frame (z = the
// fabric's normal), so a block's pooled samples at one pair differ only in their values: the
// least-squares fit to all of them is the fit to their mean (Σ_p (f − r_p)² = P (f − r̄)² + a
// constant). A block's entry is therefore fitted to the mean value per pair, and costs what a
// point's entry costs, as the paper observes ("the overall effort per level stays the same").
// Alpha per view is the block's mean alpha (fractional at coarse levels). Directions enter each
// fit in the entry's local frame (z: the averaged normal; x: the averaged tangent, made
// perpendicular to it).
#include "core/cloth/fit.h"
#include "core/stage.h"

#include <atomic>
#include <vector>

namespace mesolab::cloth {

struct SampleGrid {
    int res = 0;                   // points per side, a power of two
    std::vector<dvec3> l, v;       // per (light, view) pair: unit directions in the pattern frame
    std::vector<int> view_of;      // per pair: its index in `views`
    std::vector<dvec3> views;      // the distinct view directions
    // Per point (row-major, res² of them):
    std::vector<std::vector<dvec3>> f;       // f_r per pair (sr⁻¹)
    std::vector<std::vector<double>> alpha;  // per view: 1 surface, 0 a hole (empty: 1)
    std::vector<dvec3> normal, tangent;      // averaged over the views, pattern frame
};

// The local frame of a normal and a tangent: rows x (the tangent made perpendicular), y, z (the normal).
glm::dmat3 local_frame(dvec3 normal, dvec3 tangent);

struct BrdfPyramid {
    int res = 0;
    // level[k]: (res >> k)² models, row-major; frame[k]: their local frames (rows x, y, z).
    std::vector<std::vector<ClothBrdf>> level;
    std::vector<std::vector<glm::dmat3>> frame;
    std::vector<std::vector<FitReport>> report;
    size_t count() const;
    size_t bytes() const;  // the fitted representation as stored in floats: lobes, tables, frames
};

// Light at or below this height above an entry's horizon (z in its frame) is left out of its fit.
constexpr double kFittedLightZ = 0.05;

// Reflected radiance per unit irradiance of the entry (b, F: its model and frame) for light and
// view directions in the pattern frame: f_r(l̂', v̂') cos θ̂_l (the paper's foreshortening in the
// entry's frame). The model is evaluated only where it was fitted: a light below kFittedLightZ in
// the entry's frame is evaluated at that height with the same azimuth (l̂'), and a view below the
// entry's horizon on it (v̂'), since outside its samples a fitted lobe can grow without bound
// (a base above 1 to a large exponent); the table is read at v̂ itself, and f_r is bounded by
// ClothBrdf::f_max. Radiance still goes to 0 with cos θ̂_l.
dvec3 entry_reflectance(const ClothBrdf& b, const glm::dmat3& F, dvec3 l, dvec3 v);

// The samples of the block of 2^k × 2^k points at (bx, by) of level k, averaged per pair and
// expressed in the block's frame (returned in `frame`).
PointSamples block_samples(const SampleGrid& g, int k, int bx, int by, glm::dmat3& frame);

// Every entry of every level, coarse to fine, the entries of a level in parallel: the top entry
// tries every start; a finer one starts from its parent's lobes and the paper's grey start. `progress` gets ("cloth.fit", fraction done); a set
// `cancel` stops it with Cancelled. InputError naming cloth.spatial for a res that is not a
// power of two in [1, 1024], or a grid whose arrays do not match.
BrdfPyramid fit_pyramid(const SampleGrid& g, const FitOptions& o, const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);
}  // namespace mesolab::cloth
