// Virtual acquisition of a stitch with Embree (see acquire.h).
#include "core/cloth/stages.h"
#include "core/parallel.h"
#include "core/cloth/acquire.h"
#include "core/error.h"
#include "core/raytrace.h"

#include <tbb/blocked_range.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

namespace mesolab::cloth {

std::vector<dvec3> hemisphere_directions(int n, double z_min) {
    std::vector<dvec3> d;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (1.0 - z_min) * (double(i) + 0.5) / double(n);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * double(i);
        d.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return d;
}

namespace {
// [SECTION] The stitch's micro-geometry as a ray-casting scene (core/raytrace.h)
struct StitchScene {
    RayScene rt;
    explicit StitchScene(const TriMesh& m) {
        rt.add(m);
        rt.commit();
    }
    // The first hit along o + t d, t in (0, inf): triangle (or -1) and barycentrics of vertices 1, 2.
    int intersect(vec3 o, vec3 d, float& u, float& v) const {
        const RayHit h = rt.intersect(o, d);
        u = h.u, v = h.v;
        return h.triangle;
    }
    bool occluded(vec3 o, vec3 d) const { return rt.occluded(o, d); }
};

struct Hit {
    int tri = -1;
    float u = 0.f, v = 0.f;
};

template <class T>
T at_hit(const TriMesh& m, const std::vector<T>& per_vertex, const Hit& h, size_t stride = 1, size_t k = 0) {
    const size_t f = size_t(h.tri);
    const T a = per_vertex[m.index[3 * f] * stride + k], b = per_vertex[m.index[3 * f + 1] * stride + k], c = per_vertex[m.index[3 * f + 2] * stride + k];
    return (1.f - h.u - h.v) * a + h.u * b + h.v * c;
}

// Cosine-distributed directions around n (stratified on a k × k grid of the unit square).
std::vector<vec3> cosine_directions(vec3 n, int count, uint32_t seed) {
    const vec3 a = std::abs(n.x) < 0.9f ? vec3(1.f, 0.f, 0.f) : vec3(0.f, 1.f, 0.f);
    const vec3 t = glm::normalize(a - n * glm::dot(a, n)), b = glm::cross(n, t);
    const int k = std::max(1, int(std::lround(std::sqrt(double(count)))));
    std::vector<vec3> d;
    uint32_t s = seed * 747796405u + 2891336453u;
    auto rnd = [&] {
        s = s * 747796405u + 2891336453u;
        uint32_t w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
        return float((w >> 22u) ^ w) * (1.f / 4294967296.f);
    };
    for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
            const float u1 = (float(i) + rnd()) / float(k), u2 = (float(j) + rnd()) / float(k);
            const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
            d.push_back(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.f, 1.f - u1)) * n);
        }
    return d;
}
}  // namespace

// [SECTION] Acquisition
SampleGrid acquire(const StitchMesh& st, const AcquireParams& p, const ProgressFn& progress, const std::atomic<bool>* cancel) {
    if (p.spatial < 1 || p.spatial > 256 || (p.spatial & (p.spatial - 1)) != 0)
        throw InputError("cloth.spatial: " + std::to_string(p.spatial) + " sample points per side must be a power of two in [1, 256]");
    if (p.directions < 4 || p.directions > 128) throw InputError("cloth.directions: " + std::to_string(p.directions) + " must be in [4, 128]");
    if (p.bounces < 0 || p.bounces > 64) throw InputError("cloth.bounces: " + std::to_string(p.bounces) + " must be in [0, 64]");
    const TriMesh& m = st.mesh;
    if (m.triangle_count() == 0) throw InputError("cloth.stitch: the stitch mesh has no triangles");
    const StitchScene rt(m);
    const size_t V = m.vertex_count();
    const float eps = 1e-3f * std::max(st.tile.x, st.tile.y);
    std::mutex progress_mutex;
    auto report = [&](double f) {
        if (!progress) return;
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress(std::string(stages::acquire.name), f);
    };
    auto check_cancel = [&] {
        if (cancel && cancel->load(std::memory_order_relaxed)) throw Cancelled();
    };
    // Precomputed visibility: per vertex, where its hemisphere's rays land.
    const int K = p.visibility_rays > 0 ? std::max(1, int(std::lround(std::sqrt(double(p.visibility_rays))))) : 0;
    const size_t KK = size_t(K) * size_t(K);
    std::vector<Hit> seen(V * KK);
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, V, 256), [&](const tbb::blocked_range<size_t>& r) {
        check_cancel();
        for (size_t i = r.begin(); i != r.end(); ++i) {
            if (KK == 0) break;
            const std::vector<vec3> dirs = cosine_directions(m.normal[i], int(KK), uint32_t(i));
            for (size_t k = 0; k < KK; ++k) {
                Hit& h = seen[i * KK + k];
                h.tri = rt.intersect(m.position[i] + eps * m.normal[i], dirs[k], h.u, h.v);
            }
        }
    });
    report(0.25);
    // Lighting per light direction: L_o per vertex and light.
    const std::vector<dvec3> dirs = hemisphere_directions(p.directions);
    const size_t N = dirs.size();
    std::vector<vec3> Lo(V * N);
    const std::vector<vec3>& rho = st.color;
    mesolab::parallel_for(size_t(0), N, [&](size_t li) {
        check_cancel();
        const vec3 l = vec3(dirs[li]);
        std::vector<vec3> direct(V);
        for (size_t i = 0; i < V; ++i) {
            const float c = glm::dot(m.normal[i], l);
            const bool lit = c > 0.f && !rt.occluded(m.position[i] + eps * m.normal[i], l);
            direct[i] = lit ? rho[i] * (c * kInvPi) : vec3(0.f);
        }
        // Bounce b gathers bounce b - 1's radiance at the hits (bounce 0: the direct light).
        std::vector<vec3> L = direct, next(KK > 0 && p.bounces > 0 ? V : 0);
        for (int b = 0; b < p.bounces && KK > 0; ++b) {
            for (size_t i = 0; i < V; ++i) {
                vec3 E_ind(0.f);
                for (size_t k = 0; k < KK; ++k)
                    if (seen[i * KK + k].tri >= 0) E_ind += at_hit(m, L, seen[i * KK + k]);
                E_ind *= kPi / float(KK);
                next[i] = direct[i] + rho[i] * kInvPi * E_ind;
            }
            L.swap(next);
        }
        for (size_t i = 0; i < V; ++i) Lo[i * N + li] = L[i];
    });
    report(0.75);
    // Sampling along each view through each point of the centre tile's top face.
    SampleGrid g;
    g.res = p.spatial;
    g.views = dirs;
    for (size_t vj = 0; vj < N; ++vj)
        for (size_t li = 0; li < N; ++li) g.l.push_back(dirs[li]), g.v.push_back(dirs[vj]), g.view_of.push_back(int(vj));
    const size_t S = size_t(p.spatial) * size_t(p.spatial);
    g.f.assign(S, std::vector<dvec3>(N * N, dvec3(0.0)));
    g.alpha.assign(S, std::vector<double>(N, 0.0));
    g.normal.assign(S, dvec3(0.0, 0.0, 1.0));
    g.tangent.assign(S, dvec3(1.0, 0.0, 0.0));
    const float z_top = st.hi.z + eps;
    mesolab::parallel_for(size_t(0), S, [&](size_t s) {
        check_cancel();
        const int a = int(s) % p.spatial, b = int(s) / p.spatial;
        const vec3 x((float(a) + 0.5f) / float(p.spatial) * st.tile.x, (float(b) + 0.5f) / float(p.spatial) * st.tile.y, z_top);
        dvec3 n_sum(0.0);
        for (size_t vj = 0; vj < N; ++vj) {
            const vec3 v = vec3(dirs[vj]);
            Hit h;
            h.tri = rt.intersect(x + v, -v, h.u, h.v);
            if (h.tri < 0) continue;  // through a hole: alpha 0, no light
            g.alpha[s][vj] = 1.0;
            n_sum += dvec3(glm::normalize(at_hit(m, m.normal, h)));
            for (size_t li = 0; li < N; ++li) g.f[s][vj * N + li] = dvec3(at_hit(m, Lo, h, N, li)) / dirs[li].z;
        }
        if (glm::length(n_sum) > 0.0) g.normal[s] = glm::normalize(n_sum);
    });
    report(1.0);
    return g;
}
}  // namespace mesolab::cloth
