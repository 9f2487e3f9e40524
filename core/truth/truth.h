#pragma once
// [SECTION] The truth: a Monte-Carlo reference of the light transport a technique approximates.
// `--backend truth` renders the explicit geometry of every object with a path tracer on Embree
// (core/raytrace.h): camera rays through each pixel's centre, as the real-time paths sample
// them, so that a difference to the truth is one of light transport, not of anti-aliasing
// on silhouettes (a technique whose pixel stands for a footprint integrates it itself: bumpsynth over
// its bumps' uv, TruthMaterial::footprint; cloth over the pixel's square, TruthMaterial::pixel_filter). In texture
// mode a pixel is a texel: points of the texel's footprint on the drawn surface (uniform over it,
// one per sample: at the centre alone a surface of facets has no one normal), carried onto the
// truth's surface (a ray down the drawn surface's normal from Technique::truth_lift above it), seen
// from the camera's direction with no masking, as the real-time texture mode treats it. Next-event
// estimation towards every light with shadow rays, the environment where a path escapes, all
// bounces (Russian roulette from the fourth), surfaces two-sided as on the real-time paths.
//
// What a technique's truth traces is the technique's to say (Technique::truth_object): the mesh
// and a TruthMaterial. It reads only the physical description of the scene (geometry, materials,
// lights, environment, camera), never a technique's accuracy knobs, so one truth serves a sweep.
//
// Determinism: sample s of pixel p draws from its own random stream, seeded by (seed, p, s), and
// each pixel sums its samples in order, so a truth is the same bytes at any thread count, and a
// truth of 2N samples continues one of N. The estimate's standard error per pixel and channel
// (the sample standard deviation over sqrt(spp)) is the AOV `truth_stderr`.
//
// Shading normals: materials see the interpolated normal, as on the real-time paths; a sampled
// direction above its plane but below the triangle is mirrored to above the triangle, so that
// no light is lost where the two planes differ (a white furnace stays 1).
//
// Effects: the truth always has shadows and interreflections (they are the light transport);
// effects.environment off removes the environment's light but not the background seen directly.
#include "core/image.h"
#include "core/math.h"
#include "core/mesh.h"
#include "core/stage.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mesolab {
struct Scene;
struct Frame;
struct Evaluation;

// [SECTION] Random numbers
// A counter-based stream: the state is a 64-bit hash of (seed, pixel, sample), advanced by the
// SplitMix64 increment; next() gives floats in [0, 1).
class TruthRng {
public:
    TruthRng(uint64_t seed, uint64_t pixel, uint64_t sample);
    float next();

private:
    uint64_t state_;
};

// [SECTION] Materials
// The reflectance of a surface point for the truth, in a frame whose normal is n (unit, facing
// the incoming ray's side; two-sided surfaces are flipped by the integrator).
struct TruthHit {
    vec3 p{0.f};   // world position
    vec3 n{0.f};   // shading normal, unit, on the side of wo
    vec3 ng{0.f};  // geometric normal, unit, on the side of wo
    vec2 uv{0.f};
    int triangle = -1;
    int depth = 0;  // bounces before this hit: 0 where the camera sees it
    vec2 bary{0.f}; // barycentrics of the triangle's vertices 1 and 2
    vec3 tangent{0.f};  // world dP/du direction where the mesh has tangents (else 0), not orthogonalised
    // Where the camera sees the surface through a pixel (orbit cameras, depth 0): the pixel's
    // footprint in uv (the steps of uv across one pixel in x and y, on the hit's tangent plane),
    // and a point of it drawn for this sample, uniform in [0, 1)^2: a material whose pixel stands
    // for a footprint (a box filter over detail finer than the pixel) integrates over it at
    // uv + (jitter.x - 0.5) duv_dx + (jitter.y - 0.5) duv_dy. 0 elsewhere (texture mode draws the
    // point of the texel's footprint itself).
    vec2 duv_dx{0.f}, duv_dy{0.f};
    vec2 jitter{0.5f};
};

class TruthMaterial {
public:
    virtual ~TruthMaterial() = default;
    // f_r(wo, wi) in 1/sr, per channel (wo, wi unit, world space).
    virtual vec3 f(const TruthHit& h, vec3 wo, vec3 wi) const = 0;
    // The radiance towards wo per unit irradiance from wi at normal incidence: f_r times the
    // cosine the material's own normal makes with wi (the default: f cos θi with the shading
    // normal h.n). A material shading a facet of its own overrides it with the facet's cosine.
    virtual vec3 fcos(const TruthHit& h, vec3 wo, vec3 wi) const { return f(h, wo, wi) * std::max(0.f, glm::dot(h.n, wi)); }
    // Whether the camera's hits need the pixel's footprint (TruthHit::duv_dx, duv_dy, jitter).
    virtual bool footprint() const { return false; }
    // fcos for next-event estimation towards a light in direction wi, as an estimate whose mean over
    // `rng` is the mean of fcos over the hit's footprint (TruthHit::jitter uniform). The default is
    // fcos at the hit's own point, drawing nothing; a material whose pixel stands for a footprint
    // may average fcos over several points of it drawn from `rng`.
    virtual vec3 fcos_light(const TruthHit& h, vec3 wo, vec3 wi, TruthRng& /*rng*/) const { return fcos(h, wo, wi); }
    // Whether a pixel whose centre sees this material stands for its whole square: its samples'
    // camera rays are then spread uniformly over the pixel (a box filter over geometry finer than
    // a pixel, such as yarns, whose real-time counterpart filters it), and may miss the object.
    virtual bool pixel_filter() const { return false; }
    // Samples wi for a continuing path; returns f cos θi / pdf (0 when the path ends). The default
    // samples the cosine-weighted hemisphere around h.n.
    virtual vec3 sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const;
    // A surface that sends out light of its own (a translucent object's subsurface light, computed
    // by its TruthObject::prepare): paths end on it with beta x emitted. `sample` is the pixel's
    // sample index (the light of sample k comes from the object's k-th independent estimate).
    virtual bool emitter() const { return false; }
    virtual vec3 emitted(const TruthHit& /*h*/, vec3 /*wo*/, uint64_t /*sample*/) const { return vec3(0.f); }
    // The power per unit area the surface sends out by subsurface transport, before its texture
    // (the AOV `exitance`); 0 for surfaces without.
    virtual vec3 exitance(const TruthHit& /*h*/, uint64_t /*sample*/) const { return vec3(0.f); }
};

class RayScene;
struct Lighting;
// What TruthObject::prepare gets: the whole scene to trace in (its object is geometry `geometry`),
// the lights, the samples to prepare [first, spp), the seed and the ray offset.
struct TruthPrep {
    const RayScene& rt;
    int geometry = 0;
    const Lighting& lighting;
    int first = 0, spp = 0;
    uint64_t seed = 0;
    float eps = 1e-4f;
    vec3 centre{0.f};   // the scene's bounding sphere
    float radius = 1.f;
    const std::atomic<bool>* cancel = nullptr;
};

// One object as the truth sees it: a mesh placed by `to_world`, and its material.
struct TruthObject {
    std::shared_ptr<const TriMesh> mesh;
    mat4 to_world{1.f};
    std::shared_ptr<const TruthMaterial> material;
    // Work before the pixels' paths, once the scene is built (a translucent object's light
    // tracing); none for most.
    std::function<void(const TruthPrep&)> prepare;
};

// What the truth of `s` depends on, as canonical text: the program's physical description only.
// The values of every key the truth stages declare (and their inputs), of each technique's
// truth_params, and of the camera, lights, environment, effects.environment and each object's
// geometry, with the contents (not the names or dates) of the files they name. A technique's
// accuracy knobs are not in it, so one truth serves a sweep over them. InputError as truth_stages.
std::string truth_description(const Scene& s);

// [SECTION] Rendering
struct TruthSettings {
    int spp = 64;        // samples per pixel (--spp)
    uint64_t seed = 1;   // --seed
    int max_depth = 64;  // bounces at most (Russian roulette ends most paths far sooner)
};

// The samples of a truth so far, per pixel and channel: their sum and sum of squares, summed in
// sample order, so that continuing it to more samples gives the bytes a fresh render of as many
// would. `normal` is the first sample's first hit (0 for the background).
struct TruthAccumulator {
    int width = 0, height = 0, spp = 0;
    uint64_t seed = 0;
    std::vector<double> sum, sum2;  // 3 per pixel
    std::vector<double> exitance;   // 3 per pixel: the sum of the first hit's exitance (TruthMaterial::exitance)
    std::vector<float> normal;      // 3 per pixel
    bool continues(int w, int h, uint64_t s, int target_spp) const {
        return width == w && height == h && seed == s && spp > 0 && spp <= target_spp;
    }
};

// The truth's AOVs: radiance, normal (the first hit's shading normal), truth_stderr and exitance
// (where the camera sees a translucent object: its subsurface exitance, as translucency's AOV).
const std::vector<std::string>& truth_aovs();

// The stages the truth of `s` needs evaluated: the scene's geometry and environment map, and
// what each object's technique declares (Technique::truth_stages). InputError naming the
// technique when one has no truth.
std::vector<StageName> truth_stages(const Scene& s);

// Renders the truth of `s` at width x height. `progress` gets ("truth", fraction); `cancel`, when
// set, stops at the next row: the rows done keep their samples, the others stay 0 (std::runtime_error
// is not thrown). InputError for spp < 1, an AOV the truth does not write, or a
// technique without a truth.
Frame render_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& settings,
                   const std::vector<std::string>& aovs = {}, const std::function<void(const std::string&, double)>& progress = {},
                   const std::atomic<bool>* cancel = nullptr);

// InputError for spp < 1, a size out of range, an AOV the truth does not write or a
// technique without a truth: what render_truth checks before any work.
void check_truth_request(const Scene& s, int width, int height, const TruthSettings& settings, const std::vector<std::string>& aovs);

// The samples of the truth of `s` up to settings.spp, continuing `from` when it holds fewer samples
// of the same size and seed (from->continues), else from none. Arguments and errors as render_truth.
TruthAccumulator accumulate_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& settings,
                                  const TruthAccumulator* from = nullptr, const std::function<void(const std::string&, double)>& progress = {},
                                  const std::atomic<bool>* cancel = nullptr);
// The frame of an accumulator: radiance (the mean), normal, truth_stderr, exitance.
Frame truth_frame(const TruthAccumulator& a);

// Over the pixels that show an object in the truth (all channels): the RMS of truth_stderr over
// the mean radiance there, the truth's relative noise. 0 when no pixel shows an object.
double truth_noise_rel(const Frame& truth);

// [SECTION] Against the truth
// A real-time frame against the truth of the same scene at the same size.
struct TruthComparison {
    Image error;             // truth_error = real-time radiance − truth radiance (RGB)
    double noise_rel = 0;    // truth_noise_rel(truth)
    double rmse_rel = 0;     // RMS of `error` over the object pixels, over the truth's mean radiance there
    bool below_noise = false;  // rmse_rel <= 2 noise_rel: the truth cannot resolve the error
    int spp = 0;
    uint64_t seed = 0;
};
// std::invalid_argument when the sizes differ.
TruthComparison compare_to_truth(const Frame& realtime, const Frame& truth, const TruthSettings& settings);
}  // namespace mesolab
