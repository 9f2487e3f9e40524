// Method separable of technique translucency: screen-space separable subsurface scattering
// (Jimenez et al. 2015; see separable.h). The kernel, the blur's CPU side and the method.
#include "core/translucency/separable.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/profile.h"
#include "core/raster.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"
#include "core/translucency/separable_blur.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

#include "core/translucency/burley.h"

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <string>
#include <cmath>
#include <map>
#include <memory>

namespace mesolab::translucency {

// [SECTION] The kernel
namespace {
// 8-point Gauss–Legendre on [-1, 1].
constexpr double kGlX[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                            0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
constexpr double kGlW[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                            0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
}  // namespace

dvec3 strip_integral(const Profile& p, double m) {
    if (!(m > 0.0)) return dvec3(0.0);
    if (std::isinf(m)) return p.total_reflectance();
    // Inside the disk of radius m the whole circle lies in the strip.
    dvec3 s = p.reflectance_within(m);
    // Beyond it, r = m cosh u: L(r) dr = 4 r asin(m / r) dr = 4 m² cosh u (π/2 − atan(sinh u)) sinh u du, smooth
    // at u = 0, and uniform steps in u are logarithmic in r far out.
    const double r_far = p.radius_holding(1.0 - 1e-7);
    if (r_far <= m) return s;
    const double u_max = std::acosh(r_far / m);
    const int panels = 160;
    const double h = u_max / panels;
    dvec3 tail(0.0);
    for (int k = 0; k < panels; ++k)
        for (int g = 0; g < 8; ++g) {
            const double u = h * (k + 0.5 + 0.5 * kGlX[g]);
            const double r = m * std::cosh(u), sh = std::sinh(u);
            const double length = 4.0 * m * m * std::cosh(u) * (0.5 * kPi - std::atan(sh)) * sh;
            tail += p.Rd(r) * (length * 0.5 * h * kGlW[g]);
        }
    return s + tail;
}

SeparableKernel make_separable_kernel(const Profile& p, int taps, double reach) {
    if (taps < 3 || taps % 2 == 0) throw std::invalid_argument("make_separable_kernel: taps must be odd and at least 3");
    SeparableKernel k;
    k.total = p.total_reflectance();
    k.reach_mm = float(p.radius_holding(reach));
    const int h = taps / 2;
    // Offsets ∝ t², t uniform in [−1, 1]: denser near the centre where the profile is steep.
    std::vector<double> x(size_t(h) + 1);
    for (int i = 0; i <= h; ++i) x[size_t(i)] = double(k.reach_mm) * (double(i) / h) * (double(i) / h);
    // Strip masses of the marginal: the centre tap [−e_0, e_0], tap i ≥ 1 [e_{i−1}, e_i] on one side
    // (half the strip integral's difference), the outermost to infinity.
    std::vector<dvec3> mass(size_t(h) + 1);
    dvec3 below = strip_integral(p, 0.5 * (x[0] + x[1]));
    mass[0] = below;
    for (int i = 1; i <= h; ++i) {
        const dvec3 upto = i < h ? strip_integral(p, 0.5 * (x[size_t(i)] + x[size_t(i) + 1])) : k.total;
        mass[size_t(i)] = 0.5 * (upto - below);
        below = upto;
    }
    dvec3 norm;
    for (int c = 0; c < 3; ++c) norm[c] = k.total[c] > 0.0 ? 1.0 / std::sqrt(k.total[c]) : 0.0;
    for (int i = -h; i <= h; ++i) {
        k.offset_mm.push_back(float(i < 0 ? -x[size_t(-i)] : x[size_t(i)]));
        k.weight.push_back(vec3(mass[size_t(std::abs(i))] * norm));
    }
    return k;
}

std::shared_ptr<const SeparableKernel> separable_kernel(const Medium& medium, bool burley, int taps) {
    static std::mutex mutex;
    static std::map<std::string, std::shared_ptr<const SeparableKernel>> kept;
    char key[256];
    std::snprintf(key, sizeof key, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %d %d", medium.sigma_s.x, medium.sigma_s.y, medium.sigma_s.z, medium.sigma_a.x,
                  medium.sigma_a.y, medium.sigma_a.z, medium.eta, burley ? 1 : 0, taps);
    {
        const std::lock_guard<std::mutex> lock(mutex);
        if (auto it = kept.find(key); it != kept.end()) return it->second;
    }
    std::unique_ptr<Profile> p;
    if (burley) p = std::make_unique<BurleyProfile>(medium);
    else p = std::make_unique<Dipole>(medium);
    auto k = std::make_shared<const SeparableKernel>(make_separable_kernel(*p, taps));
    const std::lock_guard<std::mutex> lock(mutex);
    if (kept.size() >= 64) kept.clear();
    kept.emplace(key, k);
    return k;
}

// [SECTION] The blur (CPU)
void separable_blur_pass(const BlurImage& in, const std::vector<const SeparableKernel*>& kernels, bool vertical, std::vector<vec3>& out) {
    out.assign(in.value.size(), vec3(0.f));
    mesolab::parallel_for(0, in.height, [&](int y) {
        for (int x = 0; x < in.width; ++x) {
            const size_t c = size_t(y) * size_t(in.width) + size_t(x);
            const int o = in.object[c];
            if (o < 0) continue;
            const SeparableKernel* k = size_t(o) < kernels.size() ? kernels[size_t(o)] : nullptr;
            if (!k) continue;
            out[c] = blur_pixel(in, *k, x, y, vertical);
        }
    });
}

// [SECTION] The method
namespace {

struct SeparableSettings {
    Settings s;               // material (medium, profile), shadows
    int taps = 17;
    float mm_per_world = 1.f;  // translucency.mm_per_unit: the object's scale makes object units, not world units
    static SeparableSettings from(const SceneObject& o) {
        SeparableSettings r;
        r.s = Settings::from(o, Settings::Medium_ | Settings::Shadows);
        r.s.burley = o.material.get_string("separable_profile") == "burley";
        r.taps = int(o.material.get_int("separable_taps"));
        r.mm_per_world = float(o.material.get_float("mm_per_unit"));
        return r;
    }
};

class SeparableMethod final : public Method {
public:
    SeparableMethod()
        : Method("translucency", "separable", "Screen-space separable subsurface scattering (Jimenez et al. 2015)") {}

    void declare_params(ParamGroup& p) const override {
        p.add_int("separable_taps", 17).used_when("method", {"separable"}).range(3, 63).odd().more_accurate(Accuracy::Higher, int64_t(63))
            .doc("Taps of each of the two 1D blurs (odd): offsets denser near the centre, out to where the profile holds 99.5% of its reflectance");
        p.add_enum("separable_profile", {"dipole", "burley"}, "dipole").used_when("method", {"separable"})
            .doc("The diffusion profile the blur's kernel is made from: the dipole (the paper's) or Christensen and Burley's normalised profile");
        p.section("Separable subsurface scattering", {"separable_taps", "separable_profile"});
    }

    void shade_cpu(const ShadeContext& ctx) const override;

    // Both paths compute the same irradiance, depth and pixel size per pixel in float and blur them
    // with the same taps and weights; what differs is float evaluation, and the shadow maps' texels
    // along a shadow's edge (as the paper's method: a texel lit on one path, shadowed on the other),
    // which the blur spreads over its width: in spot-skin-separable (llvmpipe, 512²) 14 of 16,311
    // interior values beyond interior_max, the worst 0.056 (an irradiance of up to 5). Away from
    // shadow edges the two agree within 1e-5.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.995, .interior_max = 5e-3, .interior_outliers = 2e-3,
                .why = "float evaluation; shadow-map texels along a shadow's edge, spread by the blur"};
    }
};

// What the frame's pixels of the method's objects hold before the blur.
struct Prepass {
    BlurImage image;
    std::vector<const SeparableKernel*> kernels;  // by object id (null: not the method's)
    std::vector<std::shared_ptr<const SeparableKernel>> kernel_store;
};

void SeparableMethod::shade_cpu(const ShadeContext& ctx) const {
    if (ctx.camera.texture_mode)
        throw InputError("translucency.method = separable blurs in screen space: camera.mode = texture has no screen (use orbit)");
    const GBuffer& frame_gb = ctx.gbuffer;
    const int W = frame_gb.width, H = frame_gb.height;
    // The method's objects alone, as its GPU pass draws them: what another object hides still
    // scatters light to what it does not.
    thread_local GBuffer tls_gbuffer;
    GBuffer& gb = tls_gbuffer;  // lambdas on worker threads must see this thread's buffer
    std::vector<std::shared_ptr<const TriMesh>> meshes;
    std::vector<DrawItem> items;
    std::map<int, SeparableSettings> settings;
    std::map<int, std::vector<ShadowMap>> shadows;
    Prepass pre;
    pre.kernels.assign(ctx.scene.objects.size(), nullptr);
    for (int o : ctx.objects) {
        const SceneObject& obj = ctx.scene.objects[size_t(o)];
        const SeparableSettings st = SeparableSettings::from(obj);
        settings.emplace(o, st);
        meshes.push_back(drawn_mesh(ctx.scene, ctx.eval, o));
        const mat4 model = object_to_world(obj);
        items.push_back({meshes.back().get(), model, o, false});
        pre.kernel_store.push_back(separable_kernel(st.s.medium, st.s.burley, st.taps));
        pre.kernels[size_t(o)] = pre.kernel_store.back().get();
        if (st.s.shadows)
            for (size_t i = 0; i < ctx.lighting.lights.size() && i < size_t(kMaxShadowMaps); ++i)
                shadows[o].push_back(make_shadow_map(*meshes.back(), model, ctx.lighting.lights[i], st.s.shadow_map));
    }
    {
        PROFILE_SCOPE("raster");
        rasterize(items, ctx.camera.raster, gb);
    }
    BlurImage& im = pre.image;
    im.width = W, im.height = H;
    im.value.assign(size_t(W) * size_t(H), vec3(0.f));
    im.object.assign(im.value.size(), -1);
    im.depth_mm.assign(im.value.size(), 0.f);
    im.pixel_mm.assign(im.value.size(), 0.f);
    const std::vector<ShadowMap> no_shadows;
    const mat4 view = ctx.camera.raster.view;
    const float proj11 = ctx.camera.raster.proj[1][1];
    {
        PROFILE_SCOPE("irradiance");
        mesolab::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                const size_t px = gb.index(x, y);
                const int o = gb.object[px];
                if (o < 0) continue;
                const SeparableSettings& st = settings.at(o);
                const vec3 p = gb.position[px];
                const auto sh = shadows.find(o);
                im.value[px] = entering_irradiance(p, gb.normal[px], ctx.lighting, st.s.medium.eta, sh == shadows.end() ? no_shadows : sh->second);
                const float z = -(view * vec4(p, 1.f)).z;
                im.object[px] = o;
                im.depth_mm[px] = z * st.mm_per_world;
                im.pixel_mm[px] = pixel_size_at(z, proj11, H) * st.mm_per_world;
            }
        });
    }
    std::vector<vec3> across, B;
    {
        PROFILE_SCOPE("blur");
        separable_blur_pass(im, pre.kernels, false, across);
        BlurImage second = im;
        second.value = std::move(across);
        separable_blur_pass(second, pre.kernels, true, B);
    }
    const int out_irr = ctx.out.index("irradiance"), out_rad = ctx.out.index("radiosity"), out_loc = ctx.out.index("local"),
              out_glo = ctx.out.index("global"), out_ref = ctx.out.index("reference"), out_err = ctx.out.index("error"),
              out_exi = ctx.out.index("exitance");
    mesolab::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t px = frame_gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const SeparableSettings& st = settings.at(frame_gb.object[px]);
            const vec3 wo = ctx.camera.wo(frame_gb.position[px]);
            vec3 n = frame_gb.normal[px];
            if (glm::dot(n, wo) < 0.f) n = -n;
            const float T = float(fresnel_transmittance(std::clamp(glm::dot(n, wo), 0.f, 1.f), st.s.medium.eta));
            ctx.out.put(AovWriter::kRadiance, x, y, B[px] * (T * kInvPi));
            ctx.out.put(AovWriter::kNormal, x, y, n);
            ctx.out.put(out_irr, x, y, im.value[px]);
            ctx.out.put(out_exi, x, y, B[px] * float(diffuse_transmittance(st.s.medium.eta)));
            ctx.out.put(out_rad, x, y, B[px]);
            ctx.out.put(out_loc, x, y, B[px]);
            ctx.out.put(out_glo, x, y, vec3(0.f));
            ctx.out.put(out_ref, x, y, vec3(0.f));
            ctx.out.put(out_err, x, y, vec3(0.f));
        }
    });
}
}  // namespace
}  // namespace mesolab::translucency

namespace mesolab {
void register_translucency_separable(Registry& r) { r.add_method(std::make_unique<translucency::SeparableMethod>()); }
}  // namespace mesolab
