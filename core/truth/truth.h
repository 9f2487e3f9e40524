#pragma once
// [SECTION] The truth: a Monte-Carlo reference of the light transport a technique approximates.
// `--backend truth` renders the explicit geometry of every object with a path tracer on Embree
// (core/raytrace.h): camera rays through each pixel's centre, as the real-time paths sample
// them, so that a difference to the truth is one of light transport, not of anti-aliasing
// on silhouettes (a technique whose pixel stands for a footprint integrates it itself: bumpsynth over
// its bumps' uv, TruthMaterial::footprint; cloth over the pixel's square, TruthMaterial::pixel_filter). In texture
// mode a pixel is a texel: points of the texel's footprint on the drawn surface (uniform over it,
// one per sample: at the centre alone a surface of facets has no one normal), carried onto the
// truth's surface (a ray down the drawn surface's normal from TruthDecl::lift above it), seen
// from the camera's direction with no masking, as the real-time texture mode treats it. Next-event
// estimation towards every light with shadow rays, the environment where a path escapes, all
// bounces (Russian roulette from the fourth), surfaces two-sided as on the real-time paths.
//
// What a technique's truth traces is the technique's to say (Technique::truth, a TruthDecl): the
// mesh and a TruthMaterial. It reads only the physical description of the scene (geometry,
// materials, lights, environment, camera), never a technique's accuracy knobs, so one truth serves
// a sweep. It declares what it reads as a stage does, the truth's key on disk is made of those
// values, and the read contract (core/read_contract.h) checks that it reads nothing else.
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
    int geometry = -1;  // the object's index in the truth's scene
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
    // A surface in front of a medium (a translucent object): the truth then writes, where the
    // camera sees it, the AOVs exitance and irradiance, the power per unit area entering the medium
    // (the lights' and the sky's irradiance through `transmittance`, shadowed, one sky direction per
    // sample).
    virtual bool medium() const { return false; }
    // The fraction of the light arriving from wi (unit, world) that enters the medium: the
    // boundary's Fresnel transmittance at the facet the hit lies on (h.ng).
    virtual float transmittance(const TruthHit& /*h*/, vec3 /*wi*/) const { return 0.f; }
};

// Samples are rendered in blocks of at most this many (aligned on the sample index), each block's
// photon batches or other preparation made once for all pixels; noise, time limit and progress are
// checked between blocks.
constexpr int kTruthBlock = 4;

class RayScene;
struct Lighting;
// What TruthObject::prepare gets: the whole scene to trace in (its object is geometry `geometry`),
// the lights, the block of samples to prepare [first, end) (what was prepared for the block before
// may be dropped), the seed and the ray offset.
struct TruthPrep {
    const RayScene& rt;
    int geometry = 0;
    const Lighting& lighting;
    int first = 0, end = 0;
    uint64_t seed = 0;
    float eps = 1e-4f;
    vec3 centre{0.f};   // the scene's bounding sphere
    float radius = 1.f;
    const std::atomic<bool>* cancel = nullptr;
    // World points where the camera sees this object (the pixel centres' first hits; texture
    // mode: the texels' surface points), the same for every block of a frame; empty: unknown.
    // A light tracer may send more of its paths where they are seen (importance), never fewer
    // than a fixed share elsewhere.
    const std::vector<vec3>* seen = nullptr;
};

// One object as the truth sees it: a mesh placed by `to_world`, and its material.
struct TruthObject {
    std::shared_ptr<const TriMesh> mesh;
    mat4 to_world{1.f};
    std::shared_ptr<const TruthMaterial> material;
    // Work before the pixels' paths, for each block of samples (a translucent object's light
    // tracing); none for most.
    std::function<void(const TruthPrep&)> prepare;
    // The most samples a block may hold (what `prepare` keeps for a block is in memory at once).
    int samples_per_block = kTruthBlock;
};

// A technique's truth, declared once (Technique::truth): what it reads, and how it makes the
// objects it traces. Like a stage, it names the keys it reads and the stages whose results it reads
// (only physical ones: the mesh, material maps; never an accuracy knob's). With the scene's camera,
// lights, environment, effects.environment and each object's geometry (truth_scene_params), they
// are all a truth depends on: its key on disk (truth_description) and its read contract.
struct TruthDecl {
    std::vector<std::string> params;  // the technique's keys `object` and `lift` read (its material's)
    std::vector<StageName> stages;    // stages whose results they read
    // The explicit geometry and material of one of its objects as the truth traces them.
    std::function<TruthObject(const Scene&, const Evaluation&, int object)> object;
    // Texture-mode cameras: how far (object units, along the normal) the truth's surface of an
    // object may reach above the surface the rasteriser draws in texture space; the truth's ray for
    // a texel starts that far above the drawn point and goes down the normal to the first hit. Null
    // (or 0): the truth's surface is the drawn one.
    std::function<float(const Scene&, const Evaluation&, int object)> lift;
};

// The scene-wide keys every truth reads: camera.*, light.*, env.*, effects.environment, geometry.*.
const std::vector<std::string>& truth_scene_params();

// Every key pattern the truth of `s` may read, with the object it is read for (-1: scene-wide): the
// scene's (truth_scene_params), each object's technique's TruthDecl::params and what its truth
// stages (and their inputs) declare. InputError as truth_stages.
std::vector<std::pair<std::string, int>> truth_reads(const Scene& s);

// What the truth of `s` depends on, as canonical text: the values of every key of truth_reads,
// with the contents (not the names or dates) of the files they name. A technique's accuracy knobs
// are not in it, so one truth serves a sweep over them. InputError as truth_stages.
std::string truth_description(const Scene& s);

// [SECTION] Exact sums
// A truth's sums are kept exactly: each sample's value is rounded once to a multiple of 2^-64
// (values beyond ±2^62 are clamped, a NaN counts as 0) and the multiples are added as 128-bit
// integers. Integer addition does not depend on its order, so a truth rendered in blocks of samples,
// in parts on several processes or machines, continued from the cache or merged in any order is
// the same bytes as one rendered at once, for the same build and instruction set (truth_build()).
__extension__ typedef __int128 TruthFixed;
TruthFixed to_fixed(double x);
double from_fixed(TruthFixed f);

// The build a truth's samples come from: the program's `version`, the compiler and the instruction
// set the path tracer runs with here (Embree's and the maths library's choice follows the CPU), e.g.
// "0.1.0-bf44e1e; GCC 12.2.0; x86-64 avx2 fma". Two parts merge only when these are equal: another
// build or instruction set rounds some rays differently, and the bytes would differ.
std::string truth_build(const std::string& version);

// [SECTION] Rendering
// Why a truth stopped sampling.
enum class TruthEnd {
    Samples,    // it reached the samples asked for (--spp, or the end of --samples A:B)
    Noise,      // noise_rel reached --noise
    TimeLimit,  // --time-limit passed first (the samples done are kept)
    Cancelled,  // stopped by the caller's flag: the samples of the block under way are not complete
};
const char* to_string(TruthEnd e);

struct TruthSettings {
    int spp = 64;        // samples per pixel (--spp): with noise > 0, the most samples
    uint64_t seed = 1;   // --seed
    int max_depth = 64;  // bounces at most (Russian roulette ends most paths far sooner)
    int first = 0;       // the first sample: a partial truth of samples [first, spp) (--samples A:B)
    double noise = 0;         // > 0: sample until truth_noise_rel reaches it (--noise), from kNoiseMinSpp samples on
    double time_limit_s = 0;  // > 0: stop after this many seconds of sampling (--time-limit)
};
// The fewest samples a noise target is judged on: below that the spread over samples is itself too
// uncertain to stop on.
constexpr int kNoiseMinSpp = 16;

// The samples [first, spp) of a truth, per pixel and channel: exact sums (TruthFixed) of the
// radiance and its square, of the first hit's exitance and irradiance (where a material writes
// them; else empty), and the first hit's shading normal of sample `first` (0 for the background).
struct TruthAccumulator {
    int width = 0, height = 0;
    int first = 0, spp = 0;  // samples [first, spp)
    uint64_t seed = 0;
    std::vector<TruthFixed> sum, sum2;            // 3 per pixel
    std::vector<TruthFixed> exitance, irradiance;  // 3 per pixel, or empty
    std::vector<float> normal;                     // 3 per pixel
    TruthEnd ended = TruthEnd::Samples;
    double seconds = 0;  // time spent sampling in the call that made it (not counting samples it continued)
    int samples() const { return spp - first; }
    bool continues(int w, int h, uint64_t s, int first_sample, int target_spp) const {
        return width == w && height == h && seed == s && first == first_sample && spp > first && spp <= target_spp;
    }
};

// The truth's AOVs: radiance, normal (the first hit's shading normal), truth_stderr, exitance and
// irradiance (where the camera sees a translucent object: its subsurface exitance, and the power
// per unit area entering it, as translucency's AOVs).
const std::vector<std::string>& truth_aovs();

// The stages the truth of `s` needs evaluated: the scene's geometry and environment map, and
// what each object's technique's truth declares (TruthDecl::stages). InputError naming the
// technique when one has no truth.
std::vector<StageName> truth_stages(const Scene& s);

// Renders the truth of `s` at width x height (samples [settings.first, settings.spp), stopping
// early on settings.noise or time_limit_s). `progress` gets ("truth: ...", fraction) between
// blocks; `cancel`, when set, stops within the block under way and throws Cancelled. InputError
// for spp < 1, an empty sample range, an AOV the truth does not write, or a technique without a
// truth.
Frame render_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& settings,
                   const std::vector<std::string>& aovs = {}, const std::function<void(const std::string&, double)>& progress = {},
                   const std::atomic<bool>* cancel = nullptr);

// How a user names the sampling options, for errors: the command line's ("--spp ") or Python's
// ("spp=").
struct TruthOptionNames {
    const char* spp = "--spp ";
    const char* noise = "--noise ";
    const char* time_limit = "--time-limit ";
    const char* samples = "--samples ";
};
// InputError for spp < 1, a sample range that is empty or starts below 0, a noise target outside
// (0, 1) and not 0, a time limit below 0: the one check of a truth's sampling.
void check_truth_settings(const TruthSettings& settings, const TruthOptionNames& names = {});

// InputError for spp < 1, a sample range that is empty or starts below 0, a noise target outside
// (0, 1), a negative time limit, a size out of range, an AOV the truth does not write or a technique
// without a truth: what render_truth checks before any work.
void check_truth_request(const Scene& s, int width, int height, const TruthSettings& settings, const std::vector<std::string>& aovs);

// The samples of the truth of `s` from settings.first up to settings.spp, continuing `from` when
// it holds fewer samples of the same size, seed and first sample (from->continues), else from none;
// stops early on settings.noise (once noise_rel ≤ it) or settings.time_limit_s, and says which in
// `ended`. A cancelled call (the flag set) returns ended = Cancelled: its sums are incomplete and
// must not be kept. Arguments and errors as render_truth.
TruthAccumulator accumulate_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& settings,
                                  const TruthAccumulator* from = nullptr, const std::function<void(const std::string&, double)>& progress = {},
                                  const std::atomic<bool>* cancel = nullptr);
// The frame of an accumulator: radiance (the mean), normal, truth_stderr, exitance, irradiance.
Frame truth_frame(const TruthAccumulator& a);
// truth_noise_rel of the accumulator's frame, without making the frame.
double truth_noise_rel(const TruthAccumulator& a);

// Over the pixels that show an object in the truth (all channels): the RMS of truth_stderr over
// the mean radiance there, the truth's relative noise. 0 when no pixel shows an object.
double truth_noise_rel(const Frame& truth);

// [SECTION] Partial truths
// Samples [first, spp) of a truth, written by `capture --backend truth --samples A:B` and joined by
// `mesolab truth merge`: the sums with what they are of (the scene's name, the truth's cache key, its
// size, seed and sample range, and the build they were made with).
struct TruthPart {
    std::string scene;  // Scene::name
    std::string key;    // the truth cache's key (truth_cache_key): what the truth reads, size and seed
    std::string build;  // truth_build()
    TruthAccumulator sums;
};
// Writes through a temporary file and a rename. std::runtime_error naming the file when it cannot.
void write_truth_part(const std::string& path, const TruthPart& p);
// InputError naming the file and what is wrong: not a partial truth, truncated, inconsistent sizes.
TruthPart read_truth_part(const std::string& path);
// The same as bytes (the truth cache's entries); `name` names them in errors.
std::string truth_part_bytes(const TruthPart& p);
TruthPart truth_part_from_bytes(const std::string& bytes, const std::string& name);
// Joins parts of one truth into one: InputError naming the two parts and what differs when they
// are of another scene, key, size, seed or build, or when their sample ranges overlap or leave a
// gap (in any order given; the result runs from the lowest first sample to the highest end).
// Exact sums: the result is the same bytes as the samples rendered at once.
TruthPart merge_truth_parts(const std::vector<std::pair<std::string, TruthPart>>& named_parts);

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
