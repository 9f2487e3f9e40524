#include "core/bumpsynth/noise.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace mesolab::bumpsynth {
namespace {

constexpr float kS = 0.70710678f;  // √½: the bound of 2D gradient noise with unit gradients
constexpr float kGrad[8][2] = {{1.f, 0.f}, {-1.f, 0.f}, {0.f, 1.f}, {0.f, -1.f}, {kS, kS}, {-kS, kS}, {kS, -kS}, {-kS, -kS}};

float fade(float t) { return t * t * t * (t * (t * 6.f - 15.f) + 10.f); }

// i mod n in [0, n) (also for negative i); the lattice coordinates are mostly in [0, n) already.
int wrap(int i, int n) {
    if (unsigned(i) < unsigned(n)) return i;
    const int r = i % n;
    return r < 0 ? r + n : r;
}

// r mapped to [0, 1] from the octave sum T and the scale 1 / (2 √½ A) (see the header).
float to_unit(float T, float scale) { return std::clamp(0.5f + T * scale, 0.f, 1.f); }
float unit_scale_of(float A) { return 1.f / (2.f * kS * A); }

// uv reduced to the periodic square [0, 1] (see the header).
vec2 wrap_uv(vec2 uv) { return uv - glm::floor(uv); }

}  // namespace

vec2 noise_octave_pair(const NoiseOctaves& oc, vec2 uv, int o) {
    const int p0 = oc.period[o][0], p1 = oc.period[o][1];
    return oc.gain[o] * vec2(gradient_noise(uv * float(p0) + oc.offset[o][0], p0, oc.seed[o][0]),
                             gradient_noise(uv * float(p1) + oc.offset[o][1], p1, oc.seed[o][1]));
}

uint32_t octave_seed(uint32_t seed, int octave, int channel) { return hash32(seed * 0x9E3779B1u + uint32_t(octave * 2 + channel) * 0x85EBCA77u + 0x165667B1u); }
vec2 octave_offset(int octave, int channel) {
    const double a = 0.6180339887498949 * (octave + 1) + 0.4142135623730951 * channel;
    const double b = 0.7548776662466927 * (octave + 1) + 0.2071067811865476 * channel;
    return {float(a - std::floor(a)), float(b - std::floor(b))};
}

void NoiseParams::validate() const {
    if (base_frequency < 1 || base_frequency > 4096)
        throw InputError("bumpsynth.noise_frequency: expected an integer in [1, 4096] lattice cells per unit of uv, got " + std::to_string(base_frequency));
    if (!(gain > 0.f && gain <= 1.f)) throw InputError("bumpsynth.noise_gain: expected a value in (0, 1], got " + std::to_string(gain));
    if (octaves_max < 1 || octaves_max > 16) throw InputError("bumpsynth.octaves_max: expected an integer in [1, 16], got " + std::to_string(octaves_max));
}

uint32_t hash32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// [SECTION] Gradient noise
float gradient_noise(vec2 p, int period, uint32_t seed) {
    const float fx0 = std::floor(p.x), fy0 = std::floor(p.y);
    const float fx = p.x - fx0, fy = p.y - fy0;
    const int x0 = wrap(int(fx0), period), y0 = wrap(int(fy0), period);
    const int x1 = x0 + 1 == period ? 0 : x0 + 1, y1 = y0 + 1 == period ? 0 : y0 + 1;
    const uint32_t hy0 = hash32(uint32_t(y0) + seed), hy1 = hash32(uint32_t(y1) + seed);
    auto corner = [&](int x, uint32_t hy, float dx, float dy) {
        const uint32_t h = hash32(uint32_t(x) + hy) & 7u;
        return kGrad[h][0] * dx + kGrad[h][1] * dy;
    };
    const float n00 = corner(x0, hy0, fx, fy), n10 = corner(x1, hy0, fx - 1.f, fy);
    const float n01 = corner(x0, hy1, fx, fy - 1.f), n11 = corner(x1, hy1, fx - 1.f, fy - 1.f);
    const float u = fade(fx), v = fade(fy);
    const float a = n00 + u * (n10 - n00), b = n01 + u * (n11 - n01);
    return a + v * (b - a);
}

// [SECTION] Fractal noise
NoiseOctaves::NoiseOctaves(const NoiseParams& n) : count(std::clamp(n.octaves_max, 0, kMax)) {
    float A = 0.f;
    for (int o = 0; o < count; ++o) {
        gain[o] = std::pow(n.gain, float(o));
        A += gain[o];
        unit_scale[o + 1] = unit_scale_of(A);
        for (int c = 0; c < 2; ++c) {
            period[o][c] = (n.base_frequency + c) << o;  // see the header: decorrelated lattices
            seed[o][c] = octave_seed(n.seed, o, c);
            offset[o][c] = octave_offset(o, c);
        }
    }
}

float noise_octave(const NoiseParams& n, vec2 uv, int octave, int channel) {
    const int period = (n.base_frequency + channel) << octave;
    const vec2 p = wrap_uv(uv) * float(period) + octave_offset(octave, channel);
    return std::pow(n.gain, float(octave)) * gradient_noise(p, period, octave_seed(n.seed, octave, channel));
}

float fractal_noise(const NoiseParams& n, vec2 uv, int k, int channel) {
    float T = 0.f, A = 0.f;
    for (int o = 0; o < k; ++o) {
        T += noise_octave(n, uv, o, channel);
        A += std::pow(n.gain, float(o));
    }
    return to_unit(T, unit_scale_of(A));
}

void fractal_noise_all(const NoiseParams& n, vec2 uv, vec2* out) { fractal_noise_all(NoiseOctaves(n), uv, n.octaves_max, out); }

void fractal_noise_all(const NoiseOctaves& oc, vec2 uv, int count, vec2* out) {
    uv = wrap_uv(uv);
    vec2 T(0.f);
    for (int o = 0; o < count; ++o) {
        T += noise_octave_pair(oc, uv, o);
        out[o] = vec2(to_unit(T.x, oc.unit_scale[o + 1]), to_unit(T.y, oc.unit_scale[o + 1]));
    }
}

float octaves_at_distance(float distance, float detail_distance, int octaves_max) {
    if (!(distance > 0.f)) return float(octaves_max);  // at the eye (or NaN): full detail
    const float o = std::log2(detail_distance / distance);
    return std::clamp(std::isfinite(o) ? o : (o > 0.f ? float(octaves_max) : 0.f), 0.f, float(octaves_max));
}

// [SECTION] Input CDFs per octave count
NoiseCdfs measure_noise_cdfs(const NoiseParams& n, int samples) {
    n.validate();
    const int K = n.octaves_max, N = std::max(16, samples);
    const NoiseOctaves oc(n);
    std::vector<std::vector<float>> r(size_t(2 * K), std::vector<float>(size_t(N) * size_t(N)));
    mesolab::parallel_for(0, N, [&](int y) {
        std::mt19937 rng(uint32_t(y) * 7919u + n.seed);
        std::uniform_real_distribution<float> jitter(0.f, 1.f);
        std::vector<vec2> all(static_cast<size_t>(K));
        for (int x = 0; x < N; ++x) {
            const vec2 uv((float(x) + jitter(rng)) / float(N), (float(y) + jitter(rng)) / float(N));
            fractal_noise_all(oc, uv, K, all.data());
            const size_t i = size_t(y) * size_t(N) + size_t(x);
            for (int k = 0; k < K; ++k) r[size_t(2 * k)][i] = all[size_t(k)].x, r[size_t(2 * k + 1)][i] = all[size_t(k)].y;
        }
    });
    NoiseCdfs out;
    out.params = n;
    out.octaves = oc;
    out.G.resize(size_t(2 * K));
    out.table.resize(size_t(2 * K) * size_t(NoiseCdfs::kCdfNodes));
    mesolab::parallel_for(0, 2 * K, [&](int k) {
        out.G[size_t(k)] = measure_input_cdf(r[size_t(k)]);
        const std::vector<float> t = resample_input_cdf(out.G[size_t(k)]);
        std::copy(t.begin(), t.end(), out.table.begin() + std::ptrdiff_t(size_t(k) * size_t(NoiseCdfs::kCdfNodes)));
    });
    return out;
}

// [SECTION] The resampled input CDFs
std::vector<float> resample_input_cdf(const InputCdf& G) {
    const int n = NoiseCdfs::kCdfNodes;
    std::vector<float> t(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) t[size_t(i)] = float(G(double(i) / double(n - 1)));
    return t;
}

float NoiseCdfs::input(int k, int channel, float r) const {
    const float x = (r > 0.f ? (r < 1.f ? r : 1.f) : 0.f) * float(kCdfNodes - 1);
    const int i = std::min(int(x), kCdfNodes - 2);
    const float t = x - float(i);
    const float* g = table.data() + size_t(2 * (k - 1) + channel) * size_t(kCdfNodes) + size_t(i);
    return g[0] + t * (g[1] - g[0]);
}

namespace {
// The first k octaves' sums T of both channels at uv (wrapped).
vec2 octave_sums(const NoiseOctaves& oc, vec2 uv, int k) {
    vec2 T(0.f);
    for (int o = 0; o < k; ++o) T += noise_octave_pair(oc, uv, o);
    return T;
}
}  // namespace

vec2 noise_inputs(const NoiseCdfs& cdfs, vec2 uv, int k) {
    uv = wrap_uv(uv);
    const vec2 T = octave_sums(cdfs.octaves, uv, k);
    const float s = cdfs.octaves.unit_scale[k];
    return {cdfs.input(k, 0, to_unit(T.x, s)), cdfs.input(k, 1, to_unit(T.y, s))};
}

void noise_inputs_fading(const NoiseCdfs& cdfs, vec2 uv, int k, vec2& coarse, vec2& fine) {
    uv = wrap_uv(uv);
    vec2 T = octave_sums(cdfs.octaves, uv, k);
    if (k > 0) {
        const float s = cdfs.octaves.unit_scale[k];
        coarse = {cdfs.input(k, 0, to_unit(T.x, s)), cdfs.input(k, 1, to_unit(T.y, s))};
    }
    T += noise_octave_pair(cdfs.octaves, uv, k);
    const float s = cdfs.octaves.unit_scale[k + 1];
    fine = {cdfs.input(k + 1, 0, to_unit(T.x, s)), cdfs.input(k + 1, 1, to_unit(T.y, s))};
}

// [SECTION] Mip-mapped noise texture
int NoiseTexture::level_of(int k) const { return std::clamp(octaves_max - k, 0, int(levels.size()) - 1); }

vec2 NoiseTexture::bilinear(int level, vec2 uv) const {
    const int s = std::max(1, size >> level);
    const std::vector<vec2>& t = levels[size_t(level)];
    // a + t (b - a), as the GLSL writes it (noise_texture.glsl).
    return BilinearTaps::at_uv(uv, s, s, Edge::Wrap, Edge::Wrap).blend_lerp([&](int x, int y) { return t[size_t(y) * size_t(s) + size_t(x)]; });
}

NoiseTexture make_noise_texture(const NoiseCdfs& cdfs, int size) {
    if (size < 16 || size > 4096 || (size & (size - 1)) != 0)
        throw InputError("bumpsynth.noise_texture_size: expected a power of two in [16, 4096], got " + std::to_string(size));
    NoiseTexture tex;
    tex.size = size;
    tex.octaves_max = cdfs.params.octaves_max;
    int count = 0;
    while (count < tex.octaves_max && (size >> count) >= 1) ++count;
    tex.levels.resize(size_t(count));
    for (int l = 0; l < count; ++l) {
        const int s = size >> l, k = std::max(1, tex.octaves_max - l), sub = l == 0 ? 1 : 2;
        std::vector<vec2>& t = tex.levels[size_t(l)];
        t.resize(size_t(s) * size_t(s));
        mesolab::parallel_for(0, s, [&](int y) {
            for (int x = 0; x < s; ++x) {
                vec2 sum(0.f);
                for (int j = 0; j < sub; ++j)
                    for (int i = 0; i < sub; ++i) {
                        const vec2 uv((float(x) + (float(i) + 0.5f) / float(sub)) / float(s), (float(y) + (float(j) + 0.5f) / float(sub)) / float(s));
                        sum += noise_inputs(cdfs, uv, k);
                    }
                t[size_t(y) * size_t(s) + size_t(x)] = sum / float(sub * sub);
            }
        });
    }
    return tex;
}
}  // namespace mesolab::bumpsynth
