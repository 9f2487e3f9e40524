#pragma once
// Shadows and light scattering in a heightfield with the Method of Dependent Tests
// (Heidrich et al. 2000, §3.1-§3.2, Fig. 4; shadows §4).
//
// The micro-BRDF is Lambertian with per-texel albedo rho(p) for every bounce (a Blinn-Phong
// lobe, where enabled, is added to the direct term seen by the viewer only). Radiance leaving a
// texel is then view-independent and one bounce is one whole-texture pass over the same
// direction set for every texel (the dependent tests):
//   L_d(q)   = rho(q)/pi * E_light * max(0, n_q . l) * V(q, l)                      direct
//   E^k(p)   = pi * sum_{j in J_k} w_j(p) * L_in,j(p)                                 gathered irradiance
//   L_in,j(p)= L^{k-1}(S_j[p]) on a hit, L_env(d_j) when S_j says no hit, 0 below p's tangent plane
//   L^k(q)   = L_d(q) + rho(q)/pi * E^k(q)                                            direct added at every scattering point
// with E^0 gathering the environment alone (L^{-1} = 0), depth K keeping E^K, and w_j(p) = max(0, n_p . d_j) Omega_j / sum_j max(0, n_p . d_j) Omega_j the
// per-texel quadrature weights over the direction set (Omega_j: the direction's share of the
// sphere), normalised so that a white furnace conserves energy exactly. J_k is either all N
// directions or a random subset of M directions per bounce (the same for every texel).
// On a curved base (§5) w_j(p) are the bent, importance-weighted weights of curvature.h.
// The final gather looks S_j[p] up bilinearly (primary hits); inner bounces use the nearest
// texel (secondary hits), as in the paper.
//
// Shadows (§4, exact variant): V(p, l) interpolates the visibility of the three directions of
// the spherical triangle containing l with its barycentric weights. Masking uses the same data
// with the view direction.
#include "core/env.h"
#include "core/heightfield/heightfield.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/ellipse.h"
#include "core/microgeom/visibility.h"
#include <atomic>
#include <functional>
#include <vector>

namespace mesolab::microgeom {

// Fraction of direction w reaching texel (x, y) (0..1): exact interpolation over the 3 nearest
// directions of the triangulation. Directions below the texel's tangent plane give 0.
float visibility_fraction(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, int x, int y, vec3 w);

// The same with the spherical triangle of w located once (tri, bary from DirectionSet::locate),
// for callers that query several texels with one direction.
float visibility_fraction(const Heightfield& hf, const Visibility& vis, const std::array<int, 3>& tri, vec3 bary, int x, int y, vec3 w);

// Per-texel fractions for one direction (shadow texture for the light, masking for the view).
std::vector<float> visibility_texture(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, vec3 w);

// One bounce's gather, E(p) = pi sum_{j in J} w_j(p) L_in,j(p) / sum_{j in J} w_j(p) for every
// texel: the part of scatter() that a GPU can run (gpu/microgeom/scatter_gpu.h). scatter() calls
// begin() once, then gather() per bounce with the same arguments its own CPU gather takes.
class Gatherer {
public:
    virtual ~Gatherer() = default;
    // bent: the curved base's weights (null: the flat max(0, n_p . d_j) Omega_j); L_env per direction.
    virtual void begin(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const Importance* bent, const std::vector<vec3>& L_env) = 0;
    // L_prev: radiance per texel of the previous bounce (null: environment only); primary: bilinear hit look-ups, else nearest.
    virtual std::vector<vec3> gather(const std::vector<vec3>* L_prev, const std::vector<int>& J, bool primary) = 0;
    // Every bounce, returning E^K: E^0 gathers the environment (when `env`; else E^0 = 0), and for
    // k = 1..K, L^{k-1} = direct + albedo / pi * E^{k-1} and E^k gathers L^{k-1} over J[k]; only
    // the last gather is primary. The default calls gather() per bounce and forms L here; a GPU
    // keeps E and L on the device between bounces and reads E^K back once.
    virtual std::vector<vec3> bounces(const std::vector<vec3>& direct, const std::vector<vec3>& albedo, bool env, const std::vector<std::vector<int>>& J,
                                      int K, const std::function<void(double)>& progress);
};

struct ScatterSettings;

// Many lights' images solved at once (the goniometer's and the BTF's, goniometer.h), elsewhere
// (the GPU: gpu/microgeom/lights_gpu.h). Made for one heightfield, visibility and settings; for
// each wi, exactly what scatter(hf, dirs, vis, s) gives with light_dir = wi, light_E = 1 and
// env = null: L(x, wi) = direct + rho/pi E_indirect and shadow(x, wi), per texel.
class LightSolver {
public:
    virtual ~LightSolver() = default;
    virtual int batch() const = 0;  // lights per solve() call that fit at once (>= 1)
    // L and shadow are resized to wis.size() images of width x height texels.
    virtual void solve(const std::vector<vec3>& wis, std::vector<std::vector<vec3>>& L, std::vector<std::vector<float>>& shadow) = 0;
};

struct ScatterSettings {
    vec3 light_dir{0.f, 0.f, 1.f};   // local frame, unit, towards the light
    vec3 light_E{0.f};               // irradiance at normal incidence (RGB); 0 = no direct light
    bool shadows = true;             // V(q, l) in the direct term; false: V = 1
    const Environment* env = nullptr;  // radiance where S_j says no hit (null: black)
    int depth = 2;                   // bounces of interreflected light (0..8)
    bool all_directions = true;      // J_k = all N, or `paths` random directions per bounce
    int paths = 64;
    uint32_t seed = 1;
    const Importance* importance = nullptr;  // curved base (§5): gather weights of the bent directions (curvature.h)
    const EllipseMap* ellipses = nullptr;    // shadows from the per-texel ellipses (§4) instead of the exact test
    Gatherer* gatherer = nullptr;            // the bounces' gathers elsewhere (the GPU); null: on the CPU
};

struct ScatterResult {
    int width = 0, height = 0;
    std::vector<vec3> E_indirect;  // irradiance at each texel from scattering and the environment
    std::vector<float> shadow;     // V(p, l) * [n_p . l > 0]
    std::vector<vec3> direct;      // L_d(p): direct radiance (Lambert part)
};

// The direction subsets J_0..J_K of one scatter() call, in the order it gathers: all N
// directions each time, or s.paths random ones per bounce from std::mt19937(s.seed), j = rng() % N.
std::vector<std::vector<int>> scatter_subsets(const ScatterSettings& s, int N);

ScatterResult scatter(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s,
                      const std::function<void(double)>& progress = {});

// Light-driven scattering tabulated over light directions, for non-planar bases (where the
// tangent-space light direction varies from pixel to pixel): for each direction d_j of the set
// above the horizon (d_j.z > 0), E_j = scatter(...).E_indirect with light_dir = d_j, light_E = 1
// and no environment, i.e. the light's meaning is the planar solution's: unit irradiance at
// normal incidence from d_j (the cosines n_q . d_j are inside E_j). On the Fibonacci set
// (directions.h: z decreasing with the index) those are the first M ~ N/2 directions; directions
// at or below the horizon hold 0. At shading the light's tangent-space direction l is located in
// the spherical triangulation as for the exact shadows (DirectionSet::locate), and
//   E(p, l) = sum_{k < 3} b_k E_{j_k}(p)        (b: barycentrics of l; bilinear over texels)
// times the light's irradiance (microgeom.frag does the same). At l = d_j it is E_j exactly;
// between directions, the interpolation error is measured in tests/microgeom/scatter_directions_test.cpp.
// Memory M x texels x 12 bytes (RGB float): ~9.4 MB for 128x128 and N = 100.
struct DirectionalScatter {
    int width = 0, height = 0;
    int count = 0;           // M: directions 0..M-1 of the set (above the horizon) have a solution
    std::vector<vec3> E;     // [direction < M][row][column]

    size_t bytes() const { return E.size() * sizeof(vec3); }
    // E(p, l) at continuous texel coordinates (c, r), wrapping, for unit l in the local frame.
    vec3 irradiance(const DirectionSet& dirs, vec3 l, float c, float r) const;
    // The same for l's triangle and barycentrics (DirectionSet::locate) found by the caller.
    vec3 irradiance(const std::array<int, 3>& tri, vec3 bary, float c, float r) const;
};

// M: how many leading directions of the set lie above the horizon (throws std::logic_error if
// those above are not a prefix, i.e. the set is not ordered by decreasing z).
int directions_above_horizon(const DirectionSet& dirs);

// The table for s (its light_dir, light_E and env ignored): on the CPU, directions in parallel
// (TBB) in blocks, progress between blocks on the calling thread; with s.gatherer (the GPU), one
// direction after the other through it.
DirectionalScatter scatter_directions(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s,
                                      const std::function<void(double)>& progress = {});
}  // namespace mesolab::microgeom
