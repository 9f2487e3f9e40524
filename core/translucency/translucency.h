#pragma once
// [SECTION] Technique translucency: Lensch et al. 2002, Interactive Rendering of Translucent Objects.
// The pieces (dipole.h, mesh_prep.h, atlas.h, local.h, global.h, blend.h, reference.h) put
// together as a technique: what its stages compute once per object, and the per-frame passes
// the CPU (here) and the GPU (gpu/translucency) both run.
//
// Stages (object stages; none reads a light or the camera, so moving either reruns only the frame):
//   translucency.mesh     the object's mesh welded, cleaned and decimated to translucency.vertices
//   translucency.atlas    the texture atlas, the surface point and normal of each texel, the mesh
//                         drawn (its triangles with atlas coordinates) and the texels each
//                         texel's colour is read from where no triangle covers its centre
//   translucency.kernels  the K x K local kernels (material, mm_per_unit, kernel)
//   translucency.factors  the vertex-to-vertex factors above translucency.threshold
//   translucency.blend    blending (§5.4): the fitted weights and the corrected kernels
//   translucency.gather   per vertex, the texels it gathers irradiance from (hat-weighted) and,
//                         blended, the direct weights: one compressed-row table both devices read
//   translucency.albedo   ρ per texel: translucency.albedo_map and the veins
// Frame steps, in order (each a row of the timing tables):
//   translucency.illumination  irradiance per texel entering the medium: every light times the
//                              Fresnel transmittance T(cos θi), with the object's shadow map,
//                              plus the environment times the same T averaged over the hemisphere (diffuse_transmittance)
//   translucency.vertices      E_j per vertex (hat-weighted) and the direct part B_D (blended)
//   translucency.local         B_local per inner texel (the kernels)
//   translucency.global        B_G = F E + B_D per vertex
//   translucency.combine       B_G interpolated to the texels, B = B_local + B_G, and the texels
//                              outside the triangles filled from their nearest inner texel so
//                              that bilinear look-ups stay on the surface
//   translucency.reference     the brute-force B (only for response = reference or compare = on)
// Display: L_o = ρ(x) T(cos θo) B(x) / π (Jensen et al. 2001, Eq. 5, with the paper's Schlick T).
#include "core/math.h"
#include "core/mesh.h"
#include "core/param.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/translucency/atlas.h"
#include "core/translucency/blend.h"
#include "core/translucency/burley.h"
#include "core/translucency/dipole.h"
#include "core/translucency/global.h"
#include "core/translucency/local.h"
#include "core/translucency/mesh_prep.h"
#include "core/translucency/stages.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace mesolab::translucency {

enum class Response { Both, Local, Global, Reference };

// One object's translucency.* settings, read once.
struct Settings {
    std::string material;       // a measured material or "custom"
    Medium medium;
    bool burley = false;        // translucency.method = lensch-burley: Christensen–Burley's profile
    double mm_per_unit = 1.0;   // mm per object-space unit: translucency.mm_per_unit x geometry.scale
    int vertices = 0, atlas_size = 512, kernel = 7, shadow_map = 512;
    float chunk_angle = 30.f, threshold = 0.f;
    bool blend = true, shadows = true, compare = false;
    Response response = Response::Both;
    std::string albedo_map;
    float veins = 0.f;          // 0 = none
    vec3 vein_color{0.3f};
    double vein_scale = 10.0;   // mm per vein period
    // The keys are read by part, so that a stage or a frame step reads only those it declares (the
    // read contract checks it, core/read_contract.h); the fields of the parts not read keep their
    // defaults.
    enum Part : unsigned {
        Medium_ = 1,    // material, sigma_s, sigma_a, eta
        Scale = 2,      // mm_per_unit x geometry.scale
        Mesh = 4,       // vertices
        AtlasPart = 8,  // atlas_size, kernel, chunk_angle
        Factors = 16,   // threshold, blend
        Shadows = 32,   // shadows, shadow_map
        Rho = 64,       // albedo_map, veins, vein_color, vein_scale
        Show = 128,     // compare, response: what the frame shows
        ProfilePart = 256,  // method: which diffusion profile the stages build from the medium
        Frame = Shadows | Show,
        All = 511,
    };
    static Settings from(const SceneObject& o, unsigned parts = All);  // InputError naming a bad material key
    bool needs_reference() const { return compare || response == Response::Reference; }
    // The diffusion profile of the medium (read with Medium_ | ProfilePart): the dipole (the paper's
    // method) or Christensen and Burley's normalised profile (lensch-burley, burley.h).
    std::unique_ptr<Profile> profile() const;
};

// [SECTION] Stage results
struct AtlasStage {
    Atlas atlas;
    std::vector<vec3> texel_position, texel_normal;  // object space, per texel (0 where empty)
    // Per texel: where its displayed value comes from: itself (inner texels), the nearest inner
    // texel of its chunk (the others), or, in a chunk without inner texels, the inner texel
    // nearest in 3D; -1 for empty texels.
    std::vector<int32_t> fill;
    std::shared_ptr<const TriMesh> display;  // 3 vertices per triangle, uv = atlas coordinates (v = 1 at row 0)
    std::vector<int32_t> nonempty;           // the non-empty texels, in atlas order
    // The illumination map is lit at `lit` texels: the inner texels, and border texels whose
    // surface point has no inner texel of the chunk that owns it within a texel. Every other
    // border texel copies that inner texel ((texel, source) pairs; 72% of the bunny's non-empty
    // texels at 512²): the same surface, found where its own chunk holds it.
    std::vector<int32_t> lit;
    std::vector<ivec2> copy;
};
AtlasStage make_atlas_stage(const PreparedMesh& mesh, const AtlasParams& p);

// Per vertex j the texels t it reads: w.x = projection weight (E_j += w.x E_t, global.h) and,
// blended, w.yzw = the direct weights c (B_D,j += c ∘ E_t).
struct Gather {
    int n = 0;
    std::vector<int32_t> start;  // n + 1
    std::vector<int32_t> texel;
    std::vector<vec4> w;
    bool direct = false;
    size_t bytes() const { return start.size() * 4 + texel.size() * 4 + w.size() * 16; }
};
Gather make_gather(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<float>& vertex_area, double mm_per_unit,
                   const BlendWeights* blend, const LocalKernels* kernels);

struct Blended {
    LocalKernels kernels;  // corrected
    BlendWeights weights;
};

// ρ per texel (1 where neither a map nor veins apply). InputError naming translucency.albedo_map
// for an image that cannot be read or a mesh without texture coordinates.
std::vector<vec3> texel_albedo(const Scene& scene, const Settings& s, const PreparedMesh& mesh, const AtlasStage& a);

// Fractal veins (the paper's textured horse): ρ = mix(1, vein_color, strength × vein(x)), with x in mm.
float vein(vec3 x_mm, double scale_mm);

// [SECTION] Per frame (CPU; gpu/translucency does the same on the GPU)
// Lights beyond the first kMaxShadowMaps light the object without shadows.
inline constexpr int kMaxShadowMaps = 4;
// A shadow map of one object seen from one light: the distance from the light (directional: along
// its direction, from the plane through the object's bounding sphere; point: from the light) of
// the nearest surface per texel of a square map. Both devices build and read it with this maths.
struct ShadowMap {
    int res = 0;
    bool valid = false;     // false: the light is inside the object's bounds (no shadows)
    bool point = false;
    mat4 view_proj{1.f};
    vec3 origin{0.f};       // point: the light; directional: a point on the near plane
    vec3 dir{0.f};          // directional: the light's travel direction (unit)
    float bias = 0.f;       // world units
    std::vector<float> depth;  // res², row 0 at the top (ndc y = +1); +inf where nothing is seen
    float distance(vec3 p) const { return point ? glm::length(p - origin) : glm::dot(p - origin, dir); }
    // 1 when p (world) is lit, 0 when a nearer surface hides it.
    float visibility(vec3 p) const;
};
// The map's frame for world-space bounds (centre, radius); depth is left empty.
ShadowMap shadow_frame(const Light& l, vec3 centre, float radius, int res);
ShadowMap make_shadow_map(const TriMesh& display, const mat4& model, const Light& l, int res);

// Irradiance entering the medium at world point p with outward unit normal n: every light times
// Schlick's transmittance T(cos θi) and its shadow map (the first shadows.size() lights), plus the
// environment times the hemispherical mean of T.
vec3 entering_irradiance(vec3 p, vec3 n, const Lighting& lighting, double eta, const std::vector<ShadowMap>& shadows);
// Irradiance entering the medium at every lit texel, copied from there to the other non-empty
// texels (AtlasStage::copy); 0 at empty texels.
std::vector<vec3> illuminate(const AtlasStage& a, const mat4& model, const Lighting& lighting, double eta, const std::vector<ShadowMap>& shadows);

struct VertexValues {
    std::vector<vec3> E, direct;  // E_j, B_D,j
};
VertexValues gather_vertices(const Gather& g, const std::vector<vec3>& E);

// Every map of a frame, per texel, filled (AtlasStage::fill) for display. The radiosity is
// local + global, added where it is looked up. One record per texel, so that a look-up of the
// radiosity reads its parts from the same cache lines.
struct MapTexel {
    vec3 irradiance, local, global;
    MapTexel() {}  // left unset: combine writes every texel
    MapTexel(vec3 e, vec3 l, vec3 g) : irradiance(e), local(l), global(g) {}
};
struct Maps {
    std::vector<MapTexel> texel;
};
// The maps from the texel irradiance E, the local part and the vertex values Bv (global part,
// interpolated at each texel's fill source): one parallel pass over the texels.
Maps combine(const AtlasStage& a, const std::vector<uint32_t>& index, const std::vector<vec3>& E, const std::vector<vec3>& local,
             const std::vector<vec3>& Bv);
std::vector<vec3> fill_texels(const AtlasStage& a, const std::vector<vec3>& v);

// Bilinear look-up of a per-texel map at atlas uv (as GL_LINEAR with clamp to edge).
vec3 sample_texels(const std::vector<vec3>& map, int size, vec2 uv);
// The same bilinear look-up, its four texels and weights found once for several maps of one atlas.
struct TexelTap {
    size_t i00 = 0, i10 = 0, i01 = 0, i11 = 0;
    float ax = 0.f, ay = 0.f;
    TexelTap(int size, vec2 uv);
    vec3 operator()(const std::vector<vec3>& map) const {
        return glm::mix(glm::mix(map[i00], map[i10], ax), glm::mix(map[i01], map[i11], ax), ay);
    }
    vec3 operator()(const Maps& m, vec3 MapTexel::*part) const {
        const MapTexel* t = m.texel.data();
        return glm::mix(glm::mix(t[i00].*part, t[i10].*part, ax), glm::mix(t[i01].*part, t[i11].*part, ax), ay);
    }
};

// The radiosity of object `object` as the method computes it against the brute-force reference
// on the same atlas, for the scene's lights: RMSE over the inner texels (all channels) relative to
// the reference's mean. CPU; seconds on large meshes (the reference is O(texels²)). Needs the
// object's stages in `ev`. The sweep metric translucency.reference and the panel use it.
double radiosity_error(const Scene& s, const Evaluation& ev, int object);
}  // namespace mesolab::translucency
