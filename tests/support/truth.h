#pragma once
// Helpers for tests of the truth (core/truth/truth.h): which pixels show an object, and the mean
// radiance over them with its standard error.
#include "core/truth/cache.h"
#include "app/workbench.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/truth/truth.h"

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace mesolab::test {

// A request of `size` x `size` on `backend` with a truth of `spp` samples and `seed`.
inline RenderRequest truth_request(const std::string& backend, int size, int spp, std::vector<std::string> aovs = {}, uint64_t seed = 1) {
    RenderRequest req;
    req.renderer = backend;
    req.width = req.height = size;
    req.truth.spp = spp;
    req.truth.seed = seed;
    req.aovs = std::move(aovs);
    return req;
}

// Renders `s` in a workbench of its own whose truths are rendered every time (no test reads
// another's truth from the cache).
inline RenderResult render_uncached(const Scene& s, const RenderRequest& req) {
    Workbench wb;
    wb.set_truth_cache("");
    return wb.render(s, req);
}

// The truth's key ignores each KEY=VALUE of `knobs` (accuracy knobs: one truth serves a sweep over
// them) and follows each of `physical` (what the truth simulates).
inline void expect_truth_key(const Scene& s, const std::vector<std::string>& knobs, const std::vector<std::string>& physical) {
    const std::string base = truth_description(s);
    for (const std::string& a : knobs) {
        Scene t = s;
        apply_set(t, a);
        EXPECT_EQ(truth_description(t), base) << a;
    }
    for (const std::string& a : physical) {
        Scene t = s;
        apply_set(t, a);
        EXPECT_NE(truth_description(t), base) << a;
    }
}

// Whether the truth's pixel (x, y) shows an object (a first hit's normal; 0 for the background).
inline bool shows_object(const Frame& f, int x, int y) {
    const float* n = f.aov("normal").at(x, y);
    return n[0] != 0.f || n[1] != 0.f || n[2] != 0.f;
}

// Expects every pixel that shows an object to have radiance `L` (each channel within `tol`);
// returns how many do show one.
inline int expect_object_radiance(const Frame& f, vec3 L, float tol) {
    int shown = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            if (!shows_object(f, x, y)) continue;
            ++shown;
            const float* p = f.aov("radiance").at(x, y);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], L[c], tol) << "pixel " << x << "," << y << " channel " << c;
        }
    return shown;
}

// The mean of channel `c` of the truth's radiance over the pixels that show an object, and its
// standard error (from truth_stderr: the pixels' estimates are independent).
struct ObjectMean {
    double mean = 0, stderr_mean = 0;
    int pixels = 0;
};
inline ObjectMean object_mean(const Frame& f, int c = 1) {
    const Image& L = f.aov("radiance");
    double sum = 0.0, var = 0.0;
    ObjectMean m;
    for (int y = 0; y < L.height; ++y)
        for (int x = 0; x < L.width; ++x)
            if (shows_object(f, x, y)) {
                sum += L.at(x, y)[c];
                const double se = f.aov("truth_stderr").at(x, y)[c];
                var += se * se, ++m.pixels;
            }
    if (m.pixels) m.mean = sum / m.pixels, m.stderr_mean = std::sqrt(var) / m.pixels;
    return m;
}
// Frames of one truth under different seeds: each pixel's spread of channel `c` around its mean
// over the seeds (unbiased), against the standard errors the frames report, as the ratio of their
// root mean squares over the pixels that show an object (1 when truth_stderr is right).
struct StderrCheck {
    double ratio = 0.0;
    int pixels = 0;
};
inline StderrCheck stderr_against_spread(const std::vector<Frame>& frames, int c = 1) {
    const size_t n = frames.size();
    double spread2 = 0.0, se2 = 0.0;
    StderrCheck r;
    if (n < 2) return r;
    for (int y = 0; y < frames[0].height; ++y)
        for (int x = 0; x < frames[0].width; ++x) {
            if (!shows_object(frames[0], x, y)) continue;
            double m = 0.0;
            for (const Frame& f : frames) m += f.aov("radiance").at(x, y)[c];
            m /= double(n);
            for (const Frame& f : frames) {
                const double d = f.aov("radiance").at(x, y)[c] - m, e = f.aov("truth_stderr").at(x, y)[c];
                spread2 += d * d, se2 += e * e;
            }
            ++r.pixels;
        }
    spread2 *= double(n) / double(n - 1);
    if (se2 > 0.0) r.ratio = std::sqrt(spread2 / se2);
    std::printf("spread over seeds / reported standard error: %.3f over %d pixels\n", r.ratio, r.pixels);
    return r;
}

// The two-sided z value at which a family of n tests keeps its false-alarm rate at alpha (Šidák:
// each test at 1 - (1 - alpha)^(1/n)), from erfc by bisection.
inline double sidak_z(double alpha, int n) {
    const double each = 1.0 - std::pow(1.0 - alpha, 1.0 / double(n));
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erfc(mid / std::sqrt(2.0)) > each ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Sets MESOLAB_TRUTH_PLAIN while it lives: the truths' plain estimators (bumpsynth's direct light at
// the path's own point of the footprint, translucency's photons split evenly over the sources), to
// compare the estimators with.
struct PlainEstimator {
    PlainEstimator() { setenv("MESOLAB_TRUTH_PLAIN", "1", 1); }
    ~PlainEstimator() { unsetenv("MESOLAB_TRUTH_PLAIN"); }
    PlainEstimator(const PlainEstimator&) = delete;
    PlainEstimator& operator=(const PlainEstimator&) = delete;
};
}  // namespace mesolab::test
