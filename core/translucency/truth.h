#pragma once
// [SECTION] Technique translucency's truth: volumetric light transport inside the object's own
// closed mesh, traced from the lights, and the exitance it sends out resolved at each point the
// camera sees, independently of the mesh's tessellation (truth.cpp has the whole description).
//
// The exitance M(x) at a surface point x is the power per unit area leaving there. Most of it
// leaves straight from a scattering event inside (no reflection at the boundary on the way):
//   M_d(x) = ∫ over ω into the medium ∫_0^t_b  ρ(x + t ω) e^(-σt t) / (4π) T(θ) cos θ  dt dω,
// ρ the photons' scattering events' density of weight per unit volume, θ between -ω and the
// facet's outward normal, t_b where ω meets the boundary, T the exact Fresnel transmittance out.
// It is estimated from x: directions ∝ cos θ, distances ∝ σt e^(-σt t), and ρ at each point by the
// events within a ball of radius r (a quarter of the channel's mean free path: exitance_radius_mm)
// over the ball's volume inside the medium (the cap beyond x's facet plane taken off, to first
// order the sliver the surface's mean curvature adds, and the cap beyond the wall the direction
// meets; the ball shrinks to as little as r/4 where that wall is nearer than r). The rest (light
// that left after a reflection since its last event, or without scattering) is the photons that
// left within r of x, over π r². So the estimate blurs the events' density, not the surface, over
// r: its bias is second order in r (r²/10 ∇²ρ for the ball), shown below the noise on a slab at r
// and r/2 (tests/translucency), and nothing of the mesh's tessellation enters it. What remains of
// the boundary's shape within r of x is the facet planes': at an edge the ball's volume is taken
// from x's own facet (the furnace ball of 64 segments glows at 1 within 0.7% at 4 r).
#include "core/math.h"
#include "core/mesh.h"
#include "core/translucency/dipole.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/stage.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace mesolab {
class RayScene;
}

namespace mesolab::translucency {

// The estimators' radius in mm, per channel: a quarter of the channel's mean free path
// 1 / (σs′ + σa), kept within 1/64 of the object's bounding-sphere radius (an object smaller than a
// few mean free paths varies on its own scale) and above 2^-20 of it (the cells stay countable).
glm::dvec3 exitance_radius_mm(const Medium& medium, double bound_radius_mm);

// The truth's exitance at surface points of translucent object `object` of `s` (for tests and
// tools): its photon batches for samples [0, samples) of `seed`, lit by the scene's lights, the
// object alone traced (no other object shadows it), the estimators' radius times radius_scale; per
// point (normals: the surface's outward unit normals there), the mean over the samples and its
// standard error, per channel, in the scene's power per world unit². With `importance`, the
// photons go where the points are (as a frame's go where the camera sees the object); without,
// they start uniformly over each source.
struct ExitanceEstimate {
    std::vector<vec3> mean, stderr_;
    int photons_per_sample = 0;
    glm::dvec3 radius_mm{0.0};
};
ExitanceEstimate truth_exitance(const Scene& s, const Evaluation& ev, int object, const std::vector<vec3>& points, const std::vector<vec3>& normals,
                                int samples, uint64_t seed, double radius_scale = 1.0, bool importance = true);

// A lower bound on the distance from a point to any triangle of a RayScene, on a grid over a box
// (the translucent object's): a photon whose free path is shorter than the bound moves without a
// ray cast. The bound is the grid's Chebyshev distance to the nearest cell that a triangle
// touches, less one cell: no triangle lies nearer than that. 0 outside the box.
class DistanceBound {
public:
    DistanceBound() = default;
    // Cells of about max(extent) / cells_per_side on each axis.
    DistanceBound(const RayScene& rt, vec3 lo, vec3 hi, int cells_per_side = 128);
    float at(vec3 p) const;
    bool empty() const { return d_.empty(); }

private:
    vec3 lo_{0.f};
    float cell_ = 1.f, inv_cell_ = 1.f;
    glm::ivec3 n_{0};
    std::vector<uint8_t> d_;  // Chebyshev distance in cells to a touched cell, capped at 255
};

// Records with a position, sorted into cubic cells of one size and found again by the cells a ball
// overlaps (a dense grid of the cells where it is small next to the records, else a hash table of
// those that hold any). The records keep their given order within a cell, so that a sum over a
// query is the same whatever threads made them.
template <class Record>
class CellMap {
public:
    CellMap() = default;
    // `origin`: a corner below every record (cells are counted from it); `cell`: the cells' side.
    CellMap(std::vector<Record> records, float cell, vec3 origin) : CellMap(std::vector<std::vector<Record>*>{&records}, cell, origin) {}
    // The same from parts: their records in order, part after part, as if joined (each part is
    // emptied on the way, so that they are never held twice). With `weight`, as keep_weights(weight)
    // after it, without the records ever being held in the cells' order.
    template <class Weight = std::nullptr_t>
    CellMap(const std::vector<std::vector<Record>*>& parts, float cell, vec3 origin, Weight weight = nullptr);
    // Calls f(record) for every record in the cells that the ball (p, radius) overlaps.
    template <class F>
    void for_each_near(vec3 p, float radius, F&& f) const;
    size_t size() const { return records_.size(); }
    // For sums of weights within a ball (weight_within): the records' positions and weights
    // (weight(record)) copied into separate arrays, in the cells' order; the records themselves are
    // dropped (for_each_near then finds none).
    template <class Weight>
    void keep_weights(Weight&& weight);
    // The sum of the weights of the records within `radius` of p (keep_weights first), eight lanes
    // at a time in a fixed order: the same sum at any thread count.
    double weight_within(vec3 p, float radius) const;

private:
    struct Cell {
        int32_t x = 0, y = 0, z = 0;
        uint32_t begin = 0, end = 0;  // records_[begin, end); end == 0: an empty slot
    };
    const Cell* find(int32_t x, int32_t y, int32_t z) const;
    // The records of the cells (x0..x1, y, z): one range, since the records are sorted by cell
    // with x the fastest-changing coordinate. [begin, end); empty where none.
    std::pair<uint32_t, uint32_t> row(int32_t x0, int32_t x1, int32_t y, int32_t z) const;
    // The cells a ball overlaps, clamped to those that hold records: false where none.
    bool cells_of(vec3 p, float radius, glm::ivec3& lo, glm::ivec3& hi) const;
    std::vector<Record> records_;  // grouped by cell
    std::vector<float> x_, y_, z_, w_;  // keep_weights: the records' positions and weights, the same order
    // Where the cells' grid (n_ cells on each axis from the origin) is small next to the records,
    // each cell's first record: start_[x + n.x (y + n.y z)], one past the last cell the record count
    // (a look-up is one read, and a row's ends lie side by side). Otherwise a hash table of the
    // cells that hold records (open addressing, a power of two) and start_ empty.
    std::vector<uint32_t> start_;
    std::vector<Cell> table_;
    glm::ivec3 n_{0};
    float inv_cell_ = 0.f;
    vec3 origin_{0.f};
};

// Where a photon of one channel left the medium after a reflection since its last scattering
// event, or without any (the light that leaves straight from an event is estimated from the
// events): the point (world), its power and the outward normal of the facet it crossed.
struct PhotonExit {
    vec3 p{0.f};
    float power = 0.f;
    int8_t n[3] = {0, 0, 0};  // outward unit normal x 127

    // The exit at `at` carrying `power`, through a facet whose inward unit normal is `m`.
    static PhotonExit through(vec3 at, float power, vec3 m) {
        PhotonExit e;
        e.p = at;
        e.power = power;
        for (int c = 0; c < 3; ++c) e.n[c] = int8_t(std::lround(-127.f * m[c]));
        return e;
    }
};

// A scattering event of a photon of one channel near the surface: the point (world) and the
// photon's weight as it leaves it (after the albedo). Their density is the source of the light that leaves the
// medium straight from an event.
struct ScatterVertex {
    vec3 p{0.f};
    float weight = 0.f;
};

}  // namespace mesolab::translucency

// [SECTION] CellMap's members
namespace mesolab::translucency {
namespace detail {
inline uint64_t cell_hash(int32_t x, int32_t y, int32_t z) {
    const uint64_t h = uint64_t(uint32_t(x)) * 0x9e3779b97f4a7c15ull ^ uint64_t(uint32_t(y)) * 0xc2b2ae3d27d4eb4full ^ uint64_t(uint32_t(z)) * 0x165667b19e3779f9ull;
    return h ^ (h >> 29);
}
}  // namespace detail

template <class Record>
template <class Weight>
CellMap<Record>::CellMap(const std::vector<std::vector<Record>*>& parts, float cell, vec3 origin, Weight weight) : inv_cell_(1.f / cell), origin_(origin) {
    constexpr bool weights_only = !std::is_same_v<Weight, std::nullptr_t>;
    size_t n = 0;
    for (const std::vector<Record>* part : parts) n += part->size();
    if (n == 0 || !(cell > 0.f) || n >= size_t(UINT32_MAX)) return;
    // Each record's cell, counted from `origin` (below every record), within [0, 2^21).
    const float inv = inv_cell_;
    const vec3 o = origin_;
    auto axis = [inv](float p, float o) {
        const float f = (p - o) * inv;
        return f > 0.f ? uint32_t(std::min(f, float((1 << 21) - 1))) : 0u;
    };
    auto cell_of = [&](const Record& r) { return glm::uvec3(axis(r.p.x, o.x), axis(r.p.y, o.y), axis(r.p.z, o.z)); };
    vec3 top(-3.4e38f);
    for (const std::vector<Record>* part : parts)
        for (const Record& r : *part) top = glm::max(top, r.p);
    const glm::uvec3 most(axis(top.x, o.x), axis(top.y, o.y), axis(top.z, o.z));
    n_ = glm::ivec3(most) + 1;
    const size_t cells = size_t(n_.x) * size_t(n_.y) * size_t(n_.z);
    if (cells <= std::max(n, size_t(1) << 20)) {
        // A dense grid: a stable counting sort by cell (x fastest), the records in their given
        // order within each.
        std::vector<uint32_t> key(n);
        start_.assign(cells + 1, 0u);
        size_t i = 0;
        for (const std::vector<Record>* part : parts)
            for (const Record& r : *part) {
                const glm::uvec3 c = cell_of(r);
                key[i] = uint32_t(c.x + size_t(n_.x) * (c.y + size_t(n_.y) * c.z));
                ++start_[key[i++] + 1];
            }
        for (size_t k = 1; k <= cells; ++k) start_[k] += start_[k - 1];
        if constexpr (weights_only)
            x_.resize(n), y_.resize(n), z_.resize(n), w_.resize(n);
        else
            records_.resize(n);
        i = 0;
        for (std::vector<Record>* part : parts) {
            for (const Record& r : *part) {
                const uint32_t to = start_[key[i++]]++;  // start_[k] becomes cell k + 1's first
                if constexpr (weights_only)
                    x_[to] = r.p.x, y_[to] = r.p.y, z_[to] = r.p.z, w_[to] = weight(r);
                else
                    records_[to] = r;
            }
            std::vector<Record>().swap(*part);
        }
        for (size_t k = cells; k-- > 1;) start_[k] = start_[k - 1];
        start_[0] = 0;
        return;
    }
    std::vector<Record> records;
    if (parts.size() == 1) {
        records.swap(*parts.front());  // one part: its records as they are, not a copy
    } else {
        records.reserve(n);
        for (std::vector<Record>* part : parts) {
            records.insert(records.end(), part->begin(), part->end());
            std::vector<Record>().swap(*part);
        }
    }
    // A hash table of the cells that hold records. Each record's cell packed into a key of as many
    // bits a coordinate as the records' extent needs (x the lowest), sorted by a stable radix sort
    // of 16-bit digits: the records grouped by cell, in their given order within each.
    int bits[3];
    for (int a = 0; a < 3; ++a) {
        bits[a] = 1;
        while ((1u << bits[a]) <= most[a]) ++bits[a];
    }
    std::vector<uint64_t> key(n), key2(n);
    std::vector<uint32_t> index(n), index2(n);
    for (size_t i = 0; i < n; ++i) {
        const glm::uvec3 c = cell_of(records[i]);
        key[i] = uint64_t(c.x) | uint64_t(c.y) << bits[0] | uint64_t(c.z) << (bits[0] + bits[1]);
        index[i] = uint32_t(i);
    }
    std::vector<uint32_t> count(1 << 16);
    for (int shift = 0; shift < bits[0] + bits[1] + bits[2]; shift += 16) {
        std::fill(count.begin(), count.end(), 0u);
        for (size_t i = 0; i < n; ++i) ++count[(key[i] >> shift) & 0xffff];
        uint32_t sum = 0;
        for (uint32_t& c : count) {
            const uint32_t k = c;
            c = sum, sum += k;
        }
        for (size_t i = 0; i < n; ++i) {
            const uint32_t to = count[(key[i] >> shift) & 0xffff]++;
            key2[to] = key[i], index2[to] = index[i];
        }
        key.swap(key2), index.swap(index2);
    }
    std::vector<uint64_t>().swap(key2);
    std::vector<uint32_t>().swap(index2);
    records_.resize(n);
    size_t occupied = 0;
    for (size_t i = 0; i < n; ++i) {
        records_[i] = records[index[i]];
        occupied += i == 0 || key[i] != key[i - 1];
    }
    size_t size = 16;
    while (size < 2 * occupied) size *= 2;
    table_.assign(size, Cell{});
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && key[j] == key[i]) ++j;
        const int32_t x = int32_t(key[i] & ((1ull << bits[0]) - 1)), y = int32_t((key[i] >> bits[0]) & ((1ull << bits[1]) - 1)),
                      z = int32_t(key[i] >> (bits[0] + bits[1]));
        size_t slot = detail::cell_hash(x, y, z) & (size - 1);
        while (table_[slot].end != 0) slot = (slot + 1) & (size - 1);
        table_[slot] = Cell{x, y, z, uint32_t(i), uint32_t(j)};
        i = j;
    }
    if constexpr (weights_only) keep_weights(weight);
}

template <class Record>
template <class Weight>
void CellMap<Record>::keep_weights(Weight&& weight) {
    const size_t n = records_.size();
    x_.resize(n), y_.resize(n), z_.resize(n), w_.resize(n);
    for (size_t i = 0; i < n; ++i) x_[i] = records_[i].p.x, y_[i] = records_[i].p.y, z_[i] = records_[i].p.z, w_[i] = weight(records_[i]);
    std::vector<Record>().swap(records_);
}

template <class Record>
bool CellMap<Record>::cells_of(vec3 p, float radius, glm::ivec3& lo, glm::ivec3& hi) const {
    if (start_.empty() && table_.empty()) return false;
    const vec3 a = glm::floor((p - vec3(radius) - origin_) * inv_cell_), b = glm::floor((p + vec3(radius) - origin_) * inv_cell_);
    if (!(a.x < float(n_.x) && a.y < float(n_.y) && a.z < float(n_.z) && b.x >= 0.f && b.y >= 0.f && b.z >= 0.f)) return false;
    lo = glm::ivec3(glm::max(a, vec3(0.f)));
    hi = glm::min(glm::ivec3(b), n_ - 1);
    return true;
}

template <class Record>
std::pair<uint32_t, uint32_t> CellMap<Record>::row(int32_t x0, int32_t x1, int32_t y, int32_t z) const {
    if (!start_.empty()) {
        const size_t k = size_t(x0) + size_t(n_.x) * (size_t(y) + size_t(n_.y) * size_t(z));
        return {start_[k], start_[k + size_t(x1 - x0) + 1]};
    }
    uint32_t begin = 0, end = 0;
    for (int32_t x = x0; x <= x1; ++x)
        if (const Cell* c = find(x, y, z)) {
            if (end == 0) begin = c->begin;
            end = c->end;
        }
    return {begin, end};
}

template <class Record>
double CellMap<Record>::weight_within(vec3 p, float radius) const {
    glm::ivec3 lo, hi;
    if (!cells_of(p, radius, lo, hi)) return 0.0;
    const float r2 = radius * radius;
    double sum = 0.0;
    for (int32_t z = lo.z; z <= hi.z; ++z)
        for (int32_t y = lo.y; y <= hi.y; ++y) {
            const auto [begin, end] = row(lo.x, hi.x, y, z);
            // Eight independent lanes (GCC's vector extensions: SIMD on any target), then the
            // rest one at a time.
            typedef float f8 __attribute__((vector_size(32)));
            typedef int32_t i8 __attribute__((vector_size(32)));
            f8 acc = {0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
            uint32_t i = begin;
            for (; i + 8 <= end; i += 8) {
                f8 px, py, pz, pw;
                std::memcpy(&px, &x_[i], sizeof px), std::memcpy(&py, &y_[i], sizeof py), std::memcpy(&pz, &z_[i], sizeof pz), std::memcpy(&pw, &w_[i], sizeof pw);
                const f8 dx = px - p.x, dy = py - p.y, dz = pz - p.z;
                const i8 inside = dx * dx + dy * dy + dz * dz <= r2;
                acc += (f8)((i8)pw & inside);
            }
            float lane[8];
            std::memcpy(lane, &acc, sizeof lane);
            float rest = 0.f;
            for (; i < end; ++i) {
                const float dx = x_[i] - p.x, dy = y_[i] - p.y, dz = z_[i] - p.z;
                rest += dx * dx + dy * dy + dz * dz <= r2 ? w_[i] : 0.f;
            }
            sum += double((lane[0] + lane[1]) + (lane[2] + lane[3])) + double((lane[4] + lane[5]) + (lane[6] + lane[7])) + double(rest);
        }
    return sum;
}

template <class Record>
const typename CellMap<Record>::Cell* CellMap<Record>::find(int32_t x, int32_t y, int32_t z) const {
    const size_t mask = table_.size() - 1;
    for (size_t slot = detail::cell_hash(x, y, z) & mask;; slot = (slot + 1) & mask) {
        const Cell& c = table_[slot];
        if (c.end == 0) return nullptr;
        if (c.x == x && c.y == y && c.z == z) return &c;
    }
}

template <class Record>
template <class F>
void CellMap<Record>::for_each_near(vec3 p, float radius, F&& f) const {
    glm::ivec3 lo, hi;
    if (!cells_of(p, radius, lo, hi)) return;
    for (int32_t z = lo.z; z <= hi.z; ++z)
        for (int32_t y = lo.y; y <= hi.y; ++y) {
            const auto [begin, end] = row(lo.x, hi.x, y, z);
            for (uint32_t i = begin; i < end; ++i) f(records_[i]);
        }
}
}  // namespace mesolab::translucency
