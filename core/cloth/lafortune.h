#pragma once
// [SECTION] Cloth (Daubert, Lensch, Heidrich, Seidel 2001, Efficient Cloth Modeling and
// Rendering): the reflectance model of one sample point of a stitch pattern, §3.
//
//   f_r(l, v) = T(v) ∘ f_L(l, v)                                                   (Eq. 1)
//   f_L(l, v) = k_d + Σ_i ⌈C_x,i l_x v_x + C_y,i l_y v_y + C_z,i l_z v_z⌉^n_i        (Eq. 2)
//
// per colour channel (∘: channel by channel), with l and v unit vectors in the sample point's
// local frame (z: its average normal, x: its tangent) and ⌈a⌉ = max(a, 0) (the paper's footnote:
// a lobe whose base is negative contributes nothing). Units: f_r, f_L and k_d (= ρ_d / π) in
// sr⁻¹; C dimensionless per unit of base, n > 0. T(v) is a view-dependent table (colour and alpha
// per view direction of the acquisition, interpolated between them): the colour takes up
// shadowing, masking and colour shifts the lobes cannot; the alpha (1 = surface, 0 = a hole seen
// straight through) is not part of f_r and is used for transparency when rendering.
#include "core/math.h"

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace mesolab::cloth {
using glm::dvec2;
using glm::dvec3;
using glm::dvec4;

// One cosine lobe of Eq. 2, one value per colour channel.
struct LafortuneLobe {
    dvec3 Cx{0.0}, Cy{0.0}, Cz{0.0}, n{1.0};
    // ⌈C_x l_x v_x + C_y l_y v_y + C_z l_z v_z⌉^n per channel.
    dvec3 f(dvec3 l, dvec3 v) const;
};

// f_L of Eq. 2.
struct Lafortune {
    dvec3 kd{0.0};  // the diffuse term ρ_d / π, sr⁻¹
    std::vector<LafortuneLobe> lobes;
    dvec3 f(dvec3 l, dvec3 v) const;
};

// T(v): colour (rgb) and alpha per table direction. Between directions the table is interpolated
// over the three nearest directions by angle, with weights 1/θ_k − 1/θ_4 (θ_4: the fourth
// nearest's angle; plain 1/θ_k with fewer than four directions; an exact hit returns its entry),
// which needs no structure in the directions, so measured and acquired tables read alike, and is
// continuous in v: a direction's weight falls to 0 where it stops being one of the three nearest.
struct ViewTable {
    std::vector<dvec3> v;  // unit view directions, local frame, z >= 0
    std::vector<dvec4> T;  // per direction: rgb factor, alpha
    bool empty() const { return v.empty(); }
    // T(v); (1, 1, 1, 1) for an empty table.
    dvec4 at(dvec3 v) const;
};

// The sheen model of cloth.method = sheen (sheen.h): f_L = k_d + S g_r(l, v), with k_d = L.kd.
struct SheenLobe {
    dvec3 S{0.0};  // the sheen colour, dimensionless
    double r = 0.5;  // the distribution's roughness, (0, 1]
};

// The fitted model of one sample point (or of a group of them: a mip level's entry).
struct ClothBrdf {
    Lafortune L;
    std::optional<SheenLobe> sheen;  // set: k_d + the sheen lobe instead of L's lobes
    ViewTable table;  // empty: no lookup table (T = 1)
    // Per channel, the most f_r may reach: twice the largest sample value of its fit (fit.h).
    // Between sparse samples or outside them, a lobe with a base above 1 and a large exponent can
    // grow without bound (10^100 and more; with few view directions the table can even cancel such
    // a lobe at the samples), so evaluations clamp to this. Infinite: no bound (a model not from a fit).
    dvec3 f_max{std::numeric_limits<double>::infinity()};
    dvec3 f(dvec3 l, dvec3 v) const;  // f_r = T(v) ∘ f_L(l, v), sr⁻¹
    dvec3 f_model(dvec3 l, dvec3 v) const;  // f_L alone (the lobes' or the sheen's), kept finite
    double alpha(dvec3 v) const;      // the table's alpha (1 without a table)
};
}  // namespace mesolab::cloth
