// The sweep metric bumpsynth.ndf_histogram (see sweep_metric.h).
#include "core/bumpsynth/sweep_metric.h"
#include "core/parallel.h"
#include "core/bumpsynth/bumpsynth.h"
#include "core/error.h"
#include "core/hash.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace mesolab::bumpsynth {
namespace {

constexpr uint64_t kJitterSeed = 0x4b4854323030316bull;  // fixed: the metric is deterministic
constexpr const char* kMetricName = "bumpsynth.ndf_histogram";

// [SECTION] Sampling
// The jittered point of grid cell (i, j) of side² over the uv square.
vec2 jittered_uv(int i, int j, int side) {
    const uint64_t h = splitmix64(kJitterSeed ^ (uint64_t(j) * uint64_t(side) + uint64_t(i)));
    const double ju = double(h >> 40) / double(1 << 24), jv = double((h >> 16) & 0xffffff) / double(1 << 24);
    return vec2(float((i + ju) / side), float((j + jv) / side));
}

int bin_of(double x, int bins) { return std::clamp(int(std::floor((x + 1.0) * 0.5 * bins)), 0, bins - 1); }

// [SECTION] Binomial mean absolute deviation (de Moivre)
double binomial_mad(int64_t n, double p) {
    if (!(p > 0.0) || !(p < 1.0) || n <= 0) return 0.0;
    const double N = double(n), k = std::min(std::floor(N * p), N - 1.0);
    const double log_mad = std::log(2.0) + std::log(k + 1.0) + std::lgamma(N + 1.0) - std::lgamma(k + 2.0) - std::lgamma(N - k) +
                           (k + 1.0) * std::log(p) + (N - k) * std::log1p(-p);
    return std::exp(log_mad);
}

// [SECTION] The metric's object and reference
int first_object(const Scene& s) {
    for (size_t i = 0; i < s.objects.size(); ++i)
        if (s.objects[i].technique == "bumpsynth") return int(i);
    throw InputError(std::string("no object uses technique bumpsynth (the metric ") + kMetricName + " measures the first one's synthesised normals)");
}

Synthesis full_synthesis(const Scene& s, const Evaluation& ev, int object) {
    const Synthesis syn = synthesis_for(s, ev, object);
    if (!syn.ndf || !syn.lut || !syn.cdfs) throw std::logic_error(std::string(kMetricName) + ": the frame's evaluation lacks bumpsynth.ndf, .lut or .noise_cdf");
    return syn;
}

std::string sci(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2e", v);
    return buf;
}

std::string notes(const Scene& ref, int object, const Ndf& ndf, int octaves, double floor, double self) {
    const int B = kHistogramBins;
    const double N = double(kHistogramSamplesPerSide) * kHistogramSamplesPerSide;
    return std::string("Metric `") + kMetricName + "` (object `" + ref.objects[size_t(object)].name + "`): N = " + std::to_string(int64_t(N)) +
           " normals synthesised at full detail (" + std::to_string(octaves) +
           " octaves) at jittered uv over the uv square, each through its nearest look-up-table entry as the renderer does; "
           "the total-variation distance of their (x, y) histogram on " + std::to_string(B) + " x " + std::to_string(B) +
           " bins over [-1, 1]^2 from the reference's NDF (" + std::to_string(ndf.resolution()) + "^2 cells) summed into the same bins.\n\n"
           "Noise floor: N independent samples from the reference NDF would give an expected TV of " + sci(floor) +
           " (exact binomial mean absolute deviations; sqrt(B^2 / (2 pi N)) = " + sci(std::sqrt(B * B / (2.0 * 3.14159265358979 * N))) +
           " bounds it for mass spread over all B^2 bins). The reference setting itself measures " + sci(self) +
           ": the floor that this realisation of the noise over the uv square and the reference's table set.\n";
}

SweepMeasure prepare(const Scene& ref, const Evaluation& ev) {
    const int object = first_object(ref);
    const Synthesis syn = full_synthesis(ref, ev, object);
    const int R = syn.ndf->resolution();
    if (R % kHistogramBins != 0)
        throw InputError("bumpsynth.ndf_resolution: the reference's " + std::to_string(R) + " is not a multiple of " + std::to_string(kHistogramBins) +
                         ", the bins of the metric " + kMetricName);
    auto q = std::make_shared<const std::vector<double>>(ndf_bin_masses(*syn.ndf));
    const double floor = multinomial_tv_floor(*q, int64_t(kHistogramSamplesPerSide) * kHistogramSamplesPerSide);
    const double self = total_variation(synthesised_histogram(syn), *q);
    SweepMeasure m;
    m.error = [q](const Scene& s, const Evaluation& e) { return total_variation(synthesised_histogram(full_synthesis(s, e, first_object(s))), *q); };
    m.notes = notes(ref, object, *syn.ndf, syn.cdfs->params.octaves_max, floor, self);
    m.levels = {{"iid sampling floor", floor}, {"reference setting itself", self}};
    return m;
}
}  // namespace

// [SECTION] Histograms and distances
std::vector<double> synthesised_histogram(const Synthesis& s, int bins, int side) {
    if (bins < 1 || side < 1) throw std::invalid_argument("synthesised_histogram: bins and side must be positive");
    const float octaves = float(s.cdfs->params.octaves_max);
    const size_t cells = size_t(bins) * size_t(bins);
    tbb::combinable<std::vector<int64_t>> counts([cells] { return std::vector<int64_t>(cells, 0); });
    mesolab::parallel_for(tbb::blocked_range<int>(0, side), [&](const tbb::blocked_range<int>& rows) {
        std::vector<int64_t>& c = counts.local();
        for (int j = rows.begin(); j < rows.end(); ++j)
            for (int i = 0; i < side; ++i) {
                const vec3 m = facets_at(s, jittered_uv(i, j, side), octaves).coarse.m;
                ++c[size_t(bin_of(m.y, bins)) * size_t(bins) + size_t(bin_of(m.x, bins))];
            }
    });
    std::vector<int64_t> total(cells, 0);
    counts.combine_each([&](const std::vector<int64_t>& c) {
        for (size_t k = 0; k < cells; ++k) total[k] += c[k];
    });
    std::vector<double> p(cells);
    const double n = double(side) * double(side);
    for (size_t k = 0; k < cells; ++k) p[k] = double(total[k]) / n;
    return p;
}

std::vector<double> ndf_bin_masses(const Ndf& ndf, int bins) {
    const int R = ndf.resolution();
    if (bins < 1 || R % bins != 0) throw std::invalid_argument("ndf_bin_masses: " + std::to_string(bins) + " bins do not divide " + std::to_string(R) + " cells");
    const int per = R / bins;
    std::vector<double> q(size_t(bins) * size_t(bins), 0.0);
    for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) q[size_t(j / per) * size_t(bins) + size_t(i / per)] += ndf.mass(i, j);
    return q;
}

double total_variation(const std::vector<double>& p, const std::vector<double>& q) {
    if (p.size() != q.size()) throw std::invalid_argument("total_variation: distributions of different sizes");
    double sum = 0.0;
    for (size_t k = 0; k < p.size(); ++k) sum += std::fabs(p[k] - q[k]);
    return 0.5 * sum;
}

double multinomial_tv_floor(const std::vector<double>& q, int64_t n) {
    if (n <= 0) return 0.0;
    double sum = 0.0;
    for (double p : q) sum += binomial_mad(n, p);
    return 0.5 * sum / double(n);
}

// [SECTION] Declaration
SweepMetricDecl ndf_histogram_metric() {
    SweepMetricDecl d;
    d.name = kMetricName;
    d.label = "TV distance";
    d.unit = "fraction of the normals' probability mass, 0..1";
    d.help = "total-variation distance between the histogram of 2^20 normals synthesised at full detail (nearest look-up-table entries, "
             "as rendered) and the reference setting's NDF, on 32 x 32 bins of the normal's (x, y)";
    d.check = [](const Scene& s) { first_object(s); };
    d.prepare = prepare;
    return d;
}
}  // namespace mesolab::bumpsynth
