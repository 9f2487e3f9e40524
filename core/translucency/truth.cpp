// Technique translucency: its truth. Volumetric light transport in the object's own (closed,
// undecimated) mesh: a homogeneous medium of reduced scattering σs′ and absorption σa with an
// isotropic phase function (the similarity relation the dipole assumes), behind a smooth
// dielectric boundary of index η (exact Fresnel in and out, total internal reflection).
//
// Light paths start at the lights and the environment (a smooth boundary cannot be connected to
// a pinhole camera): photons from a disc covering the object (directional lights, environment) or
// from the point light towards it, shadowed by everything in the scene, enter with the Fresnel
// transmittance, walk (free paths of mean 1/σt, albedo σs′/σt per step, Russian roulette below a
// fifth of the weight) and, where they leave, add their power to the three vertices of the
// triangle (barycentric weights): the exitance M per vertex is that power over a third of the
// area of the vertex's triangles. Each sample of the truth is an independent batch of photons
// (N = 32 x vertices, within [32768, 2^21], split evenly over the lights and the environment, one
// colour channel per photon), so the spread over samples is the exitance's standard error.
//
// The camera sees M as radiance with the real-time display's angular distribution and texture:
// L = ρ(x) T(cos θo) M / (π t̄), t̄ = 2 ∫ T(μ) μ dμ over [0, 1] with the paper's Schlick T, so that
// the power leaving is M. That step is a model (as the display's is); the exitance is not. Light
// reflected at the surface, and light other objects reflect onto it, are left out, as on the
// real-time path.
#include "core/basic/basic.h"
#include "core/error.h"
#include "core/raytrace.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <tuple>

namespace mesolab::translucency {
namespace {
using glm::dvec3;

// Fresnel reflectance of a smooth dielectric for unpolarised light arriving at cos_i from the
// side of index 1 into index eta (eta < 1 from inside); 1 beyond the critical angle. cos_t: the
// transmitted ray's cosine.
double fresnel(double cos_i, double eta, double& cos_t) {
    const double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) {
        cos_t = 0.0;
        return 1.0;
    }
    cos_t = std::sqrt(1.0 - sin2_t);
    const double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t), rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
// The refracted direction of unit d through a surface of unit normal n facing d (n·d < 0).
vec3 refract(vec3 d, vec3 n, double eta, double cos_i, double cos_t) {
    return glm::normalize(vec3(dvec3(d) / eta + (cos_i / eta - cos_t) * dvec3(n)));
}
vec3 uniform_sphere(float u1, float u2) {
    const float z = 1.f - 2.f * u1, r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
void basis(vec3 n, vec3& t, vec3& b) {
    t = std::fabs(n.x) > 0.9f ? glm::normalize(glm::cross(vec3(0.f, 1.f, 0.f), n)) : glm::normalize(glm::cross(vec3(1.f, 0.f, 0.f), n));
    b = glm::cross(n, t);
}

// The mesh closed for the truth: positions welded (a mesh's uv seams duplicate vertices), and
// each hole (a loop of edges that one triangle uses) filled by a fan from the centroid of the
// loop's vertices, facing as the triangles around it (a scan's holes, such as the Stanford
// bunny's five under its base). `filled` counts the holes; InputError naming `what` for an edge
// that more than two triangles share or a hole whose edges do not form loops.
TriMesh closed_mesh(const TriMesh& m, const std::string& what, int& filled) {
    std::map<std::tuple<float, float, float>, uint32_t> weld;
    std::vector<uint32_t> id(m.vertex_count()), rep;  // welded id of each vertex; a vertex of each id
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const vec3 p = m.position[v];
        const auto [it, fresh] = weld.emplace(std::make_tuple(p.x, p.y, p.z), uint32_t(rep.size()));
        if (fresh) rep.push_back(uint32_t(v));
        id[v] = it->second;
    }
    std::map<std::pair<uint32_t, uint32_t>, int> directed;  // welded a -> b, by triangle winding
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const uint32_t a = id[m.index[3 * t]], b = id[m.index[3 * t + 1]], c = id[m.index[3 * t + 2]];
        if (a == b || b == c || a == c) continue;
        for (auto [x, y] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) ++directed[{x, y}];
    }
    std::map<uint32_t, uint32_t> next;  // along the holes' edges, reversed: b -> a for a boundary a -> b
    for (const auto& [e, n] : directed) {
        const int both = n + (directed.count({e.second, e.first}) ? directed.at({e.second, e.first}) : 0);
        if (both > 2) throw InputError("--backend truth: translucency's truth needs a closed mesh, and " + what + " has an edge shared by " + std::to_string(both) + " triangles");
        if (both == 1 && !next.emplace(e.second, e.first).second)
            throw InputError("--backend truth: translucency's truth needs a closed mesh, and the holes of " + what + " meet at a vertex (they cannot be filled)");
    }
    TriMesh out = m;
    filled = 0;
    while (!next.empty()) {
        std::vector<uint32_t> loop{next.begin()->first};
        for (uint32_t v = next.begin()->second; v != loop.front(); v = next.at(v)) {
            if (!next.count(v) || loop.size() > next.size()) throw InputError("--backend truth: translucency's truth needs a closed mesh, and a hole of " + what + " is not a loop");
            loop.push_back(v);
        }
        vec3 c(0.f), n(0.f);
        vec2 uv(0.f);
        for (uint32_t v : loop) {
            c += m.position[rep[v]];
            if (!m.normal.empty()) n += m.normal[rep[v]];
            if (!m.uv.empty()) uv += m.uv[rep[v]];
        }
        const float k = 1.f / float(loop.size());
        const uint32_t centre = uint32_t(out.position.size());
        out.position.push_back(c * k);
        if (!out.normal.empty()) out.normal.push_back(glm::dot(n, n) > 0.f ? glm::normalize(n) : vec3(0.f));
        if (!out.tangent.empty()) out.tangent.push_back(vec3(0.f));
        if (!out.uv.empty()) out.uv.push_back(uv * k);
        for (size_t i = 0; i < loop.size(); ++i) {
            const uint32_t a = loop[i], b = loop[(i + 1) % loop.size()];
            out.index.insert(out.index.end(), {rep[a], rep[b], centre});  // the boundary edge b -> a of the mesh, reversed
        }
        for (uint32_t v : loop) next.erase(v);
        ++filled;
    }
    return out;
}

class TranslucentTruth final : public TruthMaterial {
public:
    TranslucentTruth(std::shared_ptr<const TriMesh> mesh, mat4 to_world, Settings s, double mm_per_world, std::optional<Image> map)
        : mesh_(std::move(mesh)), to_world_(to_world), from_world_(glm::inverse(to_world)), s_(std::move(s)), mm_per_world_(mm_per_world),
          map_(std::move(map)) {
        t_bar_ = diffuse_transmittance(s_.medium.eta);
        // A third of each vertex's triangles' world area.
        area_.assign(mesh_->vertex_count(), 0.0);
        for (size_t f = 0; f < mesh_->triangle_count(); ++f) {
            const uint32_t a = mesh_->index[3 * f], b = mesh_->index[3 * f + 1], c = mesh_->index[3 * f + 2];
            const vec3 pa = vec3(to_world_ * vec4(mesh_->position[a], 1.f)), pb = vec3(to_world_ * vec4(mesh_->position[b], 1.f)),
                       pc = vec3(to_world_ * vec4(mesh_->position[c], 1.f));
            const double third = double(glm::length(glm::cross(pb - pa, pc - pa))) / 6.0;
            area_[a] += third, area_[b] += third, area_[c] += third;
        }
    }

    vec3 f(const TruthHit&, vec3, vec3) const override { return vec3(0.f); }
    bool emitter() const override { return true; }
    vec3 exitance(const TruthHit& h, uint64_t sample) const override {
        if (sample < uint64_t(first_) || sample - uint64_t(first_) >= batches_.size()) return vec3(0.f);
        const std::vector<vec3>& M = batches_[size_t(sample - uint64_t(first_))];
        const size_t f = size_t(h.triangle);
        return (1.f - h.bary.x - h.bary.y) * M[mesh_->index[3 * f]] + h.bary.x * M[mesh_->index[3 * f + 1]] + h.bary.y * M[mesh_->index[3 * f + 2]];
    }
    vec3 emitted(const TruthHit& h, vec3 wo, uint64_t sample) const override {
        const float T = float(fresnel_transmittance(std::fabs(glm::dot(h.n, wo)), s_.medium.eta));
        return rho(h) * T * exitance(h, sample) / float(kPi * t_bar_);
    }

    // The photon batches of samples [first, spp).
    void prepare(const TruthPrep& p) {
        first_ = p.first;
        batches_.assign(size_t(p.spp - p.first), {});
        // The object's bounding sphere, world.
        vec3 lo(1e30f), hi(-1e30f);
        for (const vec3& q : mesh_->position) {
            const vec3 w = vec3(to_world_ * vec4(q, 1.f));
            lo = glm::min(lo, w), hi = glm::max(hi, w);
        }
        const vec3 centre = 0.5f * (lo + hi);
        const float radius = 0.5f * glm::length(hi - lo) * 1.001f + p.eps;
        const size_t nv = mesh_->vertex_count();
        const int photons = int(std::clamp<size_t>(32 * nv, 32768, size_t(1) << 21));
        const int sources = int(p.lighting.lights.size()) + (p.lighting.env_lighting ? 1 : 0);
        constexpr int kChunks = 16;
        for (int k = p.first; k < p.spp; ++k) {
            if (p.cancel && p.cancel->load()) return;
            std::vector<std::vector<dvec3>> chunk(kChunks, std::vector<dvec3>(sources ? nv : 0, dvec3(0.0)));
            if (sources > 0)
                tbb::parallel_for(0, kChunks, [&](int c) {
                    for (int i = c; i < photons; i += kChunks) trace_photon(p, centre, radius, sources, photons, k, i, chunk[size_t(c)]);
                });
            std::vector<vec3>& M = batches_[size_t(k - p.first)];
            M.assign(nv, vec3(0.f));
            for (size_t v = 0; v < nv; ++v) {
                dvec3 sum(0.0);
                for (const auto& ch : chunk) sum += ch.empty() ? dvec3(0.0) : ch[v];  // in chunk order: the same bytes at any thread count
                if (area_[v] > 0.0) M[v] = vec3(sum / area_[v]);
            }
        }
    }

private:
    vec3 rho(const TruthHit& h) const {
        vec3 r(1.f);
        if (map_) r = basic::sample_albedo(*map_, h.uv);
        if (s_.veins > 0.f)
            r *= glm::mix(vec3(1.f), s_.vein_color, s_.veins * vein(vec3(from_world_ * vec4(h.p, 1.f)) * float(s_.mm_per_unit), s_.vein_scale));
        return r;
    }

    // Photon i of batch k: its source (lights in order, then the environment), its channel
    // (i mod 3, weight x 3), then the walk.
    void trace_photon(const TruthPrep& p, vec3 centre, float radius, int sources, int photons, int k, int i, std::vector<dvec3>& out) const {
        TruthRng rng(p.seed ^ 0x7472616e736c75ull, uint64_t(p.geometry) << 32 | uint64_t(i), uint64_t(k));
        const int source = i % sources, channel = (i / sources) % 3;
        const double per_source = double(photons) / double(sources);
        vec3 o, d;
        double power = 0.0;
        const float u1 = rng.next(), u2 = rng.next(), u3 = rng.next(), u4 = rng.next();
        auto disc = [&](vec3 towards_source) {  // a point of the disc facing `towards_source`, beyond the sphere
            vec3 t, b;
            basis(towards_source, t, b);
            const float r = radius * std::sqrt(u1), phi = 2.f * kPi * u2;
            o = centre + towards_source * (1.01f * radius) + r * (std::cos(phi) * t + std::sin(phi) * b);
            d = -towards_source;
        };
        if (source < int(p.lighting.lights.size())) {
            const Light& l = p.lighting.lights[size_t(source)];
            if (!l.point) {
                disc(glm::normalize(l.direction));
                power = double(l.radiance[channel]) * kPi * double(radius) * radius;
            } else {
                const vec3 to = centre - l.position;
                const float dist = glm::length(to);
                const double cos_max = dist > radius ? std::sqrt(1.0 - double(radius) * radius / (double(dist) * dist)) : -1.0;
                const double cos_t = 1.0 - double(u3) * (1.0 - cos_max), sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
                vec3 t, b;
                const vec3 axis = dist > 0.f ? to / dist : vec3(0.f, 0.f, 1.f);
                basis(axis, t, b);
                const float phi = 2.f * kPi * u4;
                o = l.position;
                d = glm::normalize(float(sin_t) * (std::cos(phi) * t + std::sin(phi) * b) + float(cos_t) * axis);
                power = double(l.radiance[channel]) * 2.0 * std::numbers::pi * (1.0 - cos_max);
            }
        } else {
            const vec3 w = uniform_sphere(u3, u4);  // towards where the light comes from
            disc(w);
            power = double(p.lighting.env.radiance(w)[channel]) * 4.0 * std::numbers::pi * std::numbers::pi * double(radius) * radius;
        }
        double weight = 3.0 * power / per_source;
        if (!(weight > 0.0)) return;
        // Into the medium.
        const RayHit in = p.rt.intersect(o, d);
        if (in.geometry != p.geometry) return;  // shadowed by another object, or missed
        vec3 n = glm::normalize(in.ng);
        if (glm::dot(n, d) > 0.f) n = -n;  // facing the photon: outwards here
        double cos_i = -double(glm::dot(n, d)), cos_t = 0.0;
        const double eta = s_.medium.eta;
        weight *= 1.0 - fresnel(cos_i, eta, cos_t);
        vec3 x = o + in.t * d - n * p.eps;  // just inside
        d = refract(d, n, eta, cos_i, cos_t);
        const double sigma_t = (s_.medium.sigma_s[channel] + s_.medium.sigma_a[channel]) * mm_per_world_;  // 1 / world unit
        const double albedo = (s_.medium.sigma_s[channel] + s_.medium.sigma_a[channel]) > 0.0
                                  ? s_.medium.sigma_s[channel] / (s_.medium.sigma_s[channel] + s_.medium.sigma_a[channel]) : 0.0;
        for (int step = 0; step < 1000000; ++step) {
            const double free = sigma_t > 0.0 ? -std::log(1.0 - double(rng.next())) / sigma_t : 3.4e38;
            const RayHit h = p.rt.intersect(x, d, 0.f, float(std::min(free, 3.4e38)));
            if (h.hit()) {
                if (h.geometry != p.geometry) return;  // another object inside this one: absorbed there
                vec3 m = glm::normalize(h.ng);
                if (glm::dot(m, d) > 0.f) m = -m;  // facing the photon: inwards
                const vec3 at = x + h.t * d;
                double ci = -double(glm::dot(m, d)), ct = 0.0;
                const double F = fresnel(ci, 1.0 / eta, ct);
                if (double(rng.next()) < F) {  // reflected back in (always beyond the critical angle)
                    d = glm::normalize(d + float(2.0 * ci) * m);
                    x = at + m * p.eps;
                    continue;
                }
                // Out: the power goes to the triangle's vertices by barycentric weight.
                const size_t f = size_t(h.triangle);
                const double w0 = 1.0 - double(h.u) - double(h.v);
                out[mesh_->index[3 * f]][channel] += weight * w0;
                out[mesh_->index[3 * f + 1]][channel] += weight * double(h.u);
                out[mesh_->index[3 * f + 2]][channel] += weight * double(h.v);
                return;
            }
            x += float(free) * d;
            weight *= albedo;
            if (!(weight > 0.0)) return;
            if (weight < 0.2 * 3.0 * power / per_source) {  // Russian roulette below a fifth of the start
                if (rng.next() < 0.5f) return;
                weight *= 2.0;
            }
            d = uniform_sphere(rng.next(), rng.next());
        }
    }

    std::shared_ptr<const TriMesh> mesh_;
    mat4 to_world_, from_world_;
    Settings s_;
    double mm_per_world_;
    std::optional<Image> map_;
    double t_bar_ = 1.0;
    std::vector<double> area_;
    int first_ = 0;
    std::vector<std::vector<vec3>> batches_;
};
}  // namespace

TruthObject TranslucencyTechnique::truth_object(const Scene& s, const Evaluation& ev, int object) const {
    const SceneObject& o = s.objects.at(size_t(object));
    const auto mesh = ev.get(mesolab::stages::geometry, object);
    if (!mesh) throw std::logic_error("translucency truth: scene.geometry was not evaluated");
    const std::string what = "object '" + o.name + "' (" +
                             (o.geometry.get_string("type") == "mesh" ? s.resolve(o.geometry.get_string("path")) : "geometry.type " + o.geometry.get_string("type")) + ")";
    int holes = 0;
    auto closed = std::make_shared<const TriMesh>(closed_mesh(*mesh, what, holes));
    if (o.geometry.get_string("type") == "plane")  // not a solid with holes: a sheet
        throw InputError("--backend truth: " + what + ": translucency's truth needs a closed mesh (light travels inside it), and a plane is open");
    (void)holes;
    const Settings st = Settings::from(o, Settings::Medium_ | Settings::Scale | Settings::Rho);
    std::optional<Image> map;
    if (!st.albedo_map.empty()) {
        if (mesh->uv.empty()) throw InputError("translucency.albedo_map: " + s.resolve(st.albedo_map) + " needs texture coordinates, and the object's mesh has none");
        map = read_image(s.resolve(st.albedo_map), true, true);
    }
    TruthObject t;
    t.mesh = closed;
    t.to_world = object_to_world(o);
    auto material = std::make_shared<TranslucentTruth>(closed, t.to_world, st, o.material.get_float("mm_per_unit"), std::move(map));
    t.material = material;
    t.prepare = [material](const TruthPrep& p) { material->prepare(p); };
    return t;
}

std::vector<StageName> TranslucencyTechnique::truth_stages() const { return {}; }

std::vector<std::string> TranslucencyTechnique::truth_params() const {
    return {"translucency.material", "translucency.sigma_s", "translucency.sigma_a", "translucency.eta", "translucency.mm_per_unit",
            "translucency.albedo_map", "translucency.veins", "translucency.vein_scale", "translucency.vein_color"};
}
}  // namespace mesolab::translucency
