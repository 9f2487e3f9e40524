// Method kautz-consistent of technique bumpsynth (consistent.h): the tables of the NDF the
// unresolved octaves produce, the method's key, and its registration. The stage is declared with
// the technique's (stages.cpp), and the paper's CPU shading and GPU pass read its tables
// (Synthesis::consistent): the method shares the paper's pipeline.
#include "core/bumpsynth/consistent.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>

namespace mesolab::bumpsynth {

// [SECTION] The facets
LutEntry synthesis_facet(const Synthesis& s, vec2 uv, int k) {
    if (k <= 0) return LutEntry{};
    const ivec2 e = s.lut->entry(synthesis_inputs(s, uv, k));
    return s.lut->at(e.x, e.y);
}

// [SECTION] The tables
ConsistentNdfs build_consistent_ndfs(const Ndf& ndf, const FacetAt& facet, int K, int samples, bool masking) {
    if (samples < 1) throw InputError("bumpsynth.consistent_samples: expected at least 1, got " + std::to_string(samples));
    if (K < 1) throw std::logic_error("bumpsynth/kautz-consistent: octaves_max must be at least 1");
    int side = int(std::ceil(std::sqrt(double(samples)) - 1e-9));
    while (side * side < samples) ++side;
    const int N = side * side;

    // The surface's points: one jittered point per cell of a side x side grid over the uv square.
    std::vector<vec2> uv(static_cast<size_t>(N));
    std::mt19937 rng(0x6b617574u);  // fixed seed: the tables are the same bytes in every run
    const auto unit = [&] { return float(rng() >> 8) * (1.f / 16777216.f); };
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
            const float a = unit(), b = unit();
            uv[size_t(j) * size_t(side) + size_t(i)] = vec2((float(i) + a) / float(side), (float(j) + b) / float(side));
        }
    // Every point's facets, k = 0..K.
    std::vector<LutEntry> f(size_t(N) * size_t(K + 1));
    mesolab::parallel_for(0, N, [&](int p) {
        for (int k = 0; k <= K; ++k) f[size_t(p) * size_t(K + 1) + size_t(k)] = facet(uv[size_t(p)], k);
    });

    ConsistentNdfs out;
    out.samples = N;
    const int R = ndf.resolution();
    for (int k = 0; k <= K; ++k) {
        if (k == K) {  // every facet is its own: D_K = D
            out.ndf.push_back(ndf);
            out.mean_normal.push_back(vec3(0.f, 0.f, 1.f));
            continue;
        }
        // Q_p (rows t_K, b_K, m_K in the k-frame) and 1 / m_z,p, for the points whose K-facet faces
        // the k-frame's hemisphere (all of them unless a bump folds over).
        struct Rot { vec3 r0, r1, r2; float inv_mz; };
        std::vector<Rot> q;
        q.reserve(size_t(N));
        double mean[3] = {0.0, 0.0, 0.0};
        for (int p = 0; p < N; ++p) {
            const LutEntry& a = f[size_t(p) * size_t(K + 1) + size_t(k)];
            const LutEntry& b = f[size_t(p) * size_t(K + 1) + size_t(K)];
            const auto in_a = [&](vec3 v) { return vec3(glm::dot(v, a.t), glm::dot(v, a.b), glm::dot(v, a.m)); };
            const Rot r{in_a(b.t), in_a(b.b), in_a(b.m), 0.f};
            for (int c = 0; c < 3; ++c) mean[c] += double(r.r2[c]);
            if (!(r.r2.z > 1e-4f)) continue;
            q.push_back({r.r0, r.r1, r.r2, 1.f / r.r2.z});
        }
        out.mean_normal.push_back(vec3(float(mean[0] / N), float(mean[1] / N), float(mean[2] / N)));
        // D_k at every cell's centre (pulled inside the disk at the rim), as an image for Ndf::from_image
        // (row 0 at y = +1).
        std::vector<float> img(size_t(R) * size_t(R), 0.f);
        const double inv_n = 1.0 / double(N);
        mesolab::parallel_for(0, R, [&](int j) {
            for (int i = 0; i < R; ++i) {
                if (!(ndf.cell_area(i, j) > 0.0)) continue;
                vec2 c = ndf.cell_centre(i, j);
                const float r2 = glm::dot(c, c);
                if (r2 > 0.9999f) c *= std::sqrt(0.9999f / r2);
                const vec3 hk(c.x, c.y, std::sqrt(std::max(0.f, 1.f - glm::dot(c, c))));
                double sum = 0.0;
                for (const Rot& r : q) {
                    const vec3 hK(glm::dot(r.r0, hk), glm::dot(r.r1, hk), glm::dot(r.r2, hk));
                    if (!(hK.z > 0.f)) continue;
                    sum += double(ndf.eval(vec2(hK.x, hK.y)) * r.inv_mz);
                }
                img[size_t(R - 1 - j) * size_t(R) + size_t(i)] = float(sum * inv_n);
            }
        });
        out.ndf.push_back(Ndf::from_image(img, R, R, R));
    }
    if (masking)
        for (const Ndf& d : out.ndf) out.smith.push_back(SmithTable::build(d));
    return out;
}

namespace {

// [SECTION] The method
class KautzConsistentMethod final : public Method {
public:
    KautzConsistentMethod()
        : Method("bumpsynth", "kautz-consistent",
                 "the paper's synthesis with each octave count shaded by the NDF its unresolved bumps produce (the self-convolution)") {}
    void declare_params(ParamGroup& p) const override {
        p.add_int("consistent_samples", 1024).used_when("method", {"kautz-consistent"}).range(16, 65536).log().in("points")
            .more_accurate(Accuracy::Higher, int64_t(16384))
            .doc("kautz-consistent: points of the surface (a jittered grid) over which the NDF of the unresolved octaves is measured, for every "
                 "octave count; the tables' noise falls as 1/sqrt of it");
        p.section("Consistent far field", {"consistent_samples"});
    }
    std::vector<StageName> frame_stages() const override { return BumpsynthTechnique::pipeline_stages(); }
    bool shares_paper_pipeline() const override { return true; }
    void shade_cpu(const ShadeContext&) const override {
        throw std::logic_error("bumpsynth/kautz-consistent shares the paper's pipeline: its objects are shaded by the technique");
    }
};
}  // namespace
}  // namespace mesolab::bumpsynth

namespace mesolab {
void register_bumpsynth_kautz_consistent(Registry& r) { r.add_method(std::make_unique<bumpsynth::KautzConsistentMethod>()); }
}  // namespace mesolab
