// Technique translucency: its truth. Volumetric light transport in the object's own (closed,
// undecimated) mesh: a homogeneous medium of reduced scattering σs′ and absorption σa with an
// isotropic phase function (the similarity relation the dipole assumes), behind a smooth
// dielectric boundary of index η (exact Fresnel in and out, total internal reflection).
//
// Light paths start at the lights and the environment (a smooth boundary cannot be connected to
// a pinhole camera): photons from a disc covering the object (directional lights, environment) or
// from the point light towards it, shadowed by everything in the scene, enter with the Fresnel
// transmittance, walk (free paths of mean 1/σt, albedo σs′/σt per step, Russian roulette below a
// fifth of the weight), reflect or leave at the boundary by the exact Fresnel reflectance. Each
// sample of the truth is an independent batch of photons (16 per square of the smallest mean free
// path's side of the surface, at most 2^20, or 64 per point the camera sees where that is more, at
// most 2^22; fewer where a pilot shows each photon leaving many events, so that a batch keeps about
// 16 million events, 256 MB; split over the lights and the environment by the power each brings
// where the camera looks, a quarter evenly, one colour channel per photon), so the spread over samples is the
// exitance's standard error; a batch is traced, used for every pixel and dropped, one at a time.
// A sample's gather costs about the same however many photons it finds (its look-ups wait on memory
// more than they read), so larger batches than the surface alone asks for pay where many pixels
// look: 64 a point gave the least noise² × time of 16, 64 and 256 a patch (fig9-bright, 512²).
//
// The exitance at a point x the camera sees (truth.h) does not depend on the mesh's vertices:
// - the light that leaves straight from a scattering event (most of it) comes from the events'
//   density near x: from x, 16 directions into the medium (∝ cos θ) and on each 2 distances per
//   channel (∝ σt e^-σt t), the events within r_c (a quarter of the channel's mean free path) of
//   each such point over the ball's volume inside the medium, times T / (4 σt) (exitance_at);
// - the light that leaves after a reflection since its last event, or without any, is the power of
//   those photons that left within r_c of x, over π r_c²; the light that crosses to the first wall
//   without scattering and leaves there is each photon's expected share of it (walk, [Ballistic]).
// Both blur at r_c, which the slab of tests/translucency (12 triangles or 3 mm squares, r and r/2)
// shows to be below the noise. A photon's free path shorter than the distance to the nearest
// triangle (DistanceBound) moves without a ray cast: the same result as casting it, sooner.
//
// The camera sees M as radiance with the real-time display's angular distribution and texture:
// L = ρ(x) T(cos θo) M / (π t̄), t̄ = 2 ∫ T(μ) μ dμ over [0, 1] with the paper's Schlick T, so that
// the power leaving is M. That step is a model (as the display's is); the exitance is not. Light
// reflected at the surface, and light other objects reflect onto it, are left out, as on the
// real-time path. The AOV irradiance is the power per unit area entering the medium: the lights'
// irradiance on the facet with the exact Fresnel transmittance, shadowed, and the sky's.
#include "core/basic/basic.h"
#include "core/parallel.h"
#include "core/error.h"
#include "core/raytrace.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"
#include "core/translucency/truth.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
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

// The distance from q to the triangle (a, b, c).
float triangle_distance(vec3 q, vec3 a, vec3 b, vec3 c) {
    // Ericson's closest point on a triangle, by the Voronoi regions of its vertices, edges and face.
    const vec3 ab = b - a, ac = c - a, ap = q - a;
    const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.f && d2 <= 0.f) return glm::length(q - a);
    const vec3 bp = q - b;
    const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.f && d4 <= d3) return glm::length(q - b);
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.f && d1 >= 0.f && d3 <= 0.f) return glm::length(q - (a + ab * (d1 / (d1 - d3))));
    const vec3 cp = q - c;
    const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.f && d5 <= d6) return glm::length(q - c);
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.f && d2 >= 0.f && d6 <= 0.f) return glm::length(q - (a + ac * (d2 / (d2 - d6))));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.f && (d4 - d3) >= 0.f && (d5 - d6) >= 0.f) return glm::length(q - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const float den = 1.f / (va + vb + vc);
    return glm::length(q - (a + ab * (vb * den) + ac * (vc * den)));
}

// The mean curvature of each triangle, world units: H = tr(S) / 2, S the shape operator of the
// normals the mesh interpolates (dN = S dP along the triangle's edges, in its plane), positive where
// the outward normals spread (a convex bump). 0 for a mesh without normals.
std::vector<float> facet_mean_curvature(const TriMesh& m, const mat4& to_world) {
    std::vector<float> H(m.triangle_count(), 0.f);
    if (m.normal.size() != m.vertex_count()) return H;
    const glm::mat3 nm = glm::transpose(glm::inverse(glm::mat3(to_world)));
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const uint32_t i0 = m.index[3 * f], i1 = m.index[3 * f + 1], i2 = m.index[3 * f + 2];
        const vec3 p0 = vec3(to_world * vec4(m.position[i0], 1.f)), p1 = vec3(to_world * vec4(m.position[i1], 1.f)), p2 = vec3(to_world * vec4(m.position[i2], 1.f));
        const vec3 e1 = p1 - p0, e2 = p2 - p0;
        vec3 ng = glm::cross(e1, e2);
        const float len = glm::length(ng);
        if (!(len > 0.f)) continue;
        ng /= len;
        vec3 n0 = nm * m.normal[i0], n1 = nm * m.normal[i1], n2 = nm * m.normal[i2];
        if (!(glm::dot(n0, n0) > 0.f) || !(glm::dot(n1, n1) > 0.f) || !(glm::dot(n2, n2) > 0.f)) continue;
        n0 = glm::normalize(n0), n1 = glm::normalize(n1), n2 = glm::normalize(n2);
        const float orient = glm::dot(n0 + n1 + n2, ng) < 0.f ? -1.f : 1.f;  // normals facing out as the winding, or not
        // In the triangle's plane: the edges' coordinates and the normals' changes along them.
        const vec3 t = glm::normalize(e1), b = glm::cross(ng, t);
        const glm::mat2 P(glm::dot(e1, t), glm::dot(e1, b), glm::dot(e2, t), glm::dot(e2, b));  // columns: the edges
        const vec3 d1 = (n1 - n0) * orient, d2 = (n2 - n0) * orient;
        const glm::mat2 D(glm::dot(d1, t), glm::dot(d1, b), glm::dot(d2, t), glm::dot(d2, b));
        const float det = glm::determinant(P);
        if (!(std::fabs(det) > 0.f)) continue;
        const glm::mat2 S = D * glm::inverse(P);
        H[f] = 0.5f * (S[0][0] + S[1][1]);
    }
    return H;
}

// Per sample, per channel: the photons' exits (those the events do not account for) and their
// scattering events near the surface.
struct Batch {
    std::array<CellMap<PhotonExit>, 3> exits;      // cells of 2 r_c
    std::array<CellMap<ScatterVertex>, 3> events;  // cells of 4 r_c (fewer, larger look-ups beat more, smaller ones)
};

class TranslucentTruth final : public TruthMaterial {
public:
    TranslucentTruth(std::shared_ptr<const TriMesh> mesh, mat4 to_world, Settings s, double mm_per_world, std::optional<Image> map, dvec3 radius_mm)
        : mesh_(std::move(mesh)), to_world_(to_world), from_world_(glm::inverse(to_world)), s_(std::move(s)), mm_per_world_(mm_per_world),
          map_(std::move(map)) {
        t_bar_ = diffuse_transmittance(s_.medium.eta);
        lo_ = vec3(1e30f), hi_ = vec3(-1e30f);
        for (const vec3& q : mesh_->position) {
            const vec3 w = vec3(to_world_ * vec4(q, 1.f));
            lo_ = glm::min(lo_, w), hi_ = glm::max(hi_, w);
        }
        double area = 0.0;  // world units²
        for (size_t f = 0; f < mesh_->triangle_count(); ++f) {
            const vec3 pa = vec3(to_world_ * vec4(mesh_->position[mesh_->index[3 * f]], 1.f)), pb = vec3(to_world_ * vec4(mesh_->position[mesh_->index[3 * f + 1]], 1.f)),
                       pc = vec3(to_world_ * vec4(mesh_->position[mesh_->index[3 * f + 2]], 1.f));
            area += 0.5 * double(glm::length(glm::cross(pb - pa, pc - pa)));
        }
        mean_curvature_ = facet_mean_curvature(*mesh_, to_world_);
        plain_ = std::getenv("MESOLAB_TRUTH_PLAIN") != nullptr;
        double smallest = double(glm::length(hi_ - lo_));  // mean free path, world units
        for (int c = 0; c < 3; ++c) {
            radius_[c] = float(radius_mm[c] / mm_per_world_);
            disc_[c] = std::numbers::pi * double(radius_[c]) * double(radius_[c]);
            ball_[c] = 4.0 / 3.0 * disc_[c] * double(radius_[c]);
            sigma_t_[c] = (s_.medium.sigma_s[c] + s_.medium.sigma_a[c]) * mm_per_world_;
            // Events deeper than kDepth mean free paths are not kept: the light they send straight
            // out is below e^-kDepth of it.
            depth_[c] = float(sigma_t_[c] > 0.0 ? kDepth / sigma_t_[c] : 3.4e38);
            if (sigma_t_[c] > 0.0) smallest = std::min(smallest, 1.0 / sigma_t_[c]);
        }
        longest_ = glm::length(hi_ - lo_) * 1.01f;
        // Photons per sample: kPhotonsPerPatch per square of the smallest mean free path's side of
        // the surface, within [2^14, 2^20] (prepare raises it for the points the camera sees).
        photons_ = int(std::clamp(kPhotonsPerPatch * area / (smallest * smallest), double(1 << 14), double(1 << 20)));
    }

    int photons_per_sample() const { return photons_; }
    dvec3 radius_mm() const { return dvec3(radius_[0], radius_[1], radius_[2]) * mm_per_world_; }

    vec3 f(const TruthHit&, vec3, vec3) const override { return vec3(0.f); }
    bool emitter() const override { return true; }
    bool medium() const override { return true; }
    float transmittance(const TruthHit& h, vec3 wi) const override {
        double cos_t = 0.0;
        return float(1.0 - fresnel(std::fabs(double(glm::dot(h.ng, wi))), s_.medium.eta, cos_t));
    }
    vec3 exitance(const TruthHit& h, uint64_t sample) const override {
        if (sample < uint64_t(first_) || sample - uint64_t(first_) >= batches_.size()) return vec3(0.f);
        const float H = h.triangle >= 0 && size_t(h.triangle) < mean_curvature_.size() ? mean_curvature_[size_t(h.triangle)] : 0.f;
        return exitance_at(batches_[size_t(sample - uint64_t(first_))], h.p, h.ng, H, sample);
    }
    vec3 emitted(const TruthHit& h, vec3 wo, uint64_t sample) const override {
        const float T = float(fresnel_transmittance(std::fabs(glm::dot(h.n, wo)), s_.medium.eta));
        return rho(h) * T * exitance(h, sample) / float(kPi * t_bar_);
    }

    // The photon batches of samples [first, end): each traced in chunks on every core, its exits
    // and scattering events in the photons' order.
    void prepare(const TruthPrep& p) {
        if (bound_.empty()) bound_ = DistanceBound(p.rt, lo_, hi_);
        first_ = p.first;
        seed_ = p.seed;
        rt_ = &p.rt;
        eps_ = p.eps;
        batches_.clear();
        const vec3 centre = 0.5f * (lo_ + hi_);
        const float radius = 0.5f * glm::length(hi_ - lo_) * 1.001f + p.eps;
        const int sources = int(p.lighting.lights.size()) + (p.lighting.env_lighting ? 1 : 0);
        const int samples = p.end - p.first;
        batches_.resize(size_t(std::max(0, samples)));
        if (sources == 0 || samples <= 0) return;
        std::vector<double> power = source_power(p.lighting, centre, radius);
        if (!guided_) {
            guided_ = true;
            if (!plain_ && !std::getenv("MESOLAB_TRUTH_NO_IMPORTANCE") && p.seen && !p.seen->empty()) guide(p, centre, radius, power);
        }
        if (!useful_.empty()) power = useful_;  // photons split by the power that reaches what the camera sees
        constexpr int kChunks = 64;
        if (!sized_) {
            // The events a photon leaves near the surface, from a pilot of kPilot photons whose
            // streams no sample uses (the same in every process): fewer photons a sample where each
            // leaves many (a batch's events stay within kMostEvents), whatever the range of samples.
            TruthPrep pilot = p;
            pilot.seed = 0x70696c6f74ull;
            std::vector<Walks> walks(kChunks);
            const std::vector<int> split = allocate(power, kPilot);
            mesolab::parallel_for(0, kChunks, [&](int c) {
                for (int i = c; i < split.back(); i += kChunks) trace_photon(pilot, centre, radius, split, 0, i, walks[size_t(c)]);
            });
            size_t events = 0;
            for (const Walks& w : walks)
                for (const auto& e : w.events) events += e.size();
            const double per_photon = std::max(1.0, double(events) / double(split.back()));
            // At least kPhotonsPerSeen a point the camera sees, within the events' budget.
            double photons = double(photons_);
            if (p.seen) photons = std::max(photons, kPhotonsPerSeen * double(p.seen->size()));
            photons_ = int(std::clamp(std::min(photons, double(kMostEvents) / per_photon), double(1 << 12), double(1 << 22)));
            sized_ = true;
        }
        const std::vector<int> split = allocate(power, photons_);
        std::vector<Walks> chunks(size_t(samples) * kChunks);
        mesolab::parallel_for(0, samples * kChunks, [&](int job) {
            if (p.cancel && p.cancel->load()) return;
            const int k = p.first + job / kChunks, c = job % kChunks;
            for (int i = c; i < split.back(); i += kChunks) trace_photon(p, centre, radius, split, k, i, chunks[size_t(job)]);
        });
        mesolab::parallel_for(0, 6 * samples, [&](int job) {
            const int j = job / 6, c = (job / 2) % 3;
            const vec3 origin = lo_ - vec3(4.f * radius_[c]);
            if (job % 2 == 0) {
                // The chunks in order: the same bytes at any thread count.
                std::vector<std::vector<PhotonExit>*> exits;
                for (int q = 0; q < kChunks; ++q) exits.push_back(&chunks[size_t(j) * kChunks + size_t(q)].exits[size_t(c)]);
                batches_[size_t(j)].exits[size_t(c)] = CellMap<PhotonExit>(exits, 2.f * radius_[c], origin);
            } else {
                std::vector<std::vector<ScatterVertex>*> events;
                for (int q = 0; q < kChunks; ++q) events.push_back(&chunks[size_t(j) * kChunks + size_t(q)].events[size_t(c)]);
                batches_[size_t(j)].events[size_t(c)] = CellMap<ScatterVertex>(events, 4.f * radius_[c], origin, [](const ScatterVertex& v) { return v.weight; });
            }
        });
    }

    // The exitance at x (world; n: the facet's outward unit normal) from batch b, per channel c.
    vec3 exitance_at(const Batch& b, vec3 x, vec3 n, float H, uint64_t sample) const {
        // [Events] The light that leaves at x straight from a scattering event (the photons'
        // weight w as they leave an event, isotropic; ρ_c the events' density of w per unit volume):
        //   M_d(x) = ∫ over ω into the medium ∫_0^t_b  ρ_c(x + t ω) e^(-σt t) / (4π) T(θ) cos θ  dt dω,
        // θ between -ω and n, t_b where ω meets the boundary, T the exact Fresnel transmittance
        // out (0 beyond the critical angle). kDirections directions ∝ cos θ (stratified), and on
        // each kDistances distances ∝ σt e^(-σt t) (stratified): each point z before t_b adds
        //   T ρ_c(z) / (4 σt),
        // ρ_c(z) the events within r_c of z over the ball's volume inside the medium (less the cap
        // beyond x's facet plane). Nothing grows without bound as z nears x: the 1/t² of the
        // solid angle is the t² of the volume the directions sweep.
        TruthRng rng(seed_ ^ 0x726576657273ull, position_bits(x), sample);
        vec3 t_axis, b_axis;
        basis(-n, t_axis, b_axis);
        dvec3 M(0.0);
        constexpr int directions = kDirections;
        constexpr int side = 4;  // directions: one in each cell of a side x side grid over the unit square
        static_assert(side * side == directions);
        for (int k = 0; k < directions; ++k) {
            const float u1 = (float(k % side) + rng.next()) / float(side), u2 = (float(k / side) + rng.next()) / float(side);
            const float rr = std::sqrt(u1), phi = 2.f * kPi * u2, cos_theta = std::sqrt(std::max(0.f, 1.f - u1));
            if (!(cos_theta > 1e-4f)) continue;
            const double T = transmittance_out(cos_theta);
            if (!(T > 0.0)) continue;
            const vec3 w = glm::normalize(rr * std::cos(phi) * t_axis + rr * std::sin(phi) * b_axis - cos_theta * n);
            const vec3 o = x - eps_ * n;
            const RayHit wall = rt_->intersect(o, w, 0.f, longest_);
            const double t_b = wall.hit() ? double(wall.t) : double(longest_);
            // The wall's plane across the ray: a point t along it lies (t_b - t) cos_w from it.
            const double cos_w = wall.hit() ? std::fabs(double(glm::dot(glm::normalize(wall.ng), w))) : 0.0;
            const float shift = rng.next();
            for (int c = 0; c < 3; ++c) {
                if (!(sigma_t_[c] > 0.0) || !(radius_[c] > 0.f)) continue;
                double sum = 0.0;
                for (int j = 0; j < kDistances; ++j) {
                    const double u = (double(j) + double(shift)) / double(kDistances);
                    const double t = -std::log(1.0 - u) / sigma_t_[c];
                    if (!(t < t_b)) break;  // the boundary comes first: nothing beyond it sends light straight to x
                    if (t + double(radius_[c]) > double(depth_[c])) break;  // deeper than the events kept: below e^-kDepth
                    const vec3 z = o + float(t) * w;
                    // The ball: r_c, or as far as the wall the ray meets (at least r_c / 4), so that
                    // only x's facet plane cuts it as a rule.
                    const double hw = wall.hit() ? (t_b - t) * cos_w : 3.4e38;  // distance to the wall's plane
                    const double rd = std::clamp(hw, 0.25 * double(radius_[c]), double(radius_[c]));
                    const double found = b.events[size_t(c)].weight_within(z, float(rd));
                    if (!(found > 0.0)) continue;
                    // Its volume inside the medium: less the cap beyond x's facet plane and, to first
                    // order, the sliver between that plane and the surface bending away by its mean
                    // curvature H (∫ over the cap's base, radius a, of (κ1 x² + κ2 y²) / 2 = H π a⁴ / 4);
                    // less the cap beyond the wall where the ball still reaches it.
                    const double h = t * double(cos_theta);  // depth below x's facet plane
                    double volume = 4.0 / 3.0 * std::numbers::pi * rd * rd * rd;
                    if (h < rd) {
                        const double a2 = rd * rd - h * h;
                        volume -= std::numbers::pi * (rd - h) * (rd - h) * (2.0 * rd + h) / 3.0 + double(H) * std::numbers::pi * a2 * a2 / 4.0;
                    }
                    if (hw < rd) volume -= std::numbers::pi * (rd - hw) * (rd - hw) * (2.0 * rd + hw) / 3.0;
                    sum += found / std::max(volume, 0.05 * rd * rd * rd);
                }
                M[c] += T * sum / (4.0 * sigma_t_[c] * double(kDistances));
            }
        }
        M /= double(directions);
        // [Exits] The light that left after a reflection since its last event, or without any:
        // the exits within r_c on a facet not turned away from n by more than 120°, their power
        // over π r_c².
        for (int c = 0; c < 3; ++c) {
            const float r2 = radius_[c] * radius_[c];
            double sum = 0.0;
            b.exits[size_t(c)].for_each_near(x, radius_[c], [&](const PhotonExit& e) {
                const vec3 d = e.p - x;
                if (glm::dot(d, d) > r2) return;
                if (float(e.n[0]) * n.x + float(e.n[1]) * n.y + float(e.n[2]) * n.z < -0.5f * 127.f) return;  // the far side of a sheet
                sum += double(e.power);
            });
            if (sum > 0.0) M[c] += sum / disc_[c];
        }
        return vec3(M);
    }

private:
    static constexpr double kDepth = 8.0;  // events kept within this many mean free paths of the surface
    static constexpr double kPhotonsPerPatch = 16.0;
    static constexpr double kPhotonsPerSeen = 64.0;
    static constexpr int kDirections = 16;  // directions from a point per sample
    static constexpr int kPilot = 4096;      // photons that size a batch
    static constexpr double kMostEvents = 16.0 * (1 << 20);  // events kept a sample, about (16 bytes each)
    static constexpr int kDistances = 2;    // points on each direction per channel
    static constexpr double kBallistic = 3.0;  // mean free paths to the first wall within which its exit is kept as expected
    static constexpr int kGuide = 64;       // cells per side of a source's guided square (importance)
    static constexpr int kGuidePilot = 32;  // pilot photons a cell

    // What a chunk of photons left: per channel, their exits and their events near the surface.
    struct Walks {
        std::array<std::vector<PhotonExit>, 3> exits;
        std::array<std::vector<ScatterVertex>, 3> events;
    };

    static uint64_t position_bits(vec3 x) {
        uint32_t b[3];
        std::memcpy(b, &x, sizeof b);
        return (uint64_t(b[0]) * 0x9e3779b97f4a7c15ull) ^ (uint64_t(b[1]) << 21) ^ (uint64_t(b[2]) * 0xc2b2ae3d27d4eb4full);
    }
    // The exact Fresnel transmittance from inside at cos θ (0 beyond the critical angle).
    double transmittance_out(float cos_theta) const {
        double ct = 0.0;
        return 1.0 - fresnel(double(cos_theta), 1.0 / s_.medium.eta, ct);
    }

    vec3 rho(const TruthHit& h) const {
        vec3 r(1.f);
        if (map_) r = basic::sample_albedo(*map_, h.uv);
        if (s_.veins > 0.f)
            r *= glm::mix(vec3(1.f), s_.vein_color, s_.veins * vein(vec3(from_world_ * vec4(h.p, 1.f)) * float(s_.mm_per_unit), s_.vein_scale));
        return r;
    }

    // The power each source (the lights in order, then the environment) sends towards the sphere
    // (centre, radius) around the object, summed over the channels: where its photons start.
    std::vector<double> source_power(const Lighting& lighting, vec3 centre, float radius) const {
        std::vector<double> power;
        const double disc = std::numbers::pi * double(radius) * double(radius);
        for (const Light& l : lighting.lights) {
            const double sum = double(l.radiance.r) + double(l.radiance.g) + double(l.radiance.b);
            if (!l.point) {
                power.push_back(sum * disc);
            } else {
                const float dist = glm::length(centre - l.position);
                const double cos_max = dist > radius ? std::sqrt(1.0 - double(radius) * radius / (double(dist) * dist)) : -1.0;
                power.push_back(sum * 2.0 * std::numbers::pi * (1.0 - cos_max));
            }
        }
        if (lighting.env_lighting) {
            // The environment's mean radiance over the sphere, from a fixed spiral of directions.
            constexpr int kDirs = 1024;
            double sum = 0.0;
            for (int j = 0; j < kDirs; ++j) {
                const float z = 1.f - (2.f * float(j) + 1.f) / float(kDirs), r = std::sqrt(std::max(0.f, 1.f - z * z));
                const float phi = float(j) * 2.39996323f;  // the golden angle
                const vec3 L = lighting.env.radiance(vec3(r * std::cos(phi), r * std::sin(phi), z));
                sum += double(L.r) + double(L.g) + double(L.b);
            }
            power.push_back(sum / kDirs * 4.0 * std::numbers::pi * disc);
        }
        return power;
    }
    // The photons of a batch of about `total` per source: in proportion to the source's power
    // (photons emitted by power, Jensen 2001, "Realistic Image Synthesis Using Photon Mapping",
    // §5.1), three quarters of them, and the last quarter split evenly, so that a dim source keeps
    // some photons (the light of a dim sky where the sun does not reach); a multiple of 3 each,
    // one channel per photon in turn. Source s emits photons [end[s - 1], end[s]), end[-1] = 0.
    // MESOLAB_TRUTH_PLAIN=1 (a developer switch, for measuring) splits them evenly instead.
    std::vector<int> allocate(const std::vector<double>& power, int total) const {
        double all = 0.0;
        for (double q : power) all += std::max(0.0, q);
        std::vector<int> end;
        int at = 0;
        for (double q : power) {
            const double share = all > 0.0 && !plain_ ? 0.75 * std::max(0.0, q) / all + 0.25 / double(power.size()) : 1.0 / double(power.size());
            at += 3 * std::max(1, int(std::lround(double(total) * share / 3.0)));
            end.push_back(at);
        }
        return end;
    }

    // Photon i of batch k: its source (split: allocate's), its channel (in turn, each a third of
    // the source's photons, weight x 3), where it starts (emit; the source's guide, when it has
    // one, picks the cell of its two guided numbers) and its walk.
    void trace_photon(const TruthPrep& p, vec3 centre, float radius, const std::vector<int>& split, int k, int i, Walks& out) const {
        TruthRng rng(p.seed ^ 0x7472616e736c75ull, uint64_t(p.geometry) << 32 | uint64_t(i), uint64_t(k));
        const int source = int(std::upper_bound(split.begin(), split.end(), i) - split.begin());
        const int start = source == 0 ? 0 : split[size_t(source) - 1];
        const int channel = (i - start) % 3;
        const double per_source = double(split[size_t(source)] - start);
        float u[4] = {rng.next(), rng.next(), rng.next(), rng.next()};
        double factor = 1.0;  // the uniform cell's probability over the guided cell's
        if (size_t(source) < guides_.size() && !guides_[size_t(source)].cdf.empty()) {
            const Guide& g = guides_[size_t(source)];
            const float pick = rng.next();
            const int cell = int(std::min<size_t>(g.cdf.size() - 1, size_t(std::upper_bound(g.cdf.begin(), g.cdf.end(), double(pick)) - g.cdf.begin())));
            factor = g.factor[size_t(cell)];
            const int a = guided_pair(p.lighting, source);
            u[a] = (float(cell % kGuide) + u[a]) / float(kGuide), u[a + 1] = (float(cell / kGuide) + u[a + 1]) / float(kGuide);
        }
        vec3 o, d;
        const double power = emit(p.lighting, centre, radius, source, channel, u, o, d);
        walk(p, o, d, 3.0 * power / per_source * factor, channel, rng, out);
    }

    // [Importance] More photons where the camera sees the object: importance-driven photon
    // emission (Peter and Pietrek 1998, "Importance Driven Construction of Photon Maps", EGWR),
    // with the camera's view as the importance. Each source's two guided numbers (guided_pair)
    // fall in a kGuide x kGuide grid of cells of equal probability under the plain emission; a
    // pilot of kGuidePilot photons a cell (their own streams, the same in every process) measures
    // what each cell's photons bring near the seen points: the weight of their scattering events
    // and exits within `reach` of one (three of the largest mean free path plus two radii, where
    // the gather finds them). A photon then picks cell c with probability
    //   P_c = 0.75 U_c / sum U + 0.25 / kGuide²,
    // U_c that pilot's figure, and carries the weight times (1 / kGuide²) / P_c: the mean is the
    // plain emission's for any U (a defensive mixture: a cell the pilot found useless keeps a
    // quarter of its photons, at 4 times their weight). The sources share the photons by the power
    // each brings near the seen points (the mean of U over the cells) in place of the power each
    // sends towards the object. Points the camera sees only through other surfaces (a mirror) keep
    // the defensive share.
    void guide(const TruthPrep& p, vec3 centre, float radius, const std::vector<double>& power) {
        // The seen points, dilated by `reach`: cells of a grid over the object's box.
        float reach = 0.f;
        for (int c = 0; c < 3; ++c)
            if (sigma_t_[c] > 0.0) reach = std::max(reach, float(3.0 / sigma_t_[c]) + 2.f * radius_[c]);
        if (!(reach > 0.f)) reach = longest_;
        reach = std::min(reach, longest_);
        const vec3 lo = lo_ - vec3(reach), ext = hi_ - lo_ + vec3(2.f * reach);
        const float cell = std::max(0.5f * reach, std::max({ext.x, ext.y, ext.z}) / 160.f);
        const glm::ivec3 n = glm::max(glm::ivec3(glm::ceil(ext / cell)), glm::ivec3(1));
        auto index = [&](int x, int y, int z) { return (size_t(z) * size_t(n.y) + size_t(y)) * size_t(n.x) + size_t(x); };
        std::vector<uint8_t> near(size_t(n.x) * size_t(n.y) * size_t(n.z), 0);
        for (const vec3& q : *p.seen) {
            const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((q - lo) / cell)), glm::ivec3(0), n - 1);
            near[index(c.x, c.y, c.z)] = 1;
        }
        // Dilated by m cells along each axis in turn (a running count over the window).
        const int m = int(std::ceil(reach / cell));
        for (int axis = 0; axis < 3; ++axis) {
            const int len = n[axis];
            const glm::ivec3 step(axis == 0, axis == 1, axis == 2);
            const glm::ivec3 lines = n - step * (len - 1);
            std::vector<uint8_t> line(static_cast<size_t>(len));
            for (int z = 0; z < lines.z; ++z)
                for (int y = 0; y < lines.y; ++y)
                    for (int x = 0; x < lines.x; ++x) {
                        for (int i = 0; i < len; ++i) line[size_t(i)] = near[index(x + step.x * i, y + step.y * i, z + step.z * i)];
                        int count = 0;
                        for (int i = 0; i < std::min(len, m); ++i) count += line[size_t(i)];
                        for (int i = 0; i < len; ++i) {
                            if (i + m < len) count += line[size_t(i + m)];
                            if (i - m - 1 >= 0) count -= line[size_t(i - m - 1)];
                            near[index(x + step.x * i, y + step.y * i, z + step.z * i)] = count > 0;
                        }
                    }
        }
        auto seen_near = [&](vec3 q) {
            const glm::ivec3 c = glm::ivec3(glm::floor((q - lo) / cell));
            if (glm::any(glm::lessThan(c, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(c, n))) return false;
            return near[index(c.x, c.y, c.z)] != 0;
        };
        // The pilot: per source and cell, the mean weight its photons bring near the seen points.
        constexpr int cells = kGuide * kGuide;
        const int sources = int(power.size());
        std::vector<double> U(size_t(sources) * cells, 0.0);
        mesolab::parallel_for(0, sources * cells, [&](int job) {
            const int source = job / cells, c = job % cells;
            if (!(power[size_t(source)] > 0.0)) return;
            const int a = guided_pair(p.lighting, source);
            Walks w;
            double sum = 0.0;
            for (int j = 0; j < kGuidePilot; ++j) {
                TruthRng rng(0x6775696465ull, uint64_t(p.geometry) << 32 | uint64_t(job), uint64_t(j));
                float u[4] = {rng.next(), rng.next(), rng.next(), rng.next()};
                u[a] = (float(c % kGuide) + u[a]) / float(kGuide), u[a + 1] = (float(c / kGuide) + u[a + 1]) / float(kGuide);
                vec3 o, d;
                const int channel = j % 3;
                const double start = 3.0 * emit(p.lighting, centre, radius, source, channel, u, o, d);
                walk(p, o, d, start, channel, rng, w);
                for (int ch = 0; ch < 3; ++ch) {
                    for (const ScatterVertex& v : w.events[size_t(ch)])
                        if (seen_near(v.p)) sum += double(v.weight);
                    for (const PhotonExit& e : w.exits[size_t(ch)])
                        if (seen_near(e.p)) sum += double(e.power);
                    w.events[size_t(ch)].clear(), w.exits[size_t(ch)].clear();
                }
            }
            U[size_t(job)] = sum / double(kGuidePilot);
        });
        guides_.assign(size_t(sources), Guide{});
        useful_.assign(size_t(sources), 0.0);
        double any = 0.0;
        for (int source = 0; source < sources; ++source) {
            double total = 0.0;
            for (int c = 0; c < cells; ++c) total += U[size_t(source) * cells + size_t(c)];
            useful_[size_t(source)] = total / double(cells);
            any += total;
            if (!(total > 0.0)) continue;
            Guide& g = guides_[size_t(source)];
            double cdf = 0.0;
            for (int c = 0; c < cells; ++c) {
                const double P = 0.75 * U[size_t(source) * cells + size_t(c)] / total + 0.25 / double(cells);
                cdf += P;
                g.cdf.push_back(cdf);
                g.factor.push_back(1.0 / (double(cells) * P));
            }
            for (double& v : g.cdf) v /= cdf;
        }
        if (!(any > 0.0)) useful_.clear();  // nothing seen is lit: the split by power
    }

    // Which two of a photon's four numbers place it (the guided pair, from index a): a sun's
    // point on its disc (0, 1); a point light's direction in its cone and the sky's direction (2, 3).
    static int guided_pair(const Lighting& lighting, int source) {
        return source < int(lighting.lights.size()) && !lighting.lights[size_t(source)].point ? 0 : 2;
    }

    // A photon of `source`, channel `channel`, from the numbers u: its start o and direction d
    // (towards the object), and the power the source sends that way in that channel (what the
    // photon would carry were it the source's only one).
    double emit(const Lighting& lighting, vec3 centre, float radius, int source, int channel, const float u[4], vec3& o, vec3& d) const {
        auto disc = [&](vec3 towards_source) {  // a point of the disc facing `towards_source`, beyond the sphere
            vec3 t, b;
            basis(towards_source, t, b);
            const float r = radius * std::sqrt(u[0]), phi = 2.f * kPi * u[1];
            o = centre + towards_source * (1.01f * radius) + r * (std::cos(phi) * t + std::sin(phi) * b);
            d = -towards_source;
        };
        if (source < int(lighting.lights.size())) {
            const Light& l = lighting.lights[size_t(source)];
            if (!l.point) {
                disc(glm::normalize(l.direction));
                return double(l.radiance[channel]) * kPi * double(radius) * radius;
            }
            const vec3 to = centre - l.position;
            const float dist = glm::length(to);
            const double cos_max = dist > radius ? std::sqrt(1.0 - double(radius) * radius / (double(dist) * dist)) : -1.0;
            const double cos_t = 1.0 - double(u[2]) * (1.0 - cos_max), sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
            vec3 t, b;
            const vec3 axis = dist > 0.f ? to / dist : vec3(0.f, 0.f, 1.f);
            basis(axis, t, b);
            const float phi = 2.f * kPi * u[3];
            o = l.position;
            d = glm::normalize(float(sin_t) * (std::cos(phi) * t + std::sin(phi) * b) + float(cos_t) * axis);
            return double(l.radiance[channel]) * 2.0 * std::numbers::pi * (1.0 - cos_max);
        }
        const vec3 w = uniform_sphere(u[2], u[3]);  // towards where the light comes from
        disc(w);
        return double(lighting.env.radiance(w)[channel]) * 4.0 * std::numbers::pi * std::numbers::pi * double(radius) * radius;
    }

    // A photon of `channel` starting at o towards d with `weight`, shadowed by everything in the
    // scene: its scattering events near the surface and, where it leaves after a reflection or
    // without scattering, its exit.
    void walk(const TruthPrep& p, vec3 o, vec3 d, double weight, int channel, TruthRng& rng, Walks& out) const {
        if (!(weight > 0.0)) return;
        const double start_weight = weight;
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
        const double sigma_t = sigma_t_[channel];  // 1 / world unit
        const double albedo = (s_.medium.sigma_s[channel] + s_.medium.sigma_a[channel]) > 0.0
                                  ? s_.medium.sigma_s[channel] / (s_.medium.sigma_s[channel] + s_.medium.sigma_a[channel]) : 0.0;
        // [Ballistic] Where the first wall the photon meets lies within kBallistic mean free paths,
        // the light that crosses to it without scattering and leaves there is kept as its expected
        // value: weight e^(-σt t) (1 - F) at that wall, for every such photon (an expected-value
        // estimate of one term of the walk's sum; Spanier and Gelbard 1969, "Monte Carlo
        // Principles and Neutron Transport Problems"); the walk below is drawn as before and
        // leaves nothing where its first flight ends there. Through a part thinner than a mean
        // free path (an ear) every photon then brings its share of that light, not a rare few all
        // of it. Farther walls (whether one is near depends only on where the photon enters, so
        // either estimate is unbiased) keep the drawn exit, and need no longer ray.
        const float near = sigma_t > 0.0 ? float(kBallistic / sigma_t) : 3.4e38f;
        const RayHit first = p.rt.intersect(x, d, 0.f, near);
        if (first.hit() && first.geometry == p.geometry) {
            vec3 m = glm::normalize(first.ng);
            if (glm::dot(m, d) > 0.f) m = -m;  // inwards
            double ct = 0.0;
            const double F = fresnel(-double(glm::dot(m, d)), 1.0 / eta, ct);
            const double crossed = weight * std::exp(-sigma_t * double(first.t)) * (1.0 - F);
            if (crossed > 0.0) out.exits[size_t(channel)].push_back(PhotonExit::through(x + first.t * d, float(crossed), m));
        }
        bool scattered = false, reflected = false;  // since the last scattering event
        for (int step = 0; step < 1000000; ++step) {
            const double free = sigma_t > 0.0 ? -std::log(1.0 - double(rng.next())) / sigma_t : 3.4e38;
            // Nothing within `free`: the ray cast would find nothing, so it is not cast. The first
            // flight's wall is known.
            const float bound = bound_.at(x);
            const RayHit h = step == 0 && (first.hit() || free < double(near)) ? (first.hit() && double(first.t) <= free ? first : RayHit{})
                             : free < double(bound) ? RayHit{} : p.rt.intersect(x, d, 0.f, float(std::min(free, 3.4e38)));
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
                    reflected = true;
                    continue;
                }
                // Out. Straight from an event: the events account for it; at the end of the first
                // flight: its expected value is kept already. Otherwise kept.
                if (!(step == 0 && first.hit()) && (!scattered || reflected)) out.exits[size_t(channel)].push_back(PhotonExit::through(at, float(weight), m));
                return;
            }
            x += float(free) * d;
            weight *= albedo;
            if (!(weight > 0.0)) return;
            // A scattering event: its light reaches the surface points in view of it. (It is within
            // `free` of where the bound was taken: deeper than kDepth mean free paths where that
            // bound, less `free`, says so.)
            if (double(bound) - free < double(depth_[channel])) out.events[size_t(channel)].push_back({x, float(weight)});
            scattered = true, reflected = false;
            if (weight < 0.2 * start_weight) {  // Russian roulette below a fifth of the start
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
    vec3 lo_{0.f}, hi_{0.f};  // the object's world bounds
    // Per channel, world units: the radius r_c, π r_c², the ball's volume, σt, the events' depth.
    float radius_[3] = {0.f, 0.f, 0.f};
    double disc_[3] = {0.0, 0.0, 0.0}, ball_[3] = {0.0, 0.0, 0.0}, sigma_t_[3] = {0.0, 0.0, 0.0};
    float depth_[3] = {0.f, 0.f, 0.f};
    float longest_ = 1.f;  // the bounding box's diagonal
    std::vector<float> mean_curvature_;  // per triangle, 1 / world unit (positive where the surface bends away from its outside)
    int photons_ = 0;  // per sample
    bool sized_ = false;  // photons_ set from the pilot
    bool plain_ = false;  // photons split evenly over the sources, no importance (MESOLAB_TRUTH_PLAIN)
    // Importance (guide): per source, the cells' cumulative probabilities and weight factors (none:
    // the plain emission), and the power each brings near the seen points (empty: split by power).
    struct Guide {
        std::vector<double> cdf, factor;
    };
    std::vector<Guide> guides_;
    std::vector<double> useful_;
    bool guided_ = false;  // guide ran (or had nothing to go on)
    DistanceBound bound_;
    const RayScene* rt_ = nullptr;  // the scene of the last prepare (it outlives the samples)
    float eps_ = 1e-4f;
    uint64_t seed_ = 0;
    int first_ = 0;
    std::vector<Batch> batches_;  // samples [first_, first_ + size)
};
}  // namespace

// [SECTION] The gather's radius, the distance bound and the photon map
dvec3 exitance_radius_mm(const Medium& medium, double bound_radius_mm) {
    dvec3 r;
    for (int c = 0; c < 3; ++c) {
        const double sigma_t = medium.sigma_s[c] + medium.sigma_a[c];
        r[c] = bound_radius_mm / 64.0;
        if (sigma_t > 0.0) r[c] = std::min(r[c], 0.25 / sigma_t);
        r[c] = std::max(r[c], bound_radius_mm * 0x1p-20);
    }
    return r;
}

DistanceBound::DistanceBound(const RayScene& rt, vec3 lo, vec3 hi, int cells_per_side) {
    const vec3 ext = hi - lo;
    const float longest = std::max({ext.x, ext.y, ext.z});
    if (!(longest > 0.f) || cells_per_side < 1) return;
    cell_ = longest / float(cells_per_side);
    inv_cell_ = 1.f / cell_;
    lo_ = lo - vec3(cell_);
    n_ = glm::ivec3(glm::ceil(ext * inv_cell_)) + glm::ivec3(2);
    n_ = glm::max(n_, glm::ivec3(1));
    const size_t count = size_t(n_.x) * size_t(n_.y) * size_t(n_.z);
    auto index = [&](int x, int y, int z) { return (size_t(z) * size_t(n_.y) + size_t(y)) * size_t(n_.x) + size_t(x); };
    std::vector<uint8_t> touched(count, 0);
    const vec3 box_hi = lo_ + vec3(n_) * cell_;
    const float half_diagonal = 0.5f * std::sqrt(3.f) * cell_ * 1.0001f;
    // Every point of a triangle lies in a cell whose centre is within half a diagonal of it: those
    // cells are touched.
    for (int g = 0; g < rt.geometry_count(); ++g) {
        const size_t triangles = rt.triangle_count(g);
        std::vector<std::vector<size_t>> marks(std::max<size_t>(1, std::min<size_t>(64, triangles)));
        mesolab::parallel_for(size_t(0), marks.size(), [&](size_t part) {
            for (size_t t = part; t < triangles; t += marks.size()) {
                vec3 a, b, c;
                rt.triangle(g, t, a, b, c);
                const vec3 tlo = glm::min(a, glm::min(b, c)), thi = glm::max(a, glm::max(b, c));
                if (glm::any(glm::lessThan(thi, lo_)) || glm::any(glm::greaterThan(tlo, box_hi))) continue;
                const glm::ivec3 c0 = glm::clamp(glm::ivec3(glm::floor((tlo - lo_) * inv_cell_)), glm::ivec3(0), n_ - 1);
                const glm::ivec3 c1 = glm::clamp(glm::ivec3(glm::floor((thi - lo_) * inv_cell_)), glm::ivec3(0), n_ - 1);
                const vec3 nrm = glm::cross(b - a, c - a);
                const float len = glm::length(nrm);
                const bool small = (c1.x - c0.x + 1) * (c1.y - c0.y + 1) * (c1.z - c0.z + 1) <= 8;
                for (int z = c0.z; z <= c1.z; ++z)
                    for (int y = c0.y; y <= c1.y; ++y)
                        for (int x = c0.x; x <= c1.x; ++x) {
                            if (!small) {
                                const vec3 q = lo_ + (vec3(x, y, z) + 0.5f) * cell_;
                                if (len > 0.f && std::fabs(glm::dot(q - a, nrm)) > half_diagonal * len) continue;
                                if (triangle_distance(q, a, b, c) > half_diagonal) continue;
                            }
                            marks[part].push_back(index(x, y, z));
                        }
            }
        });
        for (const auto& m : marks)
            for (size_t i : m) touched[i] = 1;
    }
    // The Chebyshev distance to a touched cell: two sweeps over the 26 neighbours.
    d_.assign(count, 255);
    for (size_t i = 0; i < count; ++i)
        if (touched[i]) d_[i] = 0;
    auto sweep = [&](int dir) {
        const int zb = dir > 0 ? 0 : n_.z - 1, ze = dir > 0 ? n_.z : -1;
        const int yb = dir > 0 ? 0 : n_.y - 1, ye = dir > 0 ? n_.y : -1;
        const int xb = dir > 0 ? 0 : n_.x - 1, xe = dir > 0 ? n_.x : -1;
        for (int z = zb; z != ze; z += dir)
            for (int y = yb; y != ye; y += dir)
                for (int x = xb; x != xe; x += dir) {
                    uint8_t& v = d_[index(x, y, z)];
                    if (v == 0) continue;
                    int best = v;
                    for (int dz = -1; dz <= 1; ++dz)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                // Only the neighbours the sweep has passed: before (x, y, z) in its order.
                                const int before = dir * (dz != 0 ? dz : dy != 0 ? dy : dx);
                                if (before >= 0) continue;
                                const int xx = x + dx, yy = y + dy, zz = z + dz;
                                if (xx < 0 || yy < 0 || zz < 0 || xx >= n_.x || yy >= n_.y || zz >= n_.z) continue;
                                best = std::min(best, int(d_[index(xx, yy, zz)]) + 1);
                            }
                    v = uint8_t(std::min(best, 255));
                }
    };
    sweep(1);
    sweep(-1);
}

float DistanceBound::at(vec3 p) const {
    if (d_.empty()) return 0.f;
    const vec3 f = (p - lo_) * inv_cell_;
    if (!(f.x >= 0.f && f.y >= 0.f && f.z >= 0.f)) return 0.f;
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    if (x >= n_.x || y >= n_.y || z >= n_.z) return 0.f;
    const int d = d_[(size_t(z) * size_t(n_.y) + size_t(y)) * size_t(n_.x) + size_t(x)];
    return d >= 2 ? float(d - 1) * cell_ * 0.999f : 0.f;
}

namespace {
// The truth's object for object `object`, its estimators' radius times radius_scale.
TruthObject make_truth_object(const Scene& s, const Evaluation& ev, int object, double radius_scale, std::shared_ptr<TranslucentTruth>* out = nullptr) {
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
    const double mm_per_world = o.material.get_float("mm_per_unit");
    vec3 lo(1e30f), hi(-1e30f);
    for (const vec3& q : closed->position) {
        const vec3 w = vec3(t.to_world * vec4(q, 1.f));
        lo = glm::min(lo, w), hi = glm::max(hi, w);
    }
    const dvec3 radius_mm = exitance_radius_mm(st.medium, 0.5 * double(glm::length(hi - lo)) * mm_per_world) * radius_scale;
    auto material = std::make_shared<TranslucentTruth>(closed, t.to_world, st, mm_per_world, std::move(map), radius_mm);
    t.material = material;
    t.prepare = [material](const TruthPrep& p) { material->prepare(p); };
    t.samples_per_block = 1;  // a batch's events and exits: some 10 to 100 MB
    if (out) *out = material;
    return t;
}
}  // namespace

TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) { return make_truth_object(s, ev, object, 1.0); }

ExitanceEstimate truth_exitance(const Scene& s, const Evaluation& ev, int object, const std::vector<vec3>& points, const std::vector<vec3>& normals,
                                int samples, uint64_t seed, double radius_scale, bool importance) {
    if (points.size() != normals.size()) throw std::invalid_argument("truth_exitance: as many normals as points");
    std::shared_ptr<TranslucentTruth> material;
    const TruthObject t = make_truth_object(s, ev, object, radius_scale, &material);
    RayScene rt;
    rt.add(*t.mesh, t.to_world);
    rt.commit();
    const Lighting lighting = make_lighting(s, ev);
    vec3 lo(1e30f), hi(-1e30f);
    for (const vec3& q : t.mesh->position) {
        const vec3 w = vec3(t.to_world * vec4(q, 1.f));
        lo = glm::min(lo, w), hi = glm::max(hi, w);
    }
    const float eps = std::max(1e-6f, 1e-5f * glm::length(hi - lo));
    std::vector<dvec3> sum(points.size(), dvec3(0.0)), sum2(points.size(), dvec3(0.0));
    for (int k = 0; k < samples; ++k) {
        t.prepare(TruthPrep{rt, 0, lighting, k, k + 1, seed, eps, 0.5f * (lo + hi), 0.5f * glm::length(hi - lo), nullptr, importance ? &points : nullptr});
        mesolab::parallel_for(size_t(0), points.size(), [&](size_t i) {
            TruthHit h;
            h.p = points[i], h.ng = h.n = glm::normalize(normals[i]);
            const dvec3 M = dvec3(material->exitance(h, uint64_t(k)));
            sum[i] += M, sum2[i] += M * M;
        });
    }
    ExitanceEstimate e;
    const double n = double(samples);
    for (size_t i = 0; i < points.size(); ++i) {
        const dvec3 mean = sum[i] / n, var = n > 1.0 ? glm::max(dvec3(0.0), (sum2[i] - n * mean * mean) / (n - 1.0)) : dvec3(0.0);
        e.mean.push_back(vec3(mean));
        e.stderr_.push_back(vec3(glm::sqrt(var / n)));
    }
    e.photons_per_sample = material->photons_per_sample();
    e.radius_mm = material->radius_mm();
    return e;
}

std::optional<TruthDecl> TranslucencyTechnique::truth() const {
    return TruthDecl{.params = {"translucency.material", "translucency.sigma_s", "translucency.sigma_a", "translucency.eta", "translucency.mm_per_unit",
            "translucency.albedo_map", "translucency.veins", "translucency.vein_scale", "translucency.vein_color"},
                     .stages = {},
                     .object = truth_object};
}
}  // namespace mesolab::translucency
