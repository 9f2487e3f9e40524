// The mip levels of a fabric's BRDF array (see pyramid.h).
#include "core/cloth/stages.h"
#include "core/parallel.h"
#include "core/cloth/pyramid.h"
#include "core/error.h"


#include <algorithm>
#include <atomic>
#include <mutex>
#include <string>

namespace mesolab::cloth {

glm::dmat3 local_frame(dvec3 n, dvec3 t) {
    const double ln = glm::length(n);
    n = ln > 0.0 ? n / ln : dvec3(0.0, 0.0, 1.0);
    t -= n * glm::dot(t, n);
    if (!(glm::length(t) > 1e-9)) t = std::abs(n.x) < 0.9 ? dvec3(1.0, 0.0, 0.0) - n * n.x : dvec3(0.0, 1.0, 0.0) - n * n.y;
    t = glm::normalize(t);
    const dvec3 b = glm::cross(n, t);
    // Rows x, y, z: glm is column-major, so build the transpose.
    return glm::transpose(glm::dmat3(t, b, n));
}

size_t BrdfPyramid::count() const {
    size_t n = 0;
    for (const auto& l : level) n += l.size();
    return n;
}

size_t BrdfPyramid::bytes() const {
    size_t b = 0;
    for (const auto& l : level)
        for (const ClothBrdf& e : l) b += (3 + 12 * e.L.lobes.size() + (e.sheen ? 4 : 0)) * 4 + e.table.T.size() * 4 * 4 + 6 * 4;
    return b;  // the table's directions are shared by every entry (the acquisition's views)
}

dvec3 entry_reflectance(const ClothBrdf& b, const glm::dmat3& F, dvec3 l, dvec3 v) {
    const dvec3 lh = F * l;
    if (!(lh.z > 0.0)) return dvec3(0.0);
    // Up to height z with the same azimuth (straight along x when there is none).
    auto lift = [](dvec3 w, double z) {
        if (w.z >= z) return w;
        const double h = std::sqrt(w.x * w.x + w.y * w.y);
        const dvec2 d = h > 1e-12 ? dvec2(w.x, w.y) / h : dvec2(1.0, 0.0);
        return dvec3(d * std::sqrt(1.0 - z * z), z);
    };
    // The lobes where they were fitted; the table (a look-up, bounded) at the view itself.
    const dvec3 vh = F * v;
    const dvec3 fl = b.f_model(lift(lh, kFittedLightZ), lift(vh, 0.0));
    const dvec3 T = b.table.empty() ? dvec3(1.0) : dvec3(b.table.at(vh));
    return glm::min(T * fl, b.f_max) * lh.z;
}

PointSamples block_samples(const SampleGrid& g, int k, int bx, int by, glm::dmat3& frame) {
    const int s = 1 << k, P = s * s;
    dvec3 n(0.0), t(0.0);
    std::vector<dvec3> mean(g.l.size(), dvec3(0.0));
    std::vector<double> alpha(g.views.size(), 0.0);
    for (int y = by * s; y < (by + 1) * s; ++y)
        for (int x = bx * s; x < (bx + 1) * s; ++x) {
            const size_t p = size_t(y) * size_t(g.res) + size_t(x);
            n += g.normal[p], t += g.tangent[p];
            for (size_t i = 0; i < mean.size(); ++i) mean[i] += g.f[p][i];
            for (size_t i = 0; i < alpha.size(); ++i) alpha[i] += g.alpha.empty() || g.alpha[p].empty() ? 1.0 : g.alpha[p][i];
        }
    frame = local_frame(n, t);
    PointSamples ps;
    ps.views.reserve(g.views.size());
    for (const dvec3& v : g.views) ps.views.push_back(frame * v);
    ps.alpha.resize(alpha.size());
    for (size_t i = 0; i < alpha.size(); ++i) ps.alpha[i] = alpha[i] / double(P);
    ps.s.resize(g.l.size());
    // The paper's foreshortening (§3): the model times cos θ̂_l in the entry's frame gives the
    // radiance, f_r cos θ_l from the fabric's normal as acquired; so f = f_r cos θ_l / cos θ̂_l,
    // weighted by cos θ̂_l (radiance). Light at or below 0.05 of the entry's horizon is left out.
    for (size_t i = 0; i < g.l.size(); ++i) {
        const dvec3 l = frame * g.l[i];
        const bool above = l.z > kFittedLightZ;
        ps.s[i] = {l, frame * g.v[i], above ? mean[i] * (g.l[i].z / (l.z * double(P))) : dvec3(0.0), g.view_of[i], above ? l.z : 0.0};
    }
    return ps;
}

BrdfPyramid fit_pyramid(const SampleGrid& g, const FitOptions& o, const ProgressFn& progress, const std::atomic<bool>* cancel) {
    if (g.res < 1 || g.res > 1024 || (g.res & (g.res - 1)) != 0)
        throw InputError("cloth.spatial: " + std::to_string(g.res) + " sample points per side must be a power of two in [1, 1024]");
    const size_t N = size_t(g.res) * size_t(g.res);
    if (g.f.size() != N || g.normal.size() != N || g.tangent.size() != N || (!g.alpha.empty() && g.alpha.size() != N) || g.v.size() != g.l.size() ||
        g.view_of.size() != g.l.size())
        throw InputError("cloth.spatial: the sample grid's arrays do not match its " + std::to_string(g.res) + "² points");
    for (const auto& f : g.f)
        if (f.size() != g.l.size()) throw InputError("cloth.spatial: a sample point has " + std::to_string(f.size()) + " values for " + std::to_string(g.l.size()) + " direction pairs");
    BrdfPyramid out;
    out.res = g.res;
    size_t total = 0;
    for (int k = 0; (g.res >> k) >= 1; ++k) {
        const size_t side = size_t(g.res >> k);
        out.level.emplace_back(side * side);
        out.frame.emplace_back(side * side);
        out.report.emplace_back(side * side);
        total += side * side;
    }
    std::atomic<size_t> done{0};
    std::atomic<bool> stopped{false};
    std::mutex progress_mutex;  // the callback is called from one thread at a time
    // Coarse to fine: the single top entry tries every start; each finer entry starts from its
    // parent's lobes and the paper's grey start only (a block's mean is close to its parts').
    for (int k = int(out.level.size()) - 1; k >= 0 && !stopped; --k) {
        const int side = g.res >> k;
        mesolab::parallel_for(size_t(0), size_t(side) * size_t(side), [&](size_t at) {
            if (stopped.load(std::memory_order_relaxed) || (cancel && cancel->load(std::memory_order_relaxed))) {
                stopped = true;
                return;
            }
            const int x = int(at % size_t(side)), y = int(at / size_t(side));
            glm::dmat3 frame;
            const PointSamples ps = block_samples(g, k, x, y, frame);
            FitOptions eo = o;
            if (k + 1 < int(out.level.size())) {
                const ClothBrdf& parent = out.level[size_t(k + 1)][size_t(y / 2) * size_t(side / 2) + size_t(x / 2)];
                eo.starts = {parent.L, default_starts(ps, o.lobes)[0]};
                eo.builtin_starts = false;
            }
            out.level[size_t(k)][at] = fit_brdf(ps, eo, &out.report[size_t(k)][at]);
            out.frame[size_t(k)][at] = frame;
            const size_t d = ++done;
            if (progress && (d % 16 == 0 || d == total)) {
                std::lock_guard<std::mutex> lock(progress_mutex);
                progress(std::string(stages::fit.name), double(d) / double(total));
            }
        });
    }
    if (stopped) throw Cancelled();
    return out;
}
}  // namespace mesolab::cloth
