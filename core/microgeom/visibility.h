#pragma once
// Visibility textures S_i (Heidrich et al. 2000, §3): for every direction d_i of a DirectionSet
// and every texel p, the point q of the heightfield that the ray from p in direction d_i hits
// first, or no hit. Exact against the triangulated heightfield surface
// (core/heightfield/heightfield.h): the ray walks the cells it crosses (2D DDA, accelerated by a
// max-height pyramid so that rays above all geometry stop at once), testing both triangles of
// each cell; nothing can be stepped over.
// Periodic fields wrap the walk across the borders.
//
// Ray origin: the texel centre P(p) lifted by eps along the texel's normal, with
// eps = 1e-3 texel sizes; directions with d . n(p) <= 0 point into the surface at p and are
// stored as kBelow without tracing.
#include "core/heightfield/heightfield.h"
#include "core/microgeom/directions.h"
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace mesolab::microgeom {

// An allocator whose resize() leaves new elements uninitialised, so that S_i's hundreds of MB
// (1024² texels × 100 directions: 400 MB) are first touched by the threads that fill them
// (hits_filled) rather than zeroed on one thread first: that took 211 ms of a 1024² GPU
// precomputation on this VM, most of it page faults.
template <class T>
struct UninitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitAllocator<U>;
    };
    UninitAllocator() = default;
    template <class U>
    UninitAllocator(const UninitAllocator<U>&) noexcept {}
    template <class U, class... Args>
    void construct(U* p, Args&&... args) { ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...); }
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) { ::new (static_cast<void*>(p)) U; }
};
using HitArray = std::vector<uint32_t, UninitAllocator<uint32_t>>;

// `n` entries of `value`, written in parallel (each thread touching its own pages first).
HitArray hits_filled(size_t n, uint32_t value);

struct Visibility {
    static constexpr uint32_t kNoHit = 0xFFFFFFFFu;  // the ray leaves the heightfield: environment
    static constexpr uint32_t kBelow = 0xFFFFFFFEu;  // the direction is below p's tangent plane
    int width = 0, height = 0, count = 0;            // texels and directions
    HitArray hit;                                    // [direction][row][column]

    // A copy of `hit` that the device which computed it keeps (gpu/microgeom/chunks.h), so that
    // later passes on that device read S_i where it already is instead of uploading it again.
    // Copies of this Visibility share it; code that changes `hit` afterwards must reset it.
    struct DeviceCopy {
        virtual ~DeviceCopy() = default;
        virtual size_t host_bytes() const = 0;  // what it holds in the host's memory (a renderer on the CPU)
    };
    std::shared_ptr<const DeviceCopy> device;

    uint32_t at(int dir, int x, int y) const { return hit[(size_t(dir) * size_t(height) + size_t(y)) * size_t(width) + size_t(x)]; }
    size_t bytes() const { return hit.size() * sizeof(uint32_t) + (device ? device->host_bytes() : 0); }

    // Hits are stored as continuous texel coordinates (c, r) of the hit point, with texel
    // centres at integer values (texel (x, y) is at (x, y)), wrapped into [0, W) x [0, H) for
    // periodic fields, in 16.16... packed as two 16-bit fixed-point numbers with 4 fractional
    // bits: (round(c*16) << 16) | round(r*16). So fields up to 4095 texels a side.
    static uint32_t encode(float c, float r);
    static vec2 decode(uint32_t packed);
};

using VisibilityProgress = std::function<void(double)>;  // may throw to cancel

// All N textures, in parallel (TBB) over directions and rows.
Visibility compute_visibility(const Heightfield& hf, const DirectionSet& dirs, const VisibilityProgress& progress = {});

// The same query for one ray against every triangle of the field (brute force, for tests):
// returns the hit in continuous texel coordinates, or false for no hit. Periodic fields are
// tested against enough wrapped copies to cover the ray's path.
bool trace_brute_force(const Heightfield& hf, vec3 origin, vec3 dir, vec2& hit_texel);
// The fast query for one ray (what compute_visibility uses).
bool trace(const Heightfield& hf, vec3 origin, vec3 dir, vec2& hit_texel);
}  // namespace mesolab::microgeom
