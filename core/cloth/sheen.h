#pragma once
// [SECTION] The microfacet sheen BRDF plus Lambert, fitted per sample point (cloth.method = sheen)
// Alejandro Conty Estevez and Christopher Kulla, "Production Friendly Microfacet Sheen BRDF",
// SIGGRAPH 2017 course "Physically Based Shading in Theory and Practice" (Sony Pictures
// Imageworks): the sheen film and game renderers use for cloth today, here fitted to the same
// virtual acquisition as the paper's Lafortune lobes (fit.h), with the same optional view table.
//
//   f_r(l, v) = T(v) ∘ (k_d + S g_r(l, v)),   g_r = D_r(h) G_r(l, v) / (4 l_z v_z)     (sr⁻¹)
//   D_r(h) = (2 + 1/r) sin(θ_h)^(1/r) / (2π)          ("Charlie": ∫ D cos θ_h dω_h = 1)
//   G_r(l, v) = 1 / (1 + Λ_r(l_z) + Λ_r(v_z))         (height-correlated Smith)
//   Λ_r(μ) = exp(L(μ))                 for μ < 1/2,
//            exp(2 L(1/2) − L(1 − μ))  otherwise,     L(x) = a / (1 + b x^c) + d x + e
// with (a, b, c, d, e) interpolated between their fits at r = 0 and r = 1 by t = (1 − r)²
// (their Table 1; the fit of the exact Λ of the sin^(1/r) distribution). r ∈ (0, 1] is the
// distribution's own roughness (their r, not a perceptual remapping); k_d = ρ_d / π and the sheen
// colour S are per colour channel, r one value per point (one fibre distribution, coloured).
// Their terminator softening of Λ is not used (it changes the shadowing of a bent base, not of the
// flat samples fitted here).
//
// [SECTION] The fit (per sample point: fit_brdf with FitOptions::sheen, fit.h)
// For fixed r the model is linear in (k_d, S) per channel: the best non-negative pair for each of
// 48 values of r spaced evenly in log r over [r_min, 1] (variable projection) gives the start;
// Levenberg–Marquardt (Ceres) then refines (k_d, S, r) together, bounds k_d, S ≥ 0 and
// r ∈ [FitOptions::r_min, 1], minimising Σ w_s² (T(v_s) f(l_s, v_s) − r_s)² (BrdfSample::w). With the view
// table the table is refitted in closed form (fit_table) and the model again from the current
// (k_d, S, r), until the table changes by less than `tolerance` on average, as the paper's
// alternation.
#include "core/math.h"

namespace mesolab::cloth {
using glm::dvec3;

// D_r(h) for cos θ_h (sr⁻¹), Λ_r(cos θ) and g_r(l, v) (sr⁻¹; 0 below the surface).
double sheen_D(double cos_h, double r);
double sheen_lambda(double cos_theta, double r);
double sheen_lobe(dvec3 l, dvec3 v, double r);
}  // namespace mesolab::cloth
